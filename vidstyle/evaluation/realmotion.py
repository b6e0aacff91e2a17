"""The real-motion split (issue 28, item 5): real mocap clips whose description names an action the demo's
classes cover, rendered at cameras and with looks the demo never trained on, scored by *action family*.

The demo's recognizers learn eight classes from procedural performers. A user's performer moves as a real
person does, so the question that matters is coarse and strict: is a real punch recognised as a punch,
and real footwork (walking, stepping) as neither punch nor kick? Families: ``punch`` (Jab, Hook,
Uppercut), ``kick`` (LowKick, RoundhouseKick), ``other`` (every other class: Guard, Defense, Step).

A clip list is a CSV ``file,family[,frames[,start,end]]`` (paths relative to the CSV's folder or to
``root``; ``family`` one of :data:`FAMILIES`; ``frames`` ``all`` (default) or ``strikes``, the action
frames of :func:`~vidstyle.evaluation.realmocap.action_frames` — the frames of a punch clip where an arm
is extended forward; ``start`` / ``end`` motion frames, default the whole clip after the conversion's
T-pose frame 0). Each clip is rendered from every camera (:func:`~vidstyle.render.render_to_file`, a
random look per clip and camera, seeded) and every recognizer given is run on the render: a 3D SIFT
recognizer on its features, a pose-sequence recognizer on the poses a pose backend finds (or on the true
keypoints: ``pose_input="true"``), and their late fusion (:mod:`vidstyle.recognition.fusion`) when both
are given with a fusion weight. A scored frame is right when the family of its smoothed label is the
clip's.

Nothing here trains, tunes or selects: the models are used as given. The lists for the pipeline's
validation and test (``pipelines/kickboxing/realmotion_{val,test}.csv``) share no clip and no subject.
"""

from __future__ import annotations

import csv
import logging
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, ParameterError
from .realmocap import KICKS, PUNCHES, StrikeCamera, StrikeEvalParams, action_frames, work_directory

log = logging.getLogger(__name__)

FAMILIES = ("punch", "kick", "other")
FRAME_SETS = ("all", "strikes")
#: cameras none of the demo's training videos use: the unseen-camera dataset's two (30 and 150 degrees at
#: 30, the held-out "moon" texture) and an oblique one from the performer's right
TEST_CAMERAS: tuple[StrikeCamera, ...] = (
    StrikeCamera(30.0, 30.0, "texture:moon"),
    StrikeCamera(150.0, 30.0, "texture:moon"),
    StrikeCamera(-45.0, 20.0, "texture"),
)
#: the validation camera: from behind the performer's left, low
VAL_CAMERAS: tuple[StrikeCamera, ...] = (StrikeCamera(120.0, 20.0, "texture:moon"),)


def family_of(label: str) -> str:
    return "punch" if label in PUNCHES else "kick" if label in KICKS else "other"


@dataclass(frozen=True)
class RealClip:
    """One clip of a real-motion list (see the module docstring)."""

    bvh: Path
    family: str
    frames: str = "all"
    start: int = 1
    end: int | None = None

    @property
    def name(self) -> str:
        return self.bvh.stem


def read_clip_list(path: str | os.PathLike, root: str | os.PathLike | None = None) -> list[RealClip]:
    """The clips of a CSV ``file,family[,frames[,start,end]]`` (a header row starting ``file`` is
    skipped; see the module docstring); a missing file or a bad row is an :class:`InputError` naming the
    row."""
    path = Path(path)
    base = Path(root) if root is not None else path.parent
    try:
        rows = list(csv.reader(path.read_text(encoding="utf-8").splitlines()))
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"{path}: cannot read the clip list ({e.__class__.__name__})") from None
    clips = []
    for n, row in enumerate(rows, 1):
        row = [c.strip() for c in row]
        if not row or not row[0] or row[0].startswith("#") or row[:2] == ["file", "family"]:
            continue
        if len(row) < 2 or len(row) > 5:
            raise InputError(f"{path}:{n}: expected file,family[,frames[,start,end]], got {len(row)} fields")
        fam = row[1]
        if fam not in FAMILIES:
            raise InputError(f"{path}:{n}: family must be one of {', '.join(FAMILIES)}, got {fam!r}")
        frames = row[2] if len(row) > 2 and row[2] else "all"
        if frames not in FRAME_SETS:
            raise InputError(f"{path}:{n}: frames must be one of {', '.join(FRAME_SETS)}, got {frames!r}")
        try:
            start = int(row[3]) if len(row) > 3 and row[3] else 1
            end = int(row[4]) if len(row) > 4 and row[4] else None
        except ValueError:
            raise InputError(f"{path}:{n}: start and end must be integers") from None
        if start < 0 or (end is not None and end <= start):
            raise InputError(f"{path}:{n}: bad frame range {start}..{end}")
        bvh = (base / row[0]) if not Path(row[0]).is_absolute() else Path(row[0])
        if not bvh.is_file():
            raise InputError(f"{path}:{n}: {bvh}: file not found")
        clips.append(RealClip(bvh, fam, frames, start, end))
    if not clips:
        raise InputError(f"{path}: no clip")
    return clips


