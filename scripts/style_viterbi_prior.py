#!/usr/bin/env python
"""How much does the Viterbi smoother's transition prior move style identification? (issue 12)

The Viterbi smoothers decode with statistics of set B's training labels (the frame-to-frame label chain;
for the explicit-duration smoother, the default, the run lengths and class changes), which pulls every
recognised chain toward the training performers' pooled chain. This script recognises the *test*
performers' performance videos once (frame scores of the model) and decodes them with

- ``duration, from B``: the explicit-duration smoother as trained (the default);
- ``duration, from V``: its run lengths and class changes from the validation performers' labels;
- ``viterbi, prior from B``: the plain Viterbi smoother with the model's chain;
- ``viterbi, prior from V``: the chain counted in the validation performers' labels instead;
- ``viterbi, flat prior``: every transition equally likely except staying (no chain information: the
  diagonal carries the same self-transition share as B's chain, off-diagonal mass spread evenly);
- ``vote (no prior)``: the thesis' window-6 vote;
- ``raw``: no smoothing;

then runs the style evaluation (``vidstyle.evaluation.style``, defaults of ``vidstyle evaluate style``) on
the test performers for each, beside their ground truth. Prints a table and writes JSON (``--out``).

Usage::

    python scripts/style_viterbi_prior.py --dataset out/dataset --features-dir out/features \\
        --model out/models/recognizer.joblib --out out/metrics/style_viterbi_prior.json
"""

from __future__ import annotations

import argparse
import logging
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vidstyle.fileio import write_json  # noqa: E402
from vidstyle.formats.validation import write_validation  # noqa: E402
from vidstyle.formats.dataset import read_dataset as load_dataset  # noqa: E402
from vidstyle.formats.labels import read_labels as load_labels  # noqa: E402
from vidstyle.recognition.io import features_path, load_features  # noqa: E402
from vidstyle.recognition.recognizer import load_model  # noqa: E402
from vidstyle.recognition.smoothing import duration_model, smooth_labels, transition_matrix  # noqa: E402
from vidstyle.evaluation.style import EvalParams, evaluate_performers, load_performers  # noqa: E402

log = logging.getLogger("style_viterbi_prior")


def flat_prior(T: np.ndarray) -> np.ndarray:
    """Same mean self-transition probability as ``T``, the rest spread evenly over the other classes."""
    K = len(T)
    stay = float(np.mean(np.diag(T)))
    F = np.full((K, K), (1 - stay) / (K - 1))
    np.fill_diagonal(F, stay)
    return F


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", required=True, type=Path, help="dataset directory (dataset.json)")
    ap.add_argument("--features-dir", required=True, type=Path)
    ap.add_argument("--model", required=True, type=Path, help="recognizer trained with --dataset (records its split)")
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--emission-weight", type=float, default=None, help="Viterbi emission weight (default: the model's)")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    rec, header = load_model(args.model)
    if args.emission_weight is not None:
        rec.emission_weight = args.emission_weight
    split = header.get("split") or {}
    test_perf, val_ids = split.get("test_performers"), split.get("val")
    if not test_perf or not val_ids:
        raise SystemExit(f"{args.model}: no test performers / validation set recorded (train it with --dataset)")
    ds = load_dataset(args.dataset)
    by_id = ds.by_id()
    index = {c: i for i, c in enumerate(rec.classes_)}
    seq_val = [np.array([index[c] for c in load_labels(ds.labels_path(by_id[i])).labels]) for i in val_ids]
    T_val = transition_matrix(seq_val, len(rec.classes_))
    priors = {}
    if getattr(rec, "durations_", None) is not None:
        priors["duration, from B" + (" (default)" if rec.smoothing == "duration" else "")] = ("duration", rec.durations_)
        priors["duration, from V"] = ("duration", duration_model(seq_val, len(rec.classes_)))
    priors.update({"viterbi, prior from B" + (" (default)" if rec.smoothing == "viterbi" else ""): ("viterbi", rec.transitions_),
              "viterbi, prior from V": ("viterbi", T_val),
              "viterbi, flat prior": ("viterbi", flat_prior(rec.transitions_)),
              "vote window 6 (no prior)": ("vote", None),
              "raw (no smoothing)": ("raw", None)})
    vids = [v for v in ds.videos if v.performer in test_perf and v.kind == "performance"]
    scored = []
    for v in vids:
        f = load_features(features_path(args.features_dir, v.id))
        scored.append((v, rec.frame_scores(rec.histograms(f))))
    classes = [str(c) for c in rec.classes_]
    results = {}
    manifest, params = ds, EvalParams()
    with tempfile.TemporaryDirectory() as tmp:
        for name, (method, T) in priors.items():
            d = Path(tmp) / str(len(results))
            d.mkdir()
            for v, (raw, scores, conf) in scored:
                if method == "raw":
                    lab, c = raw, conf
                else:
                    lab, c = smooth_labels(raw, len(classes), rec.smoothing_window if method != "vote" else 6, conf,
                                           scores, method, transitions=T if method == "viterbi" else None,
                                           emission_weight=rec.emission_weight,
                                           durations=T if method == "duration" else None)
                write_json(d / f"{v.id}.json", {"video": v.video, "fps": ds.fps, "classes": classes,
                                                "labels": [classes[i] for i in lab], "confidence": np.round(c, 4).tolist()})
            if not results:
                results["ground truth (test performers)"] = evaluate_performers(
                    load_performers(manifest, params, None, sorted(test_perf)), params)["summary"]
            results[name] = evaluate_performers(
                load_performers(manifest, params, d, sorted(test_perf)), params)["summary"]
            log.info("%s: identification %.3f", name, results[name]["identification"]["a"]["accuracy_by_heldout_data"])
    rows = []
    for name, s in results.items():
        rows.append({"labels": name, "transition_mae_a": s["transition_mae"]["a"],
                     "identification_a": s["identification"]["a"]["accuracy_by_heldout_data"],
                     "identification_a_true_chain": s["identification"]["a"]["accuracy_by_true_chain"],
                     "heldout_sequences_identified": s["identification"]["heldout_sequences_by_model_a"]["accuracy"],
                     "jsd_2gram_same": s["fidelity"]["a"]["jsd_2gram_same"],
                     "jsd_2gram_other": s["fidelity"]["a"]["jsd_2gram_other"]})
    doc = {"kind": "vidstyle.metrics.style_viterbi_prior", "schema_version": 1, "model": str(args.model),
           "seed": header.get("seed"), "emission_weight": rec.emission_weight, "test_performers": sorted(test_perf), "n_videos": len(vids),
           "command": "python scripts/style_viterbi_prior.py " + " ".join(sys.argv[1:]), "rows": rows}
    write_validation(args.out, doc)
    lines = [f"Style on the test performers ({', '.join(sorted(test_perf))}; identification among "
             f"{len(test_perf)}), seed {header.get('seed')}", "",
             "| labels | transition MAE (a) | identification (a) | by true chain | held-out seqs identified | JSD 2-gram same / other |",
             "|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['labels']} | {r['transition_mae_a']:.3f} | {100 * r['identification_a']:.0f} % | "
                     f"{100 * r['identification_a_true_chain']:.0f} % | {100 * r['heldout_sequences_identified']:.0f} % | "
                     f"{r['jsd_2gram_same']:.3f} / {r['jsd_2gram_other']:.3f} |")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
