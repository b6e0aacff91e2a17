"""Pose model: training on renders, save/load, the pose command (ps backend), errors, evaluation metrics."""

from __future__ import annotations

import json

import numpy as np
import pytest

import vidstyle.demo  # noqa: F401 - registers the "demo" training source (demo:<i> specs)
from vidstyle.mocap.keypoints import KEYPOINTS
from vidstyle.pose.data import Spec, acceptable_views, render_samples, view_of
from vidstyle.pose.estimator import PoseModel, load_model, save_model
from vidstyle.evaluation.pose import confusion, pck, strict_pcp, viewpoint_scores


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    specs = [Spec("demo:0", 1.0 + i, 2.0, az + 4 * i, 10.0, 100 + i, fps=3.0)
             for i, az in enumerate((0.0, 90.0, -90.0, 180.0, 0.0, 90.0, -90.0, 180.0))]
    samples = render_samples(specs, jobs=1)
    model = PoseModel(n_orient=8, hard_rounds=0, neg_per_pos=6, seed=3).fit(samples, jobs=1)
    path = tmp_path_factory.mktemp("pose") / "pose.joblib"
    save_model(path, model)
    return model, path, samples


def test_view_of():
    assert [view_of(a) for a in (0, 44, 46, 90, -91, 180, -170, 225)] == \
        ["front", "front", "left", "left", "right", "back", "back", "right"]


def test_acceptable_views_on_and_off_boundaries():
    # one view away from a boundary; both neighbours within 5 degrees of one (45 from two centres)
    assert acceptable_views(15.0) == ("front",) and acceptable_views(-75.0) == ("right",)
    assert acceptable_views(180.0) == ("back",) and acceptable_views(39.0) == ("front",)
    assert acceptable_views(45.0) == ("front", "left") and acceptable_views(-45.0) == ("front", "right")
    assert acceptable_views(135.0) == ("left", "back") and acceptable_views(-135.0) == ("right", "back")
    assert acceptable_views(48.0) == ("left", "front") and acceptable_views(-132.0) == ("right", "back")
    assert acceptable_views(45.0, tol=0.0) == ("front", "left") and acceptable_views(44.0, tol=0.0) == ("front",)
    for a in np.arange(-180.0, 180.0, 7.0):  # the nearest view is always first
        assert acceptable_views(a)[0] == view_of(a)


def test_viewpoint_scores_by_hand():
    az = [15.0, 45.0, 45.0, -45.0, 135.0, 90.0, 180.0, -90.0]
    true = [view_of(a) for a in az]  # front front front front left left back right
    pred = ["front", "left", "back", "front", "back", "left", "right", "right"]
    v = viewpoint_scores(true, az, pred)
    assert v["accuracy"] == 4 / 8  # nearest-view labels: frames 0, 3, 5, 7
    assert v["unambiguous"]["accuracy"] == 3 / 4  # frames 0, 5, 6, 7: the back frame called right
    assert v["unambiguous"]["per_view_accuracy"]["back"] == 0.0
    assert v["boundary"] == {"tolerance_deg": 5.0, "n": 4, "accuracy_either_neighbour": 3 / 4}  # 45 -> back is wrong
    assert v["tolerant_per_view_accuracy"] == {"front": 3 / 4, "left": 1.0, "right": 1.0, "back": 0.0}
    assert v["tolerant_accuracy"] == 6 / 8


@pytest.mark.slow
def test_model_round_trip_and_its_own_training_frames(trained):
    model, path, samples = trained
    loaded, header = load_model(path)
    assert header["params"] == model.get_params() and header["seed"] == 3
    assert loaded.get_params() == {"n_orient": 8, "cell": 4, "C": 0.05, "neg_per_pos": 6, "hard_rounds": 0,
                                   "viewpoint": "hog", "dt": "envelope", "unary_weight": 2.0,
                                   "hog_C": 0.01, "fg_weight": 2.0, "seed": 3}
    preds = np.stack([loaded.estimate(s.image, i, view=s.view).points for i, s in enumerate(samples)])
    # accuracy is asserted on held-out renders against a mean-pose baseline (test_pose_heldout.py), never
    # on training frames; here: the loaded model is the fitted one
    same = np.stack([model.estimate(s.image, i, view=s.view).points for i, s in enumerate(samples[:3])])
    np.testing.assert_allclose(same, preds[:3], rtol=1e-5, atol=1e-5)  # float32 score noise only


def test_metrics_against_hand_computed_values():
    gt = np.zeros((1, 15, 2))
    gt[0, :, 1] = np.arange(15) * 10.0  # keypoint i at (0, 10 i)
    pred = gt.copy()
    i = KEYPOINTS.index("left_wrist")  # left_forearm: left_elbow (50) -> left_wrist (70), length 20
    pred[0, i, 0] = 9.0
    assert strict_pcp(pred, gt)[0].all()  # 9 <= 0.5 * 20
    pred[0, i, 0] = 11.0
    hits = strict_pcp(pred, gt)
    assert hits[0].sum() == 9 and not hits[0, 4]
    # torso neck (10) - pelvis (20): length 10; PCK threshold 2
    k = pck(pred, gt)
    assert k[0].sum() == 14
    c = confusion(["front", "front", "left"], ["front", "back", "left"])
    assert c["per_view_accuracy"]["front"] == 0.5 and c["per_view_accuracy"]["left"] == 1.0


