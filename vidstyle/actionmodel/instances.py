"""Action instances cut from labelled mocap, their foot contacts and their motion primitives.

* An **instance** is a maximal run of frames carrying one action label (``min_frames`` or more; frames
  labelled ``unlabelled``, ``Guard`` or ``Step`` -- :data:`SKIP_LABELS` -- are not actions), taken from
  clips loaded by :func:`vidstyle.motiongraph.graph.load_clips` (demo ``.labels.json`` beside the BVH,
  label CSV ``file,label[,start,end]`` or CMU ``clips.csv``). Clips of one joint layout are retargeted
  onto the first clip's skeleton (:func:`vidstyle.mocap.retarget.retarget`: rotations kept, root path
  scaled by leg length), as ``build-graph`` does.
* **Contacts** per clip frame: the left / right ankle is near the floor and slow
  (:func:`vidstyle.reconstruct.metrics.foot_contacts` on the clip's keypoints), then runs shorter than
  ``min_run`` frames are absorbed by their neighbours (a one-frame flicker is not a keyframe).
* **Keyframes and primitives** (Du 3.1, Motion Graphs++): a keyframe is a frame where the contact state
  ``(left, right)`` changes; the segments between consecutive keyframes (sharing the keyframe) are the
  instance's primitives, each with its contact state. An instance whose contacts never change (a jab) is
  one primitive. The *signature* of an instance is its sequence of contact states; instances of one
  label with the same signature are segmented alike, which is what lets their primitives be aligned one
  to one (:class:`~vidstyle.actionmodel.model.ActionModel` models the most common signature of a label).
* Every instance is put in a **canonical frame**: rotated about the vertical so that the character
  faces +Z at its first frame, and moved so that its root starts above the origin (heights unchanged).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..mocap import Motion

SKIP_LABELS = ("unlabelled", "Guard", "Step", "other")


@dataclass
class Instance:
    """One action instance (canonical frame) and its segmentation."""

    label: str
    motion: Motion
    contacts: np.ndarray  # (F, 2) bool, left / right ankle planted
    keyframes: list[int]  # instance frames where a primitive starts (0 first); primitives end at the next
    states: list[tuple[bool, bool]]  # contact state of each primitive
    source: str = ""
    start: int = 0  # first frame in the source clip
    performer: str = ""

    @property
    def n_frames(self) -> int:
        return self.motion.n_frames

    @property
    def signature(self) -> tuple[tuple[bool, bool], ...]:
        return tuple(self.states)

    def bounds(self) -> list[tuple[int, int]]:
        """(first, last) instance frame of every primitive, inclusive (neighbours share the keyframe)."""
        ks = list(self.keyframes) + [self.n_frames - 1]
        return [(ks[k], ks[k + 1]) for k in range(len(self.keyframes))]


def clean_runs(mask: np.ndarray, min_run: int) -> np.ndarray:
    """``mask`` (F,) bool with every run shorter than ``min_run`` given its neighbours' value (shortest
    runs first; a mask that is all one short run is kept)."""
    m = np.asarray(mask, dtype=bool).copy()
    if min_run <= 1 or len(m) == 0:
        return m
    while True:
        d = np.flatnonzero(np.diff(m.astype(np.int8))) + 1
        starts = np.concatenate([[0], d])
        ends = np.concatenate([d, [len(m)]])
        if len(starts) == 1:
            return m
        lengths = ends - starts
        k = int(np.argmin(lengths))
        if lengths[k] >= min_run:
            return m
        m[starts[k]:ends[k]] = not m[starts[k]]


def clip_contacts(motion: Motion, min_run: int = 3, height_tol: float | None = None,
                  speed_tol: float | None = None) -> np.ndarray:
    """(F, 2) planted left / right ankle of a whole clip (module text)."""
    from ..mocap.keypoints import keypoint_positions
    from ..reconstruct.metrics import foot_contacts

    pts = keypoint_positions(motion)
    c = foot_contacts(pts, motion.fps, height_tol=height_tol, speed_tol=speed_tol)
    return np.stack([clean_runs(c[:, 0], min_run), clean_runs(c[:, 1], min_run)], axis=1)


def segment(contacts: np.ndarray, min_primitive: int = 3) -> tuple[list[int], list[tuple[bool, bool]]]:
    """Keyframes (first frames of primitives; 0 first) and contact states of the primitives of an
    instance with ``contacts`` (F, 2). A change that would leave a primitive shorter than
    ``min_primitive`` frames is ignored (its frames join the previous primitive)."""
    F = len(contacts)
    keys, states = [0], [tuple(bool(x) for x in contacts[0])]
    for t in range(1, F):
        s = tuple(bool(x) for x in contacts[t])
        if s != states[-1] and t - keys[-1] >= min_primitive - 1 and F - 1 - t >= min_primitive - 1:
            keys.append(t)
            states.append(s)
    # merge neighbours that ended up with the same state
    k2, s2 = [keys[0]], [states[0]]
    for k, s in zip(keys[1:], states[1:]):
        if s != s2[-1]:
            k2.append(k)
            s2.append(s)
    return k2, s2


def canonical(motion: Motion) -> Motion:
    """``motion`` facing +Z at its first frame with its root above the origin (heights kept)."""
    out = motion.normalize_facing(0, 0.0, origin=True)
    return out


def label_runs(labels: Sequence[str]) -> list[tuple[str, int, int]]:
    """(label, start, end exclusive) of every maximal run of one label."""
    out = []
    s = 0
    for t in range(1, len(labels) + 1):
        if t == len(labels) or labels[t] != labels[s]:
            out.append((labels[s], s, t))
            s = t
    return out


@dataclass
class InstanceSet:
    """Instances of labelled clips on one skeleton (the first clip's), and where they came from."""

    instances: list[Instance]
    skeleton: object
    fps: float
    sources: list[str] = field(default_factory=list)

    def labels(self) -> list[str]:
        return sorted({i.label for i in self.instances})

    def of(self, label: str) -> list[Instance]:
        return [i for i in self.instances if i.label == label]


def cut_instances(clips, min_frames: int = 6, min_run: int = 3, min_primitive: int = 3,
                  skip: Sequence[str] = SKIP_LABELS, reference=None) -> InstanceSet:
    """Instances of :class:`vidstyle.motiongraph.graph.Clip` s (module text). ``reference``: the skeleton
    to retarget onto (default the first clip's). Clips must share one frame rate."""
    from ..mocap.retarget import retarget

    clips = list(clips)
    if not clips:
        raise InputError("clips: no clips given")
    reference = clips[0].motion.skeleton if reference is None else reference
    fps = clips[0].motion.fps
    out: list[Instance] = []
    for c in clips:
        if abs(c.motion.fps - fps) > 1e-6:
            raise InputError(f"{c.path or c.name}: frame rate {c.motion.fps:g} differs from the first clip's {fps:g}; "
                             "resample the clips to one rate")
        m, _ = retarget(c.motion, reference, c.path or c.name)
        contacts = clip_contacts(m, min_run)
        performer = c.name.split("_")[0]
        for label, s, e in label_runs(c.labels):
            if label in skip or e - s < min_frames:
                continue
            inst_motion = canonical(m[s:e])
            keys, states = segment(contacts[s:e], min_primitive)
            out.append(Instance(label, inst_motion, contacts[s:e].copy(), keys, states, c.path or c.name, s, performer))
    return InstanceSet(out, reference, fps, [c.path or c.name for c in clips])


def load_labelled(paths: Sequence[str | os.PathLike], labels: Sequence[str | os.PathLike] = ()):
    """Clips of ``paths``: BVH files / directories (labels beside them or in ``labels``), or label CSVs
    ``file,label[,start,end]`` whose ``file`` column names the BVH files (relative to the CSV's folder)."""
    import csv

    from ..motiongraph.graph import load_clips

    bvhs: list[Path] = []
    label_files = [Path(p) for p in labels]
    for p in map(Path, paths):
        if p.suffix.lower() == ".csv":
            if not p.is_file():
                raise InputError(f"{p}: clip list not found")
            try:
                with open(p, newline="", encoding="utf-8") as f:
                    rows = list(csv.DictReader(f))
            except (UnicodeDecodeError, csv.Error) as e:
                raise InputError(f"{p}: not a readable CSV ({e})") from None
            if not rows or "file" not in rows[0] or "label" not in rows[0]:
                raise InputError(f"{p}: expected columns file,label[,start,end]")
            seen = set()
            for i, r in enumerate(rows, start=2):
                name = (r.get("file") or "").strip()
                if not name:
                    raise InputError(f"{p}: line {i}: empty file")
                f = Path(name) if Path(name).is_absolute() else p.parent / name
                if not f.is_file():
                    raise InputError(f"{p}: line {i}: clip {name} not found")
                if f not in seen:
                    seen.add(f)
                    bvhs.append(f)
            label_files.append(p)
        else:
            bvhs.append(p)
    return load_clips(bvhs, label_files)
