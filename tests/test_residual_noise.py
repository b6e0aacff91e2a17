"""ResidualNoise: training keypoints corrupted by the pose estimator's own errors on similar poses."""

import numpy as np
import pytest

from vidstyle.errors import ParameterError
from vidstyle.recognition.posefeatures import MIRROR_INDEX, NECK, PELVIS, mirror_track
from vidstyle.recognition.posetraining import ResidualNoise


def _pose(rng, scale=40.0):
    p = rng.normal(0.0, 1.0, (15, 2)) * scale + 100.0
    p[NECK] = p[PELVIS] + [0.0, -scale]  # torso length = scale
    return p


def test_nearest_matches_brute_force_sort():
    rng = np.random.default_rng(0)
    keys = rng.normal(size=(500, 28))
    rn = ResidualNoise(keys, np.zeros((500, 15, 2)), k=4)
    q = rng.normal(size=(300, 28))
    got = np.sort(rn.nearest(q, chunk=64), axis=1)
    d = np.linalg.norm(q[:, None, :] - keys[None], axis=2)
    want = np.sort(np.argsort(d, axis=1)[:, :4], axis=1)
    np.testing.assert_array_equal(got, want)


def test_each_frame_takes_the_residual_of_its_nearest_calibration_pose_scaled_by_the_torso():
    rng = np.random.default_rng(1)
    a, b = _pose(rng), _pose(rng)
    ra, rb = rng.normal(size=(15, 2)), rng.normal(size=(15, 2))
    true = np.stack([a, b])
    est = true + np.stack([ra, rb]) * 40.0  # torso 40 -> residuals ra, rb in torso units
    rn = ResidualNoise.from_tracks([true], [est], k=1, mirror=False)
    np.testing.assert_allclose(rn.residuals, [ra, rb])
    # a track of a, b, a at twice the size and shifted: the same residuals, in its own torso (80 px)
    track = np.stack([a, b, a]) * 2.0 + 7.0
    out = rn.apply(track, np.random.default_rng(0))
    np.testing.assert_allclose(out, track + np.stack([ra, rb, ra]) * 80.0)


def test_mirror_bank_gives_the_mirrored_residual_to_the_mirrored_pose():
    rng = np.random.default_rng(2)
    a, b = _pose(rng), _pose(rng)
    r = rng.normal(size=(2, 15, 2))
    true = np.stack([a, b])
    rn = ResidualNoise.from_tracks([true], [true + r * 40.0], k=1, mirror=True)
    assert len(rn.keys) == 4 and rn.extra["calibration_frames"] == 2
    m = mirror_track(true)
    out = rn.apply(m, np.random.default_rng(0))
    want = r[:, MIRROR_INDEX, :].copy()
    want[..., 0] *= -1
    np.testing.assert_allclose(out, m + want * 40.0)


def test_missed_frames_are_missing_and_reproducible_draws():
    rng = np.random.default_rng(3)
    true = np.stack([_pose(rng) for _ in range(20)])
    est = true + rng.normal(size=true.shape)
    est[5] = np.nan  # the estimator found nobody
    rn = ResidualNoise.from_tracks([true], [est], k=1, mirror=False)
    out = rn.apply(true, np.random.default_rng(0))
    assert np.all(np.isnan(out[5])) and np.all(np.isfinite(np.delete(out, 5, axis=0)))
    rn3 = ResidualNoise.from_tracks([true], [est], k=3)
    x = true + 0.5
    np.testing.assert_array_equal(rn3.apply(x, np.random.default_rng(7)), rn3.apply(x, np.random.default_rng(7)))
    # unknown keypoints of the track stay unknown, the rest is corrupted
    y = true.copy()
    y[2, 4] = np.nan
    out = rn.apply(y, np.random.default_rng(0))
    assert np.all(np.isnan(out[2, 4])) and np.all(out[2, 3] == y[2, 3])


def test_poses_the_calibration_never_saw_take_the_fallback_noise():
    """max_distance: a frame further than it from every calibration pose is corrupted by the fallback (here
    none: left as it is; or a KeypointNoise), a frame near one takes its residual; distances() is the
    nearest-key distance."""
    from vidstyle.recognition.posetraining import KeypointNoise

    rng = np.random.default_rng(4)
    a = _pose(rng)
    r = rng.normal(size=(1, 15, 2))
    far_pose = _pose(rng)  # another random pose: far from a in key space
    rn = ResidualNoise.from_tracks([a[None]], [a[None] + r * 40.0], k=1, mirror=False, max_distance=0.5)
    track = np.stack([a, far_pose, a + 0.5])
    d = rn.distances(track)
    assert d[0] == pytest.approx(0.0, abs=1e-9) and d[1] > 0.5 and d[2] < 0.5
    out = rn.apply(track, np.random.default_rng(0))
    np.testing.assert_allclose(out[[0, 2]], track[[0, 2]] + r[0] * 40.0)
    np.testing.assert_array_equal(out[1], track[1])
    gated = ResidualNoise(rn.keys, rn.residuals, k=1, max_distance=0.5,
                          fallback=KeypointNoise(sigma=0.1, outlier_rate=0.0, dropout_rate=0.0))
    out = gated.apply(track, np.random.default_rng(0))
    assert not np.allclose(out[1], track[1]) and np.abs(out[1] - track[1]).max() < 40.0  # ~0.1 torso noise
    np.testing.assert_allclose(out[[0, 2]], track[[0, 2]] + r[0] * 40.0)
    assert gated.to_dict()["max_distance"] == 0.5 and gated.to_dict()["fallback"]["sigma"] == 0.1
    with pytest.raises(ParameterError):
        ResidualNoise(rn.keys, rn.residuals, max_distance=-1.0)


