#!/usr/bin/env python
"""The action models' defaults (``vidstyle/actionmodel/defaults.py``: ``WARP_SMOOTHING``, ``VARIANCE``),
chosen on the demo's *validation* performers only (set V of the ``unseen-performer`` recognition split of
``--seed``; never the test performers).

Per validation performer: :func:`vidstyle.evaluation.actionmodel.evaluate_performer` fits on their
single-action takes and all performance takes but the last, and reconstructs the held-out take's
instances through encode/decode. **Score**: the held-out MPJPE (mm) pooled over labels and performers,
weighted by held-out instances (lower is better). **Constraint**: the samples' naturalness within
``TOLERANCE`` (10 %) of the source clips' for every label: velocity variance and acceleration ratios (Du's
naturalness), pinned slide and contact-height ratios. **Search**: ``warp_smoothing`` first (at the
starting variance), then ``variance`` at the chosen smoothing; of the admissible candidates within
``TIE`` (2 %) of the factor's best score the first listed wins (less variance: fewer coefficients for the
GMM to estimate; less smoothing: closer to the DTW path). Every candidate's figures go to the table.

    python scripts/validate_actionmodel.py [--dataset pipelines/kickboxing/out/dataset]

Writes ``--out`` (default ``pipelines/kickboxing/validation/actionmodel.json``) and prints the table.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")  # one core
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vidstyle.formats.validation import ACTIONMODEL_DEFAULTS, validation_header, write_validation

log = logging.getLogger("validate_actionmodel")
ROOT = Path(__file__).resolve().parents[1]
DATASET = ROOT / "pipelines" / "kickboxing" / "out" / "dataset"
DEFAULT_OUT = ROOT / "pipelines" / "kickboxing" / "validation" / "actionmodel.json"
TOLERANCE = 0.10
TIE = 0.02
START = {"warp_smoothing": 2.0, "variance": 0.95}
CANDIDATES = {"warp_smoothing": [0.0, 1.0, 2.0, 4.0], "variance": [0.8, 0.9, 0.95, 0.99, 1.0]}
RATIOS = ("ratio_velocity_variance_mm2", "ratio_acceleration_mm_per_frame2", "ratio_slide_mm_per_frame",
          "ratio_contact_height_error_mm")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", type=Path, default=DATASET)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    log.setLevel(logging.INFO)
    from vidstyle.evaluation.actionmodel import evaluate_performer, read_manifest, split_groups

    manifest = read_manifest(args.dataset)
    groups = split_groups(manifest, args.seed)
    val = groups["V"]
    unit_mm = float(manifest["mocap_unit_m"]) * 1000.0
    seen: dict[tuple, dict] = {}

    def run(values: dict) -> dict:
        key = tuple(sorted(values.items()))
        if key not in seen:
            err_sum, n, worst, per = 0.0, 0, 0.0, {}
            for p in val:
                r = evaluate_performer(args.dataset, p, dict(values), unit_mm, seed=args.seed)
                for label, row in r["labels"].items():
                    if row["mpjpe_heldout_mm"] is not None:
                        err_sum += row["mpjpe_heldout_mm"] * row["heldout_instances"]
                        n += row["heldout_instances"]
                    ratios = [row[k] for k in RATIOS if row.get(k) is not None]
                    worst = max([worst, *ratios])
                    per[f"{p}/{label}"] = {"mpjpe_heldout_mm": row["mpjpe_heldout_mm"],
                                           "heldout_instances": row["heldout_instances"],
                                           **{k: row.get(k) for k in RATIOS}}
            seen[key] = {"values": dict(values), "score_mm": err_sum / n if n else None, "heldout_instances": n,
                         "worst_ratio": worst, "admissible": worst <= 1 + TOLERANCE, "per_label": per}
            log.info("%s: %.3f mm over %d held-out instances, worst naturalness ratio %.3f", values,
                     seen[key]["score_mm"] or float("nan"), n, worst)
        return seen[key]

    chosen = dict(START)
    decisions = {}
    for factor in ("warp_smoothing", "variance"):
        rows = [(c, run({**chosen, factor: c})) for c in CANDIDATES[factor]]
        ok = [(c, r) for c, r in rows if r["admissible"] and r["score_mm"] is not None] or \
             [(c, r) for c, r in rows if r["score_mm"] is not None]
        best = min(r["score_mm"] for _, r in ok)
        pick = next(c for c, r in ok if r["score_mm"] <= best * (1 + TIE))
        chosen[factor] = pick
        decisions[factor] = {"candidates": CANDIDATES[factor], "best_score_mm": best, "chosen": pick,
                             "scores_mm": {str(c): r["score_mm"] for c, r in rows},
                             "admissible": {str(c): r["admissible"] for c, r in rows}}
    final = run(chosen)
    doc = {**validation_header(ACTIONMODEL_DEFAULTS), "script": "scripts/validate_actionmodel.py", "seed": args.seed,
           "performers": val, "dataset": str(args.dataset),
           "score": "held-out MPJPE (mm) through encode/decode, pooled over labels and validation performers",
           "constraint": f"every naturalness ratio (samples / source clips) <= {1 + TOLERANCE:g}",
           "tie": TIE, "start": START, "decisions": decisions, "chosen": chosen, "chosen_score_mm": final["score_mm"],
           "factors_not_searched": ["slope_limit (Du: 5)", "max_components", "min_run", "min_primitive",
                                    "blend_frames"],
           "table": list(seen.values())}
    write_validation(args.out, doc)
    print(f"{'warp_smoothing':>14} {'variance':>8} {'MPJPE mm':>9} {'n':>4} {'worst ratio':>11} admissible")
    for r in seen.values():
        v = r["values"]
        print(f"{v['warp_smoothing']:>14g} {v['variance']:>8g} {r['score_mm']:>9.3f} {r['heldout_instances']:>4d} "
              f"{r['worst_ratio']:>11.3f} {r['admissible']}")
    print(f"chosen: {chosen} ({final['score_mm']:.3f} mm); wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
