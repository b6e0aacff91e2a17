"""Benchmark: the annotation server's frame latency through its HTTP API, and opening a long video.

Measured against a running ``vidstyle annotate`` server (uvicorn in a thread, an HTTP client on loopback),
on numbered test videos (H.264 .mp4 from the project's writer, key frame every 250 frames):

- **step**: the next frame (i -> i+1), as a person stepping with F at ~20 presses/s (a 50 ms pause between
  requests, not timed), with the server's read-ahead (default) and without it;
- **seek**: a random frame anywhere in the video;
- **baseline**, in-process without HTTP: ``VideoReader.frame(i)`` + JPEG encoding, for the same steps and
  seeks (the ratio shows what HTTP and the server add);
- **open**: ``open_videos`` (demux index + sha256) and the first frame of a 10-minute 1080p video.

Every frame served is checked to show its own number. Median of ``--requests`` requests after a warm-up.
Goals (issue 15): step <= 10 ms; seek <= 50 ms at 640x480 and <= 100 ms at 1080p.

    python scripts/bench_annotate.py [--requests 60] [--seconds 20] [--long-minutes 10] [--workdir /tmp/bench_annotate]
        [--only all|latency|open]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from _benchutil import RESULTS, machine, write_results

from vidstyle.annotate import session as sess
from vidstyle.annotate.server import Running, new_session
from vidstyle.annotate.session import Store, open_videos
from vidstyle.video import VideoReader, write_video
from vidstyle.video.numbered import numbered_frame, read_number


def make_video(path: Path, w: int, h: int, n: int, fps: float = 30.0, texture: bool = True) -> Path:
    if path.exists():
        with VideoReader(path) as r:
            if len(r) == n and r.size == (w, h):
                return path
    # content: the frame number plus moving noise texture so the codec has real work (not flat frames)
    rng = np.random.default_rng(0)
    tex = rng.integers(0, 255, (h + 64, w + 64), dtype=np.uint8)
    tex = cv2.GaussianBlur(tex, (0, 0), 3)

    def frames():
        for i in range(n):
            img = numbered_frame(i, w, h)
            if not texture:
                yield img
                continue
            k = i % 64
            band = tex[k:k + h - h // 6, k:k + w]
            img[h // 6:, :, :] = (0.5 * img[h // 6:, :, :] + 0.5 * band[..., None]).astype(np.uint8)
            yield img

    t0 = time.perf_counter()
    write_video(frames(), path, fps)
    print(f"# wrote {path} ({w}x{h}, {n} frames) in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    return path


def stats(ts: list[float]) -> dict:
    ms = [1000 * t for t in ts]
    return {"median_ms": statistics.median(ms), "p90_ms": float(np.percentile(ms, 90)), "max_ms": max(ms), "n": len(ms)}


def bench_http(video: Path, requests: int, plan: dict, read_ahead: bool, tmp: Path) -> dict:
    import httpx

    old = sess.READ_AHEAD
    sess.READ_AHEAD = sess.READ_AHEAD if read_ahead else 0
    try:
        vids = open_videos([video])
        s = new_session(vids, Store(tmp / "ann.json", vids, ["a"]))
        with Running(s) as url, httpx.Client(base_url=url, timeout=60) as c:
            def get(i):
                t0 = time.perf_counter()
                r = c.get(f"/api/videos/0/frames/{i}")
                dt = time.perf_counter() - t0
                assert r.status_code == 200
                img = cv2.imdecode(np.frombuffer(r.content, np.uint8), cv2.IMREAD_COLOR)
                assert read_number(img) == i, (i, read_number(img))
                return dt

            start = plan["start"]
            for i in range(start, start + 5):  # warm-up
                get(i)
            step = []
            for i in range(start + 5, start + 5 + requests):
                time.sleep(0.05)
                step.append(get(i))
            back2back = [get(i) for i in range(start + 5 + requests, start + 5 + 2 * requests)] if read_ahead else []
            seek = []
            for i in plan["seek"]:
                time.sleep(0.02)
                seek.append(get(int(i)))
        for v in vids:
            v.close()
    finally:
        sess.READ_AHEAD = old
    out = {"step": stats(step), "seek": stats(seek)}
    if back2back:
        out["step_back_to_back"] = stats(back2back)
    return out


def bench_inproc(video: Path, requests: int, plan: dict) -> dict:
    with VideoReader(video) as r:

        def get(i):
            t0 = time.perf_counter()
            ok, buf = cv2.imencode(".jpg", r.frame(i), [cv2.IMWRITE_JPEG_QUALITY, sess.JPEG_QUALITY])
            return time.perf_counter() - t0

        start = plan["start"]
        for i in range(start, start + 5):
            get(i)
        step = [get(i) for i in range(start + 5, start + 5 + requests)]
        seek = [get(int(i)) for i in plan["seek"]]
    return {"step": stats(step), "seek": stats(seek)}


def bench_decode_parts(video: Path, requests: int, rng) -> dict:
    """Where a seek's time goes: decoding alone (no encoding) vs JPEG encoding alone."""
    with VideoReader(video) as r:
        n = len(r)
        idx = [int(i) for i in rng.integers(0, n, requests)]
        dec = []
        for i in idx:
            r.clear_cache()
            t0 = time.perf_counter()
            img = r.frame(i)
            dec.append(time.perf_counter() - t0)
        enc = []
        for _ in range(requests):
            t0 = time.perf_counter()
            cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, sess.JPEG_QUALITY])
            enc.append(time.perf_counter() - t0)
    return {"decode_seek": stats(dec), "jpeg_encode": stats(enc)}


