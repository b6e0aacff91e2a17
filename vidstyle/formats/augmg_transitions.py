"""``transitions.json``: per annotated transition, the poses and 3D transitions the report animates
(``vidstyle evaluate augmg --transitions``).

Schema (``kind`` = ``"vidstyle.augmg_transitions"``, ``schema_version`` 1)::

    {"kind": "vidstyle.augmg_transitions", "schema_version": 1,
     "source": "model",                   # the 2D source these entries used (model, blazepose, gt, noisy)
     "fps": 20.0,                         # rate of the transition frames below
     "entries": [{"video": "p03_perf0_front", "frame": 170,          # the mark (video id, frame)
                  "from": "Defense", "to": "Jab", "kind": "hop",     # its action pair, true transition kind
                  "accepted": true,                                  # enhancement accepted (else plain kept)
                  "match_cost": 0.8, "enhanced_cost": 3.1,  # null: no window fits
                  "reference_clip": "lib01_switch", "reference_time": 2.15,
                  "viewpoint_deg": 0.0,
                  "pose2d": [[x, y], ...],          # (15, 2) estimated pose of the marked frame, video pixels
                  "library2d": [[u, v], ...],       # (15, 2) reference library pose projected at the viewpoint
                  "truth": [[[x, y, z], ...], ...], # (F, 15, 3) the performer's true transition (CMU units)
                  "plain": [...], "augmg": [...],   # (F, 15, 3) the plain and the AugMG transition
                  "plain_mm": 83.0, "augmg_mm": 61.2}]}

Keypoints are in :data:`vidstyle.mocap.keypoints.KEYPOINTS` order.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ._base import Fields, check_header, header, read_json_document, write_checked

KIND = "vidstyle.augmg_transitions"
SCHEMA_VERSION = 1


@dataclass
class TransitionEntry:
    video: str
    frame: int
    from_action: str
    to_action: str
    kind: str
    accepted: bool
    match_cost: float
    enhanced_cost: float | None  # None: no candidate's windows fit
    reference_clip: str
    reference_time: float
    viewpoint_deg: float
    pose2d: np.ndarray  # (15, 2)
    library2d: np.ndarray  # (15, 2)
    truth: np.ndarray  # (F, 15, 3)
    plain: np.ndarray
    augmg: np.ndarray
    plain_mm: float
    augmg_mm: float

    def to_dict(self) -> dict:
        def arr(a: np.ndarray, nd: int = 3) -> list:
            return np.round(np.asarray(a, dtype=np.float64), nd).tolist()

        return {"video": self.video, "frame": self.frame, "from": self.from_action, "to": self.to_action,
                "kind": self.kind, "accepted": bool(self.accepted), "match_cost": float(self.match_cost),
                "enhanced_cost": None if self.enhanced_cost is None else float(self.enhanced_cost), "reference_clip": self.reference_clip,
                "reference_time": float(self.reference_time), "viewpoint_deg": float(self.viewpoint_deg),
                "pose2d": arr(self.pose2d, 2), "library2d": arr(self.library2d, 4), "truth": arr(self.truth),
                "plain": arr(self.plain), "augmg": arr(self.augmg), "plain_mm": float(self.plain_mm),
                "augmg_mm": float(self.augmg_mm)}


@dataclass
class AugmgTransitions:
    source: str
    fps: float
    entries: list[TransitionEntry] = field(default_factory=list)

    def to_dict(self) -> dict:
        return {**header(KIND, SCHEMA_VERSION), "source": self.source, "fps": float(self.fps),
                "entries": [e.to_dict() for e in self.entries]}


def _parse(doc, path) -> AugmgTransitions:
    check_header(doc, path, KIND, (SCHEMA_VERSION,))
    top = Fields(doc, path)
    entries = []
    for i, raw in enumerate(top.list("entries")):
        f = Fields(raw, path, f"entries[{i}]")
        truth = f.array("truth", (None, 15, 3))
        n = len(truth)
        plain, augmg = f.array("plain", (n, 15, 3)), f.array("augmg", (n, 15, 3))
        entries.append(TransitionEntry(
            f.str("video", nonempty=True), f.int("frame", min=0), f.str("from", nonempty=True),
            f.str("to", nonempty=True), f.str("kind", nonempty=True), f.bool("accepted"),
            f.number("match_cost", min=0.0), f.number("enhanced_cost", min=0.0, required=False), f.str("reference_clip"),
            f.number("reference_time", min=0.0), f.number("viewpoint_deg"), f.array("pose2d", (15, 2)),
            f.array("library2d", (15, 2)), truth, plain, augmg, f.number("plain_mm", min=0.0),
            f.number("augmg_mm", min=0.0)))
    return AugmgTransitions(top.str("source", nonempty=True), top.number("fps", positive=True), entries)


def read_augmg_transitions(path: str | os.PathLike) -> AugmgTransitions:
    """Read and validate ``path``; :class:`FormatError` names the file and the field."""
    return _parse(read_json_document(path), path)


def write_augmg_transitions(path: str | os.PathLike, doc: AugmgTransitions) -> None:
    """Validate ``doc`` (as the reader would) and write it atomically."""
    write_checked(path, doc.to_dict(), _parse, "augmg transitions")
