"""Benchmark of the recognition stage on synthetic features of the demo set's size.

Measures (median of --runs runs after a warm-up, same run for every method so ratios are fair):

- vocabulary fit on set A: MiniBatch k-means vs hierarchical (vocabulary tree) vs full k-means (baseline,
  fewer runs: it is the slow reference), and word assignment of all descriptors;
- recognition accuracy (raw / smoothed frame accuracy on unseen performers) with each vocabulary, so
  the choice of method is made on time *and* accuracy;
- recognizer training on set B (ova-ovo thesis classifier and the plain SVC baseline), prediction speed;
- vocabulary + training total against the goal (<= 120 s on 2 cores).

Writes bench_results/recognition.json. Usage: python scripts/bench_recognition.py [--quick]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _benchutil import machine, timeit, write_results  # noqa: E402

from vidstyle.recognition.evaluate import score_videos  # noqa: E402
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


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="small sizes, 2 runs (smoke test)")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--words", type=int, default=1000)
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
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
