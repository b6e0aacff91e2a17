"""``vidstyle render``: video + sidecar, labels file, one-line errors and no half-written outputs."""

from __future__ import annotations

import json

import numpy as np
import pytest

from vidstyle.cli import main
from vidstyle.mocap import write_bvh
from vidstyle.render import load_truth
from vidstyle.render.samples import sample_motion


@pytest.fixture
def bvh(tmp_path):
    p = tmp_path / "walk.bvh"
    write_bvh(sample_motion(30, fps=30.0), p)  # 1 s at 30 fps -> 20 frames at 20 fps
    return p


def test_render_writes_video_and_sidecar(tmp_path, bvh):
    out = tmp_path / "out" / "walk.mp4"
    assert main(["render", str(bvh), "--out", str(out), "--view", "left", "--size", "96x72", "--fps", "20",
                 "--background", "texture", "--seed", "4", "--appearance", "7"]) == 0
    from vidstyle.video import VideoReader

    with VideoReader(out) as r:
        assert len(r) == 20 and (r.width, r.height) == (96, 72)
        assert all(f.shape == (72, 96, 3) for f in r)
    truth = load_truth(tmp_path / "out" / "walk.truth.npz")
    assert truth["joints2d"].shape[0] == 20 and float(truth["azimuth_deg"]) == 90.0
    assert tuple(truth["size"]) == (96, 72) and float(truth["fps"]) == 20.0
    assert str(truth["background"]).startswith("texture:")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["walk.mp4", "walk.truth.npz"]


def test_render_azimuth_and_labels(tmp_path, bvh):
    labels = tmp_path / "labels.json"
    labels.write_text(json.dumps({"labels": ["jab"] * 15 + ["hook"] * 15, "transitions": [15]}))
    out = tmp_path / "a.avi"
    assert main(["render", str(bvh), "--out", str(out), "--view=-30", "--size", "64x48",
                 "--labels", str(labels), "--elevation", "5"]) == 0
    truth = load_truth(out)
    assert float(truth["azimuth_deg"]) == -30.0 and float(truth["elevation_deg"]) == 5.0
    assert truth["labels"][0] == "jab" and truth["labels"][-1] == "hook"
    assert np.flatnonzero(truth["transition"]).tolist() == [10]


@pytest.mark.parametrize(
    "args, message",
    [
        (["--size", "160"], "--size"),
        (["--view", "upward"], "view"),
        (["--background", "wallpaper"], "background"),
        (["--fps", "0"], "--fps"),
        (["--elevation", "95"], "elevation"),
        (["--appearance", "pretty"], "--appearance"),
    ],
)
def test_bad_options(tmp_path, bvh, capsys, args, message):
    out = tmp_path / "o.mp4"
    assert main(["render", str(bvh), "--out", str(out), *args]) != 0
    err = capsys.readouterr().err.strip()
    assert err.startswith("vidstyle: error:") and message in err and len(err.splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["walk.bvh"]


def test_bad_bvh_gives_error_and_no_output(tmp_path, capsys):
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n")
    out = tmp_path / "o.mp4"
    assert main(["render", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("vidstyle: error:") and str(bad) in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.bvh"]
    assert main(["render", str(tmp_path / "missing.bvh"), "--out", str(out)]) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.bvh"]


def test_bad_labels_file(tmp_path, bvh, capsys):
    labels = tmp_path / "labels.json"
    labels.write_text(json.dumps({"labels": ["jab"] * 3}))
    out = tmp_path / "o.mp4"
    assert main(["render", str(bvh), "--out", str(out), "--labels", str(labels)]) == 2
    assert "labels: 3 labels but the motion has 30 frames" in capsys.readouterr().err
    labels.write_text(json.dumps({"labels": ["jab"] * 30, "transitions": [99]}))
    assert main(["render", str(bvh), "--out", str(out), "--labels", str(labels)]) == 2
    assert "transitions[0]: must be at most 29, got 99" in capsys.readouterr().err
    assert not out.exists()


def test_bad_output_suffix(tmp_path, bvh, capsys):
    assert main(["render", str(bvh), "--out", str(tmp_path / "o.gif")]) == 2
    assert ".mp4" in capsys.readouterr().err


def test_library_render_bvh_with_defaults_writes_what_the_cli_writes(tmp_path, bvh):
    """``vidstyle render`` is render_bvh plus argument parsing: same defaults, same frames and truth."""
    from vidstyle.render.bvh import render_bvh
    from vidstyle.video import VideoReader

    cli, lib = tmp_path / "cli" / "w.mp4", tmp_path / "lib" / "w.mp4"
    assert main(["render", str(bvh), "--out", str(cli)]) == 0
    side = render_bvh(bvh, lib)
    assert side == tmp_path / "lib" / "w.truth.npz"
    a, b = load_truth(tmp_path / "cli" / "w.truth.npz"), load_truth(side)
    assert sorted(a) == sorted(b)
    for key in a:
        np.testing.assert_array_equal(np.asarray(a[key]), np.asarray(b[key]), err_msg=key)
    with VideoReader(cli) as r1, VideoReader(lib) as r2:
        f1, f2 = list(r1), list(r2)
    assert len(f1) == len(f2) == 20 and all(np.array_equal(x, y) for x, y in zip(f1, f2))
    assert tuple(a["size"]) == (160, 120) and float(a["noise_sigma"]) == 2.0  # the documented defaults


def test_library_render_bvh_checks_parameters_before_writing(tmp_path, bvh):
    from vidstyle.errors import ParameterError
    from vidstyle.render.bvh import render_bvh

    for kw, param in (({"fps": 0.0}, "fps"), ({"noise_sigma": -1.0}, "noise_sigma"), ({"appearance": "pretty"}, "appearance")):
        with pytest.raises(ParameterError) as e:
            render_bvh(bvh, tmp_path / "o.mp4", **kw)
        assert e.value.param == param
    with pytest.raises(ParameterError, match="video must end in"):
        render_bvh(bvh, tmp_path / "o.gif")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["walk.bvh"]
