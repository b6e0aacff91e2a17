"""The cnn part detector: heatmap targets, part unaries against a brute-force reading, keypoint
refinement on analytic heatmaps, a network that learns a task it can fail, and the CnnPoseModel
through save/load and the pose command's interface."""

from __future__ import annotations

import numpy as np
import pytest

import torch  # noqa: F401 - a declared dependency: missing is a failure, not a skip

import vidstyle.demo  # noqa: F401 - registers the "demo" training source (demo:<i> specs)
from vidstyle.mocap.keypoints import KEYPOINTS, PART_KEYPOINTS
from vidstyle.pose.cnn import (
    CELL,
    FLIP_KEYPOINTS,
    FLIP_VIEWS,
    LOG_FLOOR,
    CnnPoseModel,
    HeatmapCNN,
    argmax_keypoints,
    coarse_logheat,
    gaussian_targets,
    part_unaries,
    random_affine,
    refine_keypoints,
)
from vidstyle.pose.data import VIEW_NAMES, Spec, render_samples
from vidstyle.pose.model import N_PARTS, PictorialStructures, _from_frame


def test_flip_tables_swap_sides_and_are_involutions():
    assert [FLIP_KEYPOINTS[i] for i in FLIP_KEYPOINTS] == list(range(len(KEYPOINTS)))
    assert KEYPOINTS[FLIP_KEYPOINTS[KEYPOINTS.index("left_wrist")]] == "right_wrist"
    assert KEYPOINTS[FLIP_KEYPOINTS[KEYPOINTS.index("neck")]] == "neck"
    assert [VIEW_NAMES[i] for i in FLIP_VIEWS] == ["front", "right", "left", "back"]


def test_gaussian_targets_are_distributions_peaking_at_the_keypoint_cell():
    kp = np.array([[[13.5, 21.5]] * len(KEYPOINTS)])  # cell (3, 5): centre x = 3*4+1.5, y = 5*4+1.5
    t = gaussian_targets(kp, (10, 12), sigma=1.0)
    assert t.shape == (1, 15, 10, 12)
    np.testing.assert_allclose(t.sum(axis=(2, 3)), 1.0, rtol=1e-5)
    y, x = np.unravel_index(t[0, 0].argmax(), (10, 12))
    assert (x, y) == (3, 5)


def _geometry(rng):
    kp = np.zeros((40, 15, 2))
    base = rng.uniform(30, 90, (15, 2))
    for i in range(40):
        kp[i] = base + rng.normal(0, 2.0, (15, 2))
    return PictorialStructures(n_orient=8, cell=CELL).fit_geometry(kp)


def test_part_unaries_equal_brute_force_endpoint_lookups(rng):
    m = _geometry(rng)
    Hc, Wc = 9, 11
    logheat = rng.normal(-5, 1, (15, Hc, Wc)).astype(np.float32)
    got = part_unaries(logheat, m)
    assert got.shape == (N_PARTS, 8, Hc, Wc)
    ang = np.arange(8) * (2 * np.pi / 8)

    def look(kpi, y, x):
        return logheat[kpi, y, x] if 0 <= y < Hc and 0 <= x < Wc else LOG_FLOOR

    for j in range(N_PARTS):
        a, b = PART_KEYPOINTS[j]
        for k in range(8):
            oa = np.rint(_from_frame(m.proximal_[j], ang[k])).astype(int)
            ob = np.rint(_from_frame(m.distal_[j], ang[k])).astype(int)
            for y in range(Hc):
                for x in range(Wc):
                    want = look(a, y + oa[1], x + oa[0]) + look(b, y + ob[1], x + ob[0])
                    assert got[j, k, y, x] == pytest.approx(want, abs=1e-4)


