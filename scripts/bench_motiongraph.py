"""Benchmark: motion-graph all-pairs distance pass and synthesis.

For N in 1k, 10k, 50k (and 100k with --large) frames of CMU clips resampled to 30 fps (repeated to reach
N), time the exact all-pairs pass (tiled float32 GEMMs, candidates refined in float64; wall time, median
of the runs) and its peak memory (each N in a fresh subprocess, peak RSS), compare with the plain
per-pair reference at 1k frames (the one in tests/test_motiongraph_reference.py), and report the
distance's GFLOP/s (the three GEMMs' useful FLOPs over the upper triangle) and its fraction of the
machine's float32 GEMM rate measured in the same worker, right before and after its timed runs (median
of 5 + 5 products, all threads), so the ratio holds on a shared machine; and the same ratio in CPU time
(the pass's FLOPs per CPU second of all its threads over a one-thread GEMM's FLOPs per CPU second), which
other load on a shared machine disturbs far less. Also synthesis speed (output seconds per wall second).

    python scripts/bench_motiongraph.py [--large] [--runs 5] [--jobs 1]     # --runs at every size (100k: ~10 min)

Writes bench_results/motiongraph.json.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CMU = ROOT.parent / "shared" / "data" / "mocap" / "cmu"
sys.path.insert(0, str(ROOT))
K = 10


def cmu_positions(n_frames: int):
    """(positions, clip_of_frame) of CMU clips at 30 fps, cycled until ``n_frames``."""
    from vidstyle.mocap import Motion, global_positions, read_bvh
    from vidstyle.motiongraph.graph import has_tpose_first_frame

    cache = ROOT / "bench_results" / "cache" / "cmu30_positions.npz"  # git-ignored
    if cache.is_file():
        z = np.load(cache)
        pos, clip = z["pos"], z["clip"]
    else:
        rows = list(csv.DictReader(open(CMU / "clips.csv")))
        ps, cs = [], []
        for c, r in enumerate(rows):
            m = read_bvh(CMU / r["file"])
            m = m[1:] if has_tpose_first_frame(m) else m
            m = m.resample(30.0)
            ps.append(global_positions(Motion(m.skeleton, m.rotations, m.translations, m.fps)))
            cs.append(np.full(m.n_frames, c))
        pos, clip = np.concatenate(ps), np.concatenate(cs)
        cache.parent.mkdir(parents=True, exist_ok=True)
        np.savez(cache, pos=pos, clip=clip)
    reps = int(np.ceil(n_frames / len(pos)))
    n_clips = clip.max() + 1
    pos = np.concatenate([pos] * reps)[:n_frames]
    clip = np.concatenate([clip + i * n_clips for i in range(reps)])[:n_frames]
    return pos, clip


def window_set(n_frames: int):
    from vidstyle.mocap import read_bvh
    from vidstyle.motiongraph.distance import WindowSet, joint_weights

    pos, clip = cmu_positions(n_frames)
    parents = read_bvh(CMU / "02_01.bvh").skeleton.parents
    return WindowSet.from_clips(pos, clip, joint_weights(parents), K)


def threshold_sq(ws) -> float:
    from vidstyle.motiongraph.distance import sample_distances

    return float(np.quantile(sample_distances(ws, 100_000, 2 * K, 0), 0.05))


def worker(n_frames: int, runs: int, jobs: int, tile: int) -> dict:
    """One N in this process: median time of ``runs`` all-pairs passes after a warm-up tile."""
    from vidstyle.motiongraph.distance import all_pair_candidates, compute_tile

    ws = window_set(n_frames)
    thr = threshold_sq(ws)
    m = min(256, ws.n_windows)
    compute_tile(ws, 0, m, 0, m, thr, 2 * K)  # warm-up
    gemm, gemm_cpu = gemm_times(), gemm_cpu_times()
    times, cpu, res = [], [], None
    for _ in range(runs):
        t0, c0 = time.perf_counter(), time.process_time()
        res = all_pair_candidates(ws, thr, 2 * K, tile=tile, n_jobs=jobs, progress=False)
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    gemm += gemm_times()
    gemm_cpu += gemm_cpu_times()
    nw = ws.n_windows
    L = K * ws.positions.shape[1]
    flops = nw * (nw + 1) / 2 * 2 * 5 * L  # three GEMMs, inner sizes 2L, 2L, L, upper triangle
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return {"frames": n_frames, "windows": nw, "runs": runs, "times": times, "median_s": statistics.median(times),
            "gemm_flops": flops, "peak_rss_mb": peak_mb, "candidates": int(len(res.a)), "pairs": res.n_pairs,
            "gemm_peak_flops": GEMM_FLOPS / statistics.median(gemm), "cpu_times": cpu, "median_cpu_s": statistics.median(cpu),
            "gemm_cpu_flops_per_s": GEMM_FLOPS / statistics.median(gemm_cpu)}


def reference_time(n_frames: int) -> dict:
    sys.path.insert(0, str(ROOT / "tests"))
    from test_motiongraph_reference import reference_distance_matrix

    ws = window_set(n_frames)
    t0 = time.perf_counter()
    reference_distance_matrix(ws.positions, ws.starts, ws.weights, K, upper_only=True)
    return {"frames": n_frames, "windows": ws.n_windows, "runs": 1, "median_s": time.perf_counter() - t0}


GEMM_N, GEMM_L = 2048, 2 * K * 31
GEMM_FLOPS = 2 * GEMM_N * GEMM_N * GEMM_L


def gemm_times(runs: int = 5) -> list[float]:
    """Wall times of ``runs`` float32 products of a tile's shape (2048 x 620 by 620 x 2048) on BLAS's
    default threads (all cores): the machine's GEMM limit."""
    rng = np.random.default_rng(0)
    a = rng.standard_normal((GEMM_N, GEMM_L), dtype=np.float32)
    b = rng.standard_normal((GEMM_N, GEMM_L), dtype=np.float32)
    a @ b.T
    ts = []
    for _ in range(runs):
        t0 = time.perf_counter()
        a @ b.T
        ts.append(time.perf_counter() - t0)
    return ts


