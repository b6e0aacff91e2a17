"""Video reading and the ``vidstyle features`` command on tiny synthetic videos."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from vidstyle.cli import main
from vidstyle.errors import InputError
from vidstyle.formats.features import read_features
from vidstyle.video import VideoWriter


def write_video(path: Path, T=16, H=48, W=64, speed=2, fps=20.0) -> np.ndarray:
    """A bright textured disc moving right on a dark background; returns the gray frames."""
    rng = np.random.default_rng(0)
    tex = (rng.random((H, W)) * 60).astype(np.uint8)
    out = []
    with VideoWriter(path, fps) as w:
        for t in range(T):
            f = np.full((H, W), 30, np.uint8)
            mask = np.zeros((H, W), np.uint8)
            cv2.circle(mask, (12 + speed * t, H // 2), 10, 255, -1)
            f = np.where(mask > 0, 150 + np.roll(tex, speed * t, axis=1), f).astype(np.uint8)
            out.append(f)
            w.write(f)
    return np.stack(out)


@pytest.fixture
def video(tmp_path):
    p = tmp_path / "clip.mp4"
    frames = write_video(p)
    return p, frames


def test_cli_writes_the_documented_npz(video, tmp_path):
    p, frames = video
    out = tmp_path / "feat"
    assert main(["features", str(p), "--out", str(out), "--jobs", "1", "--variant", "thesis"]) == 0
    d = read_features(out / "clip.npz")
    n = len(d.points)
    assert n > 0 and d.points.dtype == np.int32 and d.points.shape == (n, 3)
    assert d.descriptors.shape == (n, 256) and d.descriptors.dtype == np.float32
    assert np.array_equal(d.frame_index, d.points[:, 0])
    # a 48-pixel-high video is below the working height: kept at its own size and rate
    assert (d.n_frames, d.height, d.width) == frames.shape
    assert np.array_equal(d.source_index, np.arange(len(frames))) and d.source_frames == len(frames)
    assert d.fps == pytest.approx(20.0) and d.video == str(p) and d.variant == "thesis"
    assert d.params["variant"] == "thesis" and d.params["salient"]["n_points"] == 10  # the validated default
    assert d.params["descriptor"]["n_subregions"] == [2, 2, 2]
    assert d.params["working"] == {"fps": 20.0, "height": 120}
    assert np.bincount(d.frame_index).max() <= 10
    assert [f.name for f in out.iterdir()] == ["clip.npz"]  # no temporary left behind


def test_cli_parallel_equals_serial_and_scovanner_variant(video, tmp_path):
    p, _ = video
    q = tmp_path / "other.mp4"
    write_video(q, speed=3)
    assert main(["features", str(p), str(q), "--out", str(tmp_path / "s"), "--jobs", "1"]) == 0
    assert main(["features", str(p), str(q), "--out", str(tmp_path / "par"), "--jobs", "2"]) == 0
    for name in ("clip.npz", "other.npz"):
        a, b = read_features(tmp_path / "s" / name), read_features(tmp_path / "par" / name)
        assert np.array_equal(a.points, b.points)
        assert np.array_equal(a.descriptors, b.descriptors)
    # the default variant is scovanner2007 (it recognises best on the demo; see the features command)
    assert main(["features", str(p), "--out", str(tmp_path / "sc"), "-j", "1"]) == 0
    d = read_features(tmp_path / "sc" / "clip.npz")
    assert d.descriptors.dtype == np.uint8 and d.descriptors.shape[1] == 640
    assert d.variant == "scovanner2007" and json.dumps(d.params).count("scovanner2007") >= 1
    assert main(["features", str(p), "--out", str(tmp_path / "2d"), "--variant", "sift2d", "-j", "1"]) == 0
    d2 = read_features(tmp_path / "2d" / "clip.npz")
    assert d2.descriptors.shape[1] == 128 and d2.variant == "sift2d"
    assert np.array_equal(d2.points, d.points)  # same salient points, only the descriptor differs
    assert main(["features", str(p), "--out", str(tmp_path / "x"), "--variant", "sift2d", "--subregions", "4"]) == 2


def test_cli_errors_leave_no_output(tmp_path, video, capsys):
    bad = tmp_path / "bad.mp4"
    bad.write_bytes(b"\x00garbage" * 100)
    out = tmp_path / "o"
    assert main(["features", str(bad), "--out", str(out), "-j", "1"]) == 2
    err = capsys.readouterr().err
    assert "bad.mp4: cannot be read as video" in err and len(err.strip().splitlines()[-1]) > 0
    if out.exists():  # the directory may be made up front; no file may be left in it
        assert list(out.iterdir()) == []
    p, _ = video
    sub = tmp_path / "sub"
    sub.mkdir()
    (sub / "clip.mp4").write_bytes(p.read_bytes())
    assert main(["features", str(p), str(sub / "clip.mp4"), "--out", str(out)]) == 2
    assert "same output name" in capsys.readouterr().err
    assert main(["features", str(tmp_path / "none.mp4"), "--out", str(out)]) == 2
    assert main(["features", str(p), "--out", str(out), "--variant", "nope"]) == 2
    assert main(["features", "--help"]) == 0


def test_npz_keys_and_load_errors(video, tmp_path):
    import zipfile

    p, _ = video
    out = tmp_path / "k"
    assert main(["features", str(p), "--out", str(out), "-j", "1", "--points", "3"]) == 0
    with zipfile.ZipFile(out / "clip.npz") as z:
        keys = {n[:-4] for n in z.namelist()}
    assert keys == {
        "kind", "schema_version", "points", "descriptors", "frame_index", "params", "variant", "n_frames",
        "height", "width", "fps", "video", "source_index", "source_frames", "source_fps", "source_width",
        "source_height",
    }  # fmt: skip
    d = read_features(out / "clip.npz")
    assert np.bincount(d.frame_index).max() <= 3
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(InputError, match="bad.npz: not a readable .npz"):
        read_features(bad)
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(InputError, match="missing"):
        read_features(tmp_path / "other.npz")
    with pytest.raises(InputError, match="not found"):
        read_features(tmp_path / "nope.npz")


def test_library_with_defaults_writes_the_cli_features(video, tmp_path):
    """vidstyle.features.extract_videos with its defaults (features/defaults.py) = `vidstyle features`."""
    import inspect

    import typer.main

    from vidstyle.cli import app
    from vidstyle.features import defaults as D
    from vidstyle.features import extract_videos

    path = video[0]
    assert main(["features", str(path), "--out", str(tmp_path / "cli"), "--jobs", "1"]) == 0
    extract_videos([path], tmp_path / "lib", jobs=1)
    a, b = (read_features(tmp_path / d / f"{path.stem}.npz") for d in ("cli", "lib"))
    np.testing.assert_array_equal(a.descriptors, b.descriptors)
    np.testing.assert_array_equal(a.points, b.points)
    assert a.params == b.params and a.params["variant"] == D.VARIANT
    cli = {p.name: p.default for p in typer.main.get_command(app).commands["features"].params}
    lib = inspect.signature(extract_videos).parameters
    for name in ("variant", "fps", "height", "points", "threshold", "min_distance", "flow", "subregions",
                 "subregion_size", "smooth"):
        assert cli[name] == lib[name].default, name


@pytest.mark.parametrize("kw,param", [({"variant": "sift4d"}, "variant"), ({"height": 4}, "height"),
                                      ({"fps": -1.0}, "fps"), ({"jobs": 0}, "jobs"),
                                      ({"subregions": 4}, "variant")])
def test_library_checks_its_parameters_before_any_work(video, tmp_path, kw, param):
    from vidstyle.errors import ParameterError
    from vidstyle.features import extract_videos

    with pytest.raises(ParameterError) as e:
        extract_videos([video[0]], tmp_path / "out", **kw)
    assert e.value.param == param and not (tmp_path / "out").exists()
