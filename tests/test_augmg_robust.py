"""Robust AugMG: window matching over a mark's neighbours, confidence weights, adaptive segment halves,
acceptance thresholds, and the report's per-annotation animations."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from vidstyle.augmg.enhance import adaptive_halves, window_distance
from vidstyle.evaluation.augmg import accept
from vidstyle.augmg.index import LibraryClip, PoseIndex, weighted_feature_distance, window_query
from vidstyle.augmg.keypoints import BONE_INDEX
from vidstyle.augmg.projection import angle_features, facing_normalised, facing_of_keypoints, project


def _smooth_clips(rng, n=3, frames=120):
    """Clips of smoothly moving random keypoints (60 fps), so neighbouring frames are similar."""
    return [LibraryClip(f"c{i}.bvh", np.cumsum(rng.normal(0, 0.03, (frames, 15, 3)), axis=0) + rng.normal(size=(15, 3)),
                        60.0) for i in range(n)]


def test_window_query_with_one_frame_is_exact_knn(rng):
    idx = PoseIndex(n_views=4, stride=3).fit(_smooth_clips(rng))
    q = rng.normal(size=(1, 15, 2))
    ids, cost = window_query(idx, q, np.zeros(1), 92.0, k=7, per_frame_k=7)
    brute = np.linalg.norm(idx.features_[1].astype(np.float64) - angle_features(q)[0], axis=-1)
    np.testing.assert_array_equal(ids, np.argsort(brute, kind="stable")[:7])
    np.testing.assert_allclose(cost, np.sort(brute)[:7], rtol=1e-5, atol=1e-6)


def test_window_query_finds_the_library_window_and_its_cost_is_the_brute_force_mean(rng):
    clips = _smooth_clips(rng)
    idx = PoseIndex(n_views=1, stride=3).fit(clips)
    # the mark is library clip 2 frame 60 (indexed), its neighbours +-1 and +-2 video frames (20 fps = 3 mocap)
    offs = np.arange(-2, 3) / 20.0
    pts = clips[2].points[[54, 57, 60, 63, 66]]
    uv = project(facing_normalised(pts, facing_of_keypoints(pts)), 0.0, 10.0)
    uv = uv + rng.normal(0, 0.02, uv.shape)  # noise: single frames may prefer a neighbour, the window not
    ids, cost = window_query(idx, uv, offs, 0.0, k=5, per_frame_k=20, tolerance=0.0)
    assert idx.clip_[ids[0]] == 2 and idx.frame_[ids[0]] == 60
    # brute force of the cost of the best candidate: mean over offsets of the min over the slack window
    feats = angle_features(uv).astype(np.float64)
    F = idx.features_[0].astype(np.float64)
    c = ids[0]
    per = []
    for d, o in enumerate(offs):
        centre = c + int(round(o * 60 / 3))
        slack = 0 if o == 0 else 1
        js = [j for j in range(centre - slack, centre + slack + 1) if idx.clip_[j] == idx.clip_[c]]
        per.append(min(np.linalg.norm(F[j] - feats[d]) for j in js))
    assert cost[0] == pytest.approx(np.mean(per), rel=1e-5)


def test_bone_weights_scale_free_and_zero_weight_ignores_a_bone(rng):
    q, f = rng.normal(size=28), rng.normal(size=28)
    assert weighted_feature_distance(q, f, None) == pytest.approx(np.linalg.norm(q - f))
    assert weighted_feature_distance(q, f, np.full(14, 0.3)) == pytest.approx(np.linalg.norm(q - f))
    w = np.ones(14)
    w[5] = 0.0
    g = f.copy()
    g[10:12] += 5.0  # bone 5's direction components differ wildly
    assert weighted_feature_distance(q, g, w) == pytest.approx(weighted_feature_distance(q, f, w))
    assert weighted_feature_distance(q, g, None) > weighted_feature_distance(q, f, None)


def test_a_corrupted_keypoint_with_low_score_does_not_move_the_match(rng):
    clips = _smooth_clips(rng, n=2)
    idx = PoseIndex(n_views=1, stride=3).fit(clips)
    pts = clips[1].points[90:91]
    uv = project(facing_normalised(pts, facing_of_keypoints(pts)), 0.0, 10.0)
    bad = uv.copy()
    bad[0, 7] += [5.0, -4.0]  # left wrist far off
    scores = np.ones((1, 15))
    scores[0, 7] = 0.0
    ids, cost = window_query(idx, bad, np.zeros(1), 0.0, k=1, per_frame_k=200, scores=scores)
    assert idx.clip_[ids[0]] == 1 and idx.frame_[ids[0]] == 90 and cost[0] < 1e-4
    # the left wrist ends bone 4 only (left_elbow -> left_wrist)
    assert set(np.flatnonzero((BONE_INDEX == 7).any(axis=1))) == {4}


def test_adaptive_halves_is_the_brute_force_minimum(rng):
    w = np.cumsum(rng.normal(0, 0.05, (90, 15, 3)), axis=0)
    src = np.cumsum(rng.normal(0, 0.05, (60, 15, 3)), axis=0)
    dst = np.cumsum(rng.normal(0, 0.05, (60, 15, 3)), axis=0)
    z, k, halves = 45, 5, (3, 6, 9, 12)
    h1, h2, cost = adaptive_halves(src, 30, w, z, dst, 20, halves, k=k)
    best = min((float(window_distance(src[26:31], w[z - a - k + 1:z - a + 1]) + window_distance(w[z + b:z + b + k], dst[20:25])), a, b)
               for a, b in itertools.product(halves, halves))
    assert (cost, h1, h2) == pytest.approx(best)
    # on its own clip the segment ends where src / dst are the clip itself: zero cost
    h1, h2, cost = adaptive_halves(w, z - 6, w, z, w, z + 9, halves, k=k)
    assert (h1, h2) == (6, 9) and cost == pytest.approx(0.0, abs=1e-6)


def test_rejected_enhancements_keep_the_plain_transition():
    rows = [{"match_cost": 0.5, "enhanced_cost": 2.0, "transition_plain_mm": 100.0, "transition_enhanced_mm": 60.0},
            {"match_cost": 1.5, "enhanced_cost": 2.0, "transition_plain_mm": 100.0, "transition_enhanced_mm": 150.0},
            {"match_cost": 0.5, "enhanced_cost": 9.0, "transition_plain_mm": 80.0, "transition_enhanced_mm": 120.0},
            {"match_cost": 0.5, "enhanced_cost": None, "transition_plain_mm": 80.0, "transition_enhanced_mm": 90.0}]
    out = accept(rows, 1.0, 5.0)
    assert [r["accepted"] for r in out] == [True, False, False, False]
    assert [r["transition_augmg_mm"] for r in out] == [60.0, 100.0, 80.0, 80.0]
    assert [r["accepted"] for r in accept(rows)] == [True, True, True, False]  # no thresholds: any fitting window


def test_pca_tree_is_exact_knn_including_its_fallback(rng):
    from vidstyle.augmg.index import PcaTree

    # features on a low-dimensional manifold plus tiny noise (as projected poses), and an isotropic set
    # where 3 principal axes bound distances poorly (the certificate must fetch more, finally everything)
    low = rng.normal(size=(3000, 4)) @ rng.normal(size=(4, 28)) + rng.normal(0, 0.01, (3000, 28))
    iso = rng.normal(size=(800, 28))
    for feats, dims in ((low, 6), (iso, 3)):
        tree = PcaTree(feats.astype(np.float32), dims=dims, ratio=2)
        q = feats[rng.choice(len(feats), 5)] + rng.normal(0, 0.05, (5, 28))
        d, i = tree.query(q, k=7)
        brute = np.linalg.norm(feats.astype(np.float32)[None] - q.astype(np.float32)[:, None], axis=-1)
        np.testing.assert_array_equal(np.sort(i, axis=1), np.sort(np.argsort(brute, axis=1)[:, :7], axis=1))
        np.testing.assert_allclose(d, np.sort(brute, axis=1)[:, :7], rtol=1e-4, atol=1e-5)


@pytest.mark.slow
def test_report_shows_one_animated_entry_per_accepted_annotation(tmp_path):
    """evaluate augmg --annotations --transitions, then the report: one entry (frame + pose, matched
    library pose, plain / AugMG / true animations) per accepted mark, none for the discarded one."""
    from typer.testing import CliRunner

    from vidstyle.demo.library import LibraryParams, make_library
    from vidstyle.cli import app
    from vidstyle.demo.dataset import DatasetParams, make_dataset
    from vidstyle.formats.annotations import Annotations, Transition, VideoAnnotations, write_annotations
    from vidstyle.formats.augmg_transitions import read_augmg_transitions
    from vidstyle.report.build import build_report

    run = tmp_path / "out"
    make_dataset(run / "dataset", DatasetParams.small(performances=1, performance_seconds=30.0, render=False), jobs=1)
    make_library(run / "augmg" / "library", LibraryParams(performers=1, action_seconds=3.0), jobs=1)
    manifest = json.loads((run / "dataset" / "dataset.json").read_text())
    videos, marks = [], []
    for v in manifest["videos"]:
        if v["kind"] != "performance":
            continue
        styled = json.loads((run / "dataset" / v["labels"]).read_text())["styled_transitions"]
        ts = [Transition(t["key"], t["from"], t["to"], "accepted") for t in styled[:2]]
        if len(styled) > 2:
            ts.append(Transition(styled[2]["key"], styled[2]["from"], styled[2]["to"], "discarded"))
        marks += [(v["id"], t.frame) for t in ts if t.status == "accepted"]
        videos.append(VideoAnnotations(f"{v['id']}.mp4", f"{len(videos):064x}", v["frames"], 20.0, ts))
    assert marks
    ann = tmp_path / "ann.json"
    write_annotations(ann, Annotations(manifest["actions"], videos))
    r = CliRunner().invoke(app, ["evaluate", "augmg", "--dataset", str(run / "dataset"), "--library",
                                 str(run / "augmg" / "library"), "--annotations", str(ann), "--out",
                                 str(run / "metrics" / "augmg.json"), "--transitions", str(run / "augmg" / "transitions.json")])
    assert r.exit_code == 0, r.output
    doc = read_augmg_transitions(run / "augmg" / "transitions.json")
    assert sorted((e.video, e.frame) for e in doc.entries) == sorted(marks)
    e = doc.entries[0]
    assert e.truth.shape == e.plain.shape == e.augmg.shape and e.truth.shape[1:] == (15, 3)
    # the plain transition starts and ends between the true endpoints; AugMG = plain when rejected
    if not e.accepted:
        np.testing.assert_allclose(e.augmg, e.plain)
    html = build_report(run)
    found = [(m.group(1), int(m.group(2))) for m in
             __import__("re").finditer(r'class="augmg-entry" data-video="([^"]+)" data-frame="(\d+)"', html)]
    assert sorted(found) == sorted(marks)
    assert html.count('<canvas class="augmg-anim"') == len(marks)
    payload = json.loads(html.split('id="augmg-anim-data">')[1].split("</script>")[0].replace("<\\/", "</"))
    assert len(payload["entries"]) == len(marks)


def test_foreshortening_weights_follow_the_bone_angle_to_the_image_plane(rng):
    from vidstyle.augmg.index import bone_length_ratios, bone_weights, foreshortening_weights
    from vidstyle.augmg.keypoints import KP

    # a 3D body: its side-on bone lengths in torso lengths are what bone_length_ratios measures
    pts3 = rng.normal(size=(1, 15, 3))
    ratios = bone_length_ratios(np.repeat(pts3, 4, axis=0))
    mid = lambda p, a, b: (p[..., KP[a], :] + p[..., KP[b], :]) / 2  # noqa: E731
    torso = np.linalg.norm(mid(pts3, "left_shoulder", "right_shoulder") - mid(pts3, "left_hip", "right_hip"))
    wrist = np.linalg.norm(pts3[0, KP["left_wrist"]] - pts3[0, KP["left_elbow"]])
    assert ratios[4] == pytest.approx(wrist / torso)  # bone 4: left_elbow -> left_wrist
    # an image of that body with the forearm turned by an angle a out of the image plane: weight cos(a)
    uv = np.zeros((3, 15, 2))
    uv[:, KP["left_shoulder"]], uv[:, KP["right_shoulder"]] = (-1.0, 0.0), (1.0, 0.0)
    uv[:, KP["left_hip"]], uv[:, KP["right_hip"]] = (-1.0, 2.0), (1.0, 2.0)  # image torso length 2
    uv[:, KP["left_elbow"]] = (3.0, 0.0)
    for i, a in enumerate((0.0, 60.0, 90.0)):
        uv[i, KP["left_wrist"]] = uv[i, KP["left_elbow"]] + (0.0, 2.0 * ratios[4] * np.cos(np.radians(a)))
    w = foreshortening_weights(uv, ratios)
    np.testing.assert_allclose(w[:, 4], [1.0, 0.5, 0.0], atol=1e-9)
    assert (w >= 0).all() and (w <= 1).all()
    # combined with confidence scores: the product
    scores = rng.uniform(0.2, 1.0, (3, 15))
    np.testing.assert_allclose(bone_weights(scores, uv, ratios), bone_weights(scores) * w)
    assert bone_weights(None) is None and bone_weights(None, uv, ratios) is not None