def test_refine_recovers_a_subcell_peak_and_radius_zero_keeps_the_point():
    Hc, Wc = 30, 40
    gy, gx = np.mgrid[0:Hc, 0:Wc]
    centre = np.array([17.3, 11.6])  # cells (x, y)
    p = np.exp(-((gx - centre[0]) ** 2 + (gy - centre[1]) ** 2) / 2.0)
    logheat = np.repeat(np.log(p / p.sum())[None], 15, axis=0)
    px = centre * CELL + (CELL - 1) / 2.0
    start = np.tile(px + [3.0, -2.0], (15, 1))  # a tree solution about one cell off
    out = refine_keypoints(start, logheat, scale=1.0, radius=3)
    np.testing.assert_allclose(out[:, :2], np.tile(px, (15, 1)), atol=0.35 * CELL)
    assert 0.5 < out[0, 2] <= 1.0  # most of the mass is within one cell of the peak
    kept = refine_keypoints(start, logheat, scale=1.0, radius=0)
    np.testing.assert_allclose(kept[:, :2], start, atol=1e-9)
    # input pixels at half the working size: the same point in the input's coordinates
    half = refine_keypoints(start / 2.0, logheat, scale=2.0, radius=3)
    np.testing.assert_allclose(half[:, :2], out[:, :2] / 2.0, atol=1e-9)
    am = argmax_keypoints(logheat)
    np.testing.assert_allclose(am[:, :2], np.tile(px, (15, 1)), atol=0.35 * CELL)


def _dot_images(rng, n, H=48, W=64):
    """Images with one bright square; every keypoint is its centre. The view is told by the square
    in a way a horizontal flip changes as it changes views (front / back: red / blue; left / right: a
    green square with a tail to its left / right), so the training flips stay truthful."""
    X = rng.integers(0, 60, (n, H, W, 3)).astype(np.uint8)
    kp = np.zeros((n, 15, 2))
    views = []
    colour = {"front": (0, 0, 255), "back": (255, 0, 0), "left": (0, 255, 0), "right": (0, 255, 0)}
    for i in range(n):
        x, y = int(rng.integers(8, W - 8)), int(rng.integers(6, H - 6))
        v = VIEW_NAMES[int(rng.integers(4))]
        X[i, y - 2:y + 3, x - 2:x + 3] = colour[v]
        if v == "left":
            X[i, y, x - 6:x - 2] = colour[v]
        elif v == "right":
            X[i, y, x + 3:x + 7] = colour[v]
        kp[i] = (x, y)
        views.append(v)
    return X, kp, views


def test_network_learns_to_find_a_dot_and_its_quadrant(rng):
    X, kp, views = _dot_images(rng, 384)
    net = HeatmapCNN(channels=16, epochs=10, batch_size=32, lr=5e-3, view_weight=1.0, seed=0, threads=1).fit(X, kp, views)
    assert len(net.loss_) == 10 and net.loss_[-1] < net.loss_[0]
    Xt, kpt, vt = _dot_images(np.random.default_rng(99), 64)
    heat, vlog = net.predict(Xt)
    assert heat.shape == (64, 15, 12, 16) and vlog.shape == (64, 4)
    np.testing.assert_allclose(np.exp(heat).sum(axis=(2, 3)), 1.0, rtol=1e-4)
    pts = np.stack([argmax_keypoints(h) for h in heat])
    err = np.linalg.norm(pts[:, 0, :2] - kpt[:, 0], axis=1)
    assert np.median(err) <= 1.5 * CELL  # an untrained net is off by ~20 px
    assert np.mean(np.array(VIEW_NAMES)[vlog.argmax(1)] == np.array(vt)) >= 0.6  # chance: 0.25


