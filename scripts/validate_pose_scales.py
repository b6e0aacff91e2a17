#!/usr/bin/env python
"""Choose the zoom factors of the pictorial structures' multi-scale inference (``vidstyle pose --backend ps
--scales``; the default of :func:`vidstyle.pose.run.estimate_video`, :data:`vidstyle.pose.defaults.PS_SCALES`)
on validation renders whose figures are smaller and larger than the training renders' (a walker crossing
a room, a phone held close).

The renders: the pose split's *validation* demo performers (``make_specs("val", ...)``: performers 30..,
never a training or test performer of the pose model), each seen from ``--views`` cameras at elevations
-10..45 degrees, figure sizes drawn from ``--figure-scales`` (1 = the training renders' nominal figure),
random looks and backgrounds. No CMU clip: the pose split's validation subject (08) is a test subject of
the held-out reconstruction and of the real-motion split.

Every frame is estimated once at scale 1 and once per zoom of the union of the candidates
(:meth:`vidstyle.pose.estimator.PoseModel.zoom_candidates`, what ``estimate`` does); a candidate set's pose of
a frame is the one of its zooms whose keypoints score highest on average (``estimate``'s rule). Scores per
candidate: PCK@0.2 (:func:`vidstyle.evaluation.pose.pck`) and strict PCP per figure-size bin, and their
mean over the bins (each range of sizes counts alike). Rule: of the candidates within ``--tolerance`` of the
best mean PCK, the one with the fewest zooms (each costs a pass of the model), then the higher PCK.

    python scripts/validate_pose_scales.py

Writes ``pipelines/kickboxing/validation/pose_scales.json`` and prints the table. About 3 min on 2 cores.
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
ROOT = Path(__file__).resolve().parents[1]
log = logging.getLogger("validate_pose_scales")

CANDIDATES = ((1.0,), (1.0, 1.2, 1.4), (1.0, 1.5), (1.0, 2.0), (1.0, 1.5, 2.0), (1.0, 1.4, 2.0),
              (1.0, 1.5, 2.0, 2.5), (0.75, 1.0, 1.5, 2.0), (0.75, 1.0, 1.4, 2.0, 2.8))
BINS = (0.3, 0.5, 0.7, 0.9, 1.1, 1.4)


_MODEL: dict = {}


def _frame_zooms(item):
    """Every zoom's pose of one clip's frames: (n_frames, n_zooms, 15, 3)."""
    import numpy as np

    from vidstyle.pose.interfaces import backend_factory
    from vidstyle.pose.run import resolve_model

    frames, zooms, background = item
    if "model" not in _MODEL:  # one load per worker process, not per clip
        _MODEL["model"] = backend_factory("ps")(str(resolve_model("ps", None)))
    model = _MODEL["model"]
    return np.stack([np.stack([c.points for c in model.zoom_candidates(f, zooms, background=background)])
                     for f in frames]) if frames else np.zeros((0, len(zooms) + 1, 15, 3))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--performers", type=int, default=20)
    ap.add_argument("--views", type=int, default=8)
    ap.add_argument("--figure-scales", default="0.3,1.4", help="LOW,HIGH figure sizes (1 = the training renders')")
    ap.add_argument("--tolerance", type=float, default=0.01, help="mean PCK@0.2 within this of the best counts as equal")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=-1)
    ap.add_argument("--out", type=Path, default=ROOT / "pipelines" / "kickboxing" / "validation" / "pose_scales.json")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    log.setLevel(logging.INFO)
    import numpy as np

    import vidstyle.demo  # noqa: F401  (registers the demo performers as a render source)
    from vidstyle.evaluation.pose import clip_backgrounds, frame_of, pck, strict_pcp
    from vidstyle.formats.validation import POSE_SCALES, validation_header, write_validation
    from vidstyle.parallel import parallel_map
    from vidstyle.pose.data import make_specs, render_samples
    from vidstyle.pose.defaults import SHIPPED_MODEL_NAME
    from vidstyle.pose.estimator import check_scales

    t0 = time.time()
    lo, hi = (float(v) for v in args.figure_scales.split(","))
    specs = make_specs("val", args.performers, 0, args.views, args.seed, None, elevation=(-10.0, 45.0),
                       scale=(lo, hi))
    samples = render_samples(specs, jobs=args.jobs, keep_bgr=True)
    figure = {s.seed: s.scale for s in specs}
    backgrounds = clip_backgrounds(samples)
    zooms = tuple(sorted({z for c in CANDIDATES for z in check_scales(c)} - {1.0}))
    by_clip: dict = {}  # the samples grouped by clip (one worker item each), in order of first appearance
    for s in samples:
        by_clip.setdefault(s.clip, []).append(s)
    items = [([frame_of(s) for s in group], zooms, backgrounds.get(c)) for c, group in by_clip.items()]
    log.info("%d frames of %d clips, zooms %s", len(samples), len(by_clip), zooms)
    P = np.concatenate(parallel_map(_frame_zooms, items, jobs=args.jobs, description="pose at every zoom"))
    samples = [s for group in by_clip.values() for s in group]  # the rows of P
    gt = np.stack([s.keypoints for s in samples])
    size = np.array([figure[s.clip] for s in samples])
    which = np.digitize(size, BINS[1:-1])
    score = P[:, :, :, 2].mean(axis=2)  # (n, 1 + zooms)
    rows = []
    for cand in CANDIDATES:
        cols = [0] + [1 + zooms.index(z) for z in cand if z != 1.0]
        pick = np.array(cols)[np.argmax(score[:, cols], axis=1)]  # the first of equals, as estimate() picks
        pred = P[np.arange(len(P)), pick]
        k = pck(pred, gt).mean(axis=1)
        c = strict_pcp(pred, gt).mean(axis=1)
        per_bin = [{"figure_scale": [BINS[b], BINS[b + 1]], "frames": int((which == b).sum()),
                    "pck@0.2": float(k[which == b].mean()), "pcp": float(c[which == b].mean())}
                   for b in range(len(BINS) - 1) if (which == b).any()]
        rows.append({"scales": list(cand), "passes": len(cols),
                     "pck@0.2": float(np.mean([r["pck@0.2"] for r in per_bin])),
                     "pcp": float(np.mean([r["pcp"] for r in per_bin])), "by_figure_scale": per_bin,
                     "zoom_chosen_share": {str(z): float(np.mean(pick == j)) for z, j in zip(cand, cols)}})
    best = max(r["pck@0.2"] for r in rows)
    chosen = min((r for r in rows if r["pck@0.2"] >= best - args.tolerance), key=lambda r: (r["passes"], -r["pck@0.2"]))
    doc = {**validation_header(POSE_SCALES), "script": "scripts/validate_pose_scales.py", "seed": args.seed,
           "model": SHIPPED_MODEL_NAME, "performers": args.performers, "views": args.views,
           "split": "val (demo performers 30..; no CMU subject)", "figure_scales": [lo, hi],
           "elevation": [-10.0, 45.0], "frames": len(samples), "clips": len(by_clip), "tolerance": args.tolerance,
           "rule": "fewest zooms within tolerance of the best mean PCK@0.2 over figure-size bins, then higher PCK",
           "candidates": rows, "chosen": chosen["scales"], "wall_seconds": round(time.time() - t0, 1)}
    write_validation(args.out, doc)
    print(f"{'scales':<28} {'passes':>6} {'PCK@0.2':>8} {'PCP':>6}  " + "  ".join(
        f"{r['figure_scale'][0]:.1f}-{r['figure_scale'][1]:.1f}" for r in rows[0]["by_figure_scale"]))
    for r in rows:
        mark = " *" if r is chosen else ""
        print(f"{','.join(f'{z:g}' for z in r['scales']):<28} {r['passes']:>6} {r['pck@0.2']:>8.3f} {r['pcp']:>6.3f}  "
              + "  ".join(f"{b['pck@0.2']:>7.3f}" for b in r["by_figure_scale"]) + mark)
    return 0


if __name__ == "__main__":
    sys.exit(main())