@pytest.mark.slow
def test_pose_command_ps_and_errors(tmp_path, trained, capsys):
    from typer.testing import CliRunner

    from vidstyle.cli import app, main
    from vidstyle.demo import Performer, build_take, performance_plan
    from vidstyle.render import render_to_file

    _, path, _ = trained
    rng = np.random.default_rng(9)
    p = Performer.random("p09", rng, video_fps=20)
    motion = build_take(p, performance_plan(p, 20, rng), rng, video_fps=20).motion.resample(10)[:6]
    video = tmp_path / "clip.mp4"
    render_to_file(motion, video, view="front", size=(320, 240), fps=10)
    out = tmp_path / "poses.json"
    r = CliRunner().invoke(app, ["pose", str(video), "--model", str(path), "--frames", "4,1", "--out", str(out), "-j", "1"])
    assert r.exit_code == 0, r.output
    doc = json.loads(out.read_text())
    assert [f["frame"] for f in doc["frames"]] == [1, 4] and doc["backend"] == "ps"
    pts = np.array(doc["frames"][0]["points"])
    assert pts.shape == (15, 3) and pts[:, 0].max() > 160  # input-video pixels, not the 160x120 working size
    capsys.readouterr()
    assert main(["pose", str(video), "--model", str(path), "--frames", "99", "--out", str(out)]) == 2
    assert "99" in capsys.readouterr().err
    bad = tmp_path / "bad.joblib"
    bad.write_bytes(b"not a model")
    assert main(["pose", str(video), "--model", str(bad), "--out", str(tmp_path / "x.json")]) == 2
    assert "bad.joblib" in capsys.readouterr().err and not (tmp_path / "x.json").exists()
    # without --model the ps backend runs the model shipped in the package (with none shipped it refuses
    # in one line: tests/test_pose_render_variety.py)
    assert main(["pose", str(video), "--backend", "ps", "--frames", "1", "--out", str(tmp_path / "x.json")]) == 0
    assert json.loads((tmp_path / "x.json").read_text())["backend"] == "ps"
    # multi-scale inference: recorded in the file; each pose is the model's own at scale 1 or a zoom
    ms = tmp_path / "ms.json"
    assert main(["pose", str(video), "--model", str(path), "--frames", "1,4", "--scales", "1.5,0.8", "--out", str(ms),
                 "-j", "1"]) == 0
    from vidstyle.formats.poses import read_poses

    got = read_poses(ms)
    assert got.params == {"scales": [1.0, 1.5, 0.8]}
    from vidstyle.pose.defaults import PS_SCALES

    assert read_poses(out).params == {"scales": list(PS_SCALES)}  # the default zooms, recorded
    one = tmp_path / "one.json"
    assert main(["pose", str(video), "--model", str(path), "--frames", "1,4", "--scales", "1", "--out", str(one),
                 "-j", "1"]) == 0
    single = read_poses(one)
    assert single.params == {}  # one scale: nothing to record
    for a, b in zip(got.frames, single.frames):  # never less confident than the single-scale pose
        assert a.scores.mean() >= b.scores.mean() - 1e-3
    capsys.readouterr()
    for bad in (["--scales", "0"], ["--scales", "1,x"], ["--scales", "1.2", "--backend", "blazepose"]):
        assert main(["pose", str(video), "--model", str(path), "--out", str(tmp_path / "y.json"), *bad]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--scales" in err[0] and not (tmp_path / "y.json").exists()


def test_evaluate_pose_writes_metrics_that_match_its_own_renders(tmp_path, trained, capsys):
    """evaluate pose on a few held-out renders: a vidstyle.metrics.pose file whose true-viewpoint PCP row is
    recomputed here, frame by frame, from the same renders through the model's public estimate()."""
    import copy

    from vidstyle.cli import main
    from vidstyle.formats.metrics import POSE, read_metrics
    from vidstyle.pose.data import make_specs

    model, _, _ = trained
    model = copy.deepcopy(model)
    model.fg_weight = 0.0  # single-image estimates: no person prior from the clips' backgrounds
    path = tmp_path / "pose_noprior.joblib"
    save_model(path, model)
    out = tmp_path / "pose_metrics.json"
    args = ["evaluate", "pose", "--model", str(path), "--out", str(out), "--demo-performers", "1", "--cmu-clips", "0",
            "--views-per-clip", "2", "--seconds", "1", "--fps", "3", "--real-dir", "none", "--seed", "5", "-j", "1"]
    assert main(args) == 0
    m = read_metrics(out, POSE)
    assert m.seed == 5 and m.doc["params"]["seed"] == 5
    # no --cmu-dir (nor VIDSTYLE_CMU_DIR): the command renders the demo performers only
    samples = render_samples(make_specs("test", 1, 0, 2, 5, None, fps=3.0, seconds=1.0), jobs=1, keep_bgr=True)
    assert m.doc["n_frames"] == len(samples) > 0
    pred = np.stack([model.estimate(s.image, view=s.view).points for s in samples])  # gray = the colour render read as gray
    hits = strict_pcp(pred, np.stack([s.keypoints for s in samples]))
    assert m.doc["pcp"]["ps_oracle_view"]["all"]["mean"] == pytest.approx(float(hits.mean()))
    views = [s.view for s in samples]
    assert m.doc["viewpoint"]["blazepose"]["counts"] and sum(map(sum, m.doc["viewpoint"]["hog"]["counts"])) == len(views)
    assert "PCP" in capsys.readouterr().out  # the tables go to stdout
