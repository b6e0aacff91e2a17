"""``vidstyle synthesize --keyframes`` on real CMU clips: the motion passes through every keyframe's pose
(joint rotations, root height) at its time for each method; bad keyframes files exit 2 with one line and
no output file. Skips without ../shared/data/mocap/cmu."""

from __future__ import annotations

import json

import numpy as np
import pytest

from vidstyle.cli import main
from vidstyle.inbetween.poses import headings
from vidstyle.mocap import read_bvh
from vidstyle.mocap.placement import yaw_quat
from vidstyle.mocap.quat import qmul
from vidstyle.mocap.retarget import retarget
from vidstyle.motiongraph import MotionGraph

CLIPS = ["02_01.bvh", "07_01.bvh"]


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    from conftest import CMU_DIR

    if not CMU_DIR.is_dir():
        pytest.skip("../shared/data/mocap/cmu is absent")
    tmp = tmp_path_factory.mktemp("kf")
    out = tmp / "graph.npz"
    assert main(["build-graph", *[str(CMU_DIR / f) for f in CLIPS], "--out", str(out)]) == 0
    keys = {"keyframes": [{"clip": str(CMU_DIR / "02_01.bvh"), "frame": 40, "time": 0.0},
                          {"clip": str(CMU_DIR / "07_01.bvh"), "frame": 200, "time": 1.0},
                          {"clip": str(CMU_DIR / "02_01.bvh"), "frame": 250, "time": 2.5}]}
    kf = tmp / "keys.json"
    kf.write_text(json.dumps(keys))
    return tmp, out, kf, keys


def _without_heading(q):
    return qmul(yaw_quat(-headings(q[None]))[0], q)


@pytest.mark.parametrize("method", ["markov", "graph", "slerp"])
def test_output_passes_through_every_keyframe(built, method):
    tmp, graph, kf, keys = built
    bvh = tmp / f"{method}.bvh"
    assert main(["synthesize", "--graph", str(graph), "--keyframes", str(kf), "--method", method, "--out", str(bvh)]) == 0
    m = read_bvh(bvh)
    assert m.fps == 30 and m.n_frames == 76  # keyframes at output frames 0, 30, 75
    skeleton = MotionGraph.load(graph).skeleton_
    for k, at in zip(keys["keyframes"], (0, 30, 75)):
        src, _ = retarget(read_bvh(k["clip"]), skeleton)  # the pose on the graph's skeleton (root scaled by leg length)
        q_out, q_src = m.rotations[at], src.rotations[k["frame"]]
        # every joint but the root: the keyframe's local rotation (BVH text precision)
        assert np.allclose(np.abs(np.sum(q_out[1:] * q_src[1:], -1)), 1.0, atol=1e-6)
        # the root: its tilt and roll (heading and floor position are free after the first keyframe)
        assert abs(np.sum(_without_heading(q_out[0]) * _without_heading(q_src[0]))) == pytest.approx(1.0, abs=1e-6)
        assert m.root_positions[at, 1] == pytest.approx(src.root_positions[k["frame"], 1], abs=1e-4)
    first = read_bvh(keys["keyframes"][0]["clip"])
    assert np.allclose(m.root_positions[0], first.root_positions[40], atol=1e-4)  # the first keeps its placement
    assert np.isfinite(m.rotations).all()


@pytest.mark.parametrize("case", ["not json", "one keyframe", "frame past the end", "missing clip", "time order",
                                  "both modes", "bad method", "method with a sequence"])
def test_bad_keyframes_exit_2_with_one_line_and_no_output(built, case, capsys):
    tmp, graph, kf, keys = built
    bad = tmp / f"bad_{case.replace(' ', '_')}.json"
    doc = json.loads(json.dumps(keys))
    extra: list[str] = []
    if case == "not json":
        bad.write_text('{"keyframes": [')
    else:
        if case == "one keyframe":
            doc["keyframes"] = doc["keyframes"][:1]
        elif case == "frame past the end":
            doc["keyframes"][1]["frame"] = 10**6
        elif case == "missing clip":
            doc["keyframes"][1]["clip"] = str(tmp / "nope.bvh")
        elif case == "time order":
            doc["keyframes"][2]["time"] = 0.5
        elif case == "both modes":
            extra = ["--sequence", str(kf)]
        elif case == "bad method":
            extra = ["--method", "spline"]
        bad.write_text(json.dumps(doc))
    out = tmp / f"out_{case.replace(' ', '_')}.bvh"
    args = ["synthesize", "--graph", str(graph), "--keyframes", str(bad), "--out", str(out), *extra]
    if case == "method with a sequence":
        args = ["synthesize", "--graph", str(graph), "--sequence", str(bad), "--method", "slerp", "--out", str(out)]
    capsys.readouterr()
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert not out.exists() and not list(tmp.glob(f".out_{case.replace(' ', '_')}*"))
    if case in ("frame past the end", "one keyframe", "time order", "not json"):
        assert str(bad) in err