def test_stride_two_head_finds_the_dot_finer(rng):
    X, kp, views = _dot_images(rng, 384)
    net = HeatmapCNN(channels=16, epochs=10, batch_size=32, lr=5e-3, view_weight=1.0, seed=0, threads=1,
                     stride=2).fit(X, kp, views)
    Xt, kpt, _vt = _dot_images(np.random.default_rng(99), 64)
    heat, _ = net.predict(Xt)
    assert heat.shape == (64, 15, 24, 32)  # twice the tree grid's resolution
    np.testing.assert_allclose(np.exp(heat).sum(axis=(2, 3)), 1.0, rtol=1e-4)
    pts = np.stack([argmax_keypoints(h, cell=2) for h in heat])
    assert np.median(np.linalg.norm(pts[:, 0, :2] - kpt[:, 0], axis=1)) <= 1.5 * 2
    coarse = np.stack([coarse_logheat(h, 2) for h in heat])
    assert coarse.shape == (64, 15, 12, 16)
    with pytest.raises(ValueError, match="stride"):
        HeatmapCNN(stride=3)


def test_coarse_logheat_sums_sub_cells():
    rng = np.random.default_rng(3)
    p = rng.random((15, 9, 12))  # an odd number of rows: the last one is dropped with its mass
    p /= p.sum(axis=(1, 2), keepdims=True)
    got = np.exp(coarse_logheat(np.log(p).astype(np.float32), 2))
    want = np.zeros((15, 4, 6))
    for y in range(4):
        for x in range(6):
            want[:, y, x] = p[:, 2 * y:2 * y + 2, 2 * x:2 * x + 2].sum(axis=(1, 2))
    np.testing.assert_allclose(got, want, rtol=1e-5)
    same = np.log(p[:, :8]).astype(np.float32)
    assert coarse_logheat(same, 4) is same


@pytest.mark.parametrize("stride", [4, 2])
def test_flip_test_is_mirror_equivariant(rng, stride):
    """With the test-time flip, the estimate of a mirrored frame is the mirror image of the frame's
    estimate (columns reversed, left and right swapped): exactly, up to float rounding, whatever the
    weights; without it an untrained network is not."""
    X, kp, views = _dot_images(rng, 64)
    net = HeatmapCNN(channels=8, epochs=1, seed=1, threads=1, stride=stride).fit(X, kp, views)
    x = X[:3]
    mx = np.ascontiguousarray(x[:, :, ::-1])
    h, v = net.predict(x, flip=True)
    hm, vm = net.predict(mx, flip=True)
    np.testing.assert_allclose(hm, h[:, FLIP_KEYPOINTS][..., ::-1], atol=1e-4)
    np.testing.assert_allclose(vm, v[:, FLIP_VIEWS], atol=1e-5)
    np.testing.assert_allclose(np.exp(h).sum(axis=(2, 3)), 1.0, rtol=1e-4)
    h0, _ = net.predict(x)
    h0m, _ = net.predict(mx)
    assert np.abs(h0m - h0[:, FLIP_KEYPOINTS][..., ::-1]).max() > 1e-3


def test_random_affine_moves_the_pixels_with_the_keypoints(rng):
    """Each keypoint is drawn as a bright dot; after the augmentation the dots must sit at the returned
    keypoints (the image and the labels go through the same map), inside the frame, and the map must
    be a similarity (pairwise keypoint distances scaled by one factor within the range)."""
    import cv2

    n, H, W = 12, 120, 160
    X = np.zeros((n, H, W, 3), np.uint8)
    kp = np.zeros((n, 15, 2))
    for i in range(n):
        c = rng.uniform([50, 40], [110, 80])
        kp[i] = c + rng.uniform(-30, 30, (15, 2)) * [1.0, 1.2]
        for j in range(15):
            cv2.circle(X[i], (int(round(kp[i, j, 0] * 16)), int(round(kp[i, j, 1] * 16))), 16, (0, 0, 255), -1,
                       lineType=cv2.LINE_AA, shift=4)
    Y, k = random_affine(X, kp, rng, scale=(0.8, 1.25), rotate_deg=20.0, margin=2.0)
    assert Y.shape == X.shape and Y.dtype == np.uint8 and k.shape == kp.shape
    assert (k[..., 0] >= 2.0 - 1e-9).all() and (k[..., 0] <= W - 3 + 1e-9).all()
    assert (k[..., 1] >= 2.0 - 1e-9).all() and (k[..., 1] <= H - 3 + 1e-9).all()
    moved = 0.0
    for i in range(n):
        d0 = np.linalg.norm(kp[i][:, None] - kp[i][None], axis=-1)
        d1 = np.linalg.norm(k[i][:, None] - k[i][None], axis=-1)
        m = d0 > 5
        ratio = d1[m] / d0[m]
        assert ratio.std() < 1e-6 and 0.8 - 1e-6 <= ratio.mean() <= 1.25 + 1e-6
        moved = max(moved, float(np.abs(k[i] - kp[i]).max()))
        red = Y[i, :, :, 2].astype(float)
        for j in range(15):
            x, y = k[i, j]
            # the warped dot's brightest pixel is within a pixel of the mapped keypoint
            ys, xs = slice(max(0, int(y) - 3), int(y) + 4), slice(max(0, int(x) - 3), int(x) + 4)
            assert red[ys, xs].max() > 150
            assert red[int(round(y)), int(round(x))] > 100
    assert moved > 3.0  # the augmentation does change the frames


