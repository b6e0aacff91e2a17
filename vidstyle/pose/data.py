"""Labelled pose frames rendered from mocap: demo performers and CMU clips at chosen azimuths and
elevations, with random looks and backgrounds (:mod:`vidstyle.render`), keypoints from
:mod:`vidstyle.mocap.keypoints` projected by the render camera.

A *spec* names one short clip excerpt and one camera; :func:`render_spec` turns it into frames.
Specs are rendered through :func:`vidstyle.parallel.parallel_map` (the project's one parallel path).

Split for evaluation (nothing held out is ever used for training, tuning or selection):

- demo performers: training ``p00..p{n-1}``; validation performers 30..; test performers 50..
  (different seeds);
- CMU subjects: training the subjects listed in ``TRAIN_CMU_SUBJECTS``, validation those in
  ``VAL_CMU_SUBJECTS``, test all the others;
- azimuths: training every 30 degrees from 0 (0, 30, ..., 330) plus jitter of at most 5 degrees;
  validation and test: 15 + 30 k degrees (never closer than 10 degrees to a training azimuth).

The validation split (``scripts/validate_pose.py`` chooses the defaults on it) and the test split
(``vidstyle evaluate pose``) share no performer and no CMU subject.

The viewpoint label of a frame is the nearest of front (0), left (+90), right (-90), back (180). An
azimuth on a boundary between two views (45 degrees from both centres, within ``BOUNDARY_TOL``) has no
single true view: the held-out grid 15 + 30 k puts a third of its frames there (+-45, +-135), and the
nearest-view label of those frames is a tie broken by the order of ``VIEW_NAMES``.
:func:`acceptable_views` gives both neighbours for such an azimuth, which the viewpoint evaluation
uses (:func:`vidstyle.evaluation.pose.viewpoint_scores`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..mocap.keypoints import keypoint_positions

VIEW_NAMES = ("front", "left", "right", "back")
VIEW_AZ = {"front": 0.0, "left": 90.0, "right": -90.0, "back": 180.0}
TRAIN_CMU_SUBJECTS = ("01", "02", "05", "06", "07", "09", "10", "12", "13", "14", "15", "16")
VAL_CMU_SUBJECTS = ("08",)
FIRST_PERFORMER = {"train": 0, "val": 30, "test": 50}
#: demo performers each split can take without reaching the next split's (test: no upper limit)
MAX_PERFORMERS = {"train": FIRST_PERFORMER["val"], "val": FIRST_PERFORMER["test"] - FIRST_PERFORMER["val"]}
FIGURE_FRACTION = 0.7  # standing figure height / frame height at the nominal camera distance
BOUNDARY_TOL = 5.0  # degrees: an azimuth this close to a view boundary (+-45, +-135) belongs to both views


def _view_distance(azimuth_deg: float, view: str) -> float:
    return abs((azimuth_deg - VIEW_AZ[view] + 180.0) % 360.0 - 180.0)


def view_of(azimuth_deg: float) -> str:
    a = (azimuth_deg + 180.0) % 360.0 - 180.0
    return min(VIEW_NAMES, key=lambda v: _view_distance(a, v))


def acceptable_views(azimuth_deg: float, tol: float = BOUNDARY_TOL) -> tuple[str, ...]:
    """The views a camera at ``azimuth_deg`` can rightly be called: the nearest one, and at a boundary
    (within ``tol`` degrees of 45 degrees from two view centres) its neighbour too; nearest first."""
    d = sorted((_view_distance(azimuth_deg, v), i, v) for i, v in enumerate(VIEW_NAMES))
    return (d[0][2],) + ((d[1][2],) if d[1][0] <= 45.0 + tol + 1e-9 else ())


@dataclass(frozen=True)
class Spec:
    source: str  # "<registered source>:<index>" (e.g. "demo:3", register_source) or a BVH path
    start_s: float  # excerpt start (seconds into the source motion)
    seconds: float
    azimuth: float
    elevation: float
    seed: int
    fps: float = 5.0
    size: tuple[int, int] = (160, 120)
    scale: float = 1.0  # figure size relative to the nominal (FIGURE_FRACTION of the frame height)
    proportions: tuple[float, float, float] = (1.0, 1.0, 1.0)  # bone-length factors: arms, legs, trunk+head


@dataclass
class Sample:
    """One labelled frame: gray image (H, W) uint8, keypoints (15, 2) px, view, azimuth, source,
    optionally the BGR frame, and the clip it belongs to."""

    image: np.ndarray
    keypoints: np.ndarray
    view: str
    azimuth: float
    source: str
    bgr: np.ndarray | None = None
    clip: int = -1  # the spec's seed: frames of one rendered clip (one camera, look and background)


#: training sources by name (:func:`register_source`): a spec's ``source`` "<name>:<index>" is rendered
#: from ``fn(index, seconds, seed)``; any other source is a BVH path
_SOURCES: dict[str, Callable] = {}


def register_source(name: str, fn: Callable) -> None:
    """Make ``"<name>:<index>"`` a training source: ``fn(index, seconds, seed)`` returns its
    :class:`vidstyle.mocap.Motion` (at least ``seconds`` long). The demo performers (``"demo:<i>"``,
    :func:`make_specs`' ``n_demo``) are registered by :mod:`vidstyle.demo.pose_sources` when
    :mod:`vidstyle.demo` is imported; ``fn`` must be a module-level function (parallel workers get it
    pickled by reference)."""
    if not name or ":" in name or not callable(fn):
        raise ValueError(f"a training source needs a name without ':' and a function, got {name!r}, {fn!r}")
    _SOURCES[name] = fn


def registered_sources() -> tuple[str, ...]:
    return tuple(_SOURCES)


def source_loader(source: str) -> Callable | None:
    """The registered function of ``source`` ("<name>:<index>"), None for a BVH path; an unregistered
    name with an integer index is an :class:`InputError` naming it."""
    name, sep, rest = source.partition(":")
    if sep and name in _SOURCES:
        return _SOURCES[name]
    if sep and rest.isdigit() and not Path(source).exists():
        raise InputError(f"training source {source!r}: no source {name!r} is registered "
                         f"(registered: {', '.join(_SOURCES) or 'none'}; the demo performers: import vidstyle.demo)")
    return None


def load_source(source: str, seed: int = 0, seconds: float = 30.0, loader: Callable | None = None):
    """Motion of a training source: a registered one (``loader``, default looked up by name) or a BVH file."""
    from ..mocap import read_bvh

    loader = loader or source_loader(source)
    if loader is not None:
        return loader(int(source.partition(":")[2]), seconds, seed)
    m = read_bvh(source)
    return m[1:]  # frame 0 of the CMU files is a T-pose


def with_proportions(motion, arms: float, legs: float, trunk: float):
    """``motion`` on a skeleton whose bones are scaled: arm bones (below the shoulders) by ``arms``, leg
    bones (below the hips) by ``legs``, the others (spine, neck, head, shoulder and hip offsets) by
    ``trunk``; the root's path by ``legs`` (its height follows the legs). Another body's proportions
    under the same motion, for training and test renders."""
    from ..mocap import Motion
    from ..mocap.keypoints import keypoint_joints
    from ..mocap.skeleton import Skeleton

    if (arms, legs, trunk) == (1.0, 1.0, 1.0):
        return motion
    sk = motion.skeleton
    kj = keypoint_joints(sk)
    limb_root = {kj[f"{side}_shoulder"].joint: arms for side in ("left", "right")}
    limb_root.update({kj[f"{side}_hip"].joint: legs for side in ("left", "right")})

    def bone_factor(j: int) -> float:  # the bone ending at j: a limb's when a limb root is above j
        p = int(sk.parents[j])
        while p >= 0:
            if p in limb_root:
                return limb_root[p]
            p = int(sk.parents[p])
        return trunk

    factor = np.array([legs if sk.parents[j] < 0 else bone_factor(j) for j in range(sk.n_joints)])
    ends = {j: np.asarray(o, dtype=np.float64) * limb_root.get(j, factor[j] if sk.parents[j] >= 0 else trunk)
            for j, o in sk.end_sites.items()}
    skel = Skeleton(sk.names, sk.parents, sk.offsets * factor[:, None], sk.channels, ends)
    return Motion(skel, motion.rotations, motion.translations * factor[None, :, None], fps=motion.fps)


def render_spec(spec: Spec, keep_bgr: bool = False, loader: Callable | None = None) -> list[Sample]:
    """Render one spec into samples (one per rendered frame); ``loader``: its source's function
    (default: looked up in the registry of this process)."""
    from ..render import Appearance, Camera, render_motion
    from ..render.body import skeleton_height

    rng = np.random.default_rng(spec.seed)
    motion = load_source(spec.source, seed=0, seconds=max(30.0, spec.start_s + spec.seconds + 1), loader=loader)
    a = int(spec.start_s * motion.fps)
    b = min(motion.n_frames, a + max(2, int(spec.seconds * motion.fps)))
    if b - a < 2:
        a, b = 0, min(motion.n_frames, 2)
    motion = with_proportions(motion[a:b].resample(spec.fps), *spec.proportions)
    _W, H = spec.size
    height = skeleton_height(motion.skeleton)
    probe = Camera.for_view(motion, view=spec.azimuth, elevation_deg=spec.elevation, size=spec.size)
    distance = probe.focal * height / (FIGURE_FRACTION * spec.scale * H)
    cam = Camera.for_view(motion, view=spec.azimuth, elevation_deg=spec.elevation, size=spec.size,
                          distance=distance)
    look = Appearance.random(rng)
    bg = ["plain", "texture", "texture:brick", "texture:grass", "texture:gravel"][int(rng.integers(5))]
    if bg == "plain":
        bg = "plain:" + ",".join(str(int(v)) for v in rng.integers(40, 230, 3))
    frames, _truth = render_motion(motion, cam, fps=motion.fps, appearance=look, background=bg,
                                   noise_sigma=float(rng.uniform(1.0, 4.0)), seed=spec.seed)
    kp3 = keypoint_positions(motion)
    uv, _ = cam.project(kp3)
    import cv2

    out = []
    for f in range(len(frames)):
        g = cv2.cvtColor(frames[f], cv2.COLOR_BGR2GRAY)
        out.append(Sample(g, uv[f].astype(np.float32), view_of(spec.azimuth), float(spec.azimuth), spec.source,
                          frames[f] if keep_bgr else None, int(spec.seed)))
    return out


def cmu_clips(cmu_dir: str | Path | None, subjects: tuple[str, ...] | None, exclude: tuple[str, ...] = ()) -> list[str]:
    if cmu_dir is None or not Path(cmu_dir).is_dir():
        return []
    files = sorted(Path(cmu_dir).glob("*.bvh"))
    out = []
    for f in files:
        subj = f.stem.split("_")[0]
        if subjects is not None and subj not in subjects:
            continue
        if subj in exclude:
            continue
        out.append(str(f))
    return out


#: camera elevations (degrees, looking down) and figure sizes (:attr:`Spec.scale`) drawn by default
ELEVATION_RANGE = (0.0, 20.0)
SCALE_RANGE = (0.9, 1.1)


def _check_range(name: str, r: tuple[float, float], lo: float, hi: float) -> tuple[float, float]:
    a, b = (float(v) for v in r)
    if not (lo <= a <= b <= hi):
        raise ValueError(f"{name} must be LOW,HIGH with {lo:g} <= LOW <= HIGH <= {hi:g}, got {a:g},{b:g}")
    return a, b


def make_specs(split: str, n_demo: int, n_cmu: int, views_per_clip: int, seed: int,
               cmu_dir: str | Path | None, fps: float = 4.0, seconds: float = 2.0, *,
               elevation: tuple[float, float] = ELEVATION_RANGE, scale: tuple[float, float] = SCALE_RANGE,
               proportions: float = 0.0, other_clips: list[str] | tuple[str, ...] = ()) -> list[Spec]:
    """Specs for ``split`` ``"train"``, ``"val"`` or ``"test"`` (see the module docstring for what is
    held out). Each clip is seen from ``views_per_clip`` cameras, each at an elevation drawn from
    ``elevation`` (degrees) with a figure size drawn from ``scale``; ``proportions`` > 0 also draws bone
    lengths (arms, legs, trunk: each a factor uniform in 1 +- ``proportions``,
    :func:`with_proportions`). ``other_clips``: BVH files rendered as well, as given (another skeleton
    or subjects the splits do not name; the caller keeps them out of training when they test). The
    defaults draw the specs this module always drew (same seed, same specs)."""
    if split not in FIRST_PERFORMER:
        raise ValueError(f"split must be train, val or test, got {split!r}")
    elevation = _check_range("elevation", elevation, -60.0, 80.0)
    scale = _check_range("scale", scale, 0.1, 3.0)
    if not 0.0 <= proportions < 0.5:
        raise ValueError(f"proportions must be in [0, 0.5), got {proportions}")
    if n_demo < 0 or n_demo > MAX_PERFORMERS.get(split, n_demo):
        raise ValueError(f"{split} split: n_demo must be between 0 and {MAX_PERFORMERS.get(split, n_demo)} "
                         f"(more would take the next split's performers), got {n_demo}")
    rng = np.random.default_rng(np.random.SeedSequence([seed, {"train": 0, "test": 1, "val": 2}[split]]))
    demo_ids = list(range(FIRST_PERFORMER[split], FIRST_PERFORMER[split] + n_demo))
    if split == "train":
        clips = cmu_clips(cmu_dir, TRAIN_CMU_SUBJECTS)
        base = np.arange(0, 360, 30.0)
        jitter = 5.0
    else:
        clips = (cmu_clips(cmu_dir, VAL_CMU_SUBJECTS) if split == "val"
                 else cmu_clips(cmu_dir, None, exclude=TRAIN_CMU_SUBJECTS + VAL_CMU_SUBJECTS))
        base = np.arange(15, 360, 30.0)
        jitter = 0.0
    if clips:
        clips = [clips[i] for i in rng.permutation(len(clips))[:n_cmu]]
    sources = [f"demo:{i}" for i in demo_ids] + clips + [str(c) for c in other_clips]
    specs = []
    for si, src in enumerate(sources):
        for v in range(views_per_clip):
            az = float(base[(si * views_per_clip + v + int(rng.integers(len(base)))) % len(base)])
            az += float(rng.uniform(-jitter, jitter))
            start = float(rng.uniform(0.0, 6.0 if src.startswith("demo:") else 2.0))
            el = float(rng.uniform(*elevation))
            spec_seed = int(rng.integers(2**31))
            size = float(rng.uniform(*scale))
            props = ((1.0, 1.0, 1.0) if proportions == 0.0
                     else tuple(float(x) for x in rng.uniform(1.0 - proportions, 1.0 + proportions, 3)))
            specs.append(Spec(src, start, seconds, (az + 180.0) % 360.0 - 180.0, el, spec_seed, fps, (160, 120),
                              size, props))
    return specs


@dataclass
class _RenderJob:
    spec: Spec
    keep_bgr: bool
    loader: Callable | None  # resolved in the calling process: workers need no registry of their own


def _render_job(job: _RenderJob) -> list[Sample]:
    return render_spec(job.spec, keep_bgr=job.keep_bgr, loader=job.loader)


def render_samples(specs: list[Spec], jobs: int = -1, scheduler: str | None = None,
                   keep_bgr: bool = False) -> list[Sample]:
    from ..parallel import parallel_map

    work = [_RenderJob(spec, keep_bgr, source_loader(spec.source)) for spec in specs]
    parts = parallel_map(_render_job, work, jobs=jobs, scheduler=scheduler, description="rendering pose frames")
    return [s for p in parts for s in p]


def spec_dict(spec: Spec) -> dict:
    return asdict(spec)

