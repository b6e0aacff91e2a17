"""AugMG query time against N projected library frames, one core (issue 14: goal <= 20 ms at 1M).

The library is the demo library's projected features (real poses, one view) tiled with small jitter up to
N frames (10k, 100k, 1M). Per N: build the kd-tree (scipy cKDTree, as PoseIndex does), then time one
query (top-10) of a real 2D pose; median of >= 5 runs after a warm-up. Baseline in the same run:
brute-force kNN (numpy, argpartition over all N distances). Prints a table, writes
bench_results/bench_augmg.json.

    vidstyle demo make-library --out /tmp/augmg_lib
    python scripts/bench_augmg.py /tmp/augmg_lib
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np


def median_ms(fn, runs: int = 7) -> float:
    fn()  # warm-up
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1000.0 * float(np.median(times))


def main(library: str, sizes=(10_000, 100_000, 1_000_000), k: int = 10) -> None:
    from scipy.spatial import cKDTree

    from vidstyle.augmg.index import PoseIndex, library_clips

    index = PoseIndex(n_views=1, stride=1).fit(library_clips([Path(library) / "clips"]))
    base = index.features_[0].astype(np.float64)
    rng = np.random.default_rng(0)
    queries = base[rng.choice(len(base), 32, replace=False)] + rng.normal(0, 0.02, (32, base.shape[1]))
    rows = []
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, one thread used")
    print(f"{'N frames':>10} {'build s':>8} {'kd-tree ms':>11} {'brute ms':>9} {'speed-up':>9}")
    for n in sizes:
        reps = int(np.ceil(n / len(base)))
        feats = np.concatenate([base + rng.normal(0, 0.01, base.shape) for _ in range(reps)])[:n].astype(np.float32)
        t0 = time.perf_counter()
        tree = cKDTree(feats, leafsize=16, balanced_tree=False, compact_nodes=False)
        build = time.perf_counter() - t0
        qi = iter(range(10**9))

        def kd():
            tree.query(queries[next(qi) % len(queries)], k=k)

        def brute():
            q = queries[next(qi) % len(queries)].astype(np.float32)
            d = np.einsum("ij,ij->i", feats - q, feats - q)
            np.argpartition(d, k)[:k]

        t_kd, t_bf = median_ms(kd), median_ms(brute, runs=5)
        rows.append({"n": n, "build_s": build, "query_ms": t_kd, "brute_ms": t_bf, "speedup": t_bf / t_kd})
        print(f"{n:>10} {build:8.2f} {t_kd:11.3f} {t_bf:9.2f} {t_bf / t_kd:9.0f}x", flush=True)
    Path("bench_results").mkdir(exist_ok=True)
    Path("bench_results/bench_augmg.json").write_text(json.dumps(
        {"machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(), "threads": 1},
         "k": k, "features": int(base.shape[1]), "library": library, "runs": "median of 7 (kd) / 5 (brute) after warm-up",
         "rows": rows, "goal_ms_at_1M": 20.0}, indent=2))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/augmg_lib")
