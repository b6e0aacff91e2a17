"""Helpers shared by the benchmark scripts: machine description, repeated timing, JSON output."""

from __future__ import annotations

import json
import os
import platform
import statistics
import time
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
RESULTS = ROOT / "bench_results"


def machine() -> dict:
    info = {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cores": os.cpu_count(),
    }
    try:
        from threadpoolctl import threadpool_info

        info["blas"] = [
            {k: p.get(k) for k in ("internal_api", "version", "num_threads", "architecture")} for p in threadpool_info()
        ]
    except Exception:  # threadpoolctl missing: the benchmark still runs
        info["blas"] = "unknown"
    return info


def timeit(fn: Callable[[], object], runs: int = 5, warmup: int = 1) -> dict:
    """Median (and min/max) wall time of ``runs`` calls after ``warmup`` calls."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return {"median_s": statistics.median(times), "min_s": min(times), "max_s": max(times), "runs": runs}


def write_results(name: str, payload: dict) -> Path:
    """Write ``bench_results/<name>.json``, stamped with the date and time of the run (``when``) unless the
    payload has one (scripts/bench_table.py shows it)."""
    import time

    payload = {"when": time.strftime("%Y-%m-%dT%H:%M:%S"), **payload}
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{name}.json"
    path.write_text(json.dumps(payload, indent=2) + "\n")
    return path
