#!/usr/bin/env python
"""The stance lead cue's premise on real motion the demo never had: CMU clips (another skeleton, real
people), rendered through cameras of several views and elevations.

The cue (:func:`vidstyle.actionmodel.stylefit.video_figures`, ``stance_side``) takes the ankle lower in the
image for the front foot. Here, per frame of each clip's true 2D projection (``Camera.for_view``, the
demo's camera model), the ankle lower in the image is compared with the ankle that is truly in front in 3D
(the larger offset along the performer's facing direction), on frames whose ankles are at least
``--min-gap`` metres apart along it. Reported per view and elevation: the share of frames where the two
agree, over all clips and for the punch / strike clips alone (``clips.csv`` descriptions). No parameter
of the cue is fitted here.

    python scripts/stance_cue_real_motion.py [--cmu ../shared/data/mocap/cmu]

Writes ``--out`` (default ``pipelines/kickboxing/results/stance_cue_cmu.json``) and prints the table.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
VIEWS = ("front", "left", "right")
ELEVATIONS = (0.0, 10.0, 30.0)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cmu", type=Path, default=ROOT.parent / "shared" / "data" / "mocap" / "cmu")
    ap.add_argument("--fps", type=float, default=20.0, help="Frame rate the clips are resampled to (the demo's video rate).")
    ap.add_argument("--min-gap", type=float, default=0.10, help="Metres between the ankles along the facing direction.")
    ap.add_argument("--out", type=Path, default=ROOT / "pipelines" / "kickboxing" / "results" / "stance_cue_cmu.json")
    args = ap.parse_args()
    from vidstyle.actionmodel.stylefit import LAN, RAN
    from vidstyle.demo.skeleton import UNIT_M  # CMU's length unit in metres (its README), the demo's too
    from vidstyle.fileio import write_text
    from vidstyle.mocap import read_bvh
    from vidstyle.mocap.keypoints import keypoint_positions
    from vidstyle.mocap.motion import facing_directions
    from vidstyle.motiongraph.graph import has_tpose_first_frame
    from vidstyle.render.camera import Camera

    desc = {r["file"]: r["description"] for r in csv.DictReader(open(args.cmu / "clips.csv"))}
    strikes = {f for f, d in desc.items() if "punch" in d or "strike" in d or "box" in d}
    counts: dict[str, dict[str, list[int]]] = {}
    for f in sorted(args.cmu.glob("*.bvh")):
        m = read_bvh(f)
        if has_tpose_first_frame(m):
            m = m[1:]
        m = m.resample(args.fps)
        pts = keypoint_positions(m)
        face = facing_directions(m)
        ahead = np.einsum("fc,fc->f", pts[:, LAN] - pts[:, RAN], face) * UNIT_M  # > 0: the left ankle in front
        sel = np.abs(ahead) >= args.min_gap
        if not sel.any():
            continue
        for view in VIEWS:
            for el in ELEVATIONS:
                uv, _ = Camera.for_view(m, view, elevation_deg=el, positions=pts).project(pts)
                left_lower = uv[:, LAN, 1] > uv[:, RAN, 1]
                agree = int(np.sum(left_lower[sel] == (ahead[sel] > 0)))
                for group in ("all", "strikes") if f.name in strikes else ("all",):
                    c = counts.setdefault(group, {}).setdefault(f"{view}@{el:g}", [0, 0])
                    c[0] += agree
                    c[1] += int(sel.sum())
    table = {g: {k: {"agreement": a / n, "frames": n} for k, (a, n) in v.items()} for g, v in counts.items()}
    doc = {"kind": "vidstyle.results.stance_cue_cmu", "schema_version": 1,
           "command": "python scripts/stance_cue_real_motion.py " + " ".join(sys.argv[1:]),
           "fps": args.fps, "min_gap_m": args.min_gap, "strike_clips": sorted(strikes), "by_group": table}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_text(args.out, json.dumps(doc, indent=1) + "\n")
    print(f"{'view@elevation':>16s} " + " ".join(f"{g:>16s}" for g in table))
    for k in table["all"]:
        print(f"{k:>16s} " + " ".join(f"{table[g][k]['agreement']:9.3f} ({table[g][k]['frames']:>5d})"
                                       if k in table[g] else f"{'':>16s}" for g in table))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
