"""Part scoring (rotated templates and orientation mixtures), the orientation min-plus, the unary
weight, the whole-person HOG viewpoint classifier and the held-out splits."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

import vidstyle.demo  # noqa: F401 - registers the "demo" training source (demo:<i> specs)
from vidstyle.pose.data import MAX_PERFORMERS, TRAIN_CMU_SUBJECTS, VAL_CMU_SUBJECTS, make_specs
from vidstyle.pose.dt import min_plus
from vidstyle.pose.estimator import HOG_DROP, HOG_WIN, ViewpointHOG, person_crop, person_hog
from vidstyle.pose.features import RotatedFeatures
from vidstyle.pose.foreground import background_model, foreground
from vidstyle.pose.model import N_PARTS, PictorialStructures, score_models

from test_pose_dt import _toy_model


def test_min_plus_matches_enumeration(rng):
    D = rng.normal(size=(5, 3, 4))
    pen = rng.uniform(0, 3, size=(5, 5))
    E, best = min_plus(D, pen)
    brute = D[None] + pen[:, :, None, None]  # [i, j, ...]
    np.testing.assert_allclose(E, brute.min(axis=1))
    np.testing.assert_array_equal(best, brute.argmin(axis=1))


def test_unary_weight_scales_the_unaries(rng):
    K, H, W = 3, 4, 5
    m = _toy_model(rng, K)
    scores = rng.normal(size=(N_PARTS, K, H, W)) * 2
    m.unary_weight = 1.7
    a = m.infer(scores)
    m.unary_weight = 1.0
    b = m.infer(1.7 * scores)
    np.testing.assert_array_equal(a["states"], b["states"])
    assert a["energy"] == pytest.approx(b["energy"])
    m.unary_weight = 1.7
    assert m.energy(scores, a["states"]) == pytest.approx(a["energy"])


def _random_frame(rng, H=48, W=64):
    img = cv2.GaussianBlur(rng.uniform(0, 255, (H, W)).astype(np.float32), (0, 0), 1.5)
    return np.clip(img, 0, 255).astype(np.uint8)


@pytest.mark.parametrize("orient", ["rotate", "mixture"])
def test_score_maps_are_window_dot_products(rng, orient):
    """Every score is the template's dot product with the cells of the window the training
    windows are cut from, plus the bias (checked where the frame's cell grid falls on whole canvas
    cells: every orientation for mixtures, the upright orientation for rotated copies)."""
    K, cell = 8, 4
    f = RotatedFeatures(_random_frame(rng), K, cell, rotate=orient == "rotate")
    m = PictorialStructures(n_orient=K, cell=cell, orient=orient)
    m.sizes_ = [(5, 3)] * N_PARTS
    C = f.feats.shape[-1]
    if orient == "mixture":
        m.templates_ = [[rng.normal(size=(5, 3, C)).astype(np.float32) for _ in range(K)] for _ in range(N_PARTS)]
        m.bias_ = rng.normal(size=(N_PARTS, K))
        ks = range(K)
    else:
        m.templates_ = [rng.normal(size=(5, 3, C)).astype(np.float32) for _ in range(N_PARTS)]
        m.bias_ = rng.normal(size=N_PARTS)
        ks = [K // 4]  # theta = pi/2: the copy is the frame itself, shifted by whole cells
    S = score_models({"m": m}, f)["m"]
    assert S.shape == (N_PARTS, K, 48 // cell, 64 // cell)
    for j in (0, 3, 9):
        for k in ks:
            for y, x in ((3, 4), (6, 10), (8, 2)):
                win = f.window(k, np.array([x * cell + (cell - 1) / 2, y * cell + (cell - 1) / 2]), 5, 3)
                T = m.templates_[j][k] if orient == "mixture" else m.templates_[j]
                b = m.bias_[j, k] if orient == "mixture" else m.bias_[j]
                assert S[j, k, y, x] == pytest.approx(float(win @ T.ravel()) + b, abs=1e-3)


def test_mixture_fit_learns_one_template_per_orientation(rng):
    from vidstyle.pose.data import Spec, render_samples

    samples = render_samples([Spec("demo:0", 1.0 + i, 1.0, az, 10.0, 7 + i, fps=3.0)
                              for i, az in enumerate((0.0, 90.0, -90.0))], jobs=1)
    kp = np.stack([s.keypoints for s in samples])
    m = PictorialStructures(n_orient=8, hard_rounds=0, neg_per_pos=4, orient="mixture").fit(
        [s.image for s in samples], kp)
    assert len(m.templates_) == N_PARTS and all(len(t) == 8 for t in m.templates_)
    assert all(h == w for h, w in m.sizes_)
    f = RotatedFeatures(samples[0].image, 8, 4, rotate=False)
    assert f.feats.shape[0] == 1  # one unrotated copy serves every orientation
    r = m.infer(m.score_maps(f))
    pts = m.keypoints(r["states"], r["unary"])
    torso = np.linalg.norm(pts[[1, 2], :2] - kp[0, [1, 2]], axis=1)  # neck, pelvis on its training frame
    assert torso.max() < 0.5 * np.linalg.norm(kp[0, 1] - kp[0, 2])


def test_person_crop_centres_below_the_torso():
    img = np.zeros((120, 160), np.uint8)
    img[50 + HOG_DROP, 70] = 255
    crop = person_crop(img, (70, 50))
    w, h = HOG_WIN
    assert crop.shape == (h, w)
    y, x = np.unravel_index(int(crop.argmax()), crop.shape)
    assert (x, y) == (w // 2, h // 2)


def _arrow(direction: str, rng) -> np.ndarray:
    w, h = HOG_WIN
    img = np.full((h, w), 90, np.uint8)
    if direction in ("left", "right"):
        pts = np.array([[12, 56], [52, 26], [52, 86]]) if direction == "left" else np.array([[52, 56], [12, 26], [12, 86]])
        cv2.fillPoly(img, [pts.astype(np.int32)], 200)
    elif direction == "front":
        cv2.rectangle(img, (26, 10), (38, 100), 200, -1)
    else:
        cv2.rectangle(img, (6, 50), (58, 62), 200, -1)
    noise = rng.normal(0, 6, img.shape)
    return np.clip(img + noise, 0, 255).astype(np.uint8)


def test_hog_classifier_learns_the_unseen_mirror_view(rng):
    """Trained on left, front and back only (plus their mirror images), the classifier labels
    right-pointing figures "right": the mirror augmentation swaps left and right."""
    views = ["left", "front", "back"] * 10
    crops = [_arrow(v, rng) for v in views]
    X = np.stack([person_hog(c) for c in crops])
    Xm = np.stack([person_hog(cv2.flip(c, 1)) for c in crops])
    clf = ViewpointHOG(C=0.1).fit(X, views, Xm)
    test = [_arrow(v, rng) for v in ("right", "left", "front", "back")]
    assert list(clf.predict(np.stack([person_hog(c) for c in test]))) == ["right", "left", "front", "back"]
    s = clf.scores(person_hog(test[0])[None])[0]
    assert max(s, key=s.get) == "right" and sum(s.values()) == pytest.approx(1.0, abs=1e-3)


def test_splits_share_no_source_and_hold_out_azimuths(cmu_dir: Path):
    tr, va, te = (make_specs(s, 3, 40, 3, 0, cmu_dir) for s in ("train", "val", "test"))
    src = [{sp.source for sp in specs} for specs in (tr, va, te)]
    assert not (src[0] & src[1]) and not (src[0] & src[2]) and not (src[1] & src[2])
    subj = [{Path(s).stem.split("_")[0] for s in x if not s.startswith("demo:")} for x in src]
    assert subj[0] <= set(TRAIN_CMU_SUBJECTS) and subj[1] <= set(VAL_CMU_SUBJECTS) and subj[1] and subj[2]
    assert not subj[2] & (set(TRAIN_CMU_SUBJECTS) | set(VAL_CMU_SUBJECTS))
    train_az = np.array([sp.azimuth for sp in tr])
    for sp in va + te:
        gap = np.abs((train_az - sp.azimuth + 180) % 360 - 180)
        assert gap.min() >= 9.99


def test_splits_refuse_more_performers_than_they_own(cmu_dir: Path):
    # the largest training set ends just before the first validation performer; one more would train on it
    tr = make_specs("train", MAX_PERFORMERS["train"], 0, 1, 0, cmu_dir)
    va = make_specs("val", 1, 0, 1, 0, cmu_dir)
    assert max(int(sp.source.split(":")[1]) for sp in tr) < int(va[0].source.split(":")[1])
    with pytest.raises(ValueError, match="n_demo"):
        make_specs("train", MAX_PERFORMERS["train"] + 1, 0, 1, 0, cmu_dir)
    with pytest.raises(ValueError, match="n_demo"):
        make_specs("val", MAX_PERFORMERS["val"] + 1, 0, 1, 0, cmu_dir)


def test_background_median_and_foreground(rng):
    bg = rng.integers(60, 200, (40, 50, 3)).astype(np.uint8)
    frames = []
    for t in range(5):  # a bright square moving across: every pixel is background in most frames
        fr = bg.copy()
        fr[10:20, 5 + 9 * t:15 + 9 * t] = 255
        frames.append(fr)
    B = background_model(frames)
    np.testing.assert_array_equal(B, bg.astype(np.float32))
    fg = foreground(frames[2], B)
    assert fg[13:17, 25:29].min() > 0.99 and fg[30:, :].max() == 0.0


def test_part_coverage_is_the_window_mean(rng):
    from vidstyle.pose.foreground import part_coverage

    K, cell = 8, 4
    f = RotatedFeatures(_random_frame(rng, 60, 80), K, cell, rotate=True)
    m = PictorialStructures(n_orient=K, cell=cell)
    m.sizes_ = [(5, 3)] * N_PARTS
    ones = part_coverage(m, f, np.ones((60, 80), np.float32))
    np.testing.assert_allclose(ones[:, :, 5:10, 5:15], 1.0, atol=1e-5)  # windows inside the frame
    half = np.zeros((60, 80), np.float32)
    half[:, :40] = 1.0
    cov = part_coverage(m, f, half)
    # upright orientation: a 3-cell wide window centred on cell column x covers x-1..x+1
    k = K // 4
    assert cov[0, k, 7, 3] == pytest.approx(1.0, abs=1e-4) and cov[0, k, 7, 16] == pytest.approx(0.0, abs=1e-4)
    assert cov[0, k, 7, 9] == pytest.approx(2 / 3, abs=1e-4)  # columns 8, 9 inside, 10 outside


def test_video_background_marks_the_performer(tmp_path, rng):
    """On a static-camera render, the median background of the whole video leaves the moving
    performer as foreground: the moving joints of a frame are foreground, the corners are not."""
    from vidstyle.demo import Performer, build_take, performance_plan
    from vidstyle.formats.truth import read_truth
    from vidstyle.pose.run import video_background
    from vidstyle.render import render_to_file
    from vidstyle.video import VideoReader

    p = Performer.random("p07", rng, video_fps=20)
    motion = build_take(p, performance_plan(p, 60, rng), rng, video_fps=20).motion.resample(10)[:30]
    video = tmp_path / "clip.mkv"
    side = render_to_file(motion, video, view=30.0, size=(160, 120), fps=10, background="texture", seed=3)
    joints = read_truth(side).joints2d[15]  # (31, 2) skeleton joints of frame 15
    with VideoReader(video) as r:
        bg = video_background(r)
        frame = np.asarray(r.frame(15))
    assert bg.shape == frame.shape
    fg = foreground(frame, bg)
    assert fg[:10, :10].max() < 0.2 and fg[-10:, -10:].max() < 0.2
    inside = [fg[int(round(y)), int(round(x))] for x, y in joints[:, :2]
              if 0 <= round(x) < 160 and 0 <= round(y) < 120]
    # the moving upper body is foreground; feet planted for most of the clip join the median
    assert np.mean(np.array(inside) > 0.5) > 0.4


def test_wilson_interval_matches_newcombes_published_values():
    """Newcombe (1998), Statistics in Medicine 17:857, Table I, method 3 (score interval without
    continuity correction)."""
    from vidstyle.evaluation.pose import wilson_interval

    for (hits, n), want in [((81, 263), (0.2553, 0.3662)), ((15, 148), (0.0624, 0.1605)), ((0, 20), (0.0, 0.1611)),
                            ((1, 29), (0.0061, 0.1718))]:
        assert wilson_interval(hits, n) == pytest.approx(want, abs=5e-5)
    lo, hi = wilson_interval(29, 30)
    assert lo < 29 / 30 < hi <= 1.0 and wilson_interval(0, 0) is None
