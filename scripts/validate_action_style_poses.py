#!/usr/bin/env python
"""Which pose backend the pipeline's ``action_style`` stage fits from, chosen on the *validation* performers
(set V of split seed 0; never the test performers).

The pipeline estimates 2D poses of the first ``--frames`` frames of one performance take per test performer
(``reconstruct_poses``, both backends) and fits each performer's action-level style from them with the
recognised labels (``vidstyle evaluate action-style --poses-dir``). Here the same is done for the
validation performers' first take: ``vidstyle pose`` with each backend on the same frames, the orthodox
model and population on the training performers (A+B), the fit from those poses with the pipeline's
recognised labels (``--labels-dir``), scored against the performers' truth. Rule: the backend of least
mean DTW-aligned MPJPE of the fitted mean over the validation performers (lead accuracy reported beside).

    python scripts/validate_action_style_poses.py --run pipelines/kickboxing/out

Writes ``--out`` (default ``pipelines/kickboxing/validation/action_style_poses.json``); logs on stderr.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import tempfile
import time
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")
sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]
ROOT = Path(__file__).resolve().parents[1]
from _actionstyle_args import pose_run_arguments

log = logging.getLogger("validate_action_style_poses")
BACKENDS = ("ps", "blazepose")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    pose_run_arguments(ap, "action_style_poses.json")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    log.setLevel(logging.INFO)
    import numpy as np

    from vidstyle.evaluation.actionstyle import (
        evaluate_performer,
        fit_training,
        performer_videos,
        pose_files,
        row_json,
        summarise,
        true_instances,
    )
    from vidstyle.formats.validation import validation_header, write_validation

    t_start = time.perf_counter()
    dataset = args.run / "dataset"
    demo, g, model, est = fit_training(dataset, args.seed, jobs=1)
    manifest, ds = demo["manifest"], demo["dataset"]
    videos = [f"{p}_perf0_front" for p in g["V"]]
    poses_root = args.poses or Path(tempfile.mkdtemp(prefix="vidstyle_asp_"))
    for b in BACKENDS:
        pose_files(dataset, videos, b, poses_root / f"poses_{b}", args.frames)
    rows, by_backend = {}, {}
    for b in BACKENDS:
        rs = []
        for p in g["V"]:
            vids = [v for v in performer_videos(ds, manifest, p, "estimated", poses_dir=poses_root / f"poses_{b}",
                                                labels_dir=args.run / "recognized") if np.isfinite(v[0]).any()]
            truth = true_instances(dataset, p, model, seed=args.seed)
            r = evaluate_performer(model, est, vids, demo["style"][p], truth, demo["actions"], demo["unit_mm"],
                                   seed=args.seed)
            r.update(performer=p, input=b)
            rs.append(r)
            log.info("%s %s: lead %s (true %s), MPJPE fitted %.1f mm", b, p, r["lead"], r["lead_true"],
                     np.mean([v["fitted_mean_mm"] for v in r["labels"].values()]))
        rows[b] = [row_json(r) for r in rs]
        by_backend[b] = summarise(rs, demo["actions"])
    best = min(BACKENDS, key=lambda b: by_backend[b]["fitted_mean_mm"])
    doc = {**validation_header("vidstyle.validation.action_style_poses"), "seed": args.seed,
           "command": "python scripts/validate_action_style_poses.py " + " ".join(sys.argv[1:]),
           "split": g, "videos": videos, "frames": args.frames,
           "rule": "least mean DTW-aligned MPJPE of the fitted mean over the validation performers",
           "by_backend": by_backend, "rows": rows, "chosen": best, "wall_seconds": time.perf_counter() - t_start}
    write_validation(args.out, doc)
    print(f"{'backend':>10s} {'lead acc':>8s} {'fitted mm':>9s} {'unfitted mm':>11s} {'unfitted, true lead mm':>22s}")
    for b, s in by_backend.items():
        print(f"{b:>10s} {s['lead_accuracy']:8.3f} {s['fitted_mean_mm']:9.1f} {s['unfitted_mean_mm']:11.1f} "
              f"{s['unfitted_mean_true_lead_mm']:22.1f}" + ("  <- chosen" if b == best else ""))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
