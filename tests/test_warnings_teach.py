"""Warnings that teach (issue 32, item 3): too little data for the model being fitted says how much is
needed and how much was given; classes the mocap library lacks are named before the graph is built;
synthesis steps that cannot be realised say why and what to do. All through `logging` (stderr)."""

from __future__ import annotations

import numpy as np
import pytest
from test_motiongraph_graph import _clips, _gait

from vidstyle.errors import InputError
from vidstyle.formats.labels import FrameLabels
from vidstyle.motiongraph import Clip, MotionGraph, Step, plan_walk
from vidstyle.motiongraph.pipeline import check_classes, warn_unwalkable
from vidstyle.recognition.recognizer import warn_few_frames
from vidstyle.style.artifact import Style, warn_few_events
from vidstyle.style.learn import style_params


def _warnings(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]


# ------------------------------------------------------------------------------------------ style
def _track(actions, frames_each=10):
    classes = ("stand", "lunge", "turn")
    return FrameLabels([a for a in actions for _ in range(frames_each)], classes, 20.0, path="t.json")


def test_learn_style_from_three_events_says_what_it_needs(caplog):
    """The issue's case: a few events of one short take fitted without a word. Now both models say how
    many transitions / events they need and how many they got."""
    with caplog.at_level("WARNING", logger="vidstyle.style"):
        style = Style.from_tracks([_track(["stand", "lunge", "turn"])], style_params(ignore=""))
    msgs = _warnings(caplog)
    assert any("only 2 action-to-action transitions (3 events in 1 label file(s)) for 3 actions" in m
               and "needs at least 9 transitions" in m for m in msgs), msgs
    if style.model_b.n_modes_ > 1:
        assert any(f"took {style.model_b.n_modes_} behaviour modes from only 3 events" in m for m in msgs), msgs


def test_enough_events_fit_without_a_warning(caplog):
    rng = np.random.default_rng(0)
    seqs = [rng.integers(0, 3, 40) for _ in range(5)]
    with caplog.at_level("WARNING", logger="vidstyle.style"):
        assert warn_few_events(seqs, 3, 1) == []
    assert not _warnings(caplog)


def test_model_b_modes_beyond_the_events_are_named():
    seqs = [np.array([0, 1, 2, 0, 1, 2, 0, 1, 2, 0])]  # 10 events, 9 transitions: model (a) has enough
    [msg] = warn_few_events(seqs, 3, 4)  # 4 modes over 3 actions: 3 + 12 + 8 = 23 free parameters
    assert "took 4 behaviour modes from only 10 events" in msg and "need at least 23 events" in msg


# ------------------------------------------------------------------------------------------ recognizer
def test_thin_classes_are_named_with_their_frames_and_the_need(caplog):
    labels = [["stand"] * 28 + ["lunge"] * 150, ["turn"] * 48]
    with caplog.at_level("WARNING", logger="vidstyle.recognition"):
        few = warn_few_frames(labels, ["stand", "lunge", "turn"], fps=20.0)
    assert few == {"stand": 28, "turn": 48}
    msgs = _warnings(caplog)
    assert len(msgs) == 2
    assert "class 'stand' has only 28 labelled training frames (1.4 s at 20 fps)" in msgs[0]
    assert "needs about 100 per class (5 s)" in msgs[0]


# ------------------------------------------------------------------------------------------ library
def test_missing_library_classes_are_refused_before_the_build():
    clips = _clips()  # walk and run only
    with pytest.raises(InputError, match=r"^require_classes: the library has no frames labelled 'lunge', "
                                         r"'turn' \(it has run, walk\)"):
        check_classes(clips, ["walk", "lunge", "turn"])
    check_classes(clips, ["walk", "run"])  # present: nothing said
    check_classes(clips, [""])  # nothing required


def test_a_class_shorter_than_a_blend_window_is_warned(caplog):
    clips = _clips() + [Clip("hop", _gait(20, 1.0, 30, 4.0), ["walk"] * 16 + ["hop"] * 4)]
    with caplog.at_level("WARNING", logger="vidstyle.motiongraph"):
        check_classes(clips, ["walk", "hop"], fps=30, window=10)
    [msg] = _warnings(caplog)
    assert "only 0.13 s of 'hop' (4 frames at 30 fps)" in msg and "10 frames" in msg


