"""Benchmark of the recognition stage on synthetic features of the demo set's size.

Measures (median of --runs runs after a warm-up, same run for every method so ratios are fair):

- vocabulary fit on set A: MiniBatch k-means vs hierarchical (vocabulary tree) vs full k-means (baseline,
  fewer runs: it is the slow reference), and word assignment of all descriptors;
- recognition accuracy (raw / smoothed frame accuracy on unseen performers) with each vocabulary, so
  the choice of method is made on time *and* accuracy;
- recognizer training on set B (ova-ovo thesis classifier and the plain SVC baseline), prediction speed;
- vocabulary + training total against the goal (<= 120 s on 2 cores).

Writes bench_results/recognition.json. Usage: python scripts/bench_recognition.py [--quick]

With ``--dataset DIR --features-dir DIR`` it measures the same stage on *real* features of a demo dataset
(``vidstyle demo make-dataset`` + ``vidstyle features``) instead: sets A and B of the seeded
unseen-performer split, the recognizer with its defaults; wall *and* CPU time (process time, all threads)
of the vocabulary fit and of the recognizer training, median of ``--runs`` runs after a warm-up, against
the goal (vocabulary + training <= 120 s on 2 cores). Writes bench_results/recognition_real.json.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _benchutil import machine, timeit, write_results  # noqa: E402

from vidstyle.evaluation.recognition import score_videos  # noqa: E402
from vidstyle.recognition.recognizer import ActionRecognizer  # noqa: E402
from vidstyle.recognition.synthetic import ACTIONS, SyntheticWorld, performance_sequence, single_sequence  # noqa: E402
from vidstyle.recognition.vocabulary import Vocabulary  # noqa: E402


def make_data(n_performers: int, views: list[str], dim: int, seed: int):
    """In-memory videos: per performer and view, one single-action video per action + one performance."""
    rng = np.random.default_rng(seed)
    perf = [f"p{i:02d}" for i in range(n_performers)]
    world = SyntheticWorld.make(rng, dim=dim, performers=perf, views=views, noise=0.8, n_points=10)
    videos = []
    for p in perf:
        items = [(a, single_sequence(rng, a, (4, 7))) for a in ACTIONS] + [(None, performance_sequence(rng, 20))]
        for v in views:
            for a, seq in items:
                videos.append({"performer": p, "view": v, "action": a, "labels": seq,
                               "features": world.video(rng, seq, p, v, f"{p}_{a}_{v}")})
    return videos


def _timed(fn, runs: int, warmup: int = 1) -> dict:
    """Median wall and CPU (process, all threads) seconds of ``runs`` calls after ``warmup`` calls."""
    import statistics

    for _ in range(warmup):
        fn()
    wall, cpu = [], []
    for _ in range(runs):
        w, c = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - w)
        cpu.append(time.process_time() - c)
    return {"median_s": statistics.median(wall), "min_s": min(wall), "max_s": max(wall),
            "cpu_median_s": statistics.median(cpu), "runs": runs}


def main_real(args) -> None:
    """Vocabulary + recognizer training on the real features of a demo dataset (issue 4, item 8)."""
    from threadpoolctl import threadpool_limits

    from vidstyle.evaluation.recognition import load_set
    from vidstyle.formats.dataset import read_dataset as load_dataset
    from vidstyle.recognition.splits import make_split

    ds = load_dataset(args.dataset)
    sp = make_split(ds, "unseen-performer", seed=0)
    t0 = time.perf_counter()
    fa, _ = load_set(ds, Path(args.features_dir), sp.vocab, args.jobs)
    fb, lb = load_set(ds, Path(args.features_dir), sp.train, args.jobs)
    ft, lt = load_set(ds, Path(args.features_dir), sp.test, args.jobs)
    load_s = time.perf_counter() - t0
    XA = np.concatenate([f.descriptors for f in fa if f.descriptors.shape[0]])
    yB = [t.labels for t in lb]
    classes = ds.classes
    sizes = {
        "videos_A": len(fa), "videos_B": len(fb), "videos_test": len(ft), "descriptors_A": int(XA.shape[0]),
        "dim": int(XA.shape[1]), "frames_B": int(sum(f.n_frames for f in fb)),
        "frames_test": int(sum(f.n_frames for f in ft)), "load_s": load_s,
        "frames_all": int(sum(v.frames or 0 for v in ds.videos)) if hasattr(ds.videos[0], "frames") else None,
    }
    print(f"data: {sizes}")
    runs = 2 if args.quick else args.runs
    result: dict = {"machine": machine(), "dataset": str(args.dataset), "features_dir": str(args.features_dir),
                    "jobs": args.jobs, "sizes": sizes}
    # BLAS limited to the same number of threads as the joblib workers, so "2 cores" means 2 cores
    with threadpool_limits(limits=args.jobs):
        voc_box = {}

        def fit_voc():
            voc_box["v"] = Vocabulary(n_words=args.words, random_state=0).fit(XA)

        tv = _timed(fit_voc, runs)
        voc = voc_box["v"]
        print(f"vocabulary minibatch {args.words} words: {tv['median_s']:.1f} s wall, {tv['cpu_median_s']:.1f} s CPU")
        rec_box = {}

        def fit_rec():
            rec_box["r"] = ActionRecognizer(vocabulary=voc, n_jobs=args.jobs, random_state=0).fit(fb, yB, classes=classes)

        tr = _timed(fit_rec, runs)
        rec = rec_box["r"]
        print(f"recognizer training (defaults): {tr['median_s']:.1f} s wall, {tr['cpu_median_s']:.1f} s CPU")
        tp = _timed(lambda: rec.predict_many(ft), max(1, runs // 2))
    outs = rec.predict_many(ft)
    by = ds.by_id()
    m = score_videos(rec.classes_, [t.labels for t in lt], outs, sp.test,
                     [by[i].action if by[i].kind == "single" else None for i in sp.test])
    total = tv["median_s"] + tr["median_s"]
    result.update({
        "vocabulary_fit": tv, "recognizer_train": tr, "predict_test": {**tp, "frames_per_s": sizes["frames_test"] / tp["median_s"]},
        "vocabulary_plus_training_s": total,
        "vocabulary_plus_training_cpu_s": tv["cpu_median_s"] + tr["cpu_median_s"], "goal_s": 120,
        "recognizer_params": rec.public_params(), "model": rec.summary(),
        "frame_accuracy": m["frame_accuracy"], "video_accuracy": m["video_accuracy"],
    })
    print(f"vocabulary + training: {total:.1f} s wall ({result['vocabulary_plus_training_cpu_s']:.1f} s CPU), goal <= 120 s; "
          f"predict {result['predict_test']['frames_per_s']:.0f} frames/s; test frame accuracy raw "
          f"{m['frame_accuracy']['raw']:.3f} smoothed {m['frame_accuracy']['smoothed']:.3f}")
    path = write_results("recognition_real_quick" if args.quick else "recognition_real", result)
    print(f"wrote {path}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="small sizes, 2 runs (smoke test)")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--words", type=int, default=1000)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--dataset", default=None, help="demo dataset: measure on its real features (with --features-dir)")
    ap.add_argument("--features-dir", default=None)
    args = ap.parse_args()
    if args.dataset or args.features_dir:
        if not (args.dataset and args.features_dir):
            ap.error("--dataset and --features-dir go together")
        return main_real(args)
    runs = 2 if args.quick else args.runs
    n_perf, dim = (7, 64) if args.quick else (10, 256)
    words = 200 if args.quick else args.words
    t0 = time.perf_counter()
    videos = make_data(n_perf, ["front", "left", "right"], dim, seed=0)
    gen_s = time.perf_counter() - t0
    # split by performer: 30 % test, 20 % vocabulary (A), the rest classifier (B)
    perfs = sorted({v["performer"] for v in videos})
    n_t, n_a = max(1, round(0.3 * len(perfs))), max(1, round(0.2 * len(perfs)))
    test_p, a_p = set(perfs[:n_t]), set(perfs[n_t : n_t + n_a])
    A = [v for v in videos if v["performer"] in a_p]
    B = [v for v in videos if v["performer"] not in a_p | test_p]
    T = [v for v in videos if v["performer"] in test_p]
    XA = np.concatenate([v["features"].descriptors for v in A])
    n_frames = sum(v["features"].n_frames for v in videos)
    sizes = {
        "videos": len(videos), "frames": n_frames, "descriptors": int(sum(len(v["features"].descriptors) for v in videos)),
        "dim": dim, "words": words, "set_A_descriptors": int(XA.shape[0]),
        "set_B_frames": int(sum(v["features"].n_frames for v in B)),
        "test_frames": int(sum(v["features"].n_frames for v in T)), "generate_s": gen_s,
    }
    print(f"data: {sizes}")

    result: dict = {"machine": machine(), "sizes": sizes, "vocabulary": {}, "recognition": {}}
    vocabs = {}
    for method, r in (("minibatch", runs), ("hierarchical", runs), ("kmeans", 1 if not args.quick else 1)):
        make = lambda m=method: Vocabulary(n_words=words, method=m, branching=10, random_state=0).fit(XA)  # noqa: E731
        t = timeit(make, runs=r, warmup=1 if method != "kmeans" else 0)
        voc = make()
        vocabs[method] = voc
        ta = timeit(lambda: voc.transform(XA), runs=r, warmup=1)
        result["vocabulary"][method] = {"fit": t, "assign_set_A": ta}
        print(f"vocabulary {method:12s} fit {t['median_s']:.2f} s, assign {ta['median_s']:.3f} s")
    base = result["vocabulary"]["minibatch"]["fit"]["median_s"]
    for m in vocabs:
        result["vocabulary"][m]["fit_ratio_vs_minibatch"] = result["vocabulary"][m]["fit"]["median_s"] / base

    # accuracy of each vocabulary with the same recognizer settings
    yB = [v["labels"] for v in B]
    fB = [v["features"] for v in B]
    classes = ACTIONS + ["Guard", "Step"]
    for method, voc in vocabs.items():
        rec = ActionRecognizer(vocabulary=voc, n_jobs=args.jobs, random_state=0)
        t = time.perf_counter()
        rec.fit(fB, yB, classes=classes)
        train_s = time.perf_counter() - t
        t = time.perf_counter()
        outs = rec.predict_many([v["features"] for v in T])
        pred_s = time.perf_counter() - t
        m = score_videos(rec.classes_, [v["labels"] for v in T], outs, [str(i) for i in range(len(T))],
                         [v["action"] for v in T])
        result["recognition"][method] = {
            "frame_accuracy": m["frame_accuracy"], "video_accuracy": m["video_accuracy"],
            "train_s_single_run": train_s, "predict_s": pred_s, "model": rec.summary(),
        }
        print(f"recognition with {method:12s}: raw {m['frame_accuracy']['raw']:.3f} smoothed "
              f"{m['frame_accuracy']['smoothed']:.3f} video {m['video_accuracy']:.3f} (train {train_s:.1f} s)")

    voc = vocabs["minibatch"]
    train = {}
    for clf in ("ova-ovo", "svc-ovr"):
        fit = lambda c=clf: ActionRecognizer(vocabulary=voc, classifier=c, n_jobs=args.jobs, random_state=0).fit(  # noqa: E731
            fB, yB, classes=classes)
        train[clf] = timeit(fit, runs=runs, warmup=1)
        print(f"train {clf}: {train[clf]['median_s']:.2f} s")
    rec = ActionRecognizer(vocabulary=voc, n_jobs=1, random_state=0).fit(fB, yB, classes=classes)
    tf = sum(v["features"].n_frames for v in T)
    pt = timeit(lambda: [rec.predict_video(v["features"]) for v in T], runs=runs, warmup=1)
    result["train"] = train
    result["train"]["ratio_ova_ovo_vs_svc_ovr"] = train["ova-ovo"]["median_s"] / train["svc-ovr"]["median_s"]
    result["predict"] = {**pt, "frames": tf, "frames_per_s_one_core": tf / pt["median_s"]}
    total = {m: result["vocabulary"][m]["fit"]["median_s"] + train["ova-ovo"]["median_s"] for m in ("minibatch", "hierarchical")}
    result["vocabulary_plus_training_s"] = total
    result["goal_s"] = 120
    print(f"predict: {tf / pt['median_s']:.0f} frames/s (one core); vocabulary + training: "
          + ", ".join(f"{m} {s:.1f} s" for m, s in total.items()) + " (goal <= 120 s)")
    path = write_results("recognition_quick" if args.quick else "recognition", result)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
