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
