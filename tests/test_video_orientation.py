"""Upright frames: the video layer applies the stream's display matrix as a player does (issue 27).

Truth is PyAV's documented meaning of the matrix it writes (``VideoStream.set_display_rotation(deg,
hflip, vflip)``: the displayed picture is the coded one rotated ``deg`` counter-clockwise, then mirrored),
so a file whose coded pictures are the inverse of an upright original must decode to that original.
The files are lossless (PNG in MOV), so "equal" means every pixel.
"""

from __future__ import annotations

import numpy as np
import pytest
from video_util import write_lossless

from vidstyle.video import VideoReader, probe
from vidstyle.video.orientation import (
    Orientation,
    orientation_from_matrix,
    orientation_from_rotate_tag,
    parse_display_matrix,
    rotation_of,
)

RNG = np.random.default_rng(0)
#: three distinct frames, so frame indexing is checked too (48 rows x 64 columns: not square)
FRAMES = [RNG.integers(0, 256, (48, 64, 3), dtype=np.uint8) for _ in range(3)]
CASES = [(deg, hf, vf) for deg in (0, 90, 180, -90) for hf in (False, True) for vf in (False, True)]


def _coded(image, deg, hflip, vflip):
    """The coded picture whose display (rotate ``deg`` CCW, then mirror) is ``image``."""
    x = image
    if vflip:
        x = x[::-1]
    if hflip:
        x = x[:, ::-1]
    return np.ascontiguousarray(np.rot90(x, -deg // 90))


@pytest.fixture(scope="module")
def upright(tmp_path_factory):
    return write_lossless(tmp_path_factory.mktemp("up") / "up.mov", FRAMES)


@pytest.mark.parametrize(("deg", "hflip", "vflip"), CASES)
def test_every_orientation_decodes_to_the_upright_pixels(tmp_path, upright, deg, hflip, vflip):
    path = write_lossless(tmp_path / "t.mov", [_coded(f, deg, hflip, vflip) for f in FRAMES], deg, hflip, vflip)
    with VideoReader(path) as r:
        assert (r.width, r.height) == (64, 48)
        assert (r.info.width, r.info.height) == (64, 48)
        got = r.read_all()
        assert np.array_equal(got, np.stack(FRAMES))
        # random access by decoded index is unchanged
        assert np.array_equal(r.frame(1), FRAMES[1])
        assert np.array_equal(r[0], FRAMES[0])
    with VideoReader(path, gray=True) as r, VideoReader(upright, gray=True) as u:
        assert np.array_equal(r.read_all(), u.read_all())


@pytest.mark.parametrize("deg", [90, -90, 180])
def test_autorotate_off_gives_the_coded_pictures(tmp_path, deg):
    coded = [_coded(f, deg, False, False) for f in FRAMES]
    path = write_lossless(tmp_path / "t.mov", coded, deg)
    with VideoReader(path, autorotate=False) as r:
        assert np.array_equal(r.read_all(), np.stack(coded))
        assert r.info.orientation.identity
    info = probe(path)
    assert info.coded_size == (coded[0].shape[1], coded[0].shape[0])
    assert info.rotation == pytest.approx(deg if deg != 180 else -180)


@pytest.mark.parametrize("deg", [90, -90, 180])
@pytest.mark.parametrize("gray", [False, True])
def test_working_size_is_the_displayed_frames(tmp_path, upright, deg, gray):
    """At a working height the rotated file has the upright one's size; resampling happens before the
    transpose (one libswscale pass on the decoded picture), so pixels may differ by one grey level from
    resampling the upright picture (horizontal and vertical passes round differently), never more."""
    path = write_lossless(tmp_path / "t.mov", [_coded(f, deg, False, False) for f in FRAMES], deg)
    with VideoReader(path, height=24, gray=gray) as r, VideoReader(upright, height=24, gray=gray) as u:
        a, b = r.read_all().astype(int), u.read_all().astype(int)
    assert a.shape == b.shape == ((3, 24, 32) if gray else (3, 24, 32, 3))
    assert np.abs(a - b).max() <= 1


def _rotation_matrix(ccw_degrees: float, hflip=False, vflip=False):
    """FFmpeg's ``av_display_rotation_set(m, -ccw_degrees)`` (it takes a clockwise angle) and
    ``av_display_matrix_flip``, written out (16.16 fixed point)."""
    r = np.radians(ccw_degrees)  # av_display_rotation_set(m, angle) uses radians(-angle)
    c, s = np.cos(r), np.sin(r)
    m = [c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0]
    scale = [65536.0, 65536.0, 1 << 30] * 3
    out = [int(round(v * k)) for v, k in zip(m, scale)]
    flip = [1 - 2 * hflip, 1 - 2 * vflip, 1]
    return tuple(v * flip[i % 3] for i, v in enumerate(out))


@pytest.mark.parametrize("deg", [0, 90, 180, 270, -90])
def test_rotation_of_inverts_the_matrix_construction(deg):
    got = rotation_of(_rotation_matrix(deg))
    assert ((got - deg + 180) % 360) - 180 == pytest.approx(0, abs=1e-9)


def test_legacy_rotate_tag_means_clockwise_degrees():
    # a 'rotate=90' tag (clockwise) is the matrix of a -90 degree (counter-clockwise) rotation
    for tag, ccw in (("90", -90), ("180", 180), ("270", 90), ("0", 0)):
        assert orientation_from_rotate_tag(tag) == orientation_from_matrix(_rotation_matrix(ccw))
    assert orientation_from_rotate_tag(None).identity
    assert orientation_from_rotate_tag("sideways").identity


def test_orientation_apply_matches_numpy_rotations():
    img = RNG.integers(0, 256, (5, 7), dtype=np.uint8)
    assert np.array_equal(orientation_from_rotate_tag("90").apply(img), np.rot90(img, -1))
    assert np.array_equal(orientation_from_rotate_tag("270").apply(img), np.rot90(img, 1))
    assert np.array_equal(orientation_from_rotate_tag("180").apply(img), np.rot90(img, 2))
    assert Orientation().apply(img) is img


def test_odd_matrices_are_left_as_decoded(caplog):
    assert orientation_from_matrix(_rotation_matrix(30)).identity
    assert "not a multiple of 90" in caplog.text
    assert orientation_from_matrix((0,) * 9).identity
    assert parse_display_matrix(b"\x00" * 35) is None
