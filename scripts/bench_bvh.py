"""Benchmark: BVH parse + forward kinematics over the 86 CMU clips, one core, against pybvh in the same run.

Both sides compute the same thing per clip: read the file, then the world positions ``(F, J, 3)`` of
every joint (End Sites excluded) in every frame.

- vidstyle: ``global_positions(read_bvh(path))``;
- pybvh 0.9 (the fastest Python peer, issue 31): ``read_bvh_file(path, world_up="+y").joint_positions()``
  (``world_up`` given, as the CMU clips are Y-up, so pybvh skips its up-axis inference: the peer's faster
  configuration; its positions are the same either way).

Before timing, the script checks on one clip that the two agree (``np.allclose``, rtol 1e-9, and the
maximum absolute difference is printed); pybvh holds angles in radians, converted on read, so the two are
equal to float rounding, not bit for bit. Also timed: vidstyle's parse alone, and the PyPI ``bvh`` parser
(parse only, a subset). Timings alternate vidstyle / pybvh run by run, so load from other jobs on a
shared machine hits both; the figure is the ratio of medians, vidstyle / pybvh (goal <= 0.7, issue 31), of
wall time (and, printed beside it, of CPU time, which load from other processes disturbs less).

    python scripts/bench_bvh.py [--runs 7] [--peer-clips 8]

Writes ``bench_results/bvh.json``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
import warnings

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[var] = "1"

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(__file__))
from _benchutil import SHARED, machine, write_results  # noqa: E402

from vidstyle.mocap import global_positions, read_bvh  # noqa: E402

GOAL_RATIO = 0.7


def interleaved(fns: dict, runs: int, warmup: int = 1) -> dict:
    """Median (and min/max) wall time of each function, the functions called in turn within each run."""
    for _ in range(warmup):
        for fn in fns.values():
            fn()
    times: dict = {name: [] for name in fns}
    cpu: dict = {name: [] for name in fns}
    for _ in range(runs):
        for name, fn in fns.items():
            c0, t0 = time.process_time(), time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
            cpu[name].append(time.process_time() - c0)
    return {name: {"median_s": statistics.median(ts), "min_s": min(ts), "max_s": max(ts), "runs": runs,
                   "median_cpu_s": statistics.median(cpu[name]), "times_s": ts, "cpu_times_s": cpu[name]}
            for name, ts in times.items()}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--peer-clips", type=int, default=8, help="clips given to the (slow) PyPI bvh parser")
    ap.add_argument("--no-pybvh", action="store_true", help="skip pybvh (e.g. when it is not installed)")
    args = ap.parse_args()
    if args.runs < 5:
        ap.error("--runs must be >= 5 (the figure is a median of >= 5 runs)")
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
            global_positions(read_bvh(f))

    def ours_parse(fs=files):
        for f in fs:
            read_bvh(f)

    fns = {"vidstyle parse+FK": ours_parse_fk}
    agreement = None
    pybvh_version = None
    if not args.no_pybvh:
        try:
            import pybvh
        except ImportError:  # the figure is the ratio to pybvh: without it, no result file is (over)written
            print("pybvh is not installed (pip install 'vidstyle[bench]'); run with --no-pybvh to time vidstyle alone",
                  file=sys.stderr)
            return 2
        else:
            pybvh_version = pybvh.__version__

            def peer_parse_fk(fs=files):
                for f in fs:
                    pybvh.read_bvh_file(f, world_up="+y").joint_positions()

            # the two compute the same thing: world positions of every joint of every frame
            check = files[0]
            ours = global_positions(read_bvh(check))
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                theirs = pybvh.read_bvh_file(check, world_up="+y").joint_positions()
                theirs_auto = pybvh.read_bvh_file(check).joint_positions()
            if ours.shape != theirs.shape or not np.allclose(ours, theirs, rtol=1e-9, atol=1e-9):
                raise SystemExit(f"vidstyle and pybvh disagree on {check.name}: shapes {ours.shape} / "
                                 f"{theirs.shape}; they must compute the same positions to be compared")
            if not np.array_equal(theirs, theirs_auto):
                raise SystemExit("pybvh's positions depend on world_up: the benchmark's configuration is unfair")
            agreement = {"clip": check.name, "shape": list(ours.shape),
                         "max_abs_diff": float(np.abs(ours - theirs).max()),
                         "max_abs_position": float(np.abs(ours).max())}
            print(f"agreement on {check.name}: positions {ours.shape}, max |vidstyle - pybvh| = "
                  f"{agreement['max_abs_diff']:.2e} (positions up to {agreement['max_abs_position']:.1f})")
            fns["pybvh parse+FK"] = peer_parse_fk
    fns["vidstyle parse"] = ours_parse
    res = interleaved(fns, runs=args.runs)
    rows = [(name, len(files), frames_all, t) for name, t in res.items()]

    subset = files[:: max(1, len(files) // args.peer_clips)][: args.peer_clips]
    frames_subset = sum(read_bvh(f).n_frames for f in subset)
    try:
        import bvh as pypi_bvh

        def bvh_parse():
            for f in subset:
                mocap = pypi_bvh.Bvh(f.read_text())
                np.asarray(mocap.frames, dtype=np.float64)

        sub = interleaved({"vidstyle parse+FK (subset)": lambda: ours_parse_fk(subset),
                           "PyPI bvh parse (subset)": bvh_parse}, runs=args.runs)
        rows += [(name, len(subset), frames_subset, t) for name, t in sub.items()]
        ratio_bvh = sub["PyPI bvh parse (subset)"]["median_s"] / sub["vidstyle parse+FK (subset)"]["median_s"]
    except ImportError:
        ratio_bvh = None

    try:
        load = [round(v, 2) for v in os.getloadavg()]
    except OSError:
        load = None
    print(f"machine: {machine()['cores']} cores, pinned to 1; runs={args.runs} (median after a warm-up, "
          f"implementations alternating run by run); load average at the end: {load}")
    print(f"{'implementation':30s} {'clips':>5s} {'frames':>8s} {'median s':>9s} {'min s':>7s} {'CPU s':>7s} "
          f"{'frames/s':>10s}")
    out_rows = []
    for name, nclips, nframes, t in rows:
        fps = nframes / t["median_s"]
        print(f"{name:30s} {nclips:5d} {nframes:8d} {t['median_s']:9.3f} {t['min_s']:7.3f} {t['median_cpu_s']:7.3f} "
              f"{fps:10.0f}")
        out_rows.append({"name": name, "clips": nclips, "frames": nframes, **t, "frames_per_s": fps})
    ratio = ratio_cpu = None
    if "pybvh parse+FK" in res:
        ratio = res["vidstyle parse+FK"]["median_s"] / res["pybvh parse+FK"]["median_s"]
        ratio_cpu = res["vidstyle parse+FK"]["median_cpu_s"] / res["pybvh parse+FK"]["median_cpu_s"]
        print(f"vidstyle / pybvh {pybvh_version} time, parse+FK of {len(files)} clips (median of {args.runs}, "
              f"same run): {ratio:.3f} wall, {ratio_cpu:.3f} CPU "
              f"(goal <= {GOAL_RATIO}: {'met' if ratio <= GOAL_RATIO else 'NOT met'})")
    if ratio_bvh is not None:
        print(f"speed-up of vidstyle parse+FK over the PyPI bvh parser (parse only): {ratio_bvh:.1f}x")
    path = write_results("bvh", {
        "machine": machine(), "load_average": load, "runs": args.runs,
        "pinned_cores": 1, "when": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "peer": {"name": "pybvh", "version": pybvh_version,
                 "call": 'pybvh.read_bvh_file(path, world_up="+y").joint_positions()'},
        "ours": {"call": "vidstyle.mocap.global_positions(vidstyle.mocap.read_bvh(path))"},
        "agreement": agreement, "rows": out_rows,
        "ratio_vs_pybvh": ratio, "ratio_vs_pybvh_cpu": ratio_cpu, "goal_ratio_vs_pybvh": GOAL_RATIO,
        "goal_met": ratio is not None and ratio <= GOAL_RATIO,
        "speedup_vs_pypi_bvh_parse": ratio_bvh,
    })
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
