#!/usr/bin/env python
"""``vidstyle reconstruct`` speed after pose estimation, one core, against libraries of 10k / 100k / 1M
indexed frames (issue 29: goal >= 30 frames/s at 1M; Tautges' MATLAB version: 2.3 frames/s at 600k).

The library is the demo library (``vidstyle demo make-library``) read once and tiled, with a small jitter of
its projected features, up to N indexed frames at 12 views (each tile a clip of its own, so the lazy
neighbourhood graph sees N distinct frames); the query is a real take: the pictorial-structures poses of a
demo test video (``--poses``, its first 200 frames). Per N and method (``nn``: per-frame neighbours only,
the same run's baseline; ``olng``: the default; ``subsequence``) the wall time of ``Reconstructor.reconstruct``
is the median of >= 5 runs after a warm-up, reported as video frames per second. Index build time is
reported apart (it is paid once per library, not per video).

    vidstyle demo make-library --out /tmp/lib
    python scripts/bench_reconstruct.py /tmp/lib/clips --poses pipelines/kickboxing/out/reconstruct/poses_ps/p02_perf0_front.poses.json
"""

from __future__ import annotations

import argparse
import copy
import os
import sys
import time
from pathlib import Path

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(var, "1")
sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]

import numpy as np
from _benchutil import machine, timeit, write_results

GOAL_FPS_AT_1M = 30.0


def tiled(lib, n: int, seed: int = 0):
    """A copy of a fitted ReconstructionLibrary grown to ``n`` indexed frames by tiling its clips."""
    from vidstyle.augmg.index import build_tree

    rng = np.random.default_rng(seed)
    base_n = lib.n_frames
    reps = int(np.ceil(n / base_n))
    out = copy.copy(lib)
    idx = copy.copy(lib.index_)
    n_clips = len(idx.paths_)
    take = lambda a: np.concatenate([a] * reps)[:n]
    out.rotations_, out.root_height_ = take(lib.rotations_), take(lib.root_height_)
    out.points_, out.contacts_, out.labels_ = take(lib.points_), take(lib.contacts_), take(lib.labels_)
    idx.clip_ = np.concatenate([idx.clip_ + r * n_clips for r in range(reps)])[:n]
    idx.frame_ = take(idx.frame_)
    idx.paths_ = [p for r in range(reps) for p in idx.paths_]
    idx.fps_ = np.concatenate([idx.fps_] * reps)
    feats = np.concatenate([idx.features_] * reps, axis=1)[:, :n]
    idx.features_ = (feats + rng.normal(0, 0.01, feats.shape)).astype(np.float32)
    idx.trees_ = [build_tree(f) for f in idx.features_]
    out.index_ = idx
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("library", type=Path, help="Demo library clips directory.")
    ap.add_argument("--poses", type=Path, required=True, help="poses.json of a demo video (ps).")
    ap.add_argument("--sizes", type=int, nargs="+", default=[10_000, 100_000, 1_000_000])
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    from vidstyle.formats.poses import read_poses
    from vidstyle.reconstruct.core import Observation, Reconstructor
    from vidstyle.reconstruct.library import ReconstructionLibrary

    lib = ReconstructionLibrary().fit([args.library])
    obs = Observation.from_poses(read_poses(args.poses), 20.0, (160, 120), args.frames)
    rows = []
    print(f"{'library frames':>14} {'method':>12} {'build s':>8} {'frames/s':>9} {'vs nn':>7}", flush=True)
    for n in args.sizes:
        t0 = time.perf_counter()
        big = tiled(lib, n)
        build = time.perf_counter() - t0
        base = None
        for method in ("nn", "olng", "subsequence"):
            rec = Reconstructor(method=method).fit_library(big)
            t = timeit(lambda: rec.reconstruct(obs), runs=args.runs)
            fps = args.frames / t["median_s"]
            base = fps if method == "nn" else base
            rows.append({"library_frames": n, "method": method, "build_s": build, "frames_per_s": fps,
                         "ratio_vs_nn": fps / base, **t})
            print(f"{n:>14,} {method:>12} {build:8.1f} {fps:9.1f} {fps / base:7.2f}", flush=True)
        del big
    top = max(args.sizes)
    default = next(r for r in rows if r["library_frames"] == top and r["method"] == "olng")
    path = write_results("reconstruct", {"machine": machine(), "frames": args.frames, "views": lib.n_views,
                                         "goal_fps_at_1M": GOAL_FPS_AT_1M, "rows": rows,
                                         "goal_met": default["frames_per_s"] >= GOAL_FPS_AT_1M if top >= 1_000_000 else None})
    print(f"wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
