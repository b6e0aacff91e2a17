#!/usr/bin/env python
"""Benchmark: ``vidstyle features`` on a long 1080p 60 fps video -- peak memory and wall time against the
video's duration (issue 11: peak RSS <= 1 GB, faster than real time on 2 cores).

The clip is made once (cached under ``bench_results/cache/``): a demo performer (``vidstyle demo
performer``) rendered at 160x120 and 60 fps (``vidstyle render``), each frame upscaled to 1440x1080
(bilinear), centred on a 1920x1080 canvas, looped to ``--seconds`` and encoded with the project's writer
(H.264 crf 17). Each run starts a fresh ``python -m vidstyle features CLIP --out DIR -j 1`` (the default
working rate 20 fps and height 120: 213x120 working frames) and reads the child's own peak RSS and wall
time (``os.wait4``). Rows, each the median of ``--runs`` runs after one warm-up, interleaved run by run:

- ``decode only``: a child that streams the same working frames through ``VideoReader(fps=20, height=120,
  gray=True)`` and does nothing else -- the baseline measured in the same run (decoding the 1080p
  stream is the floor of any features run);
- ``features``: the whole command (decode, salient points, scovanner2007 3D SIFT, write).

Prints a table and writes ``bench_results/bench_video.json``.

    python scripts/bench_video.py [--runs 5] [--seconds 60]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, os.path.dirname(__file__))
from _benchutil import RESULTS, ROOT, machine, write_results  # noqa: E402

GOAL_RSS_MB = 1024.0
SRC_FPS = 60
SIZE = (1920, 1080)

DECODE_ONLY = """
import sys
from vidstyle.video import VideoReader
n = 0
with VideoReader(sys.argv[1], fps=20.0, height=120, gray=True) as r:
    for _ in r:
        n += 1
print(n)
"""


def env() -> dict:
    e = dict(os.environ)
    e["PYTHONPATH"] = str(ROOT) + os.pathsep + e.get("PYTHONPATH", "")
    return e


def make_clip(seconds: float, cache: Path) -> Path:
    """The looped, upscaled demo clip (made once per length)."""
    import cv2
    import numpy as np

    out = cache / f"demo_1080p60_{seconds:g}s.mp4"
    if out.is_file():
        return out
    cache.mkdir(parents=True, exist_ok=True)
    from vidstyle.video import VideoReader, VideoWriter

    with tempfile.TemporaryDirectory() as d:
        bvh, small = Path(d) / "p.bvh", Path(d) / "p.mp4"
        run = [sys.executable, "-m", "vidstyle"]
        subprocess.run([*run, "demo", "performer", "--out", str(bvh), "--seconds", "10", "--fps", "60"],
                       check=True, env=env(), capture_output=True)
        subprocess.run([*run, "render", str(bvh), "--out", str(small), "--fps", str(SRC_FPS),
                        "--background", "texture"], check=True, env=env(), capture_output=True)
        with VideoReader(small) as r:
            loop = [f.copy() for f in r]
        W, H = SIZE
        h = H
        w = int(round(loop[0].shape[1] * H / loop[0].shape[0]))
        n = int(round(seconds * SRC_FPS))
        canvas = np.zeros((H, W, 3), np.uint8)
        x0 = (W - w) // 2
        with VideoWriter(out, SRC_FPS) as wr:
            for i in range(n):
                canvas[:, x0:x0 + w] = cv2.resize(loop[i % len(loop)], (w, h), interpolation=cv2.INTER_LINEAR)
                wr.write(canvas)
    return out


def run_child(args: list[str]) -> tuple[float, float, float]:
    """Wall seconds, CPU seconds (user + system) and peak RSS (MB) of one child process (its own, from
    wait4)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(args, env=env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    err = p.stderr.read().decode(errors="replace") if p.stderr else ""
    if p.returncode != 0:
        raise SystemExit(f"child failed ({p.returncode}): {' '.join(args)}\n{err[-2000:]}")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0  # ru_maxrss: kB on Linux


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("--runs", type=int, default=5, help="timed runs per row, median reported (>= 5 for a "
                    "reported figure; fewer for a quick look)")
    ap.add_argument("--seconds", type=float, default=60.0, help="length of the clip (default 60)")
    ap.add_argument("--name", default="bench_video", help="output stem in bench_results/")
    args = ap.parse_args(argv)
    if args.runs < 1 or args.seconds <= 0:
        ap.error("--runs must be >= 1 and --seconds > 0")

    from vidstyle.video import probe

    clip = make_clip(args.seconds, RESULTS / "cache")
    info = probe(clip)
    duration = info.frames / info.fps
    with tempfile.TemporaryDirectory() as d:
        feats = [sys.executable, "-m", "vidstyle", "features", str(clip), "--out", d, "-j", "1"]
        decode = [sys.executable, "-c", DECODE_ONLY, str(clip)]
        cases = [("decode only (VideoReader 20 fps, 120 px)", decode), ("vidstyle features", feats)]
        for _, c in cases:  # warm-up (page cache, imports)
            run_child(c)
        results: list[tuple[list[float], list[float], list[float]]] = [([], [], []) for _ in cases]
        for _ in range(args.runs):
            for (_, c), (walls, cpus, rss) in zip(cases, results):
                w, cpu, m = run_child(c)
                walls.append(w)
                cpus.append(cpu)
                rss.append(m)
    rows = []
    for (name, _), (walls, cpus, rss) in zip(cases, results):
        med = statistics.median(walls)
        rows.append({"case": name, "median_s": med, "runs_s": walls, "cpu_median_s": statistics.median(cpus),
                     "runs_cpu_s": cpus, "peak_rss_mb_median": statistics.median(rss),
                     "peak_rss_mb_max": max(rss), "runs_rss_mb": rss, "realtime_factor": duration / med,
                     "working_frames_per_s": duration * 20.0 / med})
    base = rows[0]["median_s"]
    for r in rows:
        r["vs_decode_only"] = r["median_s"] / base
    feat = rows[1]
    payload = {
        "benchmark": "video",
        "clip": {"path": str(clip), "frames": info.frames, "fps": info.fps, "width": info.width,
                 "height": info.height, "duration_s": duration, "codec": "h264 crf 17"},
        "runs": args.runs,
        "goal": {"peak_rss_mb": GOAL_RSS_MB, "realtime_factor": 1.0},
        "goal_met": feat["peak_rss_mb_max"] <= GOAL_RSS_MB and feat["realtime_factor"] > 1.0,
        "rows": rows,
        "machine": {**machine(), "load_average_1_5_15min": list(os.getloadavg())},
    }
    path = write_results(args.name, payload)
    print(f"video benchmark: {info.width}x{info.height} {info.fps:.0f} fps, {duration:.0f} s "
          f"({info.frames} frames), median of {args.runs} runs after a warm-up, "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    print(f"{'case':42s} {'wall s':>8s} {'x real time':>11s} {'CPU s':>7s} {'peak RSS MB':>12s} {'vs decode':>10s}")
    for r in rows:
        print(f"{r['case']:42s} {r['median_s']:8.1f} {r['realtime_factor']:11.2f} {r['cpu_median_s']:7.1f} "
              f"{r['peak_rss_mb_max']:12.0f} {r['vs_decode_only']:9.2f}x")
    verdict = "met" if payload["goal_met"] else "NOT met"
    print(f"goal: peak RSS <= {GOAL_RSS_MB:.0f} MB and faster than real time: {verdict}")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
