#!/usr/bin/env python
"""Add the ``segments`` block (boundary-tolerant accuracy and segmental F1, :mod:`vidstyle.evaluation.segments`)
to a committed recognition metrics file written before ``vidstyle evaluate recognition`` recorded it.

The recognizer is not retrained. Its labels are made again with ``vidstyle recognize`` into ``--labels-dir``
(the same model files, poses and features the metrics file names). They are scored with the library's
``score_labels_dir``, the scorer ``vidstyle evaluate recognition --labels-dir`` uses. The block is written
into ``--metrics`` only when the labels are the file's own predictions: the raw and smoothed frame
accuracies and the smoothed confusion counts must equal the file's. Otherwise exit 1 and nothing is
written. The rest of the file is kept as it is, and the command goes into ``segments_command``::

    vidstyle recognize out/features/p02_*.npz ... --model out/models/recognizer.joblib \\
        --pose-model /tmp/pose_model_seed0.joblib --poses-dir /tmp/rec_poses/ps_all --out-dir /tmp/fus
    python scripts/rescore_segments.py --metrics pipelines/kickboxing/results/recognition_fusion_ps_unseen_performer_seed0.json \\
        --labels-dir /tmp/fus --dataset pipelines/kickboxing/out/dataset/dataset.json \\
        --model pipelines/kickboxing/out/models/recognizer.joblib --split unseen-performer --seed 0
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
log = logging.getLogger("rescore_segments")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--metrics", type=Path, required=True, help="the recognition metrics file to complete")
    ap.add_argument("--labels-dir", type=Path, required=True, help="<video id>.json of vidstyle recognize")
    ap.add_argument("--dataset", type=Path, required=True)
    ap.add_argument("--model", type=Path, required=True, help="the 3D SIFT recognizer (its header names the split)")
    ap.add_argument("--split", default="unseen-performer")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--test-dataset", type=Path, default=None, help="with --split unseen-camera: the camera dataset")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stderr)
    from vidstyle.evaluation.recognition import score_labels_dir
    from vidstyle.formats.dataset import read_dataset
    from vidstyle.formats.metrics import RECOGNITION, read_metrics, write_metrics

    metrics = read_metrics(args.metrics, RECOGNITION)
    doc = dict(metrics.doc)
    scored = score_labels_dir(read_dataset(args.dataset), args.labels_dir, args.model, args.split, args.seed,
                              test_dataset=read_dataset(args.test_dataset) if args.test_dataset else None)
    same = (scored["frame_accuracy"] == doc["frame_accuracy"]
            and scored["confusion"]["counts_smoothed"] == (doc.get("confusion") or {}).get("counts_smoothed"))
    if not same:
        print(f"{args.metrics}: the labels in {args.labels_dir} are not the file's predictions (frame accuracy "
              f"{scored['frame_accuracy']} against {doc['frame_accuracy']}); nothing written", file=sys.stderr)
        return 1
    doc["segments"] = scored["segments"]
    doc["segments_command"] = " ".join(["python scripts/rescore_segments.py", *(argv if argv is not None else sys.argv[1:])])
    write_metrics(args.metrics, doc, RECOGNITION)
    sm = scored["segments"]["smoothed"]
    log.info("%s: within 1 frame %.3f, F1@50 %.3f", args.metrics.name, sm["boundary_tolerant_accuracy"]["1"],
             sm["segmental_f1"]["50"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