@dataclass
class Recognizers:
    """What is run on each render: a 3D SIFT recognizer and/or a pose-sequence recognizer (models as
    loaded by :func:`vidstyle.recognition.recognizer.load_model`), and the pose weight of their fusion
    (None: no fusion; several weights: one fused recognizer ``fusion@W`` each), smoothed by the pose
    recognizer's smoother with the fused scores to the power ``fusion_emission_weight`` (None:
    :data:`vidstyle.recognition.defaults.FUSION_EMISSION_WEIGHT`; several: the first keeps the fused
    recognizers' names, each other power ``P`` adds ``<name>^P``)."""

    sift: Any = None
    pose: Any = None
    fusion_weight: float | Sequence[float] | None = None
    fusion_emission_weight: float | Sequence[float] | None = None

    def powers(self) -> list[float]:
        """The fused scores' powers in the smoother (:data:`~vidstyle.recognition.defaults.FUSION_EMISSION_WEIGHT`
        when none is given)."""
        from ..recognition.fusion import fusion_power

        p = self.fusion_emission_weight
        if p is None or isinstance(p, (int, float)):
            return [fusion_power(p)]
        return [fusion_power(x) for x in p]

    def fusions(self) -> dict[str, tuple[float, float]]:
        """Fused recognizer name -> (pose weight, power of the fused scores)."""
        powers = self.powers()
        out = {}
        for name, w in self.weights().items():
            out[name] = (w, powers[0])
            out.update({f"{name}^{p:g}": (w, p) for p in powers[1:]})
        return out

    def weights(self) -> dict[str, float]:
        """Fusion name -> pose weight: ``fusion`` for one weight, ``fusion@W`` for each of several."""
        w = self.fusion_weight
        if w is None:
            return {}
        if isinstance(w, (int, float)):
            return {"fusion": float(w)}
        return {f"fusion@{float(x):g}": float(x) for x in w}

    def names(self) -> list[str]:
        out = [n for n, m in (("sift", self.sift), ("pose", self.pose)) if m is not None]
        return out + list(self.fusions())

    def check(self) -> None:
        if self.sift is None and self.pose is None:
            raise ParameterError("model", "give a 3D SIFT or a pose-sequence recognizer")
        if self.fusion_weight is not None:
            if self.sift is None or self.pose is None:
                raise ParameterError("fusion_weight", "fusion needs both a 3D SIFT and a pose-sequence recognizer")
            for w in self.weights().values():
                if not 0.0 <= w <= 1.0:
                    raise ParameterError("fusion_weight", f"must be in [0, 1], got {w}")
            self.powers()  # each resolved (and checked) by fusion_power


def _outputs(recs: Recognizers, motion, video: Path, truth: dict, params: StrikeEvalParams,
             work: Path, name: str) -> dict[str, dict]:
    """Each recognizer's ``predict_video`` of one render (same frames: the video's decoded frames)."""
    from .realmocap import pose_prediction

    out = {}
    if recs.sift is not None:
        from ..features.extract import process_video
        from ..features.salient import SalientParams
        from ..recognition.io import load_features

        feats = work / f"{name}.npz"
        process_video(video, feats, variant=params.variant, salient=SalientParams(n_points=params.points))
        out["sift"] = recs.sift.predict_video(load_features(feats))
    if recs.pose is not None:
        out["pose"] = pose_prediction(recs.pose, motion, video, truth, params)
    for fname, (w, power) in recs.fusions().items():
        from ..recognition.fusion import smooth_fused

        po, so = out["pose"], out["sift"]
        n = min(len(po["raw"]), len(so["raw"]))
        out[fname] = smooth_fused(recs.pose, po["scores"][:n], recs.sift, so["scores"][:n], w, power)
    return out


def _score(classes, pred: np.ndarray, mask: np.ndarray, family: str) -> dict[str, Any]:
    fam = np.array([family_of(str(classes[i])) for i in pred])
    n = min(len(fam), len(mask))
    fam, m = fam[:n], mask[:n]
    counts = {f: int(np.sum(fam[m] == f)) for f in FAMILIES}
    k = int(m.sum())
    return {"frames": k, "family_counts": counts, "family_accuracy": counts[family] / k if k else None}