def test_affine_augment_trains_and_is_checked(rng):
    X, kp, views = _dot_images(rng, 64)
    a = HeatmapCNN(channels=8, epochs=1, seed=5, threads=1, augment="affine").fit(X, kp, views)
    b = HeatmapCNN(channels=8, epochs=1, seed=5, threads=1, augment="flip").fit(X, kp, views)
    assert a.get_params()["augment"] == "affine"
    assert np.abs(a.predict(X[:4])[0] - b.predict(X[:4])[0]).max() > 1e-4  # the frames it saw differ
    with pytest.raises(ValueError, match="augment"):
        HeatmapCNN(augment="crop")


def test_network_is_reproducible_from_its_seed(rng):
    X, kp, views = _dot_images(rng, 64)
    a = HeatmapCNN(channels=8, epochs=1, seed=5, threads=1).fit(X, kp, views)
    b = HeatmapCNN(channels=8, epochs=1, seed=5, threads=1).fit(X, kp, views)
    np.testing.assert_array_equal(a.predict(X[:4])[0], b.predict(X[:4])[0])


def test_bad_training_input_is_refused(rng):
    X, kp, views = _dot_images(rng, 40)
    with pytest.raises(ValueError, match="multiples of 4"):
        HeatmapCNN(epochs=1).fit(X[:, :46], kp, views)
    with pytest.raises(ValueError, match="at least batch_size"):
        HeatmapCNN(epochs=1, batch_size=64).fit(X, kp, views)


@pytest.mark.slow
def test_cnn_pose_model_round_trip_and_pose_frames(tmp_path):
    from vidstyle.pose.estimator import load_model, save_model

    specs = [Spec("demo:0", 1.0 + i, 2.0, az + 4 * i, 10.0, 200 + i, fps=4.0)
             for i, az in enumerate((0.0, 90.0, -90.0, 180.0, 0.0, 90.0, -90.0, 180.0))]
    samples = render_samples(specs, jobs=1, keep_bgr=True)
    model = CnnPoseModel(epochs=1, channels=8, batch_size=16, threads=1, seed=2).fit(samples)
    path = tmp_path / "pose.joblib"
    save_model(path, model)
    loaded, header = load_model(path)
    assert header["params"]["detector"] == "cnn" and header["params"]["epochs"] == 1
    assert loaded.VIEWPOINTS == ("cnn",)
    frame = samples[3].bgr
    a, b = model.estimate(frame, 7), loaded.estimate(frame, 7)
    np.testing.assert_array_equal(a.points, b.points)
    # the stride-2 head and the test-time flip through the same interface and file
    m2 = CnnPoseModel(epochs=1, channels=8, batch_size=16, threads=1, seed=2, stride=2, flip_test=True).fit(samples)
    save_model(path, m2)
    loaded2, header2 = load_model(path)
    assert header2["params"]["stride"] == 2 and header2["params"]["flip_test"] is True
    p2 = loaded2.estimate(frame, 7)
    np.testing.assert_array_equal(p2.points, m2.estimate(frame, 7).points)
    assert p2.points.shape == (15, 3) and np.isfinite(p2.points).all()
    assert a.frame == 7 and a.viewpoint in VIEW_NAMES and set(a.viewpoint_scores) == set(VIEW_NAMES)
    assert a.points.shape == (15, 3) and np.isfinite(a.points).all()
    # a frame twice the working size: the same pose in the input's pixels
    import cv2

    big = cv2.resize(frame, (frame.shape[1] * 2, frame.shape[0] * 2), interpolation=cv2.INTER_NEAREST)
    c = loaded.estimate(big, 7)
    assert np.median(np.linalg.norm(c.points[:, :2] / 2.0 - a.points[:, :2], axis=1)) < 2.0
    with pytest.raises(ValueError, match="cnn"):
        loaded.set_inference(viewpoint="hog")