def gemm_cpu_times(runs: int = 5) -> list[float]:
    """CPU seconds of the same product on one BLAS thread (this thread's CPU time): the GEMM's FLOPs per
    CPU second, which a shared machine's other load disturbs far less than wall time."""
    from threadpoolctl import threadpool_limits

    rng = np.random.default_rng(0)
    a = rng.standard_normal((GEMM_N, GEMM_L), dtype=np.float32)
    b = rng.standard_normal((GEMM_N, GEMM_L), dtype=np.float32)
    ts = []
    with threadpool_limits(1, user_api="blas"):
        a @ b.T
        for _ in range(runs):
            t0 = time.thread_time()
            a @ b.T
            ts.append(time.thread_time() - t0)
    return ts


def gemm_peak(runs: int = 5) -> float:
    return GEMM_FLOPS / statistics.median(gemm_times(runs))


def synthesis_speed(runs: int) -> dict:
    """Planning + rendering speed on the mirrored CMU walk/run/jump graph (~11k frames, ~54k transitions),
    a 20-step walk/jump request of 1-3 s steps."""
    from vidstyle.motiongraph import MotionGraph, Step, load_clips, plan_walk, render_walk
    from vidstyle.motiongraph.labels import cmu_action

    rows = list(csv.DictReader(open(CMU / "clips.csv")))
    files = [CMU / r["file"] for r in rows if cmu_action(r["description"]) in ("walk", "run", "jump")]
    graph = MotionGraph(mirror=True).fit(load_clips(files, [CMU / "clips.csv"]))
    present = {graph.label_names_[i] for i in np.unique(graph.labels_[graph.scc_])}
    acts = [a for a in ("walk", "run", "jump") if a in present]
    rng = np.random.default_rng(0)
    seq = [Step(acts[i % len(acts)], int(rng.integers(30, 90))) for i in range(20)]
    plan_walk(graph, seq[:2])
    ts, plan_ts = [], []
    for _ in range(runs):
        t0 = time.perf_counter()
        walk = plan_walk(graph, seq)
        t1 = time.perf_counter()
        motion = render_walk(graph, walk)
        ts.append(time.perf_counter() - t0)
        plan_ts.append(t1 - t0)
    return {"graph_frames": graph.n_frames, "scc_frames": int(graph.scc_.sum()), "transitions": int(graph.stats_["transitions_in_scc"]),
            "actions": acts, "output_s": motion.duration, "median_s": statistics.median(ts), "plan_median_s": statistics.median(plan_ts),
            "x_real_time": motion.duration / statistics.median(ts), "cost": walk.cost}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--large", action="store_true", help="also 100k frames (several minutes)")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--tile", type=int, default=2048)
    ap.add_argument("--sizes", type=str, default=None, help="comma-separated frame counts (overrides defaults)")
    ap.add_argument("--worker", type=int, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker is not None:
        print(json.dumps(worker(args.worker, args.runs, args.jobs, args.tile)))
        return
    if not CMU.is_dir():
        sys.exit(f"{CMU} is absent")
    from threadpoolctl import threadpool_info

    window_set(1000)  # build the position cache once
    machine = {"cores": os.cpu_count(), "python": platform.python_version(), "numpy": np.__version__,
               "blas": [{k: i.get(k) for k in ("internal_api", "num_threads", "version", "architecture")} for i in threadpool_info()]}
    peak = gemm_peak()
    sizes = [int(s) for s in args.sizes.split(",")] if args.sizes else [1000, 10_000, 50_000] + ([100_000] if args.large else [])
    rows = []
    for n in sizes:
        runs = args.runs  # every size: the median of --runs (>= 5 by the project's bench rule; 100k: ~10 min)
        out = subprocess.run([sys.executable, __file__, "--worker", str(n), "--runs", str(runs), "--jobs", str(args.jobs),
                              "--tile", str(args.tile)], capture_output=True, text=True, check=True)
        r = json.loads(out.stdout.strip().splitlines()[-1])
        r["gflops"] = r["gemm_flops"] / r["median_s"] / 1e9
        r["fraction_of_gemm_peak"] = r["gemm_flops"] / r["median_s"] / r["gemm_peak_flops"]  # same worker
        r["fraction_of_start_gemm_peak"] = r["gemm_flops"] / r["median_s"] / peak
        # the same in CPU time: the pass's FLOPs per CPU second (all its threads) over one-thread GEMM's
        r["fraction_of_gemm_cpu"] = r["gemm_flops"] / r["median_cpu_s"] / r["gemm_cpu_flops_per_s"]
        rows.append(r)
        print(f"N={n}: {r['median_s']:.2f} s, {r['peak_rss_mb']:.0f} MB", file=sys.stderr)
    ref = reference_time(1000)
    fast1k = next((r for r in rows if r["frames"] == 1000), None)
    speedup = ref["median_s"] / fast1k["median_s"] if fast1k else None
    synth = synthesis_speed(max(3, args.runs))
    print(f"machine: {machine['cores']} cores, BLAS {machine['blas']}; float32 GEMM peak {peak / 1e9:.1f} GFLOP/s")
    print(f"{'N':>8} {'windows':>8} {'runs':>4} {'time s':>9} {'peak MB':>8} {'GFLOP/s':>8} {'GEMM GF/s':>9} "
          f"{'of GEMM':>8} {'CPU s':>8} {'of GEMM CPU':>11} {'speed-up':>9}")
    for r in rows:
        sp = ref["median_s"] * (r["windows"] / ref["windows"]) ** 2 / r["median_s"]
        print(f"{r['frames']:>8} {r['windows']:>8} {r['runs']:>4} {r['median_s']:>9.2f} {r['peak_rss_mb']:>8.0f} "
              f"{r['gflops']:>8.1f} {r['gemm_peak_flops'] / 1e9:>9.1f} {r['fraction_of_gemm_peak']:>8.2f} "
              f"{r['median_cpu_s']:>8.2f} {r['fraction_of_gemm_cpu']:>11.2f} {sp:>8.0f}x")
    print("GEMM GF/s: float32 GEMM rate measured in the same worker around its runs; of GEMM: the distance's "
          "GFLOP/s as a fraction of it; CPU s: the pass's CPU time (all threads); of GEMM CPU: its FLOPs per CPU "
          "second over a one-thread GEMM's, in the same worker (steadier on a shared machine)")
    print(f"per-pair reference at 1000 frames: {ref['median_s']:.1f} s (1 run); measured speed-up {speedup:.0f}x "
          "(larger N: reference extrapolated as N^2)")
    print(f"synthesis: {synth['output_s']:.1f} s of motion in {synth['median_s'] * 1000:.0f} ms = {synth['x_real_time']:.0f}x real time "
          f"(graph {synth['graph_frames']} frames, {synth['transitions']} transitions)")
    res = {"machine": machine, "when": time.strftime("%Y-%m-%dT%H:%M:%S"), "gemm_peak_flops": peak, "window": K, "jobs": args.jobs, "tile": args.tile, "rows": rows,
           "reference": ref, "speedup_1k": speedup, "synthesis": synth}
    path = ROOT / "bench_results" / "motiongraph.json"
    path.parent.mkdir(exist_ok=True)
    path.write_text(json.dumps(res, indent=2))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
