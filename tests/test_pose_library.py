"""The pose library owns its entry points and checks (issue 26): the library called with defaults gives the
CLI's poses, every parameter check raises ParameterError from the library and exits 2 naming the flag from
the CLI (before any output is written), the pose package finds its training sources through a registry the
demo fills, and backends / detectors / viewpoint classifiers are chosen through one interface each."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import vidstyle.demo  # noqa: F401 - registers the "demo" training source (demo:<i> specs)
from vidstyle.cli import main
from vidstyle.errors import InputError, ParameterError
from vidstyle.pose.data import Spec, load_source, register_source, render_samples, source_loader
from vidstyle.pose.estimator import VIEWPOINT_CLASSIFIERS, PoseModel, save_model
from vidstyle.pose.interfaces import PoseBackend, ViewpointClassifier, backend_factory, detector_class
from vidstyle.pose.training import make_model


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """A tiny hog pose model file and a 6-frame 320x240 video of another demo performer."""
    from vidstyle.demo import Performer, build_take, performance_plan
    from vidstyle.render import render_to_file

    specs = [Spec("demo:0", 1.0 + i, 2.0, az + 4 * i, 10.0, 100 + i, fps=3.0)
             for i, az in enumerate((0.0, 90.0, -90.0, 180.0, 0.0, 90.0, -90.0, 180.0))]
    model = PoseModel(n_orient=8, hard_rounds=0, neg_per_pos=6, seed=3).fit(render_samples(specs, jobs=1), jobs=1)
    d = tmp_path_factory.mktemp("pose_lib")
    save_model(d / "pose.joblib", model)
    rng = np.random.default_rng(9)
    p = Performer.random("p09", rng, video_fps=20)
    motion = build_take(p, performance_plan(p, 20, rng), rng, video_fps=20).motion.resample(10)[:6]
    render_to_file(motion, d / "clip.mp4", view="front", size=(320, 240), fps=10)
    return model, d / "pose.joblib", d / "clip.mp4"


@pytest.mark.slow
def test_library_with_defaults_gives_the_cli_poses(tmp_path, tiny):
    from vidstyle.pose import estimate_video

    model, path, video = tiny
    out = tmp_path / "poses.json"
    assert main(["pose", str(video), "--model", str(path), "--out", str(out), "-j", "1"]) == 0
    lib = estimate_video(video, model_path=path, jobs=1)  # every other setting: the library's default
    from vidstyle.formats.poses import write_poses

    write_poses(tmp_path / "lib.json", lib)
    assert (tmp_path / "lib.json").read_bytes() == out.read_bytes()  # the same file, byte for byte
    from vidstyle.pose.defaults import PS_SCALES

    # the zooms used are recorded: by default the validated ones
    assert lib.backend == "ps" and lib.params == {"scales": list(PS_SCALES)} and [f.frame for f in lib.frames] == list(range(6))
    # and both are the model's own estimate of each frame, mapped from the 120-row working size to 240 rows
    from vidstyle.pose.run import video_background
    from vidstyle.video import VideoReader

    with VideoReader(video, height=120) as r:
        bg = video_background(r)
        pf = model.estimate(np.asarray(r.frame(3)), 3, background=bg)
    np.testing.assert_allclose(lib.frames[3].points[:, :2], (pf.points[:, :2] + 0.5) * 2.0 - 0.5, atol=1e-9)
    assert lib.frames[3].viewpoint == pf.viewpoint


@pytest.mark.slow
def test_estimate_marks_gives_the_cli_poses_of_the_marks(tmp_path, tiny):
    """pose --annotations: the marks' frames and their context, inside the video, as the library's."""
    from vidstyle.formats.annotations import (
        Annotations,
        Transition,
        VideoAnnotations,
        file_sha256,
        stored_path,
        write_annotations,
    )
    from vidstyle.formats.poses import read_poses, write_poses
    from vidstyle.pose import estimate_marks, mark_frames

    _model, path, video = tiny
    ann = tmp_path / "ann.json"
    entry = VideoAnnotations(stored_path(ann, video), file_sha256(video), 6, 10.0,
                             [Transition(0, "Jab", "Hook"), Transition(4, "Hook", "Jab")])
    write_annotations(ann, Annotations(["Jab", "Hook"], [entry]))
    assert mark_frames(video, ann) == [0, 4] and mark_frames(video, ann, context=1) == [0, 1, 3, 4, 5]
    out = tmp_path / "marks.json"
    assert main(["pose", str(video), "--model", str(path), "--annotations", str(ann), "--context", "1",
                 "--out", str(out), "-j", "1"]) == 0
    lib = estimate_marks(video, ann, model_path=path, context=1, jobs=1)
    write_poses(tmp_path / "lib.json", lib)
    assert (tmp_path / "lib.json").read_bytes() == out.read_bytes()
    assert [f.frame for f in read_poses(out).frames] == [0, 1, 3, 4, 5]


# (library parameter, bad value, CLI flag): the twelve checks train-pose did itself, now the models' own
TRAIN_CHECKS = [
    ({"detector": "sift"}, "detector", "--detector", "sift"),
    ({"detector": "cnn", "epochs": 0}, "epochs", "--epochs", "0"),
    ({"detector": "cnn", "channels": 4}, "channels", "--channels", "4"),
    ({"detector": "cnn", "stride": 3}, "stride", "--heatmap-stride", "3"),
    ({"detector": "cnn", "augment": "blur"}, "augment", "--augment", "blur"),
    ({"detector": "hog", "viewpoint": "oracle"}, "viewpoint", "--viewpoint", "oracle"),
    ({"detector": "hog", "unary_weight": 0.0}, "unary_weight", "--unary-weight", "0"),
    ({"detector": "cnn", "unary_weight": -1.0}, "unary_weight", "--unary-weight", "-1"),
    ({"detector": "cnn", "refine": -1}, "refine", "--refine", "-1"),
    ({"detector": "hog", "fg_weight": -0.5}, "fg_weight", "--fg-weight", "-0.5"),
    ({"detector": "hog", "hard_rounds": 2}, "hard_rounds", "--hard-rounds", "2"),
    ({"detector": "hog", "n_orient": 3}, "n_orient", "--orientations", "3"),
    ({"detector": "cnn", "n_orient": 40}, "n_orient", "--orientations", "40"),
]


@pytest.mark.parametrize("kwargs,param,flag,value", TRAIN_CHECKS)
def test_train_checks_raise_from_the_library_and_name_the_flag_in_the_cli(tmp_path, capsys, kwargs, param, flag,
                                                                          value):
    with pytest.raises(ParameterError) as e:
        make_model(**kwargs)
    assert e.value.param == param
    if param != "detector":  # the estimators check in fit too (scikit-learn style), before any work
        cls = detector_class(kwargs["detector"])
        with pytest.raises(ParameterError) as e2:
            cls(**{k: v for k, v in kwargs.items() if k != "detector"}).fit([])
        assert e2.value.param == param
    out = tmp_path / "m.joblib"
    argv = ["train-pose", "--out", str(out), "--demo-performers", "1", "--views-per-clip", "4", "-j", "1",
            "--detector", kwargs["detector"], flag, value] if param != "detector" else \
        ["train-pose", "--out", str(out), "--detector", value]
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"vidstyle: error: {flag}: "), err
    assert not out.exists()


def test_training_set_checks_name_their_flags(tmp_path, capsys):
    from vidstyle.pose.data import MAX_PERFORMERS
    from vidstyle.pose.training import train

    with pytest.raises(ParameterError) as e:
        train(demo_performers=MAX_PERFORMERS["train"] + 1)
    assert e.value.param == "demo_performers"
    with pytest.raises(InputError, match="nowhere"):
        train(cmu_dir=tmp_path / "nowhere", demo_performers=1)
    assert main(["train-pose", "--out", str(tmp_path / "m.joblib"), "--cmu-clips", "-1"]) == 2
    assert capsys.readouterr().err.startswith("vidstyle: error: --cmu-clips: ")


def test_no_cmu_dir_is_stated_and_the_env_var_is_the_option(tmp_path, caplog, monkeypatch):
    import logging

    from vidstyle.pose.training import resolve_cmu_dir

    with caplog.at_level(logging.INFO, logger="vidstyle.pose.training"):
        assert resolve_cmu_dir(None, 5) is None
    assert "no CMU directory" in caplog.text
    monkeypatch.setenv("VIDSTYLE_CMU_DIR", str(tmp_path / "absent"))
    assert main(["train-pose", "--out", str(tmp_path / "m.joblib"), "--demo-performers", "1"]) == 2  # env var read


def test_pose_checks_raise_from_the_library_and_name_the_flag_in_the_cli(tmp_path, capsys, tiny):
    from vidstyle.pose import estimate_marks, estimate_video

    _model, path, video = tiny
    for call, param in ((lambda: estimate_video(video, "openpose", path), "backend"),
                        (lambda: estimate_video(video, "blazepose", None, scales=[1.2]), "scales"),
                        (lambda: estimate_video(video, "ps", path, scales=[9.0]), "scales"),
                        (lambda: estimate_marks(video, tmp_path / "ann.json", "ps", path, context=-1), "context")):
        with pytest.raises(ParameterError) as e:
            call()
        assert e.value.param == param
    out = tmp_path / "p.json"
    for extra, flag in ((["--backend", "openpose"], "--backend"), (["--model", str(path), "--frames", "6"], "--frames"),
                        (["--model", str(path), "--annotations", str(tmp_path / "a.json"), "--context", "-1"],
                         "--context")):
        capsys.readouterr()
        assert main(["pose", str(video), "--out", str(out), *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"vidstyle: error: {flag}: "), err
        assert not out.exists()


def test_training_sources_come_from_the_registry():
    from vidstyle.demo.pose_sources import demo_motion

    assert source_loader("demo:4") is demo_motion and source_loader("/data/01_01.bvh") is None
    with pytest.raises(InputError, match="'nosuch'"):
        load_source("nosuch:3")
    register_source("twice", demo_motion)  # a registered name renders like the demo's own
    a, b = load_source("twice:2", seconds=2.0), load_source("demo:2", seconds=2.0)
    np.testing.assert_array_equal(a.rotations, b.rotations)
    with pytest.raises(ValueError):
        register_source("a:b", demo_motion)


def test_pose_never_imports_the_demo():
    code = ("import sys, vidstyle.pose.data, vidstyle.pose.run, vidstyle.pose.estimator, vidstyle.pose.training; "
            "print(sorted(m for m in sys.modules if m.startswith('vidstyle.demo') or m.startswith('vidstyle.evaluation')))")
    got = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert got == "[]"


def test_one_interface_per_varying_thing(tiny):
    from vidstyle.pose.blazepose import BlazePoseEstimator
    from vidstyle.pose.cnn import CnnPoseModel

    model, path, _ = tiny
    assert isinstance(model, PoseBackend) and isinstance(BlazePoseEstimator(), PoseBackend)
    assert isinstance(backend_factory("ps")(str(path)), PoseModel)
    assert isinstance(backend_factory("blazepose")(None), BlazePoseEstimator)
    assert detector_class("hog") is PoseModel and detector_class("cnn") is CnnPoseModel
    assert model.uses_background and not CnnPoseModel().uses_background
    for name, get in VIEWPOINT_CLASSIFIERS.items():  # each reads its own input from the frame's features
        clf = get(model)
        assert isinstance(clf, ViewpointClassifier), name
        f, _s = model.prepare(np.zeros((120, 160), np.uint8))
        feats, _maps = model.view_features(f, full=True)
        view, scores = model.classify_view(feats, name)
        assert view == str(clf.predict(clf.input_of(feats))[0]) and abs(sum(scores.values()) - 1.0) < 1e-3


def test_cli_defaults_are_the_library_defaults():
    """Every option of train-pose and pose defaults to what the library function (or the model it builds)
    defaults to, so a Python user calling the library with defaults trains and estimates as the CLI does."""
    import inspect

    from vidstyle.commands.pose import pose, train_pose
    from vidstyle.pose.cnn import CnnPoseModel
    from vidstyle.pose.run import estimate_marks, estimate_video
    from vidstyle.pose.training import train

    def defaults(fn):
        return {k: p.default for k, p in inspect.signature(fn).parameters.items()
                if p.default is not inspect.Parameter.empty}

    def cli_defaults(fn):
        return {k: getattr(v, "default", v) for k, v in defaults(fn).items()}

    lib = {**defaults(CnnPoseModel.__init__), **defaults(PoseModel.__init__), **defaults(train)}
    lib["unary_weight"] = None  # each detector's own validated default (the models' constructors)
    cli = cli_defaults(train_pose)
    cli.pop("out")
    assert cli.pop("cmu_dir") is None and defaults(train)["cmu_dir"] is None  # no silent CMU folder
    assert cli.pop("scheduler") is None
    # ranges are text options (LOW,HIGH) that default to the library's ranges
    from vidstyle.commands.pose import _render_options

    assert cli.pop("elevations") is None and cli.pop("figure_scales") is None
    ranges = _render_options(None, None)
    assert ranges == {"elevation": defaults(train)["elevation"], "scale": defaults(train)["scale"]}
    for k, v in cli.items():
        assert lib[k] == v, k
    assert cli["detector"] == "cnn" and defaults(CnnPoseModel.__init__)["unary_weight"] != defaults(PoseModel.__init__)[
        "unary_weight"]
    got = cli_defaults(pose)
    lib_pose = {**defaults(estimate_video), **defaults(estimate_marks)}
    for k in ("backend", "context", "jobs", "scheduler"):
        assert got[k] == lib_pose[k], k
    assert got["scales"] is None and lib_pose["scales"] is None and got["model"] is None


def test_several_videos_with_out_dir_give_each_video_s_own_run(tmp_path, tiny):
    """vidstyle pose A B --out-dir D (the pipeline's pose_marks: one process per backend for all videos)
    writes D/<video stem>.poses.json byte-identical to a run per video with --out; a mix that cannot be
    written is refused before any work."""
    import shutil

    _, path, video = tiny
    videos = []
    for name in ("a", "b"):
        videos.append(tmp_path / f"{name}.mp4")
        shutil.copy(video, videos[-1])
    opts = ["--model", str(path), "-j", "1"]
    out_dir = tmp_path / "poses"
    assert main(["pose", str(videos[0]), "--frames", "0,3", *opts, "--out", str(tmp_path / "a1.json")]) == 0
    assert main(["pose", str(videos[1]), "--frames", "0,3", *opts, "--out", str(tmp_path / "b1.json")]) == 0
    assert main(["pose", *map(str, videos), "--frames", "0,3", *opts, "--out-dir", str(out_dir)]) == 0
    assert sorted(p.name for p in out_dir.iterdir()) == ["a.poses.json", "b.poses.json"]
    assert (out_dir / "a.poses.json").read_bytes() == (tmp_path / "a1.json").read_bytes()
    assert (out_dir / "b.poses.json").read_bytes() == (tmp_path / "b1.json").read_bytes()
    bad = tmp_path / "bad"
    assert main(["pose", *map(str, videos), *opts, "--out", str(bad / "x.json")]) == 2
    assert main(["pose", str(videos[0]), *opts]) == 2  # neither --out nor --out-dir
    assert main(["pose", *map(str, videos), *opts, "--out-dir", str(bad), "--overlay", str(bad / "o")]) == 2
    assert not bad.exists()
