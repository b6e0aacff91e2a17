"""``vidstyle mocap`` commands, including one-line errors and no half-written outputs."""

from __future__ import annotations

import json

import numpy as np
from bvh_samples import TWO_JOINT

from vidstyle.cli import main
from vidstyle.mocap import end_site_positions, global_positions, parse_bvh, read_bvh


def test_info_json(tmp_path, capsys):
    p = tmp_path / "a.bvh"
    p.write_text(TWO_JOINT)
    assert main(["mocap", "info", str(p), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["joints"] == 4 and info["frames"] == 3 and info["fps"] == 30.0
    assert info["duration_s"] == 2 / 30
    m = parse_bvh(TWO_JOINT)
    pts = np.concatenate([global_positions(m), end_site_positions(m)[1]], axis=1).reshape(-1, 3)
    assert np.allclose(info["bbox_min"], pts.min(0), atol=1e-4) and np.allclose(info["bbox_max"], pts.max(0), atol=1e-4)
    assert info["bbox_max"][1] >= 13.0 and info["bbox_min"][1] <= 6.0  # chest and leg End Sites at rest


def test_positions_npy_and_csv(tmp_path):
    p = tmp_path / "a.bvh"
    p.write_text(TWO_JOINT)
    ref = global_positions(parse_bvh(TWO_JOINT))
    assert main(["mocap", "positions", str(p), "--out", str(tmp_path / "pos.npy")]) == 0
    assert np.allclose(np.load(tmp_path / "pos.npy"), ref)
    assert main(["mocap", "positions", str(p), "--out", str(tmp_path / "pos.csv")]) == 0
    lines = (tmp_path / "pos.csv").read_text().splitlines()
    assert lines[0].split(",")[:4] == ["Hips_x", "Hips_y", "Hips_z", "Chest_x"]
    assert np.allclose(np.loadtxt(tmp_path / "pos.csv", delimiter=",", skiprows=1).reshape(3, 4, 3), ref, atol=1e-6)


def test_convert_mirror_and_fps(tmp_path):
    p = tmp_path / "a.bvh"
    p.write_text(TWO_JOINT)
    out = tmp_path / "b.bvh"
    assert main(["mocap", "convert", str(p), str(out), "--fps", "60", "--mirror"]) == 0
    m = read_bvh(out)
    assert m.fps == 60.0 and m.n_frames == 5
    orig = global_positions(parse_bvh(TWO_JOINT))
    got = global_positions(m)
    swap = [0, 1, 3, 2]
    assert np.allclose(got[::2], orig[:, swap] * [-1, 1, 1], atol=1e-5)


def test_errors_are_one_line_and_leave_no_output(tmp_path, capsys):
    bad = tmp_path / "bad.bvh"
    bad.write_text(TWO_JOINT.rsplit("\n", 2)[0])
    out = tmp_path / "out.npy"
    assert main(["mocap", "positions", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("vidstyle: error:") and str(bad) in err and "truncated" in err
    assert len(err.splitlines()) == 1
    assert not out.exists() and sorted(x.name for x in tmp_path.iterdir()) == ["bad.bvh"]
    assert main(["mocap", "info", str(tmp_path / "nope.bvh")]) == 2
    assert main(["mocap", "positions", str(bad), "--out", str(tmp_path / "x.txt")]) == 2


def test_usage_errors_are_short_not_tracebacks(capsys):
    assert main(["mocap", "info", "--no-such-option"]) == 2
    err = capsys.readouterr().err
    assert "No such option" in err and "Traceback" not in err


def test_help_lists_every_command_with_stages_in_pipeline_order(capsys):
    import re

    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    listed = re.findall(r"^│ ([a-z][a-z-]+) ", out, flags=re.M)
    stages = ["features", "vocabulary", "train-recognizer", "recognize", "learn-style", "generate", "build-graph",
              "synthesize", "fit-actions", "sample-action", "train-pose", "pose", "match-pose", "augment", "reconstruct"]
    assert listed[: len(stages)] == stages
    assert set(listed[len(stages):]) == {"annotate", "demo", "render", "evaluate", "report", "timing", "mocap", "init",
                                         "compile"}
    for command in listed:  # every listed command answers --help
        assert main([command, "--help"]) == 0


def test_info_and_convert_are_library_calls(tmp_path, capsys):
    """``mocap info --json`` prints vidstyle.mocap.describe.describe; ``mocap convert`` writes what
    convert writes; both check their parameters in the library (fps before the file is read)."""
    import pytest

    from vidstyle.errors import ParameterError
    from vidstyle.mocap.describe import convert, describe

    p = tmp_path / "a.bvh"
    p.write_text(TWO_JOINT)
    assert main(["mocap", "info", str(p), "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == json.loads(json.dumps(describe(read_bvh(p), p)))
    assert main(["mocap", "convert", str(p), str(tmp_path / "cli.bvh"), "--fps", "60", "--start", "1"]) == 0
    m = convert(p, tmp_path / "lib.bvh", fps=60.0, start=1)
    assert (tmp_path / "cli.bvh").read_bytes() == (tmp_path / "lib.bvh").read_bytes()
    assert m.fps == 60.0 and m.n_frames == 3  # frames 1..2 at 30 fps -> 1/30 s at 60 fps
    with pytest.raises(ParameterError) as e:
        convert(tmp_path / "absent.bvh", tmp_path / "x.bvh", fps=0.0)
    assert e.value.param == "fps" and not (tmp_path / "x.bvh").exists()
    assert main(["mocap", "convert", str(p), str(tmp_path / "y.bvh"), "--fps", "-1"]) == 2
    assert "--fps: must be positive" in capsys.readouterr().err and not (tmp_path / "y.bvh").exists()
