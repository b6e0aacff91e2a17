"""Camera placement relative to the performer, projection conventions, view parsing."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vidstyle.mocap import global_positions
from vidstyle.render import Camera, parse_view
from vidstyle.render.camera import circular_median, intrinsics
from vidstyle.render.samples import sample_motion


def test_parse_view():
    assert parse_view("front") == 0.0
    assert parse_view("LEFT") == 90.0
    assert parse_view("right") == -90.0
    assert parse_view("back") == 180.0
    assert parse_view("-45") == -45.0
    assert parse_view(30) == 30.0
    for bad in ("sideways", "nan", "inf", ""):
        with pytest.raises(ValueError):
            parse_view(bad)


def test_intrinsics_vertical_fov_and_pixel_centres():
    K = intrinsics((160, 120), vfov_deg=40.0)
    assert K[0, 0] == K[1, 1]
    assert math.degrees(2 * math.atan(60.0 / K[1, 1])) == pytest.approx(40.0)
    assert (K[0, 2], K[1, 2]) == (79.5, 59.5)


def test_circular_median_wraps():
    a = np.radians([179.0, -179.0, 178.0, -178.0, 180.0])
    assert abs(abs(circular_median(a)) - math.pi) < math.radians(1.5)


@pytest.mark.parametrize("facing_deg", [0.0, 90.0, -135.0])
def test_views_are_relative_to_facing(facing_deg):
    m = sample_motion(10, speed=0.0).rotate_about_vertical(math.radians(facing_deg))
    facing = np.array([math.sin(math.radians(facing_deg)), 0.0, math.cos(math.radians(facing_deg))])
    left_of_performer = np.cross(np.array([0.0, 1.0, 0.0]), facing)  # +X when facing +Z
    for view, expect in (("front", facing), ("left", left_of_performer), ("right", -left_of_performer),
                         ("back", -facing)):
        cam = Camera.for_view(m, view=view, elevation_deg=0.0)
        target = cam.extra["target"]
        d = cam.center - target
        d[1] = 0
        d /= np.linalg.norm(d)
        assert np.allclose(d, expect, atol=1e-6), view
        # the camera looks at the target: it projects to the image centre
        uv, z = cam.project(target)
        assert np.allclose(uv, [(cam.width - 1) / 2, (cam.height - 1) / 2], atol=1e-6) and z > 0
    assert Camera.for_view(m, view="left").azimuth_deg == 90.0


def test_left_view_performer_faces_image_left():
    # seen from their left side, a performer facing +Z looks towards the image's left
    m = sample_motion(10, speed=0.0)
    cam = Camera.for_view(m, view="left")
    pos = global_positions(m)[0]
    head, hips = pos[m.skeleton.index("Head")], pos[0]
    uv0, _ = cam.project(hips)
    uv1, _ = cam.project(hips + np.array([0.0, 0.0, 0.5]))
    assert uv1[0] < uv0[0]
    # +Y is up in the image
    assert cam.project(head)[0][1] < uv0[1]


def test_elevation_looks_down():
    m = sample_motion(10, speed=0.0)
    cam = Camera.for_view(m, view="front", elevation_deg=30.0)
    assert cam.center[1] > cam.extra["target"][1]
    assert cam.R[2, 1] < 0  # viewing direction points downwards
    with pytest.raises(ValueError):
        Camera.for_view(m, elevation_deg=90.0)


@pytest.mark.parametrize("view", ["front", "left", 30.0, 200.0])
def test_fit_keeps_whole_clip_inside_image(view):
    m = sample_motion(60, speed=1.5)
    cam = Camera.for_view(m, view=view, size=(160, 120))
    uv, z = cam.project(global_positions(m))
    assert np.all(z > 0)
    assert uv[..., 0].min() >= 0 and uv[..., 0].max() <= 159
    assert uv[..., 1].min() >= 0 and uv[..., 1].max() <= 119
    # and is not needlessly far: the clip spans a good part of the image in one direction
    span = max(np.ptp(uv[..., 0]) / 160, np.ptp(uv[..., 1]) / 120)
    assert span > 0.5


def test_explicit_distance():
    m = sample_motion(5, speed=0.0)
    cam = Camera.for_view(m, view="front", elevation_deg=0.0, distance=7.0)
    assert np.linalg.norm(cam.center - cam.extra["target"]) == pytest.approx(7.0)
    with pytest.raises(ValueError):
        Camera.for_view(m, distance=-1.0)


def test_rotation_is_orthonormal_and_projection_matches_formula(rng):
    m = sample_motion(5)
    cam = Camera.for_view(m, view=37.0, elevation_deg=12.0, size=(320, 240))
    assert np.allclose(cam.R @ cam.R.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(cam.R) == pytest.approx(1.0)
    X = rng.normal(size=(20, 3)) + cam.extra["target"]
    uv, z = cam.project(X)
    xc = X @ cam.R.T + cam.t
    h = xc @ cam.K.T
    assert np.allclose(uv, h[:, :2] / h[:, 2:], atol=1e-9)
    assert np.allclose(z, xc[:, 2])


def test_camera_imports_and_projects_without_opencv():
    """Camera geometry is numpy only: with cv2 unimportable, Camera still loads, places and projects."""
    import subprocess
    import sys

    code = (
        "import sys; sys.modules['cv2'] = None\n"
        "from vidstyle.render import Camera\n"
        "from vidstyle.render.samples import sample_motion\n"
        "cam = Camera.for_view(sample_motion(5), 'left')\n"
        "uv, z = cam.project([[0.0, 1.0, 0.0]])\n"
        "assert z[0] > 0 and 0 <= uv[0, 0] < cam.width\n"
        "assert sys.modules['cv2'] is None\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
