"""``vidstyle build-graph``, ``synthesize`` and ``evaluate motion`` on real CMU clips."""

from __future__ import annotations

import json

import numpy as np
import pytest

from vidstyle.cli import main
from vidstyle.mocap import read_bvh
from vidstyle.motiongraph import MotionGraph

WALKS = ["02_01.bvh", "02_02.bvh", "05_01.bvh", "07_01.bvh", "08_01.bvh"]
SLOW = ["07_04.bvh", "08_04.bvh"]  # "slow walk": walk by the CMU keyword table, "slow" by our override CSV


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    from conftest import CMU_DIR

    if not CMU_DIR.is_dir():
        pytest.skip("../shared/data/mocap/cmu is absent")
    tmp = tmp_path_factory.mktemp("mg")
    files = [str(CMU_DIR / f) for f in WALKS + SLOW]
    out = tmp / "graph.npz"
    override = tmp / "slow.csv"
    override.write_text("file,label\n" + "".join(f"{f},slow\n" for f in SLOW))
    assert main(["build-graph", *files, "--labels", str(CMU_DIR / "clips.csv"), "--labels", str(override), "--out", str(out), "--mirror"]) == 0
    return tmp, out


def test_build_graph_from_cmu(built):
    _, out = built
    g = MotionGraph.load(out)
    assert set(g.label_names_) == {"walk", "slow"}
    assert g.fps == 30 and g.clips_["first"] == [1] * 14  # CMU T-pose frames dropped
    assert g.stats_["transitions_in_scc"] > 100
    lab = g.labels_[g.scc_]
    assert {g.label_names_[i] for i in np.unique(lab)} == {"walk", "slow"}
    assert g.clips_["frames"][0] == pytest.approx((344 - 2) / 4 + 1, abs=1)  # 120 -> 30 fps


def test_synthesize_writes_bvh_labels_and_realises_the_sequence(built):
    tmp, out = built
    seq = tmp / "seq.json"
    seq.write_text(json.dumps({"classes": ["walk", "slow"], "fps": 20,
                               "sequence": [{"action": 0, "frames": 40}, {"action": 1, "frames": 30}, {"action": "walk", "frames": 40}]}))
    bvh = tmp / "motion.bvh"
    assert main(["synthesize", "--graph", str(out), "--sequence", str(seq), "--out", str(bvh)]) == 0
    m = read_bvh(bvh)
    assert m.n_frames == 60 + 45 + 60 and m.fps == 30 and m.n_joints == 31
    doc = json.loads((tmp / "motion.labels.json").read_text())
    assert len(doc["labels"]) == m.n_frames and doc["labels"][0] == "walk" and doc["labels"][70] == "slow"
    fid = np.mean([a == b for a, b in zip(doc["labels"], doc["source_labels"])])
    assert fid > 0.8
    metrics = tmp / "m.json"
    assert main(["evaluate", "motion", "--graph", str(out), str(bvh), "--out", str(metrics)]) == 0
    res = json.loads(metrics.read_text())
    assert res["summary"]["label_fidelity"] == pytest.approx(fid)
    assert res["summary"]["transitions_used"] == len(doc["transitions_used"])
    assert doc["kind"] == "vidstyle.labels" and doc["bvh"] == "motion.bvh"  # a labels file build-graph reads too
    from vidstyle.motiongraph.labels import LabelBook

    assert LabelBook().load(tmp / "motion.labels.json").specs  # (as the labels of its BVH)


def test_evaluate_motion_refuses_labels_that_do_not_fit_the_bvh(built, capsys):
    tmp, out = built
    seq = tmp / "seq2.json"
    seq.write_text(json.dumps({"classes": ["walk"], "fps": 20, "sequence": [{"action": 0, "frames": 40}]}))
    bvh = tmp / "m2.bvh"
    assert main(["synthesize", "--graph", str(out), "--sequence", str(seq), "--out", str(bvh)]) == 0
    capsys.readouterr()
    lab = tmp / "m2.labels.json"
    doc = json.loads(lab.read_text())
    doc["transition"] = doc["transition"][:-1]
    lab.write_text(json.dumps(doc))
    metrics = tmp / "m2.json"
    assert main(["evaluate", "motion", "--graph", str(out), str(bvh), "--out", str(metrics)]) == 2
    err = capsys.readouterr().err
    assert str(lab) in err and "transition" in err and err.count("\n") == 1 and not metrics.exists()
    lab.unlink()
    assert main(["evaluate", "motion", "--graph", str(out), str(bvh), "--out", str(metrics)]) == 2
    assert str(lab) in capsys.readouterr().err and not metrics.exists()


def test_unknown_action_is_a_one_line_error(built, capsys):
    tmp, out = built
    seq = tmp / "bad.json"
    seq.write_text(json.dumps(["walk", "dance"]))
    assert main(["synthesize", "--graph", str(out), "--sequence", str(seq), "--out", str(tmp / "bad.bvh")]) == 2
    err = capsys.readouterr().err
    assert "step 1 ('dance'" in err and err.count("\n") == 1
    assert not (tmp / "bad.bvh").exists()


def test_evaluate_random_walks(built):
    tmp, out = built
    metrics = tmp / "r.json"
    assert main(["evaluate", "motion", "--graph", str(out), "--walks", "2", "--steps", "4", "--out", str(metrics)]) == 0
    s = json.loads(metrics.read_text())["summary"]
    assert s["walks"] == 2 and 0.5 < s["label_fidelity"] <= 1.0
    assert s["velocity_jump"]["original_median"] > 0


def test_preview_uses_the_renderer(built):
    import vidstyle.render  # noqa: F401
    tmp, out = built
    seq = tmp / "short.json"
    seq.write_text(json.dumps([{"action": "walk", "frames": 15}]))
    video = tmp / "p.mp4"
    assert main(["synthesize", "--graph", str(out), "--sequence", str(seq), "--out", str(tmp / "p.bvh"), "--preview", str(video)]) == 0
    assert video.is_file() and video.stat().st_size > 0


def test_bad_clip_path(tmp_path, capsys):
    assert main(["build-graph", str(tmp_path / "nope.bvh"), "--out", str(tmp_path / "g.npz")]) == 2
    assert "nope.bvh" in capsys.readouterr().err
