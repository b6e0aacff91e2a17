"""Late fusion of recognizers and the calibration of training noise to a pose estimator's error (issue 28,
item 2 and 4): checked against hand-computed means and against noise of known parameters."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.errors import InputError, ParameterError
from vidstyle.evaluation.poserecognition import noise_from_error, pose_error
from vidstyle.recognition.fusion import aligned_scores, fuse_scores
from vidstyle.recognition.posefeatures import NECK, PELVIS
from vidstyle.recognition.posetraining import KeypointNoise


def test_aligned_scores_reorders_columns_and_zero_fills():
    s = np.array([[0.7, 0.3], [0.1, 0.9]])
    out = aligned_scores(s, ["b", "a"], ["a", "b", "c"])
    np.testing.assert_array_equal(out, [[0.3, 0.7, 0.0], [0.9, 0.1, 0.0]])
    with pytest.raises(InputError):
        aligned_scores(s, ["a", "z"], ["a", "b"])


def test_fuse_scores_is_the_weighted_mean_of_aligned_scores():
    pose = np.array([[0.6, 0.4], [0.2, 0.8], [0.5, 0.5]])
    sift = np.array([[0.1, 0.9], [0.3, 0.7], [0.9, 0.1]])  # columns b, a
    raw, fused, conf = fuse_scores([pose, sift], [["a", "b"], ["b", "a"]], [3.0, 1.0], ["a", "b"])
    want = 0.75 * pose + 0.25 * sift[:, ::-1]
    np.testing.assert_allclose(fused, want)
    np.testing.assert_array_equal(raw, np.argmax(want, axis=1))
    np.testing.assert_allclose(conf, want.max(axis=1))
    # weight 1 on one recognizer is that recognizer
    _, f1, _ = fuse_scores([pose, sift], [["a", "b"], ["b", "a"]], [1.0, 0.0], ["a", "b"])
    np.testing.assert_allclose(f1, pose)
    with pytest.raises(ParameterError):
        fuse_scores([pose, sift], [["a", "b"], ["b", "a"]], [0.0, 0.0], ["a", "b"])
    with pytest.raises(InputError):
        fuse_scores([pose, sift[:2]], [["a", "b"], ["b", "a"]], [1.0, 1.0], ["a", "b"])


def _tracks(rng, n=40, F=200):
    base = rng.normal(0, 1, (15, 2)) * 30 + 100
    base[NECK], base[PELVIS] = (100, 50), (100, 150)  # torso length 100 px
    return [np.repeat(base[None], F, axis=0) + rng.normal(0, 5, (F, 15, 2)) for _ in range(n)]


def test_noise_calibration_recovers_known_noise():
    """Noise of known parameters applied to true tracks, measured by pose_error and turned back into a
    KeypointNoise by noise_from_error, gives those parameters back (sampling error only)."""
    rng = np.random.default_rng(0)
    trues = _tracks(rng)
    known = KeypointNoise(sigma=0.04, outlier_rate=0.0, dropout_rate=0.1, dropout_length=5.0)
    ests = [known.apply(t, rng) for t in trues]
    got = noise_from_error(pose_error(trues, ests))
    assert got.sigma == pytest.approx(0.04, rel=0.03)
    assert got.outlier_rate < 0.001
    assert got.dropout_rate == pytest.approx(0.1, rel=0.2)
    # runs of missing frames that touch merge, so measured runs are a little longer than drawn ones
    assert got.dropout_length == pytest.approx(5.0, rel=0.25)
    # outliers far from the truth (RMS 2 torso lengths per coordinate) are counted as outliers
    wild = KeypointNoise(sigma=0.02, outlier_rate=0.1, outlier_sigma=2.0, dropout_rate=0.0)
    got = noise_from_error(pose_error(trues, [wild.apply(t, rng) for t in trues]))
    # a 2D Gaussian of sigma 2 lies beyond 0.5 with probability exp(-0.5**2 / (2 * 2**2)) = exp(-1/32)
    assert got.outlier_rate == pytest.approx(0.1 * np.exp(-1 / 32), rel=0.05)
    assert got.outlier_sigma == pytest.approx(2.0, rel=0.1)
    assert got.sigma < 0.03


def test_the_fusion_default_is_the_validated_choice():
    """The default weight and the fused scores' power are the choice of the validation run with the best score
    (with and without the extra labelled walks in training, and with the 3D SIFT model trained also on more
    camera views: validation/pose_recognition{,_cmuwalks,_moreviews}_seed0.json)."""
    import json
    from pathlib import Path

    from vidstyle.recognition import defaults as D

    docs = [json.loads(p.read_text()) for p in
            sorted((Path(__file__).resolve().parents[1] / "pipelines/kickboxing/validation").glob("pose_recognition*_seed0.json"))]
    assert len(docs) == 3 and all(d["scored_set"] == "V" for d in docs)
    for d in docs:
        assert max(r["score"] for r in d["rows"]) == d["chosen"]["score"]
    best = max(docs, key=lambda d: d["chosen"]["score"])
    assert D.FUSION_WEIGHT == best["chosen"]["weight_pose"]
    # the fused scores' power in the smoother: chosen with it (stage 2 of the same validation)
    assert D.FUSION_EMISSION_WEIGHT == best["chosen"]["emission_weight"]
    assert best["chosen"]["emission_weight"] in best["fusion_emission_weights"]


def test_the_fused_scores_power_is_resolved_and_checked_in_one_place():
    import math

    import pytest

    from vidstyle.errors import ParameterError
    from vidstyle.recognition import defaults as D
    from vidstyle.recognition.fusion import fusion_power

    assert fusion_power(None) == D.FUSION_EMISSION_WEIGHT and fusion_power(3) == 3.0
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ParameterError, match="fusion_emission_weight"):
            fusion_power(bad)
