"""AugMG's validated defaults: the values the library functions (:func:`vidstyle.augmg.match_poses`,
:func:`vidstyle.augmg.augment`, :func:`vidstyle.augmg.augment.augment_graph`,
:func:`vidstyle.evaluation.augmg.evaluate`) and the CLI options (``vidstyle match-pose``, ``augment``,
``evaluate augmg``) default to, so a Python user and a CLI user get the same numbers.

The matching and placement values and the acceptance thresholds were chosen on the validation performers
by ``scripts/validate_augmg.py`` and are recorded in ``pipelines/kickboxing/validation/augmg.json``
(never on the test performers); ``tests/test_augmg_defaults.py`` fails when they and that file part.
The thresholds are that file's values rounded to three decimals (the values the pipeline's committed
results were made with).
"""

from __future__ import annotations

from ..pose.defaults import MAX_CONTEXT as POSE_MAX_CONTEXT

# --- chosen on the validation performers (pipelines/kickboxing/validation/augmg.json) --------------
#: library segment through the reference point: fixed, nodes or adaptive
SEGMENT = "fixed"
#: video frames either side of a mark matched with it (temporal coherence)
CONTEXT = 2
#: weight bones by the pose's confidence scores
SCORES = False
#: also weight bones by their foreshortening
FORESHORTENING = True
#: placement of the library segment on the performer: first, both or drift
PLACE = "drift"
#: library poses aligned for the placement: ends or nodes
ANCHOR = "nodes"
#: fraction of the transition, centred on the reference pose, that follows the segment with full weight
HOLD = 0.2
#: zoom factors of the pose stage's multi-scale inference (``vidstyle pose --scales``); None: one scale
POSE_SCALES: list[float] | None = [1.0, 1.2, 1.4]
#: candidate reference points per query / mark (validation.json's ``k``)
K = 10
#: acceptance thresholds per 2D source (``model`` = pictorial structures, ``blazepose``, ``gt``,
#: ``noisy``; a source not named has none): reject an enhancement whose match cost exceeds
#: MAX_MATCH_COST, whose enhanced distance (mocap length units) exceeds MAX_ENH_COST, or whose reference
#: pose lies less than MIN_GAIN (mm) from the plain transition's middle frame
MAX_MATCH_COST: dict[str, float] = {"blazepose": 0.637}
MAX_ENH_COST: dict[str, float] = {"model": 4.833}
MIN_GAIN: dict[str, float] = {"model": 83.322, "gt": 90.371, "noisy": 111.448}

# --- fixed by design (not searched by the validation) ----------------------------------------------
#: azimuths the library is projected at (360 / N_VIEWS apart)
N_VIEWS = 12
#: camera elevation of the projection (degrees) of ``match-pose`` / ``augment``
ELEVATION_DEG = 10.0
#: index every STRIDE-th library frame (``match-pose``)
STRIDE = 3
#: video rate of the poses' frame numbers when the marks do not say (``match-pose --coherence``, augment)
VIDEO_FPS = 20.0
#: enhancement nodes on each side of a mark (departures x arrivals edges)
EDGES_PER_SIDE = 3
#: enhancement edge cost as a fraction of the cheapest plain blend of that action pair
ENHANCEMENT_COST = 0.5
#: window (frames) of the enhanced distance in ``evaluate augmg``
ENH_WINDOW = 9
#: library half-segment as a fraction of the transition's half-length (``segment="fixed"``)
SEGMENT_SCALE = 1.0
#: 2D noise sigma of the ``noisy`` source, as a fraction of the torso length
NOISE = 0.05

# --- bounds of the parameters (checked by the commands and the library; refused beyond them) ---------
#: most video frames either side of a mark (``--context``; also less than the video's frame count): the
#: pose stage's bound (the poses of a mark's neighbours come from ``vidstyle pose --context``)
MAX_CONTEXT = POSE_MAX_CONTEXT
#: most azimuths (``--views``: one per degree)
MAX_VIEWS = 360
#: most candidates per query / mark (``--k``)
MAX_K = 1000
#: most enhancement nodes on each side of a mark (``--edges-per-side``)
MAX_EDGES_PER_SIDE = 1000
#: most library frames skipped between indexed ones (``--stride``)
MAX_STRIDE = 10000