def test_bad_banks_are_refused():
    with pytest.raises(ParameterError):
        ResidualNoise(np.zeros((0, 28)), np.zeros((0, 15, 2)))
    with pytest.raises(ParameterError):
        ResidualNoise(np.full((2, 28), np.nan), np.zeros((2, 15, 2)))
    with pytest.raises(ParameterError):
        ResidualNoise.from_tracks([np.zeros((3, 15, 2))], [np.zeros((4, 15, 2))])
    with pytest.raises(ParameterError):
        ResidualNoise.from_tracks([np.full((3, 15, 2), np.nan)], [np.zeros((3, 15, 2))])


@pytest.mark.slow
def test_train_recognizer_noise_poses_calibrates_on_the_training_videos_only(tmp_path):
    """train-recognizer --features pose --noise-poses DIR: the bank holds the pose files of the split's
    training performers (sets A and B), not those of the validation or test performers, whose files are
    there too; and its residuals are what those files differ from the truth by (here a known shift)."""
    from vidstyle.cli import main
    from vidstyle.demo.dataset import DatasetParams, make_dataset
    from vidstyle.evaluation.poserecognition import true_keypoints
    from vidstyle.formats.dataset import read_dataset
    from vidstyle.formats.poses import PoseFrame, Poses, write_poses
    from vidstyle.formats.recognizer_model import read_recognizer_model
    from vidstyle.recognition.splits import make_split

    ds_dir = tmp_path / "dataset"
    make_dataset(ds_dir, DatasetParams.small(views=("front",), single_seconds=2.0, performance_seconds=4.0), jobs=1)
    ds = read_dataset(ds_dir / "dataset.json")
    sp = make_split(ds, "unseen-performer", seed=0)
    poses = tmp_path / "poses"
    poses.mkdir()
    n_train = 0
    for v in ds.videos:
        xy = true_keypoints(ds, v.id) + [3.0, 0.0]  # 3 px to the right
        if v.id in set(sp.vocab) | set(sp.train):
            n_train += len(xy)
        pts = np.concatenate([xy, np.ones(xy.shape[:2] + (1,))], axis=-1)
        write_poses(poses / f"{v.id}.poses.json", Poses(str(ds_dir / v.raw["video"]), "ps",
                                                          [PoseFrame(i, "front", p) for i, p in enumerate(pts)]))
    out = tmp_path / "m.joblib"
    args = ["train-recognizer", "--features", "pose", "--dataset", str(ds_dir / "dataset.json"), "--views", "1",
            "--out", str(out), "--jobs", "1"]
    assert main([*args, "--noise-poses", str(poses), "--residual-k", "2", "--residual-gate", "0"]) == 0
    _, header = read_recognizer_model(out)
    noise = header["training"]["noise"]
    assert noise["kind"] == "residuals" and noise["k"] == 2 and noise["calibration_frames"] == n_train
    assert noise["calibrated_on_videos"] == len(sp.vocab) + len(sp.train) and "max_distance" not in noise
    # gated (the default): the gate a quantile of the validation performer's distances, the fallback the
    # Gaussian of the pose files' error (a 3 px shift: every keypoint an inlier of that size)
    assert main([*args, "--noise-poses", str(poses)]) == 0
    noise = read_recognizer_model(out)[1]["training"]["noise"]
    assert noise["gate_quantile"] == 0.99 and noise["max_distance"] > 0
    torso = np.median([np.linalg.norm(true_keypoints(ds, i)[:, 1] - true_keypoints(ds, i)[:, 2], axis=-1).mean()
                       for i in list(sp.vocab) + list(sp.train)])
    assert noise["fallback"]["sigma"] == pytest.approx(3.0 / np.sqrt(2) / torso, rel=0.2)
    assert noise["fallback"]["outlier_rate"] == 0.0
    # the bank's residuals are the shift, in torso lengths: right in the image, right in the mirror's x -> -x
    from vidstyle.evaluation.poserecognition import residual_noise

    bank = residual_noise(ds, poses, list(sp.vocab) + list(sp.train), k=2)
    dx = bank.residuals[..., 0]
    assert np.all(bank.residuals[..., 1] == pytest.approx(0.0, abs=1e-3))
    assert np.all(np.abs(dx) > 0) and (dx > 0).mean() == pytest.approx(0.5)
    # bad input: no dataset, not a directory, no file of a training video
    assert main([*args[:3], "--clips", "x.bvh", "--noise-poses", str(poses), "--out", str(out)]) == 2
    assert main([*args, "--noise-poses", str(tmp_path / "nope")]) == 2
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main([*args, "--noise-poses", str(empty)]) == 2
