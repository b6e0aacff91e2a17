"""The several-people take (vidstyle.demo.crowd) and its scoring (vidstyle.evaluation.people)."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.demo.crowd import make_crowd
from vidstyle.evaluation.multiview import project
from vidstyle.evaluation.people import identities, pck, score_view, switches
from vidstyle.formats.calibration import read_calibration
from vidstyle.video import VideoReader


@pytest.fixture(scope="module")
def crowd(tmp_path_factory):
    return make_crowd(tmp_path_factory.mktemp("crowd") / "take", n_people=2, n_views=2, seconds=1.0,
                      size=(160, 120), seed=3)


def test_calibration_projects_the_true_3d_keypoints_onto_the_true_2d(crowd):
    calib = read_calibration(crowd / "calibration.toml")
    truth = np.load(crowd / "truth.npz")
    assert calib.names() == [str(v) for v in truth["views"]] == ["cam01", "cam02"]
    for v, cam in enumerate(calib.cameras):
        for p in range(2):
            uv = project(truth["keypoints3d"][p].reshape(-1, 3), cam).reshape(truth["keypoints2d"][v, p].shape)
            assert np.abs(uv - truth["keypoints2d"][v, p]).max() < 0.05


def test_both_people_are_in_every_view_and_the_nearer_one_is_drawn_on_top(crowd):
    truth = np.load(crowd / "truth.npz")
    kp2, depth = truth["keypoints2d"], truth["depth"]
    for v in range(2):
        with VideoReader(crowd / f"cam{v + 1:02d}.mp4") as r:
            frame = r[0].astype(int)
            bg = np.median(frame.reshape(-1, 3), axis=0)
            assert len(r) == kp2.shape[2]
        for p in range(2):
            x, y = kp2[v, p, 0].T
            assert np.all((x > 0) & (x < 159) & (y > 0) & (y < 119))  # everyone inside every view
            # the pelvis of each person shows a figure, not the background
            px, py = np.round(kp2[v, p, 0, 2]).astype(int)
            assert np.abs(frame[py, px] - bg).sum() > 30
        assert depth[v, :, 0].min() > 0


def test_identity_switches_and_pck_on_known_tracks():
    rng = np.random.default_rng(0)
    truth = rng.uniform(0, 100, (2, 6, 15, 2))
    truth[1] += 300  # two people far apart
    est = np.concatenate([truth[0], np.full((6, 15, 1), 0.9)], axis=-1)
    est[3] = np.concatenate([truth[1, 3], np.full((15, 1), 0.9)], axis=-1)  # frame 3 on the other person
    est[4] = np.nan  # no pose
    ids = identities(est, truth)
    assert ids.tolist() == [0, 0, 0, 1, -1, 0]
    assert switches(ids) == 2
    s = score_view(est, truth)
    assert s["chosen"] == 0 and s["identity_switches"] == 2
    assert s["pck@0.2"] == pytest.approx(4 / 6)
    assert pck(est[:1], truth[0, :1]) == 1.0


def test_pose_annotations_follow_the_person_clicked_in_the_crowd(tmp_path, caplog):
    """BlazePose on a two-person take: the performer stored in the annotations file (a person's true pelvis
    at the middle frame, as a click would give) is followed on every marked frame, before and after that
    frame, and it is the person the default choice (the most prominent) does not follow."""
    from vidstyle.formats.annotations import (
        Annotations,
        PerformerChoice,
        Transition,
        VideoAnnotations,
        file_sha256,
        write_annotations,
    )
    from vidstyle.pose.run import estimate_marks

    take = make_crowd(tmp_path / "take", n_people=2, n_views=1, seconds=1.5, fps=10.0, size=(320, 240), seed=3)
    kp2 = np.load(take / "truth.npz")["keypoints2d"][0].astype(np.float64)  # (people, frames, 15, 2)
    video = take / "cam01.mp4"
    F = kp2.shape[1]
    entry = VideoAnnotations(video.name, file_sha256(video), F, 10.0, [Transition(2, "a", "b"), Transition(12, "b", "a")])
    ann = take / "ann.json"
    write_annotations(ann, Annotations(["a", "b"], [entry]))

    def followed():
        poses = estimate_marks(video, ann, "blazepose", context=2, jobs=1, track=True)
        assert [pf.frame for pf in poses.frames] == [0, 1, 2, 3, 4, 10, 11, 12, 13, 14]
        est = np.stack([pf.points for pf in poses.frames])
        return identities(est, kp2[:, [pf.frame for pf in poses.frames]])

    default = followed()
    assert len(set(default.tolist())) == 1 and default[0] >= 0  # the most prominent person, throughout
    other = 1 - int(default[0])
    mid = F // 2  # 7: not a marked frame; marks lie both before and after it
    x, y = kp2[other, mid, 2]  # the pelvis
    entry.performer = PerformerChoice(mid, round(float(x)), round(float(y)))
    write_annotations(ann, Annotations(["a", "b"], [entry]))
    with caplog.at_level("INFO", logger="vidstyle.pose.run"):
        chosen = followed()
    assert f"of frame {mid}, as chosen in" in caplog.text
    assert chosen.tolist() == [other] * len(chosen)
