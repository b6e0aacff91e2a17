"""2D pose of video frames (method 2 of the thesis, AugMG's first step).

- :mod:`.dt`: generalised distance transform (Felzenszwalb-Huttenlocher lower envelope) + brute force.
- :mod:`.features`: dense gradient-orientation cells of rotated copies of a frame.
- :mod:`.model`: pictorial structures for one viewpoint (rotated part templates, tree prior, exact
  min-sum inference).
- :mod:`.estimator`: viewpoint-specific + generic models and the viewpoint SVMs (``train-pose``).
- :mod:`.blazepose`: MediaPipe BlazePose backend mapped onto the same 15 keypoints.
- :mod:`.data`: labelled frames rendered from mocap; :mod:`.run`: poses of a video;
  its evaluation harness (strict PCP, PCK, viewpoint confusion) is :mod:`vidstyle.evaluation.pose`.
"""
