"""``vidstyle annotate``: a local web page to mark transition frames and action segments on videos,
frame-exact (frames are decoded on the server by index; the page never derives a frame from a time), and
to choose each video's performer (a click on the frame: that frame and pixel of the input video).

* :mod:`.session` - the videos a server was started with (one locked reader each) and the annotations
  store (atomic, schema-validated saves; a save is a compare-and-swap on the file under a lock, so stale
  pages and other processes on the same file never lose a save);
* :mod:`.overlays` - recognised labels, 2D poses and pose matches shown over the frames;
* :mod:`.exchange` - export / import: native, Label Studio (TimelineLabels), CVAT for video 1.1, VIA 3;
* :mod:`.server` - the Starlette app (JSON API, security checks) and ``serve``.
"""
