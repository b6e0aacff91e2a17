"""vidstyle.video: frame-exact reading (by decoded index), working rate and size, atomic writing.

Truth is independent of the decoder: every test video shows its own frame number
(:func:`vidstyle.video.numbered.numbered_frame`), read back from the pixels with ``read_number``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vidstyle.errors import InputError
from vidstyle.video import CODECS, VideoReader, VideoWriter, probe, write_video
from vidstyle.video.numbered import numbered_frame, read_number

REAL = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "video" / "real"
SUFFIXES = (".mp4", ".mkv", ".avi")


def numbered_video(path: Path, n: int, fps: float = 30.0, times=None, size=(160, 120)) -> Path:
    return write_video((numbered_frame(i, *size) for i in range(n)), path, fps, times=times)


def numbers(frames) -> list[int]:
    return [read_number(f) for f in frames]


def brute_force_nearest(t: np.ndarray, fps: float) -> np.ndarray:
    """For each tick k / fps up to the last frame (plus half a native frame), the frame of nearest
    timestamp (ties to the earlier one), by exhaustive search; repeated picks once."""
    native = (len(t) - 1) / t[-1]
    picks = []
    k = 0
    while k / fps < t[-1] + 0.5 / native:
        d = np.abs(t - k / fps)
        picks.append(int(np.flatnonzero(d <= d.min() + 1e-9)[0]))
        k += 1
    return np.unique(picks)


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_constant_rate_sequential_and_random_access(tmp_path, suffix, rng):
    p = numbered_video(tmp_path / f"n{suffix}", 75, fps=30.0)
    with VideoReader(p) as r:
        assert len(r) == 75 and r.info.frames == 75 and (r.width, r.height) == (160, 120)
        assert r.info.constant_rate and r.fps == pytest.approx(30.0, rel=1e-3)
        assert np.allclose(r.timestamps, np.arange(75) / 30.0, atol=6e-4)  # Matroska: 1 ms ticks
        assert numbers(r) == list(range(75))  # sequential
        order = rng.permutation(75)
        assert [read_number(r[int(i)]) for i in order] == order.tolist()  # random, both directions
        assert [i for i, _ in r.iter_frames(70, 200)] == [70, 71, 72, 73, 74]
        with pytest.raises(IndexError):
            r.frame(75)
    # a fresh reader jumping straight to the end (seek before any decoding)
    with VideoReader(p) as r:
        assert read_number(r[74]) == 74 and read_number(r[0]) == 0 and read_number(r[40]) == 40


@pytest.mark.parametrize("suffix", [".mp4", ".mkv"])
def test_variable_rate_by_decoded_index_and_nearest_timestamp(tmp_path, suffix, rng):
    gaps = rng.choice([1 / 60, 1 / 30, 1 / 24, 1 / 12], size=89)
    times = np.concatenate([[0.0], np.cumsum(gaps)])
    p = numbered_video(tmp_path / f"vfr{suffix}", 90, fps=30.0, times=times)
    info = probe(p)
    assert info.frames == 90 and not info.constant_rate
    assert np.allclose(info.timestamps, times, atol=6e-4)
    with VideoReader(p) as r:
        assert numbers(r) == list(range(90))  # index = decoded order, not time x fps
        order = rng.permutation(90)[:30]
        assert [read_number(r[int(i)]) for i in order] == order.tolist()
    with VideoReader(p, fps=20.0) as w:
        ref = brute_force_nearest(info.timestamps, 20.0)
        assert np.array_equal(w.source_index, ref)
        assert numbers(w) == ref.tolist()
        assert np.array_equal(w.timestamps, info.timestamps[ref])


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_working_rate_60_to_20_takes_every_third_frame(tmp_path, suffix):
    p = numbered_video(tmp_path / f"r{suffix}", 60, fps=60.0)
    with VideoReader(p, fps=20.0) as r:
        assert np.array_equal(r.source_index, np.arange(0, 60, 3)) and r.fps == 20.0
        assert numbers(r) == list(range(0, 60, 3))
        assert read_number(r[7]) == 21
    with VideoReader(p, fps=120.0) as r:  # never raises the rate
        assert len(r) == 60


def test_working_size_and_gray(tmp_path):
    p = numbered_video(tmp_path / "s.mkv", 10, size=(320, 240))
    with VideoReader(p, height=60, gray=True) as r:
        f = r[3]
        assert f.shape == (60, 80) and f.dtype == np.uint8 and (r.width, r.height) == (80, 60)
        assert numbers(r) == list(range(10))
    import cv2

    with VideoReader(p, height=60) as c, VideoReader(p, height=60, gray=True) as g:
        assert np.array_equal(g[5], cv2.cvtColor(c[5], cv2.COLOR_BGR2GRAY))  # OpenCV's gray of the BGR
    with VideoReader(p, height=480, enlarge=False) as r:
        assert r[0].shape == (240, 320, 3)
    with VideoReader(p, height=480) as r:
        assert r[0].shape == (480, 640, 3)
    with pytest.raises(InputError, match="height"):
        VideoReader(p, height=3)
    with pytest.raises(InputError, match="fps"):
        VideoReader(p, fps=0)


def test_lossless_codec_round_trips_pixels(tmp_path, rng):
    frames = rng.integers(0, 256, (5, 24, 32, 3), dtype=np.uint8)
    write_video(frames, tmp_path / "x.mkv", 25.0)
    with VideoReader(tmp_path / "x.mkv") as r:
        assert np.array_equal(r.read_all(), frames)


def test_bad_inputs_name_the_file(tmp_path):
    good = numbered_video(tmp_path / "good.mp4", 60)
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    empty = tmp_path / "empty.mp4"
    empty.write_bytes(b"")
    text = tmp_path / "notes.mp4"
    text.write_text("this is a text file, not a video\n" * 40)
    folder = tmp_path / "folder.mp4"
    folder.mkdir()
    for bad in (cut, empty, text, folder, tmp_path / "missing.mp4"):
        with pytest.raises(InputError, match=bad.name):
            with VideoReader(bad) as r:
                r.read_all()


def test_truncated_stream_with_index_at_the_front(tmp_path):
    """A Matroska file cut in half: the frames that are there decode, the missing ones are an error."""
    good = numbered_video(tmp_path / "good.mkv", 60)
    cut = tmp_path / "cut.mkv"
    cut.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    try:
        r = VideoReader(cut)
    except InputError as e:
        assert "cut.mkv" in str(e)
        return
    with r:
        assert 0 < len(r) < 60
        assert numbers(r) == list(range(len(r)))


def test_writer_leaves_no_file_on_error(tmp_path):
    out = tmp_path / "v.mp4"
    with pytest.raises(RuntimeError):
        with VideoWriter(out, 20.0) as w:
            w.write(numbered_frame(0))
            raise RuntimeError("boom")
    with pytest.raises(ValueError, match="differs"):
        with VideoWriter(out, 20.0) as w:
            w.write(numbered_frame(0))
            w.write(numbered_frame(1, 80, 60))
    with pytest.raises(ValueError, match="not after"):
        write_video([numbered_frame(0), numbered_frame(1)], out, 20.0, times=[0.5, 0.5])
    with pytest.raises(InputError, match="no frames"):
        write_video([], out, 20.0)
    with pytest.raises(InputError, match="must end in"):
        write_video([numbered_frame(0)], tmp_path / "v.gif", 20.0)
    assert list(tmp_path.iterdir()) == []
    assert sorted(CODECS) == [".avi", ".m4v", ".mkv", ".mov", ".mp4"]


@pytest.mark.shared
@pytest.mark.parametrize("name", ["pose2sim_single_cam01.mp4", "sports2d_demo.mp4"])
def test_real_footage_random_access_equals_sequential(name, rng):
    path = REAL / name
    if not path.is_file():
        pytest.skip(f"{path} absent")
    n = 40
    with VideoReader(path, height=120, gray=True) as r:
        assert r.info.frames > 50 and r.height == 120
        seq = [f.copy() for _, f in r.iter_frames(0, n)]
    with VideoReader(path, height=120, gray=True) as r:
        for i in rng.permutation(n)[:8]:
            assert np.array_equal(r[int(i)], seq[int(i)]), int(i)
    with VideoReader(path, fps=20.0, height=120, gray=True) as w:
        assert np.array_equal(w.source_index, brute_force_nearest(w.info.timestamps, 20.0))
        for k in (9, 1, 5):
            assert np.array_equal(w[k], seq[int(w.source_index[k])])


@pytest.mark.parametrize("height", [None, 60, 180])
def test_frames_equal_a_fresh_conversion_of_each_decoded_frame(tmp_path, rng, height):
    """The reader's one reusable swscale context gives, frame after frame and after seeks, exactly the
    pixels of a new conversion of each decoded frame (PyAV's per-frame ``reformat``), at the native
    size (which is OpenCV's own BGR) and shrunk or enlarged; gray is OpenCV's gray of that BGR."""
    import av
    import cv2

    frames = [rng.integers(0, 256, (120, 160, 3), dtype=np.uint8) for _ in range(12)]
    p = write_video(iter(frames), tmp_path / "noise.mp4", 20.0)
    with av.open(str(p)) as c:
        decoded = list(c.decode(c.streams.video[0]))
    if height is None:
        want = [f.to_ndarray(format="bgr24") for f in decoded]
    else:
        w = round(160 * height / 120)
        interp = "AREA" if height < 120 else "BILINEAR"
        want = [f.reformat(width=w, height=height, format="bgr24", interpolation=interp).to_ndarray()
                for f in decoded]
    order = list(range(12)) + [int(i) for i in rng.permutation(12)]
    with VideoReader(p, height=height, enlarge=True) as r:
        for i in order:
            np.testing.assert_array_equal(r[i], want[i])
    with VideoReader(p, height=height, enlarge=True, gray=True) as r:
        for i in order:
            np.testing.assert_array_equal(r[i], cv2.cvtColor(want[i], cv2.COLOR_BGR2GRAY))
    if height is None:  # OpenCV's own decoding of the file
        cap = cv2.VideoCapture(str(p))
        ok, first = cap.read()
        cap.release()
        assert ok
        np.testing.assert_array_equal(first, want[0])


def _faststart_mp4(path: Path, n: int, b_frames: bool = False) -> Path:
    """An H.264 mp4 with its moov atom (the index) before the data, as phones and web uploads write it."""
    import av

    c = av.open(str(path), "w", options={"movflags": "faststart"})
    st = c.add_stream("libx264", rate=20)
    st.width, st.height, st.pix_fmt = 160, 120, "yuv420p"
    # no B-frames: the file's first half then holds a prefix of the frames in presentation order (with
    # B-frames, as PyAV 18's x264 uses by default, a P-frame before the cut can show after B-frames that
    # are past it, and the frames that decode are no longer 0..n-1)
    st.options = {} if b_frames else {"bf": "0"}
    for i in range(n):
        for p in st.encode(av.VideoFrame.from_ndarray(numbered_frame(i, 160, 120), format="bgr24")):
            c.mux(p)
    for p in st.encode():
        c.mux(p)
    c.close()
    return path


def test_mp4_cut_in_half_with_index_at_the_front_counts_only_frames_that_decode(tmp_path):
    """The index promises every frame; the file holds about half, the last one truncated (issue 33: it was
    counted, and asking for it failed). Every counted frame decodes, in order and at random."""
    import av

    if "libx264" not in av.codecs_available:
        pytest.skip("PyAV without libx264")
    good = _faststart_mp4(tmp_path / "good.mp4", 60)
    raw = good.read_bytes()
    assert raw.find(b"moov") < raw.find(b"mdat")
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(raw[: len(raw) // 2])
    with VideoReader(cut) as r:
        n = len(r)
        assert 0 < n < 60
        assert numbers(r) == list(range(n))
        assert read_number(r[n - 1]) == n - 1 and read_number(r[0]) == 0


def test_a_still_image_renamed_mp4_is_not_a_video(tmp_path):
    import cv2

    ok, png = cv2.imencode(".png", numbered_frame(3))
    fake = tmp_path / "photo.mp4"
    fake.write_bytes(png.tobytes())
    with pytest.raises(InputError, match=r"photo\.mp4: is a still image \(png\), not a video"):
        VideoReader(fake)
    with pytest.raises(InputError, match="still image"):
        probe(fake)


@pytest.mark.parametrize("suffix,shape", [(".mp4", (120, 160, 3)), (".mp4", (121, 161, 3)), (".mp4", (48, 64))])
def test_background_encoder_writes_the_same_file(tmp_path, suffix, shape):
    """VideoWriter(background=True) encodes on a thread of its own: the same bytes as the encoder in the
    caller's thread, also when the caller reuses one frame buffer for every frame (the encoder must not
    see a later frame's pixels), more frames than the hand-over queue holds. (H.264 in mp4 only: the MKV
    muxer does not write the same bytes twice even from one thread.)"""
    rng = np.random.default_rng(4)
    frames = [rng.integers(0, 256, shape, dtype=np.uint8) for _ in range(23)]
    paths = []
    for background in (False, True):
        out = tmp_path / f"v{int(background)}{suffix}"
        buf = np.empty(shape, np.uint8)
        with VideoWriter(out, 20.0, background=background) as w:
            for f in frames:
                buf[...] = f
                w.write(buf)
        paths.append(out)
    assert paths[0].read_bytes() == paths[1].read_bytes()


def test_background_encoder_error_leaves_no_file(tmp_path):
    """An error while writing with the background encoder (a frame of another size) leaves no file and no
    temporary behind, and the encoder thread ends."""
    import threading

    out = tmp_path / "v.mp4"
    with pytest.raises(ValueError):
        with VideoWriter(out, 20.0, background=True) as w:
            for _ in range(6):
                w.write(np.zeros((32, 32, 3), np.uint8))
            w.write(np.zeros((16, 16, 3), np.uint8))
    assert list(tmp_path.iterdir()) == []
    assert not any(t.name == "vidstyle-video-encoder" for t in threading.enumerate())


def test_mp4_with_b_frames_cut_in_half_reads_the_same_frames_in_order_and_at_random(tmp_path):
    """With B-frames the frames that survive a cut need not be a prefix (a P-frame shown after B-frames
    that were cut off): whatever is counted is read in increasing order, and random access agrees."""
    import av

    if "libx264" not in av.codecs_available:
        pytest.skip("PyAV without libx264")
    raw = _faststart_mp4(tmp_path / "good.mp4", 60, b_frames=True).read_bytes()
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(raw[: len(raw) // 2])
    with VideoReader(cut) as r:
        n = len(r)
        assert 0 < n < 60
        nums = numbers(r)
        assert len(nums) == n and nums[0] == 0
        assert all(a < b for a, b in zip(nums, nums[1:]))
        for i in (n - 1, n // 2, 0, n - 2):
            assert read_number(r[i]) == nums[i]

