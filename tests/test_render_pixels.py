"""The renderer's pixels against an independent pinhole projection (supersedes the `F == len(masks)`
assertion of tests/test_render_core.py::test_visible_joints_lie_on_the_figure).

A hand-built camera (K, R, t written out here, not :meth:`Camera.for_view`) looks at a known motion; the
joints and End Sites are projected with the pinhole formula ``uv = K (R X + t)`` computed in this file.
Then, with no sensor noise over a plain background:

* every pixel farther from every projected bone than the thickest body part can reach is background,
  all of one colour;
* the figure's pixels exist, and lie near the projected bones; the pixel under each visible projected
  joint is figure, not background;
* the figure's bounding box spans the projected skeleton's (height of the figure in pixels = f * h / z).
"""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.mocap import end_site_positions, forward_kinematics
from vidstyle.render import Appearance, Camera, render_motion
from vidstyle.render.samples import sample_motion

W, H, FOCAL = 320, 240, 300.0
# metres; the performer (1.71 m, facing and walking along +Z from the origin) is seen from his left side,
# so his walk moves the figure across the image
EYE = np.array([4.0, 0.85, 0.3])
# camera looking along world -X: camera x = world -Z, camera y (down) = world -Y, camera z = world -X
R = np.array([[0, 0, -1.0], [0, -1.0, 0], [-1.0, 0, 0]])
K = np.array([[FOCAL, 0, (W - 1) / 2], [0, FOCAL, (H - 1) / 2], [0, 0, 1]])
HEIGHT = 1.71
# the body's documented thickness (vidstyle.render.body: capsule radii as fractions of the figure's height,
# build 1.0): no part reaches farther than the torso's 0.074 x height from its bone; the torso is at least
# 0.068 x height thick (radius) at the chest
THICK, TORSO = 0.074 * HEIGHT, 0.068 * HEIGHT
AA = 1.5  # pixels of anti-aliasing / rounding


def _project(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    xc = (X - EYE) @ R.T
    return xc[..., :2] * FOCAL / xc[..., 2:] + K[:2, 2], xc[..., 2]


def _seg_dist(px: np.ndarray, a: np.ndarray, b: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Distance of pixels (P, 2) to 2D segments a-b (S, 2), in world units at each segment's depth (S,)
    (pixels x depth / f): (P,) minimum over segments."""
    d = b - a
    t = np.clip(((px[:, None] - a[None]) * d[None]).sum(-1) / np.maximum((d * d).sum(-1), 1e-12), 0, 1)
    dist = np.linalg.norm(px[:, None] - (a[None] + t[..., None] * d[None]), axis=-1)
    return (dist * depth[None] / FOCAL).min(axis=1)


@pytest.fixture(scope="module")
def rendered():
    m = sample_motion(4, fps=5.0, speed=0.8)  # 16 cm (6 px) of walking between frames
    cam = Camera(K, R, -R @ EYE, size=(W, H))
    frames, truth, masks = render_motion(m, cam, fps=m.fps, appearance=Appearance(), background="plain",
                                         noise_sigma=0.0, seed=0,
                                         return_masks=True)
    pos, mats = forward_kinematics(m)
    ends_idx, ends = end_site_positions(m, mats, pos)
    return m, frames, truth, masks, pos, ends_idx, ends


def test_background_far_from_the_projected_bones_and_figure_near_them(rendered):
    m, frames, _, masks, pos, ends_idx, ends = rendered
    parents = m.skeleton.parents
    rows, cols = np.mgrid[0:H, 0:W]
    pix = np.stack([cols.ravel(), rows.ravel()], axis=1).astype(float)
    bg_colours = set()
    for f in range(len(frames)):
        uv, z = _project(pos[f])
        euv, ez = _project(ends[f])
        child = [j for j in range(len(parents)) if parents[j] >= 0]
        pa = [parents[j] for j in child]
        a = np.concatenate([uv[pa], uv[ends_idx]])
        b = np.concatenate([uv[child], euv])
        depth = np.concatenate([(z[pa] + z[child]) / 2, (z[ends_idx] + ez) / 2])
        reach = THICK * FOCAL / z.min()  # pixels the thickest part can reach at the nearest depth
        dist = _seg_dist(pix, a, b, depth).reshape(H, W)
        img = frames[f].astype(int)
        far = dist > THICK + AA * depth.max() / FOCAL
        assert far.mean() > 0.5
        colours = np.unique(img[far].reshape(-1, 3), axis=0)
        assert len(colours) == 1, f"frame {f}: {len(colours)} colours where only background can be"
        bg_colours.add(tuple(colours[0]))
        figure = np.any(img != colours[0], axis=-1)
        assert figure.sum() > 200, f"frame {f}: no figure drawn"
        assert not np.any(figure & far)
        # the figure is where the projection says: the pixel under every joint is figure (its own body part
        # or one in front of it)
        ij = np.rint(uv).astype(int)
        assert np.all((ij >= 0) & (ij < [W, H]))
        assert figure[ij[:, 1], ij[:, 0]].all()
        # and as thick as the body: the figure's run through the chest joint, along the image row
        # (the figure is seen from the side: the chest's depth), spans the torso's diameter
        c, r = ij[m.skeleton.names.index("Spine1")]
        row = figure[r]
        lo, hi = c, c
        while lo > 0 and row[lo - 1]:
            lo -= 1
        while hi < W - 1 and row[hi + 1]:
            hi += 1
        assert hi - lo + 1 >= 2 * TORSO * FOCAL / z[m.skeleton.names.index("Spine1")] - 2 * AA
        # the figure's vertical extent is the projected skeleton's, padded at most by the body thickness
        fr = np.nonzero(figure.any(axis=1))[0]
        all_v = np.concatenate([uv[:, 1], euv[:, 1]])
        assert all_v.min() - reach - AA <= fr.min() <= all_v.min() + 2
        assert all_v.max() - 2 <= fr.max() <= all_v.max() + reach + AA
        # the part masks agree with the pixels (but for anti-aliased edge pixels)
        inside = masks[f] >= 0
        assert np.all(figure[inside])
        assert (figure & ~inside).sum() <= 0.25 * inside.sum()
    assert len(bg_colours) == 1  # one plain background for the whole clip


def test_truth_joints_are_the_pinhole_projection(rendered):
    _, _, truth, _, pos, *_ = rendered
    uv, z = _project(pos)
    assert np.allclose(truth["joints2d"], uv, atol=1e-3)
    assert np.allclose(truth["depth"], z, atol=1e-4)
