"""``vidstyle features`` streams: windows of frames with the descriptor's temporal margin give exactly the
points and descriptors of the whole volume, and memory does not grow with the video's length."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from vidstyle.cli import main
from vidstyle.features.descriptors import DEFAULT_VARIANT, REGISTRY, get_descriptor
from vidstyle.features.extract import extract_features, extract_stream, process_video
from vidstyle.features.salient import SalientParams
from vidstyle.formats.features import read_features
from vidstyle.video import VideoReader


def moving_blobs(T: int, H: int = 60, W: int = 80, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[:H, :W]
    vol = np.empty((T, H, W), np.uint8)
    for t in range(T):
        cx, cy = 10 + (0.8 * t) % (W - 20), H / 2 + H / 6 * np.sin(t / 5)
        blob = 200 * np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / 50)
        vol[t] = np.clip(blob + rng.integers(0, 20, (H, W)), 0, 255)
    return vol


@pytest.mark.parametrize("variant", sorted(REGISTRY))
def test_windows_equal_the_whole_volume(variant):
    vol = moving_blobs(45)
    ref = extract_features(vol.astype(np.float32) * np.float32(1 / 255), variant)
    assert len(ref["points"]) > 300
    margin = get_descriptor(variant).temporal_margin
    for window in (3, margin + 1, 64):
        pts, desc = extract_stream(iter(vol), len(vol), variant, window=window)
        assert np.array_equal(pts, ref["points"]), window
        assert desc.dtype == ref["descriptors"].dtype
        assert np.array_equal(desc, ref["descriptors"]), window  # bit for bit


def test_streamed_demo_video_equals_the_whole_volume(tmp_path):
    bvh, video = tmp_path / "p.bvh", tmp_path / "p.mp4"
    assert main(["demo", "performer", "--out", str(bvh), "--seconds", "2", "--action", "Jab"]) == 0
    assert main(["render", str(bvh), "--out", str(video), "--background", "texture"]) == 0
    process_video(video, tmp_path / "p.npz", window=8)
    got = read_features(tmp_path / "p.npz")
    with VideoReader(video, fps=20, height=120, gray=True) as r:
        whole = r.read_all().astype(np.float32) * np.float32(1 / 255)
    ref = extract_features(whole, DEFAULT_VARIANT)
    assert len(ref["points"]) > 100
    assert np.array_equal(got.points, ref["points"]) and np.array_equal(got.descriptors, ref["descriptors"])
    assert (got.n_frames, got.height, got.width, got.fps) == (len(whole), 120, 160, 20.0)
    assert np.array_equal(got.source_index, np.arange(len(whole)))


def test_working_rate_and_size_are_recorded(tmp_path):
    from vidstyle.video import write_video

    vol = moving_blobs(36, 240, 320)
    video = tmp_path / "v.mkv"
    write_video(np.repeat(vol, 1, axis=0), video, 60.0)
    process_video(video, tmp_path / "v.npz", fps=20.0, height=120)
    f = read_features(tmp_path / "v.npz")
    assert (f.n_frames, f.height, f.width, f.fps) == (12, 120, 160, 20.0)
    assert np.array_equal(f.source_index, np.arange(0, 36, 3))
    assert (f.source_frames, f.source_width, f.source_height) == (36, 320, 240)
    assert f.source_fps == pytest.approx(60.0, rel=1e-3)
    assert f.points[:, 1].max() < 120 and f.points[:, 2].max() < 160
    assert f.params["working"] == {"fps": 20.0, "height": 120}


def _peak_bytes(T: int, window: int) -> int:
    vol = moving_blobs(1)[0]
    frames = (np.roll(vol, 2 * t, axis=1) for t in range(T))  # made on the fly, never all in memory
    tracemalloc.start()
    try:
        extract_stream(frames, T, "scovanner2007", SalientParams(n_points=1), window=window)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_memory_is_bounded_by_the_window_not_the_length():
    short, long = _peak_bytes(40, 16), _peak_bytes(200, 16)
    growth = (200 - 40) * 60 * 80 * 4  # what holding the float volume would add: 3.1 MB
    assert long - short < growth / 3, (short, long)


def test_out_of_memory_is_one_line_exit_3(tmp_path, monkeypatch, capsys):
    from vidstyle.features import extract
    from vidstyle.video import write_video

    write_video(moving_blobs(6), tmp_path / "v.mkv", 20.0)

    def boom(*a, **k):
        raise MemoryError

    monkeypatch.setattr(extract, "extract_stream", boom)
    assert main(["features", str(tmp_path / "v.mkv"), "--out", str(tmp_path / "o"), "-j", "1"]) == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "v.mkv: out of memory" in err[0]
    assert not (tmp_path / "o" / "v.npz").exists()
    # a MemoryError anywhere else is one line and exit 3 too
    monkeypatch.setattr(extract, "run_features", boom)
    import vidstyle.features.extract as fx

    monkeypatch.setattr(fx, "run_features", boom)
    assert main(["features", str(tmp_path / "v.mkv"), "--out", str(tmp_path / "o"), "-j", "1"]) == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["vidstyle: error: out of memory (try a smaller input, working size or fewer jobs)"]


def test_descriptor_interface():
    from vidstyle.features import describe

    assert DEFAULT_VARIANT == "scovanner2007" == get_descriptor().name
    assert describe(moving_blobs(16).astype(np.float32), [[8, 30, 40]]).dtype == np.uint8
    vol = moving_blobs(20).astype(np.float32) / 255
    pts = np.array([[10, 30, 40], [0, 5, 5]])
    for name in REGISTRY:
        d = get_descriptor(name)
        out = d.describe(vol, pts)
        assert out.shape == (2, d.dimension) and out.dtype == d.dtype
        import json

        assert json.loads(json.dumps(d.parameters()))["variant"] == name
    perm = get_descriptor("scovanner2007").mirror_permutation()
    assert sorted(perm.tolist()) == list(range(640))
    assert get_descriptor("thesis").mirror_permutation() is None
