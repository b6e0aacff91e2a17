"""Benchmark: BVH parse + forward kinematics throughput over the 86 CMU clips, one core.

Compares, in the same run, vidstyle's reader (parse, and parse + FK) with the PyPI `bvh` parser (parse
to a numeric frame array, no FK) on a subset of the clips, and prints the throughput ratio.
Goal (issue 2): all 86 clips parsed with FK in under 5 s on one core.

    python scripts/bench_bvh.py [--runs 5] [--peer-clips 8]
"""

from __future__ import annotations

import argparse
import os
import sys

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[var] = "1"

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(__file__))
from _benchutil import SHARED, machine, timeit, write_results  # noqa: E402

from vidstyle.mocap import forward_kinematics, read_bvh  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--peer-clips", type=int, default=8, help="clips given to the (slow) peer parser")
    args = ap.parse_args()
    cmu = SHARED / "data" / "mocap" / "cmu"
    files = sorted(cmu.glob("*.bvh"))
    if not files:
        print(f"no CMU clips under {cmu}; nothing to benchmark")
        return 1
    try:
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})  # one core
    except (AttributeError, OSError):
        pass

    frames_all = sum(read_bvh(f).n_frames for f in files)

    def ours_parse_fk(fs=files):
        for f in fs:
            forward_kinematics(read_bvh(f), return_matrices=False)

    def ours_parse(fs=files):
        for f in fs:
            read_bvh(f)

    subset = files[:: max(1, len(files) // args.peer_clips)][: args.peer_clips]
    frames_subset = sum(read_bvh(f).n_frames for f in subset)

    rows = []
    t = timeit(ours_parse_fk, runs=args.runs)
    rows.append(("vidstyle parse+FK", len(files), frames_all, t))
    t = timeit(ours_parse, runs=args.runs)
    rows.append(("vidstyle parse", len(files), frames_all, t))
    t_ours_sub = timeit(lambda: ours_parse_fk(subset), runs=args.runs)
    rows.append(("vidstyle parse+FK (subset)", len(subset), frames_subset, t_ours_sub))
    try:
        import bvh as peer

        def peer_parse():
            for f in subset:
                mocap = peer.Bvh(f.read_text())
                np.asarray(mocap.frames, dtype=np.float64)

        t_peer = timeit(peer_parse, runs=args.runs)
        rows.append(("PyPI bvh parse (subset)", len(subset), frames_subset, t_peer))
        ratio = t_peer["median_s"] / t_ours_sub["median_s"]
    except ImportError:
        ratio = None

    print(f"machine: {machine()['cores']} cores, pinned to 1; runs={args.runs} (median after warm-up)")
    print(f"{'implementation':30s} {'clips':>5s} {'frames':>8s} {'median s':>9s} {'frames/s':>10s}")
    out_rows = []
    for name, nclips, nframes, t in rows:
        fps = nframes / t["median_s"]
        print(f"{name:30s} {nclips:5d} {nframes:8d} {t['median_s']:9.3f} {fps:10.0f}")
        out_rows.append({"name": name, "clips": nclips, "frames": nframes, **t, "frames_per_s": fps})
    if ratio is not None:
        print(f"speed-up of vidstyle parse+FK over the PyPI bvh parser (parse only): {ratio:.1f}x")
    goal = rows[0][3]["median_s"] < 5.0
    print(f"goal: all {len(files)} clips parse+FK < 5 s on one core: {'met' if goal else 'NOT met'}")
    path = write_results("bench_bvh", {"machine": machine(), "rows": out_rows, "ratio_vs_bvh": ratio, "goal_met": goal})
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
