"""Whole video to 3D motion by temporally coherent search of a mocap library (Tautges 2012, seed 001).

- :mod:`.library`: the library clips on one skeleton with their 2D index (AugMG's
  :class:`~vidstyle.augmg.index.PoseIndex`) and per indexed frame the pose, root height, foot contacts
  and label.
- :mod:`.olng`: the online lazy neighbourhood graph that rates each frame's nearest library neighbours
  by the cost of the best temporally coherent library path leading to them (chapter 3).
- :mod:`.subsequence`: the whole-sequence alternative (section 4.3): windows of the video matched to
  library subsequences by subsequence DTW and chained through a subsequence graph into per-frame
  library frames and cross-fade weights.
- :mod:`.core`: :class:`~.core.Reconstructor`, from a video's 2D poses to a blended, smoothed 3D motion
  with its root placed by :mod:`.camera` (the static pinhole camera from 2D keypoints) and planted feet
  locked (:mod:`.metrics` also holds the contacts and the 3D error metrics).
- :mod:`.footlock`: planted feet pinned by two-bone IK of the legs (:func:`~.footlock.pin_feet`).
- :mod:`.run`: ``vidstyle reconstruct`` as a library call (BVH, ``reconstruction.json``, labels, preview).
"""
