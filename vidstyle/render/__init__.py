"""Render mocap to video with per-frame ground truth.

>>> from vidstyle.render import Camera, Appearance, render_motion, render_to_file   # doctest: +SKIP
>>> cam = Camera.for_view(motion, view="left", elevation_deg=10, size=(160, 120))     # doctest: +SKIP
>>> frames, truth = render_motion(motion, cam, fps=20, appearance=Appearance.random(3))  # doctest: +SKIP
>>> render_to_file(motion, "clip.mp4", view="front")   # writes clip.mp4 + clip.truth.npz  # doctest: +SKIP

The figure is a set of shaded, tapered capsules derived from any skeleton (see :mod:`.body`), drawn
with a per-pixel z-buffer (:mod:`.raster`) by a static pinhole camera whose azimuth is relative to the
performer's facing direction (:mod:`.camera`), over a plain or textured background, with seeded
Gaussian sensor noise. Everything is deterministic given ``seed``.

Sidecar ``<video stem>.truth.npz`` (F video frames, J joints in file order):

=================  ===============  =========================================================
key                shape / dtype    meaning
=================  ===============  =========================================================
``joints2d``       (F, J, 2) f32    pixel coordinates, x = column, y = row (integer = pixel centre)
``joints3d``       (F, J, 3) f32    world positions (the motion's units, +Y up)
``visible``        (F, J) bool      inside the image and not hidden by another body part (see below)
``depth``          (F, J) f32       camera-space z (distance along the viewing axis)
``joint_names``    (J,) str
``parents``        (J,) int64       parent joint index, -1 for a root
``K``              (3, 3) f64       intrinsics; ``uv ~ K (R X + t)``
``R``, ``t``       (3, 3), (3,)     extrinsics, world -> camera (OpenCV axes: x right, y down)
``azimuth_deg``    ()               view azimuth relative to the performer's facing (0 front, +90 left)
``elevation_deg``  ()               camera elevation (positive = looking down)
``facing_deg``     ()               the performer's median facing angle the azimuth refers to
``fps``            ()               video frame rate
``size``           (2,) int64       (W, H)
``labels``         (F,) str         action label per video frame ("" when none given)
``transition``     (F,) bool        transition flag per video frame
``source_time``    (F,) f64         time in the source motion (seconds) shown by the frame
``part_owner``     (C,) int64       joint index owning each body capsule (the ids in part masks)
``appearance``     () str           JSON of the :class:`Appearance`
``background``     () str           what background was drawn
``seed``           () int64         (files written by :func:`render_to_file` only)
``noise_sigma``    () f64           (files written by :func:`render_to_file` only)
=================  ===============  =========================================================

A joint is *visible* when its pixel lies on the figure and the surface seen there is the joint's own
body part: a capsule containing the joint, or the torso volume when the joint is inside the torso and
in its near half (the spine seen from the side is visible, the far hip and far shoulder are not), or a
surface no further in front of the joint than the thickness of the parts around it.

Part masks are not stored; ``render_motion(..., return_masks=True)`` returns them: (F, H, W) int8, the
joint index owning the front-most body part at each pixel (-1 = background).
"""

# Submodules load on first use (PEP 562), so ``from vidstyle.render import Camera`` (camera geometry:
# numpy only) works without OpenCV; the rasteriser, backgrounds and video output need it.
_LAZY = {
    "Appearance": "appearance",
    "BodyModel": "body", "build_body": "body", "classify_bone": "body", "skeleton_height": "body",
    "Camera": "camera", "parse_view": "camera",
    "SIDECAR_SUFFIX": "core", "load_truth": "core", "render_motion": "core", "render_to_file": "core",
    "sidecar_path": "core",
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "SIDECAR_SUFFIX",
    "Appearance",
    "BodyModel",
    "Camera",
    "build_body",
    "classify_bone",
    "load_truth",
    "parse_view",
    "render_motion",
    "render_to_file",
    "sidecar_path",
    "skeleton_height",
]
