"""The AugMG mocap library: clips that hold the demo's transition poses, but never the transition.

The thesis' premise (5.2) is that "some or all of the poses in the transition motion exist somewhere in
the motion database". The library makes that true for the demo without cheating: it is performed by
*library performers* (their own bodies, styles and seeds, disjoint from every dataset performer) and
contains

- every action as a single-action clip (the motion graph's source and target clips), and
- three context clips per library performer, each holding one transition pose in another context:
  ``dodge`` (slips to either side that sink into the crouch), ``switch`` (a double stance switch whose
  airborne middle is the square-stance hop), ``stop`` (steps forward, then a stop that settles back
  with the guard dropped). None of them goes from one action into another through the pose.

Real CMU clips can be added (``cmu_dir``); they are retargeted onto the library skeleton
(:func:`vidstyle.mocap.retarget.retarget_rest_corrected`), resampled to the library rate, and their
calibration T-pose frame dropped.

Layout of ``DIR``::

    library.json                 manifest: seed, params, performers, one entry per clip
                                 (owner: :mod:`vidstyle.formats.library`)
    clips/<name>.bvh             60 fps, CMU 31-joint skeleton
    clips/<name>.labels.json     per-frame labels (the motion graph reads them beside the BVH)
"""

from __future__ import annotations

import logging
import os
import zlib
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..fileio import staged_dir

log = logging.getLogger(__name__)

CONTEXT_KINDS = {"dodge": "crouch", "switch": "hop", "stop": "step_back"}
"""Library context clip -> the transition pose (:mod:`vidstyle.demo.transitions`) it holds."""


@dataclass(frozen=True)
class LibraryParams:
    seed: int = 0
    performers: int = 3
    action_seconds: float = 6.0
    fps: int = 20  # the rate plans are laid out in (video frames)
    mocap_fps: int = 60
    cmu_clips: int = 0  # CMU clips to add from cmu_dir (0: none; -1: all)

    def validate(self) -> LibraryParams:
        if self.performers < 1:
            raise InputError(f"performers: must be at least 1, got {self.performers}")
        if self.action_seconds < 2:
            raise InputError(f"action_seconds: must be at least 2, got {self.action_seconds}")
        if self.mocap_fps % self.fps:
            raise InputError(f"mocap_fps {self.mocap_fps} must be a multiple of fps {self.fps}")
        return self


def library_performer(params: LibraryParams, index: int):
    """Library performer ``index``: a seed stream no dataset performer uses ([seed, 7919, index])."""
    from .performer import Performer

    rng = np.random.default_rng(np.random.SeedSequence([params.seed, 7919, index]))
    return Performer.random(f"lib{index:02d}", rng, video_fps=params.fps)


def scaled_pose(pose: dict, factor: float, extra: dict | None = None) -> dict:
    """``pose`` moved ``factor`` of the way from the reference guard (1 = the pose itself)."""
    from .actions import GUARD

    out = {}
    for name, value in pose.items():
        g = GUARD[name]
        if isinstance(value, tuple):
            out[name] = tuple(float(gv + factor * (v - gv)) for gv, v in zip(g, value))
        else:
            out[name] = float(g + factor * (value - g))
    out.update(extra or {})
    return out


def _context_plan(kind: str, p, rng: np.random.Generator):
    """Plan of one context clip (segments with their own keys) of library performer ``p``."""
    from .actions import ANKLE, BASE_SECONDS
    from .timeline import PlanStep
    from .transitions import CROUCH_POSE, HOP_POSE, STEP_BACK_POSE

    fps = p.chain.video_fps

    def frames(seconds: float) -> int:
        return max(6, int(round(seconds * fps / p.style.speed)))

    plan = [PlanStep("Guard", frames(0.5))]
    if kind == "dodge":
        for rep in range(4):
            side = 1.0 if rep % 2 == 0 else -1.0
            f = float(rng.uniform(0.75, 1.15))
            slip = scaled_pose(CROUCH_POSE, f, {"px": 0.035 * side, "roll": 7.0 * side, "croll": 5.0 * side})
            plan += [PlanStep("Dodge", frames(0.7), keys=[(0.0, {}), (0.45, slip), (0.55, slip), (1.0, {})]),
                     PlanStep("Guard", frames(float(rng.uniform(0.3, 0.6))))]
    elif kind == "switch":
        switched = {"lf": (0.07, ANKLE, -0.15), "rf": (-0.09, ANKLE, 0.15), "yaw": 22.0, "lfyaw": 40.0,
                    "rfyaw": 12.0, "lh": (-0.36, 0.17, 0.32), "rh": (0.30, 0.20, 0.42)}
        for _ in range(3):
            air = scaled_pose(HOP_POSE, float(rng.uniform(0.8, 1.1)))
            plan += [PlanStep("Switch", frames(1.6), keys=[(0.0, {}), (0.17, air), (0.34, switched), (0.66, switched),
                                                          (0.83, air), (1.0, {})]),
                     PlanStep("Guard", frames(float(rng.uniform(0.3, 0.6))))]
    elif kind == "stop":
        step = int(round(BASE_SECONDS["Step"] / p.style.speed * fps))
        for _ in range(3):
            stop = scaled_pose(STEP_BACK_POSE, float(rng.uniform(0.8, 1.15)))
            plan += [PlanStep("Step", step, 1), PlanStep("Guard", 3), PlanStep("Step", step, 1),
                     PlanStep("Stop", frames(1.2), keys=[(0.0, {}), (0.3, stop), (0.7, stop), (1.0, {})]),
                     PlanStep("Guard", frames(float(rng.uniform(0.3, 0.6)))), PlanStep("Step", step, -1),
                     PlanStep("Guard", 3), PlanStep("Step", step, -1), PlanStep("Guard", frames(0.3))]
    else:
        raise ValueError(f"unknown context kind {kind!r}")
    return plan


