"""Pose accuracy on held-out renders (not training frames) against a mean-pose baseline.

Supersedes the accuracy assertion of tests/test_pose_model.py::test_model_round_trip_and_fit_on_training_frames
(it scored the model on its own training frames). The model is trained as there (8 short clips of demo
performer 0); it is scored on clips it never saw: another performer, other excerpts, other seeds (look,
background, camera jitter), azimuths between the training ones. The baseline predicts, for every frame,
the mean training pose of the frame's view (the model is given the view too), so a model that learned
nothing about the image scores as the baseline does.
"""

from __future__ import annotations

import numpy as np
import pytest

# the evaluation metrics through one import (the module moves to vidstyle.evaluation.pose: one line to change)
from vidstyle.evaluation import pose as pose_eval
from vidstyle.pose.data import Spec, render_samples
from vidstyle.pose.estimator import PoseModel

TRAIN = [Spec("demo:0", 1.0 + i, 2.0, az + 4 * i, 10.0, 100 + i, fps=3.0)
         for i, az in enumerate((0.0, 90.0, -90.0, 180.0, 0.0, 90.0, -90.0, 180.0))]
HELD_OUT = [Spec("demo:1", 3.5 + i, 2.0, az, 10.0, 500 + i, fps=3.0)
            for i, az in enumerate((10.0, 80.0, -80.0, 170.0, -10.0, 100.0))]


@pytest.fixture(scope="module")
def scored():
    train = render_samples(TRAIN, jobs=1)
    test = render_samples(HELD_OUT, jobs=1)
    assert {s.clip for s in train}.isdisjoint({s.clip for s in test})
    model = PoseModel(n_orient=8, hard_rounds=0, neg_per_pos=6, seed=3).fit(train, jobs=1)
    pred = np.stack([model.estimate(s.image, i, view=s.view).points for i, s in enumerate(test)])
    mean_by_view = {v: np.mean([s.keypoints for s in train if s.view == v], axis=0) for v in {s.view for s in train}}
    base = np.stack([mean_by_view[s.view] for s in test])
    gt = np.stack([s.keypoints for s in test])
    return pred, base, gt


@pytest.mark.slow
def test_pose_on_held_out_renders_beats_the_mean_pose(scored):
    pred, base, gt = scored
    assert len(gt) >= 30
    pcp_model, pcp_base = pose_eval.strict_pcp(pred, gt).mean(), pose_eval.strict_pcp(base, gt).mean()
    pck_model, pck_base = pose_eval.pck(pred, gt).mean(), pose_eval.pck(base, gt).mean()
    err_model = np.linalg.norm(pred[..., :2] - gt, axis=-1).mean(axis=1)  # (N,) mean keypoint error, px
    err_base = np.linalg.norm(base - gt, axis=-1).mean(axis=1)
    print(f"held-out PCP model {pcp_model:.3f} mean pose {pcp_base:.3f}; PCK@0.2 {pck_model:.3f} vs {pck_base:.3f}; "
          f"median error {np.median(err_model):.2f} vs {np.median(err_base):.2f} px; "
          f"frames better {np.mean(err_model < err_base):.2f}")
    # measured (seed 3): PCP 0.69 vs 0.57, PCK@0.2 0.35 vs 0.26
    assert pcp_model >= pcp_base + 0.06
    assert pck_model >= pck_base + 0.05
    assert np.mean(err_model < err_base) >= 0.65  # better than the mean pose on most frames (measured 0.78)
    # the torso and head (the parts found most reliably) on most held-out frames
    hits = pose_eval.strict_pcp(pred, gt)
    assert hits[:, 0].mean() >= 0.6
