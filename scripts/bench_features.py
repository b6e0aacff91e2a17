#!/usr/bin/env python
"""Benchmark: frames/s of salient points + 3D SIFT at 160x120 on one core (goal >= 300 frames/s).

The clip is synthetic and made in memory (textured blobs moving in different directions, 20 fps), so
the numbers measure feature extraction, not video decoding. Every row is the median of ``--runs``
timed runs after one warm-up; everything runs on one thread (OpenCV and BLAS limited to 1).

Wall-clock frames/s is the reported figure; CPU-time frames/s is printed beside it because on a shared
machine other processes stretch wall time (the cases are interleaved run by run for the same reason).

Rows, all on the same frames and the same points:

- ``salient points``: silhouette + DIS optical flow + non-maximum suppression (10 points/frame);
- ``thesis 3D SIFT``: the vectorised descriptor alone;
- ``thesis, naive per-point loop``: the straightforward one-point-at-a-time implementation
  (``vidstyle.features._reference``), the baseline of the row above;
- ``salient + thesis`` and ``salient + scovanner2007``: the whole per-frame work of ``vidstyle features``
  for each variant (the goal applies to these);
- ``2D SIFT (ablation)`` and ``salient + sift2d``: the 2D descriptor of the ablation, alone and whole.

Prints a table and writes ``bench_results/bench_features.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

GOAL_FPS = 300.0


def synthetic_clip(n_frames: int, height: int = 120, width: int = 160, seed: int = 0) -> np.ndarray:
    """Textured blobs on a textured static background, moving right, up and diagonally."""
    rng = np.random.default_rng(seed)
    bg = 0.15 + 0.1 * rng.random((height, width))
    tex = 0.2 * rng.random((height, width))
    t = np.arange(n_frames)[:, None, None]
    r = np.arange(height)[None, :, None]
    c = np.arange(width)[None, None, :]
    vol = np.broadcast_to(bg, (n_frames, height, width)).copy()
    for r0, c0, vr, vc, rad in [(60, 30, 0.0, 2.0, 14), (90, 110, -1.5, 0.0, 10), (30, 60, 1.0, 1.0, 8)]:
        rr = (r0 + vr * t) % height
        cc = (c0 + vc * t) % width
        inside = (r - rr) ** 2 + (c - cc) ** 2 <= rad * rad
        vol = np.where(inside, 0.6 + np.roll(tex, int(vc), axis=1)[None], vol)
    return vol.astype(np.float32)


def machine_info() -> dict:
    import cv2
    from threadpoolctl import threadpool_info

    cpu = platform.processor()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    blas = [
        {k: d.get(k) for k in ("internal_api", "version", "architecture", "num_threads", "filepath")}
        for d in threadpool_info()
    ]
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "affinity": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "opencv": cv2.__version__,
        "blas": blas,
        "load_average_1_5_15min": list(os.getloadavg()) if hasattr(os, "getloadavg") else None,
    }


def timed_interleaved(cases: list, runs: int) -> list[tuple[list[float], list[float]]]:
    """(wall times, CPU times) of each case; one warm-up each, then the cases take turns run by run, so
    that load from other processes on a shared machine spreads evenly over all of them."""
    for _, fn, _ in cases:
        fn()
    out: list[tuple[list[float], list[float]]] = [([], []) for _ in cases]
    for _ in range(runs):
        for (_, fn, _), (wall, cpu) in zip(cases, out):
            w0, c0 = time.perf_counter(), time.process_time()
            fn()
            cpu.append(time.process_time() - c0)
            wall.append(time.perf_counter() - w0)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=100, help="frames in the clip (default 100)")
    ap.add_argument("--runs", type=int, default=7, help="timed runs per row, median reported (>= 5)")
    ap.add_argument("--out", type=Path, default=ROOT / "bench_results" / "bench_features.json")
    args = ap.parse_args(argv)
    if args.runs < 5:
        ap.error("--runs must be >= 5")

    import cv2
    from threadpoolctl import threadpool_limits

    from vidstyle.features._reference import describe_thesis_loop
    from vidstyle.features.salient import SalientParams, salient_points
    from vidstyle.features.sift3d import Sift3DParams, describe

    cv2.setNumThreads(1)
    clip = synthetic_clip(args.frames)
    T, H, W = clip.shape
    sp = SalientParams()
    rows = []
    with threadpool_limits(limits=1):
        pts = salient_points(clip, sp)
        n_pts = len(pts)
        cases = [
            ("salient points (DIS)", lambda: salient_points(clip, sp), T),
            ("thesis 3D SIFT (vectorised)", lambda: describe(clip, pts, "thesis"), T),
            (
                "thesis 3D SIFT, naive per-point loop",
                lambda: describe_thesis_loop(clip, pts, Sift3DParams()),
                T,
            ),
            ("scovanner2007 3D SIFT", lambda: describe(clip, pts, "scovanner2007"), T),
            ("salient + thesis", lambda: describe(clip, salient_points(clip, sp), "thesis"), T),
            ("salient + scovanner2007", lambda: describe(clip, salient_points(clip, sp), "scovanner2007"), T),
            ("2D SIFT (ablation)", lambda: describe(clip, pts, "sift2d"), T),
            ("salient + sift2d", lambda: describe(clip, salient_points(clip, sp), "sift2d"), T),
        ]
        for (name, _, frames), (wall, cpu) in zip(cases, timed_interleaved(cases, args.runs)):
            med = statistics.median(wall)
            rows.append(
                {
                    "case": name,
                    "frames": frames,
                    "points": n_pts,
                    "median_s": med,
                    "runs_s": wall,
                    "cpu_median_s": statistics.median(cpu),
                    "cpu_runs_s": cpu,
                    "frames_per_s": frames / med,
                    "frames_per_cpu_s": frames / statistics.median(cpu),
                    "us_per_point": 1e6 * med / max(n_pts, 1),
                }
            )
    by = {r["case"]: r for r in rows}
    base = by["thesis 3D SIFT, naive per-point loop"]["median_s"]
    for r in rows:
        if "3D SIFT" in r["case"]:
            r["speedup_vs_naive_loop"] = base / r["median_s"]
    headline = by["salient + thesis"]["frames_per_s"]
    result = {
        "benchmark": "features",
        "size": {"frames": T, "height": H, "width": W, "points_per_frame": sp.n_points, "points": n_pts},
        "runs": args.runs,
        "threads": 1,
        "goal_frames_per_s": GOAL_FPS,
        "headline_frames_per_s": headline,
        "goal_met": headline >= GOAL_FPS,
        "realtime_factor_at_20fps": headline / 20.0,
        "rows": rows,
        "machine": machine_info(),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.out.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(result, indent=2) + "\n")
    os.replace(tmp, args.out)

    m = result["machine"]
    print(
        f"features benchmark: {T} frames {W}x{H}, {n_pts} points ({sp.n_points}/frame), one thread, "
        f"median of {args.runs} runs after a warm-up"
    )
    print(
        f"machine: {m['cpu']}, {m['cores']} cores, load average {m['load_average_1_5_15min'][0]:.1f}; BLAS: "
        + ", ".join(f"{b['internal_api']} {b['version']} ({b['architecture']})" for b in m["blas"])
    )
    print(f"{'case':40s} {'frames/s':>10s} {'frames/cpu-s':>13s} {'us/point':>10s} {'vs naive':>9s}")
    for r in rows:
        sp_ = f"{r['speedup_vs_naive_loop']:.1f}x" if "speedup_vs_naive_loop" in r else ""
        print(
            f"{r['case']:40s} {r['frames_per_s']:10.1f} {r['frames_per_cpu_s']:13.1f} "
            f"{r['us_per_point']:10.1f} {sp_:>9s}"
        )
    verdict = "met" if result["goal_met"] else "NOT met"
    print(
        f"salient + thesis: {headline:.0f} frames/s = {headline / 20:.1f}x real time at 20 fps "
        f"(goal {GOAL_FPS:.0f} frames/s: {verdict})"
    )
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
