"""Score the pose-sequence recognizer (issue 28) on a demo split; drives
:func:`vidstyle.evaluation.poserecognition.evaluate_pose_recognition`.

    PYTHONPATH=. python scripts/eval_pose_recognition.py --split unseen-camera --views 2 \
        --out pipelines/kickboxing/results/recognition_pose_true2d_unseen_camera_seed0.json
"""

import argparse
import json
import logging
import sys
from pathlib import Path

from vidstyle.evaluation.poserecognition import evaluate_pose_recognition
from vidstyle.formats.dataset import read_dataset
from vidstyle.recognition.posetraining import KeypointNoise

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--out-root", default="pipelines/kickboxing/out", help="the pipeline's out/ directory")
ap.add_argument("--split", default="unseen-performer")
ap.add_argument("--seed", type=int, default=0)
ap.add_argument("--views", type=int, default=4, help="virtual cameras per training take")
ap.add_argument("--sigma", type=float, default=0.05, help="keypoint noise, torso lengths (< 0: no noise)")
ap.add_argument("--outliers", type=float, default=0.05)
ap.add_argument("--dropout", type=float, default=0.02)
ap.add_argument("--poses-dir", help="score <id>.poses.json files instead of the true 2D keypoints")
ap.add_argument("--score-set", default="test", choices=("test", "val"))
ap.add_argument("--C", type=float, default=10.0)
ap.add_argument("--cap", type=int, default=1500, help="SVM training frames per class")
ap.add_argument("--out", required=True)
a = ap.parse_args()
logging.basicConfig(level=logging.INFO, stream=sys.stderr)
root = Path(a.out_root)
ds = read_dataset(root / "dataset/dataset.json")
tds = read_dataset(root / "camera_dataset/dataset.json") if a.split == "unseen-camera" else None
noise = KeypointNoise(sigma=a.sigma, outlier_rate=a.outliers, dropout_rate=a.dropout) if a.sigma >= 0 else None
r = evaluate_pose_recognition(ds, a.split, a.seed, tds, a.poses_dir, a.views, noise,
                              {"C": a.C, "max_frames_per_class": a.cap, "n_jobs": 1}, a.score_set)
r["command"] = " ".join(sys.argv)
Path(a.out).write_text(json.dumps(r, indent=1))
print(a.out, r["frame_accuracy"], r["video_accuracy"])