def test_build_graph_cli_refuses_a_library_without_the_required_class(tmp_path, capsys):
    from vidstyle.cli import main
    from vidstyle.mocap import write_bvh

    clip = tmp_path / "a.bvh"
    write_bvh(_gait(60, 1.0, 30, 4.0), clip)
    csv = tmp_path / "labels.csv"
    csv.write_text("file,label\na.bvh,walk\n")
    out = tmp_path / "g.npz"
    assert main(["build-graph", str(clip), "--labels", str(csv), "--require-classes", "walk,lunge",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--require-classes: the library has no frames labelled 'lunge' (it has walk)" in err
    assert "file,label[,start,end]" in err and not out.exists()


def test_actions_lost_to_pruning_are_warned(caplog):
    clips = _clips() + [Clip("spin", _gait(40, 3.0, 80, 0.0), ["spin"] * 40)]  # unlike the rest: no transitions
    graph = MotionGraph(window=6, fps=30, threshold_quantile=0.02, random_state=0).fit(clips)
    names = graph.label_names_
    walkable = {names[i] for i in np.unique(graph.labels_[graph.scc_])}
    with caplog.at_level("WARNING", logger="vidstyle.motiongraph"):
        lost = warn_unwalkable(graph)
    assert "spin" in lost and lost == sorted({"walk", "run", "spin"} - walkable)
    [msg] = _warnings(caplog)
    assert "'spin'" in msg and "synthesize cannot perform" in msg and "raise --quantile" in msg


# ------------------------------------------------------------------------------------------ synthesize
@pytest.fixture(scope="module")
def graph():
    return MotionGraph(window=6, fps=30, threshold_quantile=0.1, random_state=0).fit(_clips())


def test_every_missing_action_is_named_up_front(graph):
    steps = [Step("walk", 10), Step("jump", 10), Step("run", 10), Step("lunge", 10), Step("jump", 10)]
    with pytest.raises(InputError) as err:
        plan_walk(graph, steps)
    msg = str(err.value)
    assert msg.startswith("steps: step 1 ('jump', after 'walk'): the graph cannot perform 'jump' (steps 1, 4); "
                          "'lunge' (step 3)")
    assert "build-graph --labels" in msg and "--require-classes" in msg and "It can perform run, walk" in msg


def test_steps_not_shown_say_why_and_what_helps(graph, caplog):
    steps = [Step("walk", 20), Step("run", 2), Step("walk", 20)]  # 2 frames of run: shorter than any blend
    with caplog.at_level("WARNING", logger="vidstyle.motiongraph"):
        plan_walk(graph, steps, strict=False)  # the CLI's default (--lenient)
    msgs = _warnings(caplog)
    step = [m for m in msgs if m.startswith("step 1 ('run', 2 frames = 0.07 s, after 'walk')")]
    assert step, msgs
    assert "Longer steps (synthesize --seconds" in step[0] and "--strict" in step[0]
    assert any(m.startswith("1 of 3 steps are mostly not shown") for m in msgs), msgs


# ------------------------------------------------------------------------------------------ augment
def test_augment_leaves_out_marks_of_videos_without_poses_with_a_warning(tmp_path, graph, caplog):
    """A pipeline poses the videos it names; the marks of the other annotated videos are left out, saying
    which and how to use them (before: the command failed on the first such mark)."""
    from vidstyle.augmg import augment
    from vidstyle.formats.annotations import Annotations, Transition, VideoAnnotations, write_annotations
    from vidstyle.formats.poses import PoseFrame, Poses, write_poses

    ann = tmp_path / "ann.json"
    write_annotations(ann, Annotations(["run", "walk"], [
        VideoAnnotations("v.mp4", "0" * 64, 100, 20.0, [Transition(10, "walk", "run", "discarded")]),
        VideoAnnotations("w.mp4", "1" * 64, 100, 20.0, [Transition(12, "walk", "run", "accepted")])]))
    poses = tmp_path / "v.poses.json"
    pts = np.column_stack([np.arange(15.0), np.arange(15.0), np.ones(15)])
    write_poses(poses, Poses("v.mp4", "blazepose", [PoseFrame(10, "front", pts)]))
    with caplog.at_level("WARNING", logger="vidstyle.augmg"):
        _g, inserted = augment(graph, ann, [tmp_path], poses=[poses], context=0)
    assert inserted == []  # v's only mark is discarded: the plain graph stays
    [msg] = _warnings(caplog)
    assert msg.startswith("the transition marks of w are left out: no poses of it were given")
    assert "--annotations" in msg and "--poses" in msg
