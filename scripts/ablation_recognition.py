#!/usr/bin/env python
"""Ablation table of the recognition stage (issue 4, item 6): which of the thesis' choices help?

Every row trains the vocabulary on set A and the recognizer on set B of the same seeded split and scores
the same held-out test videos (``vidstyle.evaluation.recognition.evaluate_recognition``); only the named
choice differs from the reference row ("vidstyle defaults"):

- ``no word grouping``, ``no +/-2 frame context`` (histogram of frame n only), ``no smoothing`` (window 1),
  ``no mirror-image training`` (only the videos as recorded; scovanner2007 features only);
- ``thesis smoothing`` (window-6 vote instead of the default smoother);
- ``vocabulary 500 / 1500`` words (the reference has the default 1000);
- descriptors: ``scovanner2007`` 3D SIFT (the authors' released code) and ``2D SIFT`` (frame patch only)
  instead of the thesis 3D SIFT, each from its own features directory made by ``vidstyle features``;
- classifier: the plain multi-class SVC baseline instead of the thesis' one-vs-all + one-vs-one SVMs
  (scored in the reference run itself, on the same features).

Usage::

    python scripts/ablation_recognition.py --dataset /tmp/demo_full \\
        --features thesis=/tmp/f_thesis --features scovanner2007=/tmp/f_scov --features sift2d=/tmp/f_2d

Rows are scored on the *validation* performers by default (``--score-set val``): an ablation guides
choices, and choices must not see the test performers. ``--score-set test`` reports the test split (only
for a final report of fixed choices; the defaults are chosen by ``scripts/validate_recognition.py``).

Rows whose features directory is not given are skipped. Writes ``bench_results/ablation_recognition.json``
and ``bench_results/ablation_recognition.md`` (``--name`` changes the stem).
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _benchutil import RESULTS, machine, write_results

from vidstyle.evaluation.recognition import evaluate_recognition
from vidstyle.formats.dataset import read_dataset as load_dataset

log = logging.getLogger("ablation")


def rows_spec(features: dict[str, str], reference: str = "thesis") -> list[dict]:
    """(name, features variant, evaluate_recognition keyword overrides) of every row; the reference row and
    the rows that switch one recognizer choice use the ``reference`` variant's features."""
    names = {"thesis": "thesis 3D SIFT", "scovanner2007": "scovanner2007 3D SIFT", "sift2d": "2D SIFT"}
    rows = [
        {"name": "vidstyle defaults (thesis 3D SIFT)", "variant": "thesis", "kw": {}},
        {"name": "no word grouping", "variant": "thesis", "kw": {"ablation": "no-grouping"}},
        {"name": "no +/-2 frame context", "variant": "thesis", "kw": {"ablation": "no-context"}},
        {"name": "no smoothing", "variant": "thesis", "kw": {"ablation": "no-smoothing"}},
        {"name": "no mirror-image training", "variant": "thesis", "kw": {"ablation": "no-mirror"}},
        {"name": "thesis smoothing (vote, window 6)", "variant": "thesis",
         "kw": {"recognizer_params": {"smoothing": "vote", "smoothing_window": 6}}},
        {"name": "vocabulary 500", "variant": "thesis", "kw": {"n_words": 500}},
        {"name": "vocabulary 1500", "variant": "thesis", "kw": {"n_words": 1500}},
        {"name": "scovanner2007 3D SIFT", "variant": "scovanner2007", "kw": {}, "descriptor": True},
        {"name": "2D SIFT instead of 3D", "variant": "sift2d", "kw": {}, "descriptor": True},
    ]
    for r in rows:
        if not r.get("descriptor"):
            r["variant"] = reference
    rows[0]["name"] = f"vidstyle defaults ({names.get(reference, reference)})"
    # the descriptor rows: every variant other than the reference
    rows = [r for r in rows if not r.get("descriptor") or r["variant"] != reference]
    if reference != "thesis":
        rows.append({"name": "thesis 3D SIFT instead", "variant": "thesis", "kw": {}})
    return [r for r in rows if r["variant"] in features]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", required=True, help="dataset.json or its directory")
    ap.add_argument("--features", action="append", default=[], metavar="VARIANT=DIR",
                    help="features directory per variant: thesis=..., scovanner2007=..., sift2d=...")
    ap.add_argument("--reference", default="thesis",
                    help="variant of the reference row and of the grouping/context/smoothing/vocabulary rows")
    ap.add_argument("--split", default="unseen-performer", help="unseen-performer | unseen-view")
    ap.add_argument("--test-view", default=None)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--only", action="append", default=[], help="run only rows whose name contains this")
    ap.add_argument("--name", default="ablation_recognition", help="output stem in bench_results/")
    ap.add_argument("--score-set", default="val", choices=["val", "test"],
                    help="score the validation performers (default) or the test performers")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s")
    features = {}
    for f in args.features:
        if "=" not in f:
            ap.error(f"--features: expected VARIANT=DIR, got {f!r}")
        k, v = f.split("=", 1)
        features[k] = v
    if args.reference not in features:
        ap.error(f"--features {args.reference}=DIR is required (the reference row)")
    ds = load_dataset(args.dataset)
    rows = rows_spec(features, args.reference)
    if args.only:
        rows = [r for r in rows if any(o.lower() in r["name"].lower() for o in args.only)]
    results = []
    for r in rows:
        kw = dict(r["kw"])
        # the baseline classifier is scored inside the reference run (same vocabulary, histograms, PCA)
        baseline = r["name"].startswith("vidstyle defaults")
        t0 = time.perf_counter()
        m = evaluate_recognition(
            ds, features[r["variant"]], split_kind=args.split, seed=args.seed, test_view=args.test_view,
            n_jobs=args.jobs, baseline=baseline, score_set=args.score_set, **kw,
        )
        wall = time.perf_counter() - t0
        row = {
            "name": r["name"], "variant": r["variant"], "overrides": kw, "features_dir": features[r["variant"]],
            "frame_accuracy_raw": m["frame_accuracy"]["raw"], "frame_accuracy_smoothed": m["frame_accuracy"]["smoothed"],
            "video_accuracy": m["video_accuracy"], "n_test_frames": m["n_test_frames"],
            "n_test_single_videos": m["n_test_single_videos"], "timing_s": m["timing_s"], "wall_s": wall,
            "params": m["params"], "per_class": m["per_class"],
        }
        results.append(row)
        log.info("%s: raw %.3f smoothed %.3f video %s", r["name"], row["frame_accuracy_raw"],
                 row["frame_accuracy_smoothed"], row["video_accuracy"])
        if baseline and "baseline" in m:
            b = m["baseline"]
            results.append({
                "name": "plain SVC baseline instead of OvA+OvO", "variant": r["variant"], "overrides": {"classifier": "svc-ovr"},
                "features_dir": features[r["variant"]], "frame_accuracy_raw": b["frame_accuracy"]["raw"],
                "frame_accuracy_smoothed": b["frame_accuracy"]["smoothed"], "video_accuracy": b["video_accuracy"],
                "n_test_frames": m["n_test_frames"], "n_test_single_videos": m["n_test_single_videos"],
                "timing_s": {"train": b["train_s"]}, "wall_s": b["train_s"],
            })
    payload = {
        "kind": "vidstyle.ablation.recognition", "dataset": str(args.dataset), "split": args.split,
        "test_view": args.test_view, "seed": args.seed, "score_set": args.score_set, "features": features, "machine": machine(), "rows": results,
    }
    path = write_results(args.name, payload)
    md = [
        f"# Recognition ablation ({args.split}{', test view ' + args.test_view if args.test_view else ''}, seed {args.seed}, "
        f"scored on the {'validation' if args.score_set == 'val' else 'test'} performers)",
        "",
        (
            f"Dataset `{args.dataset}`; every row trains on the same sets A/B and tests on the same "
            f"{results[0]['n_test_frames'] if results else 0} frames. Thesis: 64 % raw, 70 % smoothed, ~90 % video."
        ),
        "",
        "| variant | frame acc. raw | frame acc. smoothed | video acc. | train s |",
        "|---|---:|---:|---:|---:|",
    ]
    for r in results:
        va = "n/a" if r["video_accuracy"] is None else f"{100 * r['video_accuracy']:.1f} %"
        train_s = r["timing_s"].get("train", float("nan")) + r["timing_s"].get("vocabulary", 0.0)
        md.append(f"| {r['name']} | {100 * r['frame_accuracy_raw']:.1f} % | {100 * r['frame_accuracy_smoothed']:.1f} % "
                  f"| {va} | {train_s:.0f} |")
    mdp = RESULTS / f"{args.name}.md"
    mdp.write_text("\n".join(md) + "\n")
    print("\n".join(md))
    print(f"wrote {path} and {mdp}")


if __name__ == "__main__":
    main()
