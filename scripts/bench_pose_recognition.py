"""Benchmark the pose-sequence recognizer after pose estimation (issue 28: it must not be the bottleneck).

A recognizer of the size the validated configuration has (8 demo classes; C 10, 1500 SVM frames per
class, so the same number of support vectors' order) is trained on procedural demo performers' takes
(4 performers, 6 single actions of 8 s and a 60 s performance each, 2 virtual views, Gaussian keypoint
noise); then, on one core, in the same run:

* the recognizer: ``predict_video`` on a 60 s performance of a fifth performer (1200 working frames at
  20 fps; features, SVM scores, duration smoothing), median of ``--runs`` after a warm-up;
* the baseline: the shipped pictorial-structures model (``vidstyle pose``'s ps backend) on 160x120
  renders of that performance, ms per frame over ``--frames`` frames, median of ``--runs``.

The figure is the recognizer's time per frame as a share of the pose stage's (goal: <= 10 %), and its
frames/s. Writes ``bench_results/pose_recognition.json``.

    python scripts/bench_pose_recognition.py [--runs 5] [--frames 10]
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]

import numpy as np
from _benchutil import machine, timeit, write_results

GOAL_SHARE = 0.10


def _motion(params, index: int, take: int):
    """The LabelledMotion (working rate) and the Motion of a demo take."""
    from vidstyle.demo.dataset import make_performer, make_take
    from vidstyle.mocap.keypoints import keypoint_positions
    from vidstyle.recognition.posetraining import LabelledMotion
    from vidstyle.render.camera import circular_median

    perf = make_performer(params, index)
    t = make_take(params, perf, index, take)
    pts = keypoint_positions(t.motion)[:: t.ratio]
    labels = t.video_labels[: len(pts)]
    lm = LabelledMotion(pts[: len(labels)], labels, float(params.fps), circular_median(t.motion.facing_angles()),
                        f"{perf.id}_{take}")
    return lm, t.motion


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--frames", type=int, default=10, help="frames the pose estimator runs on per run")
    ap.add_argument("--out", type=Path, default=None, help="default: bench_results/pose_recognition.json")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr)
    try:
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    except (AttributeError, OSError):
        pass
    import cv2
    from threadpoolctl import threadpool_limits

    from vidstyle.demo.actions import ACTIONS
    from vidstyle.demo.dataset import DatasetParams
    from vidstyle.pose.estimator import load_model
    from vidstyle.recognition.posefeatures import PoseTrack
    from vidstyle.recognition.poserecognizer import PoseRecognizer
    from vidstyle.recognition.posetraining import (
        KeypointNoise,
        camera_for,
        project_keypoints,
        virtual_views,
    )
    from vidstyle.render import Appearance, Camera, render_motion

    cv2.setNumThreads(1)
    params = DatasetParams(seed=0, single_seconds=8.0, performance_seconds=60.0)
    perf_take = 100  # the first performance take
    with threadpool_limits(1):
        train = [_motion(params, i, t)[0] for i in range(4) for t in [*range(len(ACTIONS)), perf_take]]
        noise = KeypointNoise()
        tracks, labels = virtual_views(train, 2, 0, noise)
        t0 = time.perf_counter()
        rec = PoseRecognizer(C=10.0, max_frames_per_class=1500, n_jobs=1, random_state=0, fps=float(params.fps))
        rec.fit(tracks, labels)
        train_s = time.perf_counter() - t0
        test, test_motion = _motion(params, 4, perf_take)
        cam = camera_for(test, azimuth_deg=20.0, elevation_deg=10.0, distance=3.5, vfov_deg=40.0)
        track = PoseTrack(noise.apply(project_keypoints(test.points, cam), np.random.default_rng(1)), float(params.fps))
        rec_t = timeit(lambda: rec.predict_video(track), args.runs)
        rec_ms = 1000.0 * rec_t["median_s"] / track.n_frames

        model = load_model(Path(__file__).resolve().parents[1] / "vidstyle/pose/weights/ps_cnn.joblib")[0]
        motion = test_motion.resample(float(params.fps))
        start = motion.n_frames // 2
        clip = motion[start:start + args.frames]
        rcam = Camera.for_view(clip, view=20.0, size=(160, 120))
        frames, _ = render_motion(clip, rcam, fps=float(params.fps), appearance=Appearance.random(2),
                                  background="texture")
        ps_t = timeit(lambda: [model.estimate(f) for f in frames], args.runs)
        ps_ms = 1000.0 * ps_t["median_s"] / len(frames)
    share = rec_ms / ps_ms
    n_sv = int(sum(getattr(c, "n_support_", np.zeros(1)).sum() for c in getattr(rec, "estimators_", []) or []))
    print(f"pose recognizer: {rec_ms:.3f} ms/frame ({1000.0 / rec_ms:.0f} frames/s) over {track.n_frames} frames; "
          f"pictorial structures: {ps_ms:.1f} ms/frame; recognizer / pose stage = {100 * share:.2f} % "
          f"(goal <= {100 * GOAL_SHARE:.0f} %); trained in {train_s:.0f} s on {sum(len(t.xy) for t in tracks)} frames")
    payload = {"machine": machine(), "runs": args.runs, "goal_share": GOAL_SHARE,
               "recognizer": {"ms_per_frame": rec_ms, "frames_per_s": 1000.0 / rec_ms, "frames": track.n_frames,
                              "timing": rec_t, "train_s": train_s, "train_frames": int(sum(len(t.xy) for t in tracks)),
                              "classes": [str(c) for c in rec.classes_], "support_vectors": n_sv or None,
                              "params": {"C": 10.0, "max_frames_per_class": 1500}},
               "pose_stage": {"backend": "ps (shipped cnn model)", "size": [160, 120], "ms_per_frame": ps_ms,
                              "frames": len(frames), "timing": ps_t},
               "share": share}
    if args.out is None:
        print(f"wrote {write_results('pose_recognition', payload)}")
    else:
        import json

        args.out.write_text(json.dumps(payload, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
