"""Score the pose-sequence recognizer (issue 28) on demo splits of one seed from the true 2D keypoints (or
pose files); drives :mod:`vidstyle.evaluation.poserecognition`. One recognizer is trained per seed (the
unseen-performer and unseen-camera splits share their training performers) and each split's test set is
scored once::

    PYTHONPATH=. python scripts/eval_pose_recognition.py --seed 1 --split unseen-performer unseen-camera \
        --camera-dataset /tmp/cam_all --views 2 --out-dir pipelines/kickboxing/results

writes ``recognition_pose_true2d_{unseen_performer,unseen_camera}_seed1.json``. ``--camera-dataset``: the
unseen-camera dataset with the seed's test performers (the pipeline's has seed 0's; for other seeds
``vidstyle demo make-dataset --unseen-camera --out CAM --seed 0 --performers 10 --single-seconds 8
--performance-seconds 60``, every performer, as ``scripts/recognition_results.py`` uses).
"""

import argparse
import json
import logging
import sys
from pathlib import Path

from vidstyle.evaluation.poserecognition import score_pose_recognizer, train_for_split
from vidstyle.formats.dataset import read_dataset
from vidstyle.formats.metrics import write_metrics
from vidstyle.recognition.posetraining import KeypointNoise
from vidstyle.recognition.splits import make_split

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--out-root", default="pipelines/kickboxing/out", help="the pipeline's out/ directory")
ap.add_argument("--split", nargs="+", default=["unseen-performer"])
ap.add_argument("--camera-dataset", help="unseen-camera dataset directory (default: OUT_ROOT/camera_dataset)")
ap.add_argument("--seed", type=int, default=0)
ap.add_argument("--views", type=int, default=4, help="virtual cameras per training take")
ap.add_argument("--sigma", type=float, default=0.05, help="keypoint noise, torso lengths (< 0: no noise)")
ap.add_argument("--outliers", type=float, default=0.05)
ap.add_argument("--dropout", type=float, default=0.02)
ap.add_argument("--poses-dir", help="score <id>.poses.json files instead of the true 2D keypoints")
ap.add_argument("--score-set", default="test", choices=("test", "val"))
ap.add_argument("--C", type=float, default=10.0)
ap.add_argument("--cap", type=int, default=1500, help="SVM training frames per class")
ap.add_argument("--out-dir", default="pipelines/kickboxing/results")
a = ap.parse_args()
logging.basicConfig(level=logging.INFO, stream=sys.stderr)
root = Path(a.out_root)
ds = read_dataset(root / "dataset/dataset.json")
cam = Path(a.camera_dataset) if a.camera_dataset else root / "camera_dataset"
tds = read_dataset(cam / "dataset.json") if "unseen-camera" in a.split else None
noise = KeypointNoise(sigma=a.sigma, outlier_rate=a.outliers, dropout_rate=a.dropout) if a.sigma >= 0 else None
params = {"C": a.C, "max_frames_per_class": a.cap, "n_jobs": 1}
rec, training = train_for_split(ds, make_split(ds, "unseen-performer", seed=a.seed), a.seed, a.views, noise, params)
training["seed"] = a.seed
source = "true2d" if a.poses_dir is None else "poses"
for kind in a.split:
    split = make_split(ds, kind, seed=a.seed, test_dataset=tds if kind == "unseen-camera" else None)
    r = score_pose_recognizer(rec, training, ds, split, tds, a.poses_dir, a.score_set)
    r["command"] = "python scripts/eval_pose_recognition.py " + " ".join(sys.argv[1:])
    out = Path(a.out_dir) / f"recognition_pose_{source}_{kind.replace('-', '_')}_seed{a.seed}.json"
    write_metrics(out, r)
    print(out, json.dumps(r["frame_accuracy"]), r["video_accuracy"])
