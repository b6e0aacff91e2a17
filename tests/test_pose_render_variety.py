"""Training and test renders of other bodies and cameras: bone proportions (checked against the keypoint
geometry they must produce), elevation and figure-size ranges, another skeleton's clips as a group, and
the shipped pose model as ``vidstyle pose --backend ps``'s default."""

from __future__ import annotations

import numpy as np
import pytest

import vidstyle.demo  # noqa: F401 - registers the "demo" training source
from vidstyle.demo.pose_sources import demo_motion
from vidstyle.errors import ParameterError
from vidstyle.mocap.keypoints import KEYPOINT_INDEX as K
from vidstyle.mocap.keypoints import keypoint_positions
from vidstyle.pose.data import make_specs, render_spec, with_proportions

BONES = {"arms": [("left_shoulder", "left_elbow"), ("right_elbow", "right_wrist")],
         "legs": [("left_hip", "left_knee"), ("right_knee", "right_ankle")],
         "trunk": [("neck", "pelvis"), ("neck", "head_top"), ("left_hip", "right_hip")]}


def _length(kp: np.ndarray, a: str, b: str) -> np.ndarray:
    return np.linalg.norm(kp[:, K[a]] - kp[:, K[b]], axis=-1)


@pytest.fixture(scope="module")
def motion():
    return demo_motion(1, 1.0, 0)[:6]


def test_proportions_scale_each_limb_by_its_factor(motion):
    factors = {"arms": 1.25, "legs": 0.8, "trunk": 1.1}
    scaled = with_proportions(motion, factors["arms"], factors["legs"], factors["trunk"])
    k0, k1 = keypoint_positions(motion), keypoint_positions(scaled)
    for group, bones in BONES.items():
        for a, b in bones:
            np.testing.assert_allclose(_length(k1, a, b), factors[group] * _length(k0, a, b), rtol=1e-9)
    # the root's path follows the legs
    np.testing.assert_allclose(scaled.root_positions, factors["legs"] * motion.root_positions, rtol=1e-12)
    assert with_proportions(motion, 1.0, 1.0, 1.0) is motion


def test_specs_draw_cameras_sizes_and_bodies_in_their_ranges():
    specs = make_specs("test", 4, 0, 6, 3, None, elevation=(-10.0, 45.0), scale=(0.7, 1.15), proportions=0.1)
    el = np.array([s.elevation for s in specs])
    sc = np.array([s.scale for s in specs])
    pr = np.array([s.proportions for s in specs])
    assert el.min() >= -10 and el.max() <= 45 and el.min() < 0 and el.max() > 20  # the range is used
    assert sc.min() >= 0.7 and sc.max() <= 1.15
    assert np.all(np.abs(pr - 1) <= 0.1) and np.std(pr) > 0.02
    plain = make_specs("test", 4, 0, 6, 3, None)
    assert all(s.proportions == (1.0, 1.0, 1.0) and 0 <= s.elevation <= 20 for s in plain)
    # the first camera is drawn before any body: it does not move (later ones do, the stream is shared)
    assert (plain[0].azimuth, plain[0].start_s, plain[0].seed) == (specs[0].azimuth, specs[0].start_s, specs[0].seed)
    with pytest.raises(ValueError, match="elevation"):
        make_specs("test", 1, 0, 1, 0, None, elevation=(30.0, 10.0))
    with pytest.raises(ValueError, match="proportions"):
        make_specs("test", 1, 0, 1, 0, None, proportions=0.7)


def test_rendered_keypoints_follow_the_proportions():
    spec = make_specs("test", 1, 0, 1, 0, None, proportions=0.2)[0]
    samples = render_spec(spec)
    plain = render_spec(type(spec)(**{**spec.__dict__, "proportions": (1.0, 1.0, 1.0)}))
    arm = lambda ss: np.mean([np.linalg.norm(s.keypoints[K["left_shoulder"]] - s.keypoints[K["left_elbow"]])  # noqa: E731
                              for s in ss])
    torso = lambda ss: np.mean([np.linalg.norm(s.keypoints[K["neck"]] - s.keypoints[K["pelvis"]])  # noqa: E731
                                for s in ss])
    # the camera frames the figure by its height, so compare the arm relative to the torso
    ratio = (arm(samples) / torso(samples)) / (arm(plain) / torso(plain))
    assert ratio == pytest.approx(spec.proportions[0] / spec.proportions[2], rel=0.08)


def test_train_refuses_a_bad_range_naming_it():
    from vidstyle.pose.training import train

    with pytest.raises(ParameterError, match="elevation"):
        train(None, demo_performers=1, cmu_clips=0, views_per_clip=1, elevation=(50.0, 10.0))


def test_the_ps_backend_defaults_to_the_shipped_model_file(tmp_path, monkeypatch):
    from vidstyle.pose import defaults, run

    shipped = tmp_path / "weights" / "ps_cnn.joblib"
    monkeypatch.setattr(defaults, "shipped_model_path", lambda: shipped)
    with pytest.raises(ParameterError, match="no shipped model"):
        run.resolve_model("ps", None)
    shipped.parent.mkdir()
    shipped.write_bytes(b"x")
    assert run.resolve_model("ps", None) == str(shipped)
    assert run.resolve_model("ps", "mine.joblib") == "mine.joblib"  # a given model always wins
    assert run.resolve_model("blazepose", None) is None