def evaluate_real_motion(clips: Sequence[RealClip], recs: Recognizers,
                         cameras: Sequence[StrikeCamera] = TEST_CAMERAS, params: StrikeEvalParams | None = None,
                         seed: int = 0, work_dir: str | os.PathLike | None = None) -> dict[str, Any]:
    """The real-motion metrics document (kind ``vidstyle.metrics.real_motion``): per clip, camera and
    recognizer the family counts of the scored frames and the share in the clip's family; overall per
    recognizer the frame-weighted family accuracy, per family and per camera, and the share of
    (clip, camera) videos whose majority family is right."""
    from ..formats.truth import read_truth
    from ..logutil import progress
    from ..mocap import read_bvh
    from ..render import Appearance, render_to_file

    recs.check()
    params = params or StrikeEvalParams()
    names = recs.names()
    rows = []
    with work_directory(work_dir, "vidstyle-realmotion-") as work:
        jobs = [(ci, clip, ki, cam) for ci, clip in enumerate(clips) for ki, cam in enumerate(cameras)]
        motions: dict[int, tuple] = {}
        for ci, clip, ki, cam in progress(jobs, "real-motion renders"):
            if ci not in motions:
                full = read_bvh(clip.bvh)
                end = full.n_frames if clip.end is None else min(clip.end, full.n_frames)
                if not 0 <= clip.start < end:
                    raise InputError(f"{clip.bvh}: the frame range {clip.start}..{end} is empty")
                motion = full[clip.start:end]
                mask = action_frames(motion) if clip.frames == "strikes" else np.ones(motion.n_frames, bool)
                motions = {ci: (motion, mask)}
            motion, mask = motions[ci]
            look = int(np.random.SeedSequence([seed, ci, ki, 3]).generate_state(1)[0])
            rseed = int(np.random.SeedSequence([seed, ci, ki, 2]).generate_state(1)[0])
            appearance = Appearance.random(look)
            name = f"{clip.name}_{cam.name}"
            video = work / f"{name}.mp4"
            side = render_to_file(motion, video, view=cam.azimuth_deg, size=tuple(params.size), fps=params.fps,
                                  elevation_deg=cam.elevation_deg, appearance=appearance,
                                  background=cam.background, noise_sigma=params.noise_sigma, seed=rseed)
            truth = read_truth(side).to_arrays()
            src = np.clip(np.rint(truth["source_time"] * motion.fps).astype(np.int64), 0, motion.n_frames - 1)
            vmask = mask[src]
            outs = _outputs(recs, motion, video, truth, params, work, name)
            for rname in names:
                model = recs.sift if rname == "sift" else recs.pose
                rows.append({"clip": clip.name, "family": clip.family, "frames_set": clip.frames,
                             "camera": cam.name, "recognizer": rname, "appearance": appearance.to_dict(),
                             **_score(model.classes_, outs[rname]["smoothed"], vmask, clip.family)})
    return {"seed": int(seed), "params": params.to_dict(), "recognizers": names,
            "fusion_weight": recs.fusion_weight,
            "fusion_emission_weight": (None if recs.fusion_weight is None
                                       else powers[0] if len(powers := recs.powers()) == 1 else powers),
            "cameras": [c.to_dict() for c in cameras],
            "clips": [{"clip": c.name, "bvh": str(c.bvh), "family": c.family, "frames": c.frames,
                       "start": c.start, "end": c.end} for c in clips],
            "rows": rows, "overall": summarise(rows, names)}


def summarise(rows: list[dict], names: Sequence[str]) -> dict[str, Any]:
    """Per recognizer: frame-weighted family accuracy overall, per family, per camera; majority-family
    accuracy over the (clip, camera) videos."""
    out = {}
    for r in names:
        mine = [x for x in rows if x["recognizer"] == r and x["frames"]]

        def acc(sel):
            n = sum(x["frames"] for x in sel)
            return sum(x["family_counts"][x["family"]] for x in sel) / n if n else None

        out[r] = {
            "family_accuracy": acc(mine),
            "frames": sum(x["frames"] for x in mine),
            "per_family": {f: acc([x for x in mine if x["family"] == f]) for f in FAMILIES
                           if any(x["family"] == f for x in mine)},
            "per_camera": {c: acc([x for x in mine if x["camera"] == c]) for c in dict.fromkeys(x["camera"] for x in mine)},
            "video_majority_accuracy": (float(np.mean([max(x["family_counts"], key=x["family_counts"].get) == x["family"]
                                                        for x in mine])) if mine else None),
        }
    return out


def real_motion_table(doc: dict[str, Any]) -> str:
    """Markdown: one row per recognizer with the overall and per-family accuracy."""
    fams = [f for f in FAMILIES if any(f in v["per_family"] for v in doc["overall"].values())]
    head = "| recognizer | family accuracy | " + " | ".join(fams) + " | videos right (majority) |"
    lines = [head, "|" + "---|" * (3 + len(fams))]

    def pct(v):
        return "—" if v is None else f"{100 * v:.1f} %"

    for r, v in doc["overall"].items():
        lines.append(f"| {r} | {pct(v['family_accuracy'])} | " + " | ".join(pct(v["per_family"].get(f)) for f in fams)
                     + f" | {pct(v['video_majority_accuracy'])} |")
    return "\n".join(lines)