def bench_open(video: Path, runs: int) -> dict:
    opens, firsts = [], []
    for _ in range(runs):
        t0 = time.perf_counter()
        vids = open_videos([video])
        t1 = time.perf_counter()
        vids[0].image(0, read_ahead=False)
        t2 = time.perf_counter()
        frames = vids[0].frames
        vids[0].close()
        opens.append(t1 - t0)
        firsts.append(t2 - t1)
    # the test video is small (flat content); a camera's 10 minutes of 1080p is ~750 MB (10 Mbit/s), so the
    # content hash is measured on its own: MB/s of file_sha256 over a 256 MB file
    from vidstyle.formats.annotations import file_sha256

    blob = video.parent / "sha_probe.bin"
    with open(blob, "wb") as f:
        f.write(b"\0" * (256 << 20))
    t0 = time.perf_counter()
    file_sha256(blob)
    sha_mb_s = 256 * 1.048576 / (time.perf_counter() - t0)
    blob.unlink()
    return {"open_s": statistics.median(opens), "first_frame_s": statistics.median(firsts), "frames": frames,
            "runs": runs, "size_mb": video.stat().st_size / 1e6, "sha256_mb_per_s": sha_mb_s,
            "estimated_open_s_at_10_mbit_s": statistics.median(opens) + 750 / sha_mb_s}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--requests", type=int, default=60)
    ap.add_argument("--seconds", type=float, default=20, help="length of the 640x480 and 1080p test videos")
    ap.add_argument("--long-minutes", type=float, default=10)
    ap.add_argument("--workdir", type=Path, default=Path("/tmp/bench_annotate"))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--only", choices=("all", "latency", "open"), default="all",
                    help="run only the latency part or only the long-video open (results merge into one JSON)")
    args = ap.parse_args()
    args.workdir.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(args.seed)
    fps = 30.0
    n = int(args.seconds * fps)
    sizes = {"640x480": (640, 480), "1080p": (1920, 1080)}
    rows = {}
    for name, (w, h) in (sizes.items() if args.only != "open" else []):
        v = make_video(args.workdir / f"{name}.mp4", w, h, n, fps)
        tmp = args.workdir / f"run_{name}"
        tmp.mkdir(exist_ok=True)
        (tmp / "ann.json").unlink(missing_ok=True)
        # the same frames for every variant: a start for the steps, random frames for the seeks
        plan = {"start": int(rng.integers(0, n - 2 * args.requests - 10)),
                "seek": [int(i) for i in rng.integers(0, n, args.requests)]}
        rows[name] = {"http": bench_http(v, args.requests, plan, True, tmp)}
        (tmp / "ann.json").unlink(missing_ok=True)
        rows[name]["http_no_read_ahead"] = bench_http(v, args.requests, plan, False, tmp)
        rows[name]["in_process"] = bench_inproc(v, args.requests, plan)
        rows[name]["parts"] = bench_decode_parts(v, min(30, args.requests), rng)
    opened = None
    if args.only != "latency":
        long = make_video(args.workdir / f"long_{args.long_minutes:g}min_1080p.mp4", 1920, 1080,
                          int(args.long_minutes * 60 * 25), 25.0, texture=False)
        opened = bench_open(long, 5)
    goals = {"640x480": (10, 50), "1080p": (10, 100)}
    if rows:
        print("| size | measure | HTTP (read-ahead) | HTTP (no read-ahead) | in-process baseline | goal |")
        print("|---|---|---|---|---|---|")
    for name, r in rows.items():
        for m, g in zip(("step", "seek"), goals[name]):
            print(f"| {name} | {m} median ms | {r['http'][m]['median_ms']:.1f} | {r['http_no_read_ahead'][m]['median_ms']:.1f} "
                  f"| {r['in_process'][m]['median_ms']:.1f} | <= {g} |")
        print(f"| {name} | step back-to-back median ms | {r['http']['step_back_to_back']['median_ms']:.1f} | | | |")
        print(f"| {name} | parts: decode-only seek / JPEG encode ms | {r['parts']['decode_seek']['median_ms']:.1f} / "
              f"{r['parts']['jpeg_encode']['median_ms']:.1f} | | | |")
    if opened:
        print(f"\nopen a {args.long_minutes:g}-minute 1080p video ({opened['frames']} frames, {opened['size_mb']:.0f} MB): "
              f"{opened['open_s']:.2f} s (demux index + sha256), first frame {1000 * opened['first_frame_s']:.0f} ms; "
              f"sha256 {opened['sha256_mb_per_s']:.0f} MB/s, so a 750 MB camera file (10 Mbit/s) opens in about "
              f"{opened['estimated_open_s_at_10_mbit_s']:.1f} s")
    prev = RESULTS / "annotate.json"
    old = json.loads(prev.read_text()) if prev.exists() and args.only != "all" else {}
    out = write_results("annotate", {"machine": machine(), "args": {k: str(v) for k, v in vars(args).items()},
                                     "results": rows or old.get("results", {}),
                                     "open_long": opened or old.get("open_long"),
                                     "goals_ms": {k: {"step": a, "seek": b} for k, (a, b) in goals.items()}})
    print(f"wrote {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
