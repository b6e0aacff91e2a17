"""Benchmark: renderer throughput (frames/s) at 160x120 and 640x480 on ONE core.

For each motion and size it times, as the median of ``--runs`` runs after a warm-up:

- ``render_motion``: the whole in-memory rendering (resampling, FK, projection, z-buffer raster,
  shading, outline, background, noise, visibility) divided by the number of frames;
- ``raster only``: the per-frame part alone (precomputation excluded);
- ``render_to_file``: the same plus mp4 encoding and the sidecar, i.e. what ``vidstyle render`` costs.

Both wall-clock and CPU (process) time are reported; on a shared machine the CPU time is the steadier
measure of what one core delivers. The goal is judged on wall-clock time.

Motions: CMU 02_05 (punch/strike, 120 fps resampled to 20 fps) when ../shared is present, and the
built-in sample walk. Goal (issue 3): >= 200 frames/s at 160x120, so rendering never dominates a
pipeline run.

    python scripts/bench_render.py [--runs 5] [--frames 200]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[var] = "1"

import cv2

sys.path.insert(0, os.path.dirname(__file__))
from _benchutil import SHARED, machine, write_results

from vidstyle.mocap import read_bvh
from vidstyle.render import Appearance, Camera, render_motion, render_to_file
from vidstyle.render.core import RenderJob
from vidstyle.render.samples import sample_motion

GOAL_FPS = 200.0
SIZES = [(160, 120), (640, 480)]


def timeit(fn, runs: int, warmup: int = 1) -> dict:
    """Median wall and CPU (process) time of ``runs`` calls after ``warmup`` calls. On a shared, loaded
    machine the CPU time is the steadier measure of what one core delivers."""
    for _ in range(warmup):
        fn()
    wall, cpu = [], []
    for _ in range(runs):
        c0, t0 = time.process_time(), time.perf_counter()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return {"median_s": statistics.median(wall), "min_s": min(wall), "max_s": max(wall),
            "median_cpu_s": statistics.median(cpu), "runs": runs}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--frames", type=int, default=200, help="video frames per run (20 fps)")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    try:
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})  # one core
    except (AttributeError, OSError):
        pass

    motions = {}
    clip = SHARED / "data" / "mocap" / "cmu" / "02_05.bvh"
    if clip.is_file():
        m = read_bvh(clip)
        motions["cmu 02_05"] = m[: int(args.frames * m.fps / 20.0)]
    motions["sample walk"] = sample_motion(args.frames, fps=20.0)

    rows = []
    look = Appearance.random(0)
    with tempfile.TemporaryDirectory() as tmp:
        for name, m in motions.items():
            for size in SIZES:
                cam = Camera.for_view(m, view="front", size=size)
                frames, _ = render_motion(m, cam, fps=20.0, appearance=look, background="texture")
                n = len(frames)

                def full(m=m, cam=cam):
                    render_motion(m, cam, fps=20.0, appearance=look, background="texture", seed=1)

                job = RenderJob(m, cam, 20.0, look, "texture", 2.0, 1, None, None)

                def raster_only(job=job):
                    for _ in job.frames(False):
                        pass

                def to_file(m=m, cam=cam, out=Path(tmp) / "b.mp4"):
                    render_to_file(m, out, camera=cam, fps=20.0, appearance=look, background="texture")

                for stage, fn in (("render_motion", full), ("raster only", raster_only), ("render_to_file", to_file)):
                    t = timeit(fn, runs=args.runs, warmup=1)
                    fps = n / t["median_s"]
                    cpu_fps = n / t["median_cpu_s"]
                    rows.append({"motion": name, "size": f"{size[0]}x{size[1]}", "stage": stage, "frames": n,
                                 **t, "frames_per_s": fps, "frames_per_cpu_s": cpu_fps,
                                 "goal_ratio": fps / GOAL_FPS if size == (160, 120) else None})

    print(f"renderer, one core, median of {args.runs} runs after a warm-up (goal >= {GOAL_FPS:g} frames/s at 160x120)")
    try:
        load = " ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        load = "?"
    print(f"load average at the end: {load} (wall-clock numbers suffer when other jobs share the core)")
    print(f"{'motion':<12} {'size':>8} {'stage':<15} {'frames':>6} {'median s':>9} {'frames/s':>9} "
          f"{'per CPU s':>9} {'vs goal':>8}")
    for r in rows:
        ratio = f"{r['goal_ratio']:.2f}x" if r["goal_ratio"] is not None else ""
        print(f"{r['motion']:<12} {r['size']:>8} {r['stage']:<15} {r['frames']:>6} {r['median_s']:>9.3f} "
              f"{r['frames_per_s']:>9.0f} {r['frames_per_cpu_s']:>9.0f} {ratio:>8}")
    ok = all(r["frames_per_s"] >= GOAL_FPS for r in rows if r["size"] == "160x120" and r["stage"] == "render_motion")
    path = write_results("render", {"machine": machine(), "load_average": load, "runs": args.runs,
                                    "goal_frames_per_s": GOAL_FPS,
                                    "goal_met": ok, "results": rows, "when": time.strftime("%Y-%m-%dT%H:%M:%S")})
    print(f"goal {'met' if ok else 'NOT met'}; wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
