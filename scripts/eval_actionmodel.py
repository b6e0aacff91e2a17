#!/usr/bin/env python
"""Statistical action models on the demo (seed 000, Du 2014): naturalness of samples against the source
clips, reconstruction of held-out instances, and speed.

Performers: the ``unseen-performer`` recognition split of ``--seed`` (``vidstyle.recognition.splits``;
the pipeline's ``recognition.split``). Models are fitted on the *training* performers (sets A and B)
only, with the defaults of ``vidstyle/actionmodel/defaults.py`` (chosen on the validation performers by
``scripts/validate_actionmodel.py``):

1. **Per performer** (a performer's own action style; :func:`vidstyle.evaluation.actionmodel.evaluate_performer`):
   fitted on their single-action takes and every performance take but the last; per label the
   naturalness of samples (pinned, and unpinned for reference) against the performer's source instances
   (the truth clips the motion graph is built from), the held-out take's instances through
   encode/decode (and the mean instance, z = 0, for reference), fit seconds per label and sample
   milliseconds per instance, one core. Pooled over the training performers (instance-weighted).
2. **Pooled** (:func:`~vidstyle.evaluation.actionmodel.evaluate_pooled`): one model on every training
   performer; reconstruction MPJPE of every instance of the *test* performers (unseen performers,
   scored only, never used to fit or choose).

Issue goal: per label, every naturalness figure of the samples within 10 % of the source clips'
(``within_10pct``; ratios <= 1.1; lower is better for all four figures).

    python scripts/eval_actionmodel.py --dataset pipelines/kickboxing/out/dataset

``--variance V`` overrides the default variance kept (a sensitivity run, written to
``actionmodel_seed<seed>_variance<V>.json``). Writes ``--out`` (default
``pipelines/kickboxing/results/actionmodel_seed<seed>.json``, kind
``vidstyle.metrics.actionmodel``) and prints the tables.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")  # one core
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

log = logging.getLogger("eval_actionmodel")
ROOT = Path(__file__).resolve().parents[1]
DATASET = ROOT / "pipelines" / "kickboxing" / "out" / "dataset"
FIG = ("slide_mm_per_frame", "contact_height_error_mm", "velocity_variance_mm2", "acceleration_mm_per_frame2")
TOLERANCE = 0.10


def _wmean(pairs):
    pairs = [(v, w) for v, w in pairs if v is not None and w]
    tot = sum(w for _, w in pairs)
    return sum(v * w for v, w in pairs) / tot if tot else None


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", type=Path, default=DATASET)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--variance", type=float, default=None,
                    help="Override the default variance kept (a sensitivity run; output name gets _variance<V>).")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    suffix = "" if args.variance is None else f"_variance{args.variance:g}"
    out = args.out or ROOT / "pipelines" / "kickboxing" / "results" / f"actionmodel_seed{args.seed}{suffix}.json"
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    log.setLevel(logging.INFO)
    from vidstyle.actionmodel import ActionModel
    from vidstyle.actionmodel import defaults as D
    from vidstyle.evaluation.actionmodel import (
        evaluate_performer,
        evaluate_pooled,
        read_manifest,
        split_groups,
    )
    from vidstyle.formats.metrics import ACTIONMODEL, write_metrics

    t_start = time.perf_counter()
    manifest = read_manifest(args.dataset)
    groups = split_groups(manifest, args.seed)
    train = sorted(groups["A"] + groups["B"])
    unit_mm = float(manifest["mocap_unit_m"]) * 1000.0
    params = {k: v for k, v in ActionModel().get_params().items() if k != "random_state"}
    if args.variance is not None:
        params["variance"] = args.variance
    per_perf = {}
    for p in train:
        per_perf[p] = evaluate_performer(args.dataset, p, params, unit_mm, seed=args.seed)
        log.info("%s done (%.0f s so far)", p, time.perf_counter() - t_start)
    pooled = evaluate_pooled(args.dataset, train, groups["T"], params, unit_mm, seed=args.seed)
    labels = sorted({lab for r in per_perf.values() for lab in r["labels"]})
    summary = {}
    for lab in labels:
        rows = [r["labels"][lab] for r in per_perf.values() if lab in r["labels"]]
        s = {}
        for which in ("samples", "samples_unpinned", "sources"):
            s[which] = {k: _wmean([(r[which][k], r[which]["instances"]) for r in rows]) for k in FIG}
        ratios = {k: (s["samples"][k] / s["sources"][k]) if s["samples"][k] is not None and s["sources"][k] else None
                  for k in FIG}
        pl = pooled["labels"].get(lab)
        summary[lab] = {
            "performers": len(rows), "instances": sum(r["instances"] for r in rows),
            "other_signature": sum(r["other_signature"] for r in rows),
            "primitives": sorted({r["primitives"] for r in rows}),
            "gmm_components": sorted({r["gmm_components"] for r in rows}),
            "coefficients_mean": sum(r["coefficients"] for r in rows) / len(rows),
            **{f"samples_{k}": s["samples"][k] for k in FIG},
            **{f"samples_unpinned_{k}": s["samples_unpinned"][k] for k in FIG},
            **{f"sources_{k}": s["sources"][k] for k in FIG},
            **{f"ratio_{k}": ratios[k] for k in FIG},
            "sample_to_nearest_source_mm": _wmean([(r["sample_to_nearest_source_mm"], r["instances"]) for r in rows]),
            "source_to_nearest_other_mm": _wmean([(r["source_to_nearest_other_mm"], r["instances"]) for r in rows]),
            "within_10pct": all(v is None or v <= 1 + TOLERANCE for v in ratios.values()),
            "heldout_instances": sum(r["heldout_instances"] for r in rows),
            "mpjpe_heldout_mm": _wmean([(r["mpjpe_heldout_mm"], r["heldout_instances"]) for r in rows]),
            "mpjpe_mean_instance_mm": _wmean([(r["mpjpe_mean_mm"], r["heldout_instances"]) for r in rows]),
            "unseen_instances": pl["unseen"]["heldout_instances"] if pl else 0,
            "mpjpe_unseen_performers_mm": pl["unseen"]["mpjpe_heldout_mm"] if pl else None,
            "mpjpe_unseen_mean_instance_mm": pl["unseen"]["mpjpe_mean_mm"] if pl else None,
            "fit_seconds_per_performer": sum(r["fit_seconds"] for r in rows) / len(rows),
            "sample_ms_per_instance": sum(r["sample_ms"] for r in rows) / len(rows),
            "pooled_fit_seconds": pl["fit_seconds"] if pl else None,
        }
    cmd = "python scripts/eval_actionmodel.py " + " ".join(sys.argv[1:])
    doc = {"kind": ACTIONMODEL, "schema_version": 1, "seed": args.seed, "command": cmd.strip(),
           "dataset": str(args.dataset), "mm_per_unit": unit_mm,
           "split": {"kind": "unseen-performer", "seed": args.seed, **{k: v for k, v in groups.items()}},
           "params": {**params, "random_state": args.seed, "validation": "pipelines/kickboxing/validation/actionmodel.json",
                      "defaults": {"VARIANCE": D.VARIANCE, "WARP_SMOOTHING": D.WARP_SMOOTHING}},
           "labels": summary, "per_performer": per_perf, "pooled": pooled,
           "goal": "every naturalness ratio (samples / source clips) <= 1.1",
           "wall_seconds": time.perf_counter() - t_start}
    write_metrics(out, doc, kind=ACTIONMODEL)

    def f(x, p=2):
        return "-" if x is None else f"{x:.{p}f}"

    print(f"Naturalness, samples (pinned) / source clips, {len(train)} training performers (mm; ratio)")
    print(f"{'label':<15}{'n':>5} {'slide/frame':>18} {'contact height':>18} {'velocity var':>20} "
          f"{'accel':>16} {'<=1.1':>6}")
    for lab, r in summary.items():
        cells = [f"{f(r[f'samples_{k}'])}/{f(r[f'sources_{k}'])} {f(r[f'ratio_{k}'])}" for k in FIG]
        print(f"{lab:<15}{r['instances']:>5} {cells[0]:>18} {cells[1]:>18} {cells[2]:>20} {cells[3]:>16} "
              f"{'yes' if r['within_10pct'] else 'NO':>6}")
    print("\nUnpinned samples (what the foot pinning removes): slide mm/frame, contact height mm")
    for lab, r in summary.items():
        print(f"{lab:<15} {f(r['samples_unpinned_slide_mm_per_frame'])} {f(r['samples_unpinned_contact_height_error_mm'])}")
    print("\nNovelty: median nearest-neighbour distance (mm, time-normalised joint positions)")
    print(f"{'label':<15}{'sample->source':>15}{'source->other':>15}")
    for lab, r in summary.items():
        print(f"{lab:<15}{f(r['sample_to_nearest_source_mm']):>15}{f(r['source_to_nearest_other_mm']):>15}")
    print("\nReconstruction MPJPE (mm) through encode/decode; mean instance (z = 0) for reference")
    print(f"{'label':<15}{'held-out take':>14}{'(mean)':>8}{'n':>5}{'unseen perf.':>14}{'(mean)':>8}{'n':>5}"
          f"{'fit s/perf':>11}{'sample ms':>10}{'K':>4}{'G':>6}")
    for lab, r in summary.items():
        print(f"{lab:<15}{f(r['mpjpe_heldout_mm']):>14}{f(r['mpjpe_mean_instance_mm']):>8}{r['heldout_instances']:>5}"
              f"{f(r['mpjpe_unseen_performers_mm']):>14}{f(r['mpjpe_unseen_mean_instance_mm']):>8}"
              f"{r['unseen_instances']:>5}{f(r['fit_seconds_per_performer']):>11}{f(r['sample_ms_per_instance'], 1):>10}"
              f"{','.join(map(str, r['primitives'])):>4}{','.join(map(str, r['gmm_components'])):>6}")
    print(f"\nwrote {out} ({time.perf_counter() - t_start:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
