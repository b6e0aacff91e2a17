"""AugMG query time against N projected library frames, one core (issue 14: goal <= 20 ms at 1M).

The library is the demo library's projected features (real poses, one view) tiled with small jitter up to
N frames (10k, 100k, 1M). Per N and index: build it, then time one query (top-10) of a real 2D pose;
median of >= 5 runs after a warm-up. Baseline in the same run: exact brute-force kNN (numpy,
argpartition over all N distances); recall = share of its top-10 an index returns (32 queries).
Indexes: scipy cKDTree over the 28-d features (leaf size, balanced), and
:class:`vidstyle.augmg.index.PcaTree` (kd-tree over a 6..12-d PCA projection, exact re-ranking with a
lower-bound certificate: exact by construction). Prints a table, writes bench_results/bench_augmg.json.

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


def _recall(got: np.ndarray, exact: np.ndarray) -> float:
    return float(np.mean([len(set(g) & set(e)) / len(e) for g, e in zip(got, exact)]))


def main(library: str, sizes=(10_000, 100_000, 1_000_000), k: int = 10) -> None:
    from scipy.spatial import cKDTree

    from vidstyle.augmg.index import PcaTree, PoseIndex, library_clips

    index = PoseIndex(n_views=1, stride=1).fit(library_clips([Path(library) / "clips"]))
    base = index.features_[0].astype(np.float64)
    rng = np.random.default_rng(0)
    queries = base[rng.choice(len(base), 32, replace=False)] + rng.normal(0, 0.02, (32, base.shape[1]))
    rows = []
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, one thread used")
    print("query: one 2D pose, top-10; recall = share of the exact (brute-force) top-10 returned, over 32 queries")
    print(f"{'N frames':>10} {'index':>26} {'build s':>8} {'query ms':>9} {'vs brute':>9} {'recall':>7}")
    for n in sizes:
        reps = int(np.ceil(n / len(base)))
        feats = np.concatenate([base + rng.normal(0, 0.01, base.shape) for _ in range(reps)])[:n].astype(np.float32)
        qi = iter(range(10**9))

        def brute_knn(q):
            q = q.astype(np.float32)
            d = np.einsum("ij,ij->i", feats - q, feats - q)
            part = np.argpartition(d, k)[:k]
            return part[np.argsort(d[part])]

        exact = np.stack([brute_knn(q) for q in queries])
        t_bf = median_ms(lambda: brute_knn(queries[next(qi) % len(queries)]), runs=5)
        rows.append({"n": n, "index": "brute force (numpy)", "build_s": 0.0, "query_ms": t_bf, "speedup": 1.0,
                     "recall": 1.0})
        print(f"{n:>10} {'brute force (numpy)':>26} {0.0:8.2f} {t_bf:9.2f} {1.0:8.1f}x {1.0:7.3f}", flush=True)
        variants = [(f"kd-tree 28-d leaf {leaf}{' bal' if bal else ''}",
                     (lambda leaf=leaf, bal=bal: cKDTree(feats, leafsize=leaf, balanced_tree=bal, compact_nodes=bal)))
                    for leaf, bal in ((16, False), (32, False), (16, True))]
        variants += [(f"PCA-{m} kd-tree + exact", (lambda m=m: PcaTree(feats, dims=m))) for m in (6, 8, 10, 12)]
        for name, build_fn in variants:
            t0 = time.perf_counter()
            tree = build_fn()
            build = time.perf_counter() - t0
            got = np.stack([np.asarray(tree.query(q, k=k)[1]).ravel() for q in queries])
            rec = _recall(got, exact)
            t = median_ms(lambda: tree.query(queries[next(qi) % len(queries)], k=k))
            rows.append({"n": n, "index": name, "build_s": build, "query_ms": t, "speedup": t_bf / t, "recall": rec})
            print(f"{n:>10} {name:>26} {build:8.2f} {t:9.3f} {t_bf / t:8.1f}x {rec:7.3f}", flush=True)

    Path("bench_results").mkdir(exist_ok=True)
    Path("bench_results/bench_augmg.json").write_text(json.dumps(
        {"machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(), "threads": 1},
         "k": k, "features": int(base.shape[1]), "library": library,
         "runs": "median of 7 (indexes) / 5 (brute) after a warm-up", "queries": 32,
         "rows": rows, "goal_ms_at_1M": 20.0, "when": time.strftime("%Y-%m-%dT%H:%M:%S")}, indent=2))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/augmg_lib")
