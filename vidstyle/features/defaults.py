"""Validated defaults of the features stage, in one place: :func:`vidstyle.features.extract_videos` and
``vidstyle features`` take theirs from here (a Python user with defaults gets the CLI's features).

The descriptor variant and the points per frame were chosen on the demo's validation performers and a
validation camera (``scripts/validate_recognition.py``; ``pipelines/kickboxing/validation/recognition.json``
holds the scores): scovanner2007 recognises better than the thesis variant, whose rotation to the dominant
orientation discards the direction of motion that tells a jab from a hook. The working rate is the
method's 20 fps; a 120-pixel working height keeps the demo's 160x120 and turns a 1080x1920 phone clip into
68x120. The rest are the thesis' / the released code's values.
"""

from __future__ import annotations

VARIANT = "scovanner2007"      # scovanner2007 | thesis | sift2d
WORKING_FPS = 20.0             # 0 / None: every decoded frame
WORKING_HEIGHT = 120           # 0 / None: the video's own size; else >= 8
MIN_HEIGHT = 8
N_POINTS = 10                  # salient points per frame (validated; thesis 10)
THRESHOLD = 0.05               # silhouette threshold on |f(t+1) - f(t-1)|, intensities in [0, 1]
MIN_DISTANCE = 5.0             # pixels between the points of one frame
FLOW = "dis"                   # dis | dis-ultrafast | dis-medium | farneback
# thesis variant only
SUBREGIONS = 2                 # per axis: 2 -> 2x2x2 -> 256-D
SUBREGION_SIZE = 4.0           # pixels and frames
SMOOTH = 1.0                   # Gaussian sigma of the volume before gradients