def library_jobs(params: LibraryParams) -> list[tuple[LibraryParams, int, str]]:
    from .actions import ACTIONS

    names = [a.lower() for a in ACTIONS] + list(CONTEXT_KINDS)
    return [(params, i, n) for i in range(params.performers) for n in names]


def make_library_clip(job: tuple[LibraryParams, int, str]):
    """(name, Motion, labels, entry) of one library clip. Module level for the parallel path."""
    from .actions import ACTIONS
    from .timeline import build_take, single_action_plan

    params, index, what = job
    p = library_performer(params, index)
    rng = np.random.default_rng(np.random.SeedSequence([params.seed, 7919, index, zlib.crc32(what.encode()), 1]))
    ratio = params.mocap_fps // params.fps
    actions = {a.lower(): a for a in ACTIONS}
    if what in actions:
        plan = single_action_plan(p, actions[what], int(round(params.action_seconds * params.fps)), rng)
    else:
        plan = _context_plan(what, p, rng)
    take = build_take(p, plan, rng, video_fps=params.fps, ratio=ratio)
    name = f"{p.id}_{what}"
    entry = {"name": name, "performer": p.id, "kind": "action" if what in actions else "context",
             "holds_pose": CONTEXT_KINDS.get(what), "frames": take.motion.n_frames}
    return name, take.motion, take.labels, entry


def make_library(out: str | os.PathLike, params: LibraryParams, cmu_dir: str | os.PathLike | None = None,
                 overwrite: bool = False, jobs: int = -1, scheduler: str | None = None) -> Path:
    """Write the library into ``out`` (see the module docstring); returns the manifest path."""
    from .dataset import label_document
    from ..formats.library import library_document, write_library
    from ..mocap import write_bvh
    from ..parallel import parallel_map

    params.validate()
    out = Path(out)
    with staged_dir(out, overwrite) as tmp:
        (tmp / "clips").mkdir()
        results = parallel_map(make_library_clip, library_jobs(params), jobs=jobs, scheduler=scheduler,
                               description="library clips")
        entries = []
        for name, motion, labels, entry in results:
            bvh = f"clips/{name}.bvh"
            write_bvh(motion, tmp / bvh)
            _write_clip_labels(tmp / f"clips/{name}.labels.json",
                               label_document(labels, float(params.mocap_fps), [], bvh=bvh, performer=entry["performer"]))
            entries.append({**entry, "bvh": bvh, "labels": f"clips/{name}.labels.json"})
        if cmu_dir is not None and params.cmu_clips != 0:
            entries += _add_cmu(Path(cmu_dir), tmp, params, results[0][1].skeleton)
        write_library(tmp / "library.json", library_document(
            asdict(params), [library_performer(params, i).to_dict() for i in range(params.performers)], entries))
    log.info("wrote %s: %d clips", out, len(entries))
    return out / "library.json"


def _write_clip_labels(path: Path, doc: dict) -> None:
    """A clip's labels through their owner; the classes are the demo's plus the clip's own (Dodge, Switch,
    Stop, CMU labels), so the file validates."""
    from ..formats.labels import write_labels

    classes = list(doc["classes"])
    classes += [c for c in dict.fromkeys(doc["labels"]) if c not in classes]
    write_labels(path, {**doc, "classes": classes})


def _add_cmu(cmu_dir: Path, tmp: Path, params: LibraryParams, skeleton) -> list[dict]:
    from .dataset import label_document
    from ..mocap import read_bvh, write_bvh
    from ..motiongraph.graph import has_tpose_first_frame
    from ..motiongraph.labels import LabelBook
    from ..mocap.retarget import retarget_rest_corrected

    files = sorted(cmu_dir.glob("*.bvh"))
    if not files:
        raise InputError(f"{cmu_dir}: no CMU .bvh clips")
    if params.cmu_clips > 0:
        files = files[: params.cmu_clips]
    book = LabelBook()
    if (cmu_dir / "clips.csv").is_file():
        book.load(cmu_dir / "clips.csv")
    entries = []
    for f in files:
        m = read_bvh(f)
        if has_tpose_first_frame(m):
            m = m[1:]
        m = retarget_rest_corrected(m.resample(params.mocap_fps), skeleton)
        labels = book.frame_labels(f, m.n_frames) if book.has(f) else ["other"] * m.n_frames
        name = f"cmu_{f.stem}"
        bvh = f"clips/{name}.bvh"
        write_bvh(m, tmp / bvh)
        _write_clip_labels(tmp / f"clips/{name}.labels.json", label_document(labels, float(params.mocap_fps), [],
                                                                             bvh=bvh, source=str(f)))
        entries.append({"name": name, "performer": f"cmu{f.stem.split('_')[0]}", "kind": "cmu", "holds_pose": None,
                        "frames": m.n_frames, "bvh": bvh, "labels": f"clips/{name}.labels.json", "source": str(f)})
    return entries
