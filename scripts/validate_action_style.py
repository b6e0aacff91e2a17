#!/usr/bin/env python
"""Choose the style fit's prior weight, Cauchy loss scale and number of fitted coefficients on the
*validation* performers (set V of split seed 0; never the test performers).

Model and population are fitted on the training performers (A+B) as in ``scripts/eval_action_style.py``;
each candidate fits the validation performers from noisy 2D (true 2D + 5 % torso Gaussian noise + 5 %
outliers, seeded: the candidate must hold up on imperfect tracks) and from true 2D, true labels; the
score is the mean DTW-aligned MPJPE (mm) of the fitted mean against their true instances (noisy input).
Rule: the candidate of least score; the defaults in ``vidstyle/actionmodel/defaults.py`` are set from it.

    python scripts/validate_action_style.py --dataset pipelines/kickboxing/out/dataset
"""

from __future__ import annotations

import argparse
import itertools
import logging
import os
import sys
import time
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
ROOT = Path(__file__).resolve().parents[1]
log = logging.getLogger("validate_action_style")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", type=Path, default=ROOT / "pipelines" / "kickboxing" / "out" / "dataset")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--prior-weights", type=float, nargs="+", default=[0.0, 0.001, 0.01, 0.1, 1.0])
    ap.add_argument("--loss-scales", type=float, nargs="+", default=[0.05, 0.2])
    ap.add_argument("--n-fit", type=int, nargs="+", default=[12, 30])
    ap.add_argument("--max-segments", type=int, default=6)
    ap.add_argument("--out", type=Path, default=ROOT / "pipelines" / "kickboxing" / "validation" / "action_style.json")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    log.setLevel(logging.INFO)
    import json

    import numpy as np

    from vidstyle.evaluation.actionmodel import split_groups
    from vidstyle.evaluation.actionstyle import (
        demo_truth,
        evaluate_performer,
        fit_population,
        orthodox_model,
        performer_videos,
        summarise,
        true_instances,
    )
    from vidstyle.fileio import json_default
    from vidstyle.formats._base import write_json_document

    t_start = time.perf_counter()
    demo = demo_truth(args.dataset)
    manifest, ds, unit_mm, actions, truth_style = (demo[k] for k in ("manifest", "dataset", "unit_mm", "actions", "style"))
    g = split_groups(manifest, args.seed)
    train = sorted(g["A"] + g["B"])
    model = orthodox_model(args.dataset, manifest, train, args.seed)
    cache: dict = {}
    est = fit_population(ds, manifest, train, cache=cache)
    data = {}
    for p in g["V"]:
        truth = true_instances(args.dataset, p, model, seed=args.seed)
        for kind in ("noisy", "true"):
            data[(p, kind)] = (performer_videos(ds, manifest, p, kind, rng=np.random.default_rng([args.seed, int(p[1:])]),
                                                cache=cache), truth)
    cands = []
    for pw, ls, nf in itertools.product(args.prior_weights, args.loss_scales, args.n_fit):
        params = {"prior_weight": pw, "loss_scale": ls, "n_fit": nf}
        res = {}
        for kind in ("noisy", "true"):
            rows = [evaluate_performer(model, est, data[(p, kind)][0], truth_style[p], data[(p, kind)][1], actions, unit_mm,
                                       params=params, max_segments=args.max_segments, seed=args.seed) for p in g["V"]]
            s = summarise(rows, actions)
            res[kind] = {k: s.get(k) for k in ("fitted_mean_mm", "fitted_sample_mm", "unfitted_mean_mm",
                                               "unfitted_mean_true_lead_mm", "mpjpe_reduction_vs_true_lead")}
        cands.append({"params": params, "score_mm": res["noisy"]["fitted_mean_mm"], **res})
        log.info("%s: noisy %.2f mm, true %.2f mm (pooled mean with true lead %.2f)", params, res["noisy"]["fitted_mean_mm"],
                 res["true"]["fitted_mean_mm"], res["true"]["unfitted_mean_true_lead_mm"])
    best = min(cands, key=lambda c: c["score_mm"])
    doc = {"kind": "vidstyle.validation.action_style", "schema_version": 1, "seed": args.seed,
           "command": "python scripts/validate_action_style.py " + " ".join(sys.argv[1:]),
           "split": g, "validation_performers": g["V"], "max_segments": args.max_segments,
           "rule": "least mean DTW-aligned MPJPE of the fitted mean (noisy 2D input) over the validation performers",
           "candidates": cands, "chosen": best["params"], "wall_seconds": time.perf_counter() - t_start}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_json_document(args.out, json.loads(json.dumps(doc, default=json_default), parse_constant=lambda c: None))
    print(f"{'prior_w':>8s} {'loss':>6s} {'n_fit':>5s} {'noisy mm':>9s} {'true mm':>8s} {'pool+lead':>9s}")
    for c in cands:
        p = c["params"]
        print(f"{p['prior_weight']:8g} {p['loss_scale']:6g} {p['n_fit']:5d} {c['noisy']['fitted_mean_mm']:9.2f} "
              f"{c['true']['fitted_mean_mm']:8.2f} {c['true']['unfitted_mean_true_lead_mm']:9.2f}")
    print("chosen:", best["params"], f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
