"""The compiled rasteriser kernel (numba) against its numpy reference: the same buffer to the bit, so
a render (and every video the demo makes) is byte-identical whichever runs (issue 31: the renderer's
speed without changing an output)."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.render import Appearance, Camera, render_motion
from vidstyle.render import raster
from vidstyle.render.samples import sample_motion


def _with_numpy_draw(monkeypatch):
    monkeypatch.setattr(raster.Rasterizer, "draw", raster.Rasterizer.draw_numpy)
    monkeypatch.setattr(raster.Rasterizer, "render_frame", raster.Rasterizer.render_frame_numpy)


@pytest.mark.parametrize("view,size,seed", [("front", (160, 120), 0), ("left", (160, 120), 3),
                                            ("back", (320, 240), 5), ("right", (96, 72), 7)])
def test_renders_are_identical_with_the_numpy_reference(monkeypatch, view, size, seed):
    m = sample_motion(30, fps=20.0)
    cam = Camera.for_view(m, view=view, size=size)
    app = Appearance.random(seed)
    fast, truth_fast, masks_fast = render_motion(m, cam, appearance=app, seed=seed, return_masks=True)
    _with_numpy_draw(monkeypatch)
    ref, truth_ref, masks_ref = render_motion(m, cam, appearance=app, seed=seed, return_masks=True)
    assert np.array_equal(fast, ref) and np.array_equal(masks_fast, masks_ref)
    assert np.array_equal(truth_fast["visible"], truth_ref["visible"])


def test_buffers_are_bit_equal_on_random_capsules_including_degenerate_ones():
    """Random capsules: tapered and not, zero-length, behind the camera, partly and wholly off-image,
    split materials, heads with and without a face direction; every channel compared bit for bit."""
    rng = np.random.default_rng(11)
    W, H = 80, 60
    for trial in range(40):
        C = int(rng.integers(1, 12))
        uv = rng.uniform(-20, 100, size=(C, 2, 2))
        if trial % 5 == 0:
            uv[0, 1] = uv[0, 0]  # zero length
        z = rng.uniform(-0.5, 6, size=(C, 2))
        rpx = rng.uniform(0.1, 9, size=(C, 2))
        rpx[::3, 1] = rpx[::3, 0]  # untapered
        rworld = rng.uniform(0.02, 0.2, size=(C, 2))
        mat = rng.integers(0, 8, size=(C, 2))
        split = rng.uniform(0, 1, size=C)
        order = rng.permutation(C)
        head = rng.random(C) < 0.3
        face = None if trial % 4 == 0 else rng.normal(size=3)
        a, b = raster.Rasterizer(W, H), raster.Rasterizer(W, H)
        for _ in range(2):  # the second frame starts from the first one's buffer (clear by bbox)
            a.draw(uv, z, rpx, rworld, mat, split, order, head, face)
            b.draw_numpy(uv, z, rpx, rworld, mat, split, order, head, face)
            assert a.bbox == b.bbox
            assert a.buf.tobytes() == b.buf.tobytes(), f"trial {trial}"
            uv = uv + rng.normal(size=uv.shape)


def test_shaded_frames_are_byte_equal_on_random_buffers():
    """render_frame (compiled shading, outlines, blending, noise, clipping) against render_frame_numpy on
    random buffers: normals up to and past the unit disc, depth jumps around the outline threshold,
    background pixels (code -1) inside the box, boxes touching the image's edges or empty, with and without
    noise, colours pushed past 0 and 255."""
    from vidstyle.render.background import NoiseBank

    rng = np.random.default_rng(5)
    W, H = 48, 36
    for trial in range(30):
        a, b = raster.Rasterizer(W, H), raster.Rasterizer(W, H)
        y0, x0 = int(rng.integers(0, H // 2)), int(rng.integers(0, W // 2))
        y1, x1 = int(rng.integers(y0, H + 1)), int(rng.integers(x0, W + 1))
        if trial % 7 == 0:
            y1 = y0  # nothing drawn
        reg = a.buf[y0:y1, x0:x1]
        n = reg.shape[:2]
        jump = float(rng.uniform(0.01, 0.1))
        reg[..., raster.D] = np.where(rng.random(n) < 0.2, raster.FAR, rng.uniform(1, 1 + 4 * jump, size=n))
        reg[..., raster.NX] = rng.uniform(-1.1, 1.1, size=n)
        reg[..., raster.NY] = rng.uniform(-1.1, 1.1, size=n)
        reg[..., raster.COV] = np.clip(rng.uniform(-0.2, 1.2, size=n), 0, 1)
        caps = rng.integers(-1, 6, size=n)
        reg[..., raster.CODE] = np.where(caps < 0, -1, caps * raster.MAT_BITS + rng.integers(0, 8, size=n))
        b.buf[...] = a.buf
        a.bbox = b.bbox = (y0, y1, x0, x1)
        group = np.array([0, 0, 2, 3, 4, 5, -1], dtype=np.int32)
        palette = rng.uniform(0, 300, size=(16, 3)).astype(np.float32)
        bg = (rng.uniform(-20, 280, size=(H, W, 3)) + 0.5).astype(np.float32)
        sigma = 0.0 if trial % 3 == 0 else 6.0
        na, nb = NoiseBank((W, H), sigma, np.random.default_rng(trial)), NoiseBank((W, H), sigma, np.random.default_rng(trial))
        out_a, out_b = np.empty((H, W, 3), np.uint8), np.empty((H, W, 3), np.uint8)
        a.render_frame(out_a, bg, palette, jump, group, na)
        b.render_frame_numpy(out_b, bg, palette, jump, group, nb)
        assert out_a.tobytes() == out_b.tobytes(), f"trial {trial}"
        if y1 > y0 and x1 > x0:
            assert a.shade.tobytes() == b.shade.tobytes() and np.array_equal(a.material, b.material)
