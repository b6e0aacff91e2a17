"""Benchmark the 2D pose backends: ms/frame of pictorial structures (ps) and BlazePose at 160x120 and
640x480 on one core (median of 5 runs after a warm-up; ps once per viewpoint classifier, the
model's own first, and the default detector with multi-scale inference), BlazePose followed through a
1080p sequence (``vidstyle pose``'s default) against BlazePose alone, plus the distance transform
alone (Felzenszwalb-Huttenlocher lower envelope vs separable brute force, the baseline, same run). Wall
and CPU ms are both printed: on a shared, loaded machine the CPU figure is the fairer one.

    python scripts/bench_pose.py [--model pose.joblib] [--out bench_results/pose.json]

Without --model a small model of each detector (hog, cnn) is trained first (a few demo renders; speed
does not depend on how well they are trained). Prints a table and writes JSON.
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

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("GLOG_minloglevel", "2")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import cv2
import numpy as np


CPU_MS: dict = {}
MULTI_SCALES = (1.0, 1.2, 1.4)


def _median_ms(fn, runs: int = 5) -> tuple[float, list[float]]:
    """Median wall-clock ms of ``runs`` calls after a warm-up; the median CPU ms of this process goes
    to ``CPU_MS[id(fn)]`` (on a shared, loaded machine CPU time is the fairer figure)."""
    fn()  # warm-up
    ts, cpu = [], []
    for _ in range(runs):
        t, c = time.perf_counter(), time.process_time()
        fn()
        ts.append((time.perf_counter() - t) * 1000)
        cpu.append((time.process_time() - c) * 1000)
    CPU_MS[id(fn)] = statistics.median(cpu)
    return statistics.median(ts), ts


def _frame(size):
    from vidstyle.demo import Performer, build_take, performance_plan
    from vidstyle.render import Appearance, Camera, render_motion

    rng = np.random.default_rng(5)
    p = Performer.random("p05", rng, video_fps=20)
    m = build_take(p, performance_plan(p, 20, rng), rng, video_fps=20).motion.resample(20)[5:6]
    cam = Camera.for_view(m, view=20.0, size=size)
    frames, _ = render_motion(m, cam, fps=20, appearance=Appearance.random(2), background="texture")
    return frames[0]


def _sequence_1080p(n: int = 10) -> list:
    """``n`` consecutive 1920x1080 frames of a demo performer, shrunk to BlazePose's working height (720 rows,
    as ``vidstyle pose`` reads a 1080p video)."""
    from vidstyle.demo import Performer, build_take, performance_plan
    from vidstyle.pose.blazepose import BlazePoseEstimator
    from vidstyle.render import Appearance, Camera, render_motion

    rng = np.random.default_rng(5)
    p = Performer.random("p05", rng, video_fps=20)
    m = build_take(p, performance_plan(p, 40, rng), rng, video_fps=20).motion.resample(20)[5:5 + n]
    cam = Camera.for_view(m, view=20.0, size=(1920, 1080))
    frames, _ = render_motion(m, cam, fps=20, appearance=Appearance.random(2), background="texture")
    h = BlazePoseEstimator.MAX_HEIGHT
    return [cv2.resize(f, (round(f.shape[1] * h / f.shape[0]), h), interpolation=cv2.INTER_AREA) for f in frames]


def _bench_tracked(runs: int) -> list[dict]:
    """BlazePose followed through a 1080p sequence (vidstyle pose's default) against BlazePose alone on the
    same frames (the baseline, same run): ms per frame, the tracker's state carried from frame to frame."""
    from vidstyle.pose.blazepose import BlazePoseEstimator
    from vidstyle.pose.people import PerformerTracker

    seq = _sequence_1080p()
    est = BlazePoseEstimator()

    def alone():
        for i, f in enumerate(seq):
            est.estimate(f, i)

    def tracked():
        tr = PerformerTracker(est)
        for i, f in enumerate(seq):
            tr.step(f, i)

    rows = []
    for name, fn in (("blazepose alone, 1080p video (720-row working frames)", alone),
                     ("blazepose followed (--track, the default), 1080p video", tracked)):
        ms, r = _median_ms(fn, runs)
        rows.append({"what": name, "size": "1920x1080", "ms_per_frame": ms / len(seq),
                     "cpu_ms_per_frame": CPU_MS[id(fn)] / len(seq), "runs_ms": [x / len(seq) for x in r]})
    est.close()
    return rows


def _small_models() -> dict:
    """One small model per detector (hog, cnn): speed does not depend on how well they are trained."""
    import vidstyle.demo  # noqa: F401 - registers the "demo" training source (demo:<i> specs)
    from vidstyle.pose.cnn import CnnPoseModel
    from vidstyle.pose.data import Spec, render_samples
    from vidstyle.pose.defaults import CNN_DEFAULTS
    from vidstyle.pose.estimator import PoseModel

    specs = [Spec("demo:0", 1.0 + i, 2.0, az, 10.0, 100 + i, fps=8.0)
             for i, az in enumerate((0.0, 90.0, -90.0, 180.0))]
    samples = render_samples(specs, jobs=1, keep_bgr=True)
    return {"hog": PoseModel(hard_rounds=0, neg_per_pos=6).fit(samples, jobs=1),
            "cnn": CnnPoseModel(epochs=1, channels=CNN_DEFAULTS["channels"], batch_size=16, threads=1).fit(samples)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", type=Path, default=None)
    ap.add_argument("--out", type=Path, default=Path("bench_results/pose.json"))
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    try:
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    except (AttributeError, OSError):
        pass
    cv2.setNumThreads(1)
    from threadpoolctl import threadpool_limits

    from vidstyle.pose.blazepose import BlazePoseEstimator
    from vidstyle.pose.dt import brute_dt2d, dt2d
    from vidstyle.pose.estimator import load_model

    rows = []
    with threadpool_limits(1):
        if args.model:
            m = load_model(args.model)[0]
            models = {getattr(m, "detector", "hog"): m}
        else:
            models = _small_models()
        from vidstyle.pose.defaults import DETECTOR

        order = sorted(models, key=lambda d: d != DETECTOR)  # the default detector first
        bp = BlazePoseEstimator()
        for size in ((160, 120), (640, 480)):
            frame = _frame(size)
            for det in order:
                model = models[det]
                default_view = model.viewpoint
                views = [default_view] + [v for v in model.VIEWPOINTS if v != default_view]
                for view in views:
                    model.set_inference(viewpoint=view)
                    f_ps = lambda f=frame, m=model: m.estimate(f)  # noqa: E731
                    ps_ms, ps_runs = _median_ms(f_ps, args.runs)
                    rows.append({"what": f"ps {det} (n_orient={model.n_orient}, viewpoint={view}"
                                         f"{', the default' if view == default_view and det == DETECTOR else ''})",
                                 "size": f"{size[0]}x{size[1]}", "ms_per_frame": ps_ms,
                                 "cpu_ms_per_frame": CPU_MS[id(f_ps)], "runs_ms": ps_runs})
                model.set_inference(viewpoint=default_view)
                if det == DETECTOR:  # multi-scale inference (vidstyle pose --scales): one more pass per zoom
                    model.set_inference(scales=MULTI_SCALES)
                    f_ms = lambda f=frame, m=model: m.estimate(f)  # noqa: E731
                    ms_ms, ms_runs = _median_ms(f_ms, args.runs)
                    rows.append({"what": f"ps {det} --scales {','.join(str(z) for z in MULTI_SCALES)}",
                                 "size": f"{size[0]}x{size[1]}", "ms_per_frame": ms_ms,
                                 "cpu_ms_per_frame": CPU_MS[id(f_ms)], "runs_ms": ms_runs})
                    model.set_inference(scales=(1.0,))
            model = models.get("hog", models[order[0]])
            if getattr(model, "fg_weight", 0.0):  # video input: the person prior's extra work (any background)
                bg = cv2.GaussianBlur(frame, (31, 31), 0)
                f_pr = lambda f=frame, b=bg: model.estimate(f, background=b)  # noqa: E731
                pr_ms, pr_runs = _median_ms(f_pr, args.runs)
                rows.append({"what": f"ps hog (viewpoint={model.viewpoint}) + person prior (video input)",
                             "size": f"{size[0]}x{size[1]}", "ms_per_frame": pr_ms,
                             "cpu_ms_per_frame": CPU_MS[id(f_pr)], "runs_ms": pr_runs})
            f_bp = lambda f=frame: bp.estimate(f)  # noqa: E731
            bp_ms, bp_runs = _median_ms(f_bp, args.runs)
            rows.append({"what": "blazepose (complexity 1)", "size": f"{size[0]}x{size[1]}", "ms_per_frame": bp_ms,
                         "cpu_ms_per_frame": CPU_MS[id(f_bp)], "runs_ms": bp_runs})
        bp.close()
        rows += _bench_tracked(args.runs)
        rng = np.random.default_rng(0)
        maps = rng.normal(size=(5 * model.n_orient, 30, 40))
        f_env = lambda: dt2d(maps, 0.3, 0.3)  # noqa: E731
        f_bru = lambda: brute_dt2d(maps, 0.3, 0.3)  # noqa: E731
        env_ms, env_runs = _median_ms(f_env, args.runs)
        bru_ms, bru_runs = _median_ms(f_bru, args.runs)
        rows.append({"what": f"distance transform, lower envelope ({maps.shape[0]} maps 30x40)", "size": "30x40",
                     "ms_per_frame": env_ms, "cpu_ms_per_frame": CPU_MS[id(f_env)], "runs_ms": env_runs})
        rows.append({"what": f"distance transform, brute force baseline ({maps.shape[0]} maps)", "size": "30x40",
                     "ms_per_frame": bru_ms, "cpu_ms_per_frame": CPU_MS[id(f_bru)], "runs_ms": bru_runs})
    print(f"{'what':62s} {'size':>8s} {'wall ms':>9s} {'cpu ms':>8s}   (medians of {args.runs}, load {os.getloadavg()[0]:.1f})")
    for r in rows:
        print(f"{r['what']:62s} {r['size']:>8s} {r['ms_per_frame']:9.1f} {r['cpu_ms_per_frame']:8.1f}")
    print(f"ratio brute-force / lower-envelope DT: {bru_ms / env_ms:.2f}")
    ps160 = [r for r in rows if r["what"].startswith("ps") and r["size"] == "160x120"]
    bp160 = next(r for r in rows if r["what"].startswith("blazepose") and r["size"] == "160x120")
    print(f"ratio ps (default) / blazepose CPU ms at 160x120: {ps160[0]['cpu_ms_per_frame'] / bp160['cpu_ms_per_frame']:.2f}")
    alone, tracked = (next(r for r in rows if r["what"].startswith(k)) for k in ("blazepose alone", "blazepose followed"))
    print(f"ratio followed / alone BlazePose CPU ms at 1080p: {tracked['cpu_ms_per_frame'] / alone['cpu_ms_per_frame']:.2f}")
    doc = {"benchmark": "pose", "rows": rows, "dt_speedup_vs_brute": bru_ms / env_ms, "runs": args.runs,
           "one_core": True, "python": platform.python_version(), "machine": platform.machine(),
           "model": str(args.model) if args.model else "small models (hog, cnn) trained by the script", "load_avg": os.getloadavg()}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(doc, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