@pytest.mark.slow
def test_train_pose_cnn_and_evaluate_pose_cli(tmp_path, capsys):
    """train-pose --detector cnn writes a model whose evaluate-pose true-viewpoint PCP is recomputed
    here frame by frame through its public estimate(); the viewpoint row is the network's head."""
    from vidstyle.cli import main
    from vidstyle.formats.metrics import POSE, read_metrics
    from vidstyle.pose.data import make_specs
    from vidstyle.pose.estimator import load_model
    from vidstyle.evaluation.pose import strict_pcp

    path = tmp_path / "cnn.joblib"
    assert main(["train-pose", "--detector", "cnn", "--epochs", "1", "--out", str(path), "--demo-performers", "4",
                 "--cmu-clips", "0", "--views-per-clip", "4", "--seconds", "1", "--fps", "4", "--seed", "0",
                 "--channels", "16", "-j", "1"]) == 0
    model, header = load_model(path)
    assert header["params"]["detector"] == "cnn" and header["training"]["demo_performers"] == 4
    assert header["params"]["channels"] == 16 and model.cnn_.weights_["kp.weight"].shape[1] == 32  # stride-2 head
    assert model.cnn_.weights_["view.weight"].shape == (4, 16)
    out = tmp_path / "m.json"
    assert main(["evaluate", "pose", "--model", str(path), "--out", str(out), "--demo-performers", "1",
                 "--cmu-clips", "0", "--views-per-clip", "2", "--seconds", "1", "--fps", "3", "--real-dir", "none",
                 "--seed", "5", "-j", "1"]) == 0
    m = read_metrics(out, POSE)
    samples = render_samples(make_specs("test", 1, 0, 2, 5, None, fps=3.0, seconds=1.0), jobs=1, keep_bgr=True)
    pred = np.stack([model.estimate(s.bgr, view=s.view).points for s in samples])
    hits = strict_pcp(pred, np.stack([s.keypoints for s in samples]))
    assert m.doc["pcp"]["ps_oracle_view"]["all"]["mean"] == pytest.approx(float(hits.mean()))
    assert set(m.doc["viewpoint"]) == {"cnn", "blazepose"} and m.doc["ps_viewpoint_method"] == "cnn"
    assert "PCP" in capsys.readouterr().out


def test_train_pose_refuses_validation_performers(tmp_path, capsys):
    """More demo performers than the training split owns would train on validation performers: a
    one-line error before any rendering, exit 2, no model written."""
    from vidstyle.cli import main
    from vidstyle.pose.data import MAX_PERFORMERS

    path = tmp_path / "m.joblib"
    assert main(["train-pose", "--out", str(path), "--demo-performers", str(MAX_PERFORMERS["train"] + 1),
                 "--cmu-clips", "0", "-j", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--demo-performers" in err[0] and not path.exists()
