"""Whole video to 3D motion by temporally coherent search of a mocap library (Tautges 2012, seed 001).

Built so far: :mod:`vidstyle.reconstruct.olng`, the online lazy neighbourhood graph that rates each
frame's nearest library neighbours by the cost of the best temporally coherent library path leading to
them; :mod:`vidstyle.reconstruct.subsequence`, the whole-sequence alternative (section 4.3): windows of
the video matched to library subsequences by subsequence DTW and chained through a subsequence graph
into per-frame library frames and cross-fade weights. The ``vidstyle reconstruct`` command (pose
blending, reprojection fit, BVH) builds on them.
"""
