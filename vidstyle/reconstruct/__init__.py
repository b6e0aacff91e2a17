"""Whole video to 3D motion by temporally coherent search of a mocap library (Tautges 2012, seed 001).

Built so far: :mod:`vidstyle.reconstruct.olng`, the online lazy neighbourhood graph that rates each
frame's nearest library neighbours by the cost of the best temporally coherent library path leading to
them; :mod:`vidstyle.reconstruct.camera`, the static pinhole camera (per-frame translation, focal
length) from 2D keypoints and camera-axis poses; :mod:`vidstyle.reconstruct.metrics`, the 3D error
metrics (MPJPE, PA-MPJPE, acceleration error, foot skate) and foot contacts. The ``vidstyle reconstruct`` command (pose blending, reprojection fit, BVH) builds on it.
"""
