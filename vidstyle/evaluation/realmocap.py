"""Real human motion through the demo-trained recognizer: which strike frames come out as punches?

The demo performers are procedural; the users are not. :func:`evaluate_strikes` renders a real mocap
clip of punches (CMU ``02_05``, "punch/strike") with :mod:`vidstyle.render` - the renderer the demo
dataset uses, its looks and backgrounds - from several cameras, extracts features and runs a trained
recognizer on each video, and counts how many of the clip's *action frames* are recognised as punches
(Jab, Hook, Uppercut) rather than kicks (LowKick, RoundhouseKick) or anything else.

Which frames are action frames is decided from the mocap alone, never by the recognizer
(:func:`action_frames`, parameters :class:`StrikeRule`): a frame is a strike frame when an arm is

* extended: hand-to-shoulder distance >= ``extension_min`` (0.8) of the arm's length (upper arm +
  forearm; a bent guard arm is about 0.5-0.65), and
* reaching out: the hand lies >= ``reach_min`` (0.6) arm lengths from the shoulder horizontally,
  in front of the body: along the pelvis' facing direction (from the hip joints), so a straight arm
  hanging at the side or raised sideways (the end of the clip) is not a strike,

kept only in runs of at least ``min_seconds`` (0.05 s), runs closer than ``merge_seconds`` (0.1 s)
merged. Nothing of it is learned or tuned on the recognizer's output; the rule, its plot and its
result for ``02_05`` are committed (``pipelines/kickboxing/strikes/``) so it can be checked by eye.

The clip never trains, tunes or selects anything: the recognizer is used as given.
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import math
import os
import tempfile
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError

log = logging.getLogger(__name__)

PUNCHES: tuple[str, ...] = ("Jab", "Hook", "Uppercut")
KICKS: tuple[str, ...] = ("LowKick", "RoundhouseKick")
GOAL = 0.80


@dataclass(frozen=True)
class StrikeRule:
    """Thresholds of the action-frame rule (see the module docstring)."""

    extension_min: float = 0.8
    reach_min: float = 0.6
    min_seconds: float = 0.05
    merge_seconds: float = 0.1
    arms: tuple[str, ...] = ("Left", "Right")

    def validate(self) -> StrikeRule:
        if not 0 < self.extension_min <= 1:
            raise ParameterError("extension_min", f"must be in (0, 1], got {self.extension_min}")
        if not -1 <= self.reach_min <= 1:
            raise ParameterError("reach_min", f"must be in [-1, 1], got {self.reach_min}")
        if self.min_seconds < 0 or self.merge_seconds < 0:
            raise ParameterError("min_seconds", "min_seconds and merge_seconds must be >= 0")
        if not self.arms or any(a not in ("Left", "Right") for a in self.arms):
            raise ParameterError("arms", f"must be Left and/or Right, got {self.arms}")
        return self

    def to_dict(self) -> dict:
        d = asdict(self)
        d["arms"] = list(self.arms)
        return d


def _joint(names: Sequence[str], name: str) -> int:
    try:
        return list(names).index(name)
    except ValueError:
        raise ParameterError("motion", f"the skeleton has no joint {name!r} (a CMU 31-joint skeleton is needed)") from None


def arm_signals(motion) -> dict[str, dict[str, np.ndarray]]:
    """Per arm (``"Left"``, ``"Right"``): ``extension`` (F,) hand-shoulder distance over arm length and
    ``reach`` (F,) the hand's horizontal distance in front of the shoulder along the pelvis' facing
    direction, in arm lengths. CMU joint names (``LeftArm`` = shoulder, ``LeftForeArm`` = elbow,
    ``LeftHand`` = wrist; ``LeftUpLeg`` / ``RightUpLeg`` = hips)."""
    from ..mocap import forward_kinematics

    pos, _ = forward_kinematics(motion, return_matrices=False)
    names = motion.skeleton.names
    across = pos[:, _joint(names, "LeftUpLeg")] - pos[:, _joint(names, "RightUpLeg")]
    fwd = np.cross(across, np.array([0.0, 1.0, 0.0]))
    fwd[:, 1] = 0.0
    fwd /= np.maximum(np.linalg.norm(fwd, axis=1, keepdims=True), 1e-9)
    out = {}
    for side in ("Left", "Right"):
        s, e, h = (pos[:, _joint(names, side + j)] for j in ("Arm", "ForeArm", "Hand"))
        length = np.linalg.norm(e - s, axis=1) + np.linalg.norm(h - e, axis=1)
        length = np.maximum(length, 1e-9)
        d = h - s
        out[side] = {"extension": np.linalg.norm(d, axis=1) / length,
                     "reach": np.einsum("fk,fk->f", d, fwd) / length}
    return out


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    m = np.concatenate([[False], np.asarray(mask, bool), [False]])
    d = np.flatnonzero(m[1:] != m[:-1])
    return [(int(a), int(b)) for a, b in zip(d[::2], d[1::2])]


def clean_mask(mask: np.ndarray, fps: float, min_seconds: float, merge_seconds: float) -> np.ndarray:
    """``mask`` with gaps shorter than ``merge_seconds`` filled, then runs shorter than ``min_seconds``
    dropped."""
    mask = np.asarray(mask, bool).copy()
    runs = _runs(mask)
    gap = round(merge_seconds * fps)
    for (_, b0), (a1, _) in itertools.pairwise(runs):
        if a1 - b0 < gap:
            mask[b0:a1] = True
    keep = round(min_seconds * fps)
    for a, b in _runs(mask):
        if b - a < keep:
            mask[a:b] = False
    return mask


def action_frames(motion, rule: StrikeRule | None = None) -> np.ndarray:
    """(F,) bool: the frames of ``motion`` that the rule calls strike frames (module docstring)."""
    rule = (rule or StrikeRule()).validate()
    sig = arm_signals(motion)
    raw = np.zeros(motion.n_frames, bool)
    for side in rule.arms:
        raw |= (sig[side]["extension"] >= rule.extension_min) & (sig[side]["reach"] >= rule.reach_min)
    return clean_mask(raw, motion.fps, rule.min_seconds, rule.merge_seconds)


def segments(mask: np.ndarray) -> list[dict[str, int]]:
    """Runs of True as ``{"start", "end"}`` (end exclusive)."""
    return [{"start": a, "end": b} for a, b in _runs(mask)]


def action_labels_document(mask: np.ndarray, fps: float, bvh: str, rule: StrikeRule) -> dict:
    """The action frames as a :mod:`vidstyle.formats.labels` document (classes ``Rest`` / ``Strike``,
    one label per motion frame, ``events`` the strikes) with the rule's parameters under ``rule``."""
    labels = ["Strike" if m else "Rest" for m in mask]
    events = [{"label": "Strike", **s} for s in segments(mask)]
    transitions = [i for i in range(1, len(labels)) if labels[i] != labels[i - 1]]
    return {"bvh": bvh, "fps": float(fps), "classes": ["Rest", "Strike"], "labels": labels, "events": events,
            "transitions": transitions, "rule": rule.to_dict(),
            "method": "vidstyle.recognition.realmocap.action_frames"}


def plot_action_frames(motion, mask: np.ndarray, rule: StrikeRule, path: str | os.PathLike,
                       title: str = "") -> None:
    """The rule's signals (extension and reach of both arms, the thresholds) over time with the action
    frames shaded, written atomically to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..fileio import atomic_path

    sig = arm_signals(motion)
    t = np.arange(motion.n_frames) / motion.fps
    fig, axes = plt.subplots(2, 1, figsize=(14, 5), sharex=True)
    for ax, key, thr in ((axes[0], "extension", rule.extension_min), (axes[1], "reach", rule.reach_min)):
        for side, colour in (("Left", "tab:blue"), ("Right", "tab:red")):
            ax.plot(t, sig[side][key], colour, lw=1, label=f"{side} arm")
        ax.axhline(thr, color="k", ls="--", lw=0.8, label=f"threshold {thr:g}")
        for s in segments(mask):
            ax.axvspan(s["start"] / motion.fps, s["end"] / motion.fps, color="orange", alpha=0.3, lw=0)
        ax.set_ylabel(f"arm {key}\n(arm lengths)")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="lower right", fontsize=8, ncol=3)
    axes[1].set_xlabel("seconds (shaded: action frames)")
    axes[0].set_title(title or f"action frames: {int(mask.sum())} of {len(mask)}")
    fig.tight_layout()
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=80, format="png")
    plt.close(fig)


# --------------------------------------------------------------------------- cameras
@dataclass(frozen=True)
class StrikeCamera:
    """One camera of the evaluation: azimuth relative to the performer's median facing (degrees, 0 =
    front, +90 = their left), elevation (degrees, looking down) and the background
    (:func:`vidstyle.render.background.make_background` spec)."""

    azimuth_deg: float
    elevation_deg: float
    background: str

    @property
    def name(self) -> str:
        az = f"{self.azimuth_deg:g}".replace("-", "m").replace(".", "p")
        return f"az{az}_el{self.elevation_deg:g}_{self.background.replace(':', '-')}"

    def to_dict(self) -> dict:
        return {"name": self.name, **asdict(self)}


#: the demo's training cameras (front, left, right at 10 degrees, its "texture" backgrounds), the
#: unseen-camera dataset's cameras (30 and 150 degrees at 30, the held-out "moon" texture) and an
#: oblique camera from the performer's right (-45 at 20 degrees)
DEFAULT_CAMERAS: tuple[StrikeCamera, ...] = (
    StrikeCamera(0.0, 10.0, "texture"),
    StrikeCamera(90.0, 10.0, "texture"),
    StrikeCamera(-90.0, 10.0, "texture"),
    StrikeCamera(30.0, 30.0, "texture:moon"),
    StrikeCamera(150.0, 30.0, "texture:moon"),
    StrikeCamera(-45.0, 20.0, "texture"),
)


def parse_cameras(spec: str) -> tuple[StrikeCamera, ...]:
    """``"AZ:EL:BACKGROUND,..."`` (background may itself hold a colon: ``30:30:texture:moon``)."""
    cams = []
    for item in (s.strip() for s in spec.split(",")):
        if not item:
            continue
        parts = item.split(":", 2)
        if len(parts) != 3:
            raise ParameterError("cameras", f"expected AZIMUTH:ELEVATION:BACKGROUND, got {item!r}")
        try:
            az, el = float(parts[0]), float(parts[1])
        except ValueError:
            raise ParameterError("cameras", f"azimuth and elevation must be numbers in {item!r}") from None
        if not (math.isfinite(az) and math.isfinite(el) and abs(el) < 89):
            raise ParameterError("cameras", f"bad azimuth or elevation in {item!r}")
        cams.append(StrikeCamera(az, el, parts[2]))
    if not cams:
        raise ParameterError("cameras", "give at least one camera")
    if len({c.name for c in cams}) != len(cams):
        raise ParameterError("cameras", "a camera is repeated")
    return tuple(cams)


# --------------------------------------------------------------------------- evaluation
@dataclass(frozen=True)
class StrikeEvalParams:
    """How the clip is filmed and described (defaults: the demo dataset's and the pipeline's)."""

    fps: float = 20.0
    size: tuple[int, int] = (160, 120)
    noise_sigma: float = 2.0
    variant: str = "scovanner2007"
    points: int = 10
    start: int = 1  # first motion frame (frame 0 of a CMU file is the conversion's T-pose)
    stop: int | None = None  # motion frame after the last (None: the end)
    pose_input: str = "ps"  # a pose-sequence recognizer's input: a pose backend on the video, or "true" 2D

    def __post_init__(self) -> None:
        if self.pose_input not in POSE_INPUTS:
            raise ParameterError("pose_input", f"must be one of {', '.join(POSE_INPUTS)}, got {self.pose_input!r}")
        if self.start < 0:
            raise ParameterError("start", f"must be >= 0, got {self.start}")
        if self.stop is not None and self.stop <= self.start:
            raise ParameterError("stop", f"must be 0 (the end) or above start ({self.start}), got {self.stop}")
        if self.points < 1:
            raise ParameterError("points", f"must be >= 1, got {self.points}")

    @classmethod
    def for_model(cls, model_path: str | os.PathLike, variant: str | None = None, points: int | None = None,
                  start: int = 1, stop: int | None = None, pose_input: str = "ps") -> StrikeEvalParams:
        """Checked parameters for the recognizer ``model_path``: ``variant`` / ``points`` default to those
        its training features were extracted with (its header), else scovanner2007 / 10; ``stop`` 0 or
        None is the end of the clip."""
        if variant is None or points is None:
            from ..recognition.recognizer import read_header

            fp = read_header(model_path).get("features_params") or {}
            variant = variant or fp.get("variant", "scovanner2007")
            points = points if points is not None else int((fp.get("salient") or {}).get("n_points", 10))
        return cls(variant=variant, points=points, start=start, stop=stop or None, pose_input=pose_input)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["size"] = list(self.size)
        return d


POSE_INPUTS = ("ps", "blazepose", "true")


def pose_prediction(model, motion, video: Path, truth: dict, params: StrikeEvalParams) -> dict:
    """``predict_video`` of a pose-sequence recognizer on a rendered clip: from the poses a pose backend
    finds in ``video`` (``params.pose_input`` ps / blazepose), or from the motion's true keypoints at the
    frames the video shows, projected through its camera (``"true"``, the upper bound)."""
    from ..recognition.posefeatures import PoseTrack, track_from_poses

    n = len(truth["source_time"])
    if params.pose_input == "true":
        from ..mocap.keypoints import keypoint_positions
        from ..render.camera import Camera

        idx = np.clip(np.rint(truth["source_time"] * motion.fps).astype(np.int64), 0, motion.n_frames - 1)
        cam = Camera(truth["K"], truth["R"], truth["t"], size=tuple(int(s) for s in truth["size"]))
        uv, _ = cam.project(keypoint_positions(motion)[idx])
        track = PoseTrack(np.asarray(uv, dtype=np.float64), params.fps, source=str(video))
    else:
        from ..pose.run import estimate_video

        poses = estimate_video(video, params.pose_input, None, jobs=1)
        track = track_from_poses(poses, params.fps, n)
    return model.predict_video(track)


def _counts(names: np.ndarray, classes: Sequence[str]) -> dict[str, int]:
    return {c: int(np.sum(names == c)) for c in classes}


def _fractions(counts: dict[str, int], n: int) -> dict[str, Any]:
    punch = sum(counts.get(c, 0) for c in PUNCHES)
    kick = sum(counts.get(c, 0) for c in KICKS)
    return {
        "punch": punch, "kick": kick, "other": n - punch - kick,
        "punch_fraction": punch / n if n else None,
        "kick_fraction": kick / n if n else None,
        "punch_share_of_strikes": punch / (punch + kick) if punch + kick else None,
    }


def evaluate_camera(motion, mask: np.ndarray, camera: StrikeCamera, model, params: StrikeEvalParams,
                    seed: int, work_dir: Path, index: int) -> dict[str, Any]:
    """Render ``motion`` from ``camera``, extract features, recognise; count per class over the video
    frames that show an action frame of the motion (``mask``, per motion frame)."""
    from ..features.extract import process_video
    from ..features.salient import SalientParams
    from ..recognition.io import load_features
    from ..render import Appearance, render_to_file

    look_seed = int(np.random.SeedSequence([seed, index, 3]).generate_state(1)[0])
    render_seed = int(np.random.SeedSequence([seed, index, 2]).generate_state(1)[0])
    appearance = Appearance.random(look_seed)
    video = work_dir / f"{camera.name}.mp4"
    side = render_to_file(motion, video, view=camera.azimuth_deg, size=tuple(params.size), fps=params.fps,
                          elevation_deg=camera.elevation_deg, appearance=appearance, background=camera.background,
                          noise_sigma=params.noise_sigma, seed=render_seed)
    from ..formats.truth import read_truth

    truth = read_truth(side).to_arrays()
    if is_pose_model(model):
        pred = pose_prediction(model, motion, video, truth, params)
    else:
        feats_path = work_dir / f"{camera.name}.npz"
        process_video(video, feats_path, variant=params.variant, salient=SalientParams(n_points=params.points))
        pred = model.predict_video(load_features(feats_path))
    src = np.clip(np.rint(truth["source_time"] * motion.fps).astype(np.int64), 0, motion.n_frames - 1)
    # the features' working frames are the video's decoded frames (same rate and size)
    n = min(len(src), len(pred["raw"]))
    act = mask[src[:n]]
    classes = [str(c) for c in model.classes_]
    out: dict[str, Any] = {**camera.to_dict(), "appearance": appearance.to_dict(), "render_seed": render_seed,
                           "video_frames": int(n), "action_video_frames": int(act.sum())}
    for key in ("smoothed", "raw"):
        names = np.asarray(model.classes_)[pred[key][:n]].astype(str)
        counts = _counts(names[act], classes)
        out[key] = {"action_counts": counts, **_fractions(counts, int(act.sum())),
                    "rest_counts": _counts(names[~act], classes)}
    out["per_strike"] = []
    for s in segments(act):
        names = np.asarray(model.classes_)[pred["smoothed"][s["start"]:s["end"]]].astype(str)
        c = _counts(names, classes)
        out["per_strike"].append({**s, "punch_fraction": _fractions(c, s["end"] - s["start"])["punch_fraction"],
                                  "majority": max(c, key=c.get)})
    return out


@contextlib.contextmanager
def work_directory(work_dir: str | os.PathLike | None, prefix: str):
    """``work_dir`` (made if missing, kept afterwards), or a temporary directory removed afterwards."""
    if work_dir is not None:
        work = Path(work_dir)
        work.mkdir(parents=True, exist_ok=True)
        yield work
        return
    with tempfile.TemporaryDirectory(prefix=prefix) as tmp:
        yield Path(tmp)


def is_pose_model(model) -> bool:
    from ..recognition.poserecognizer import PoseRecognizer

    return isinstance(model, PoseRecognizer)


def labelled_action_frames(path: str | os.PathLike, n_frames: int, action_labels: Sequence[str],
                           start: int = 0) -> np.ndarray:
    """(n_frames,) bool from a :mod:`vidstyle.formats.labels` file with one label per motion frame of the
    whole clip (e.g. a demo take's ``mocap/<take>.labels.json``, or a hand-checked file): the frames
    ``start .. start + n_frames`` whose label is one of ``action_labels``."""
    from ..formats._base import FormatError
    from ..formats.labels import read_labels

    track = read_labels(path)
    labels = np.asarray(track.labels, dtype=str)
    if len(labels) < start + n_frames:
        raise FormatError(path, "labels", f"{len(labels)} labels, the motion needs {start + n_frames}")
    return np.isin(labels[start:start + n_frames], list(action_labels))


def evaluate_strikes(bvh: str | os.PathLike, model_path: str | os.PathLike, cameras: Sequence[StrikeCamera] = DEFAULT_CAMERAS,
                     rule: StrikeRule | None = None, params: StrikeEvalParams | None = None, seed: int = 0,
                     work_dir: str | os.PathLike | None = None, actions: str | os.PathLike | None = None,
                     action_labels: Sequence[str] = ("Strike", "Jab", "Hook", "Uppercut")) -> dict[str, Any]:
    """The strikes metrics document (kind ``vidstyle.metrics.strikes``, :mod:`vidstyle.formats.metrics`):
    per camera and overall, how many action frames (video frames showing a strike frame of the motion)
    the recognizer labels a punch, a kick or anything else (smoothed and raw labels). Action frames come
    from ``rule`` (:func:`action_frames`) or, with ``actions``, from that labels file
    (:func:`labelled_action_frames` with ``action_labels``). ``work_dir`` keeps the rendered videos and
    features (default: a temporary directory, removed)."""
    from ..formats.annotations import file_sha256
    from ..logutil import progress
    from ..mocap import read_bvh
    from ..recognition.recognizer import load_model

    rule = (rule or StrikeRule()).validate()
    params = params or StrikeEvalParams()
    motion_all = read_bvh(bvh)
    stop = motion_all.n_frames if params.stop is None else min(params.stop, motion_all.n_frames)
    if not 0 <= params.start < stop:
        raise ParameterError("start", f"the frame range [{params.start}, {stop}) of {bvh} is empty")
    motion = motion_all[params.start:stop]
    if actions is None:
        mask = action_frames(motion, rule)
    else:
        mask = labelled_action_frames(actions, motion.n_frames, action_labels, params.start)
    model, header = load_model(model_path)
    model.n_jobs = 1
    missing = [c for c in PUNCHES + KICKS if c not in set(map(str, model.classes_))]
    if missing:
        raise ParameterError("model", f"{model_path}: the recognizer has no class {missing[0]!r}")
    with work_directory(work_dir, "vidstyle-strikes-") as work:
        per_camera = []
        for i, cam in progress(list(enumerate(cameras)), "strike cameras"):
            per_camera.append(evaluate_camera(motion, mask, cam, model, params, seed, work, i))
    classes = [str(c) for c in model.classes_]
    overall: dict[str, Any] = {}
    for key in ("smoothed", "raw"):
        counts = {c: sum(pc[key]["action_counts"][c] for pc in per_camera) for c in classes}
        n = sum(pc["action_video_frames"] for pc in per_camera)
        overall[key] = {"action_counts": counts, **_fractions(counts, n)}
    overall["action_video_frames"] = sum(pc["action_video_frames"] for pc in per_camera)
    overall["video_frames"] = sum(pc["video_frames"] for pc in per_camera)
    overall["min_camera_punch_fraction"] = min((pc["smoothed"]["punch_fraction"] or 0.0) for pc in per_camera)
    return {
        "seed": int(seed),
        "goal": {"punch_fraction": GOAL},
        "bvh": str(bvh),
        "bvh_sha256": file_sha256(bvh),
        "model": {"path": str(model_path), "sha256": file_sha256(model_path), "seed": header.get("seed"), "split": (header.get("split") or {}).get("kind"),
                  "params": header.get("params")},
        "params": params.to_dict(),
        "rule": rule.to_dict() if actions is None else {"labels_file": str(actions), "action_labels": list(action_labels)},
        "action_source": "rule" if actions is None else "labels",
        "punches": list(PUNCHES),
        "kicks": list(KICKS),
        "classes": classes,
        "action_frames": {"motion_frames": int(motion.n_frames), "fps": float(motion.fps),
                          "action_motion_frames": int(mask.sum()), "segments": segments(mask),
                          "frame_offset": int(params.start)},
        "cameras": per_camera,
        "overall": overall,
    }


def strikes_rows(doc: dict[str, Any]) -> list[dict[str, Any]]:
    """The rows of a strikes metrics document: one per camera, then ``overall`` (named "all cameras"),
    each with ``name``, ``azimuth_deg``/``elevation_deg``/``background`` (None for overall),
    ``action_video_frames``, ``overall`` (bool) and the ``smoothed`` and ``raw`` counts and fractions."""
    rows = []
    for c in [*(doc.get("cameras") or []), {"name": "all cameras", **(doc.get("overall") or {}), "overall": True}]:
        sm, raw = c.get("smoothed") or {}, c.get("raw") or {}
        frames = c.get("action_video_frames", sum(int(sm.get(k) or 0) for k in ("punch", "kick", "other")))
        rows.append({"name": c.get("name"), "azimuth_deg": c.get("azimuth_deg"), "elevation_deg": c.get("elevation_deg"),
                     "background": c.get("background"), "action_video_frames": frames,
                     "overall": bool(c.get("overall")), "smoothed": sm, "raw": raw})
    return rows


def strikes_table(doc: dict[str, Any]) -> str:
    """A Markdown table of a strikes metrics document: per camera and overall (:func:`strikes_rows`)."""
    lines = [("| camera | azimuth | elevation | background | action frames | punch (smoothed) | kick (smoothed) | "
              "punch share of punch+kick | punch (raw) |"), "|---|---:|---:|---|---:|---:|---:|---:|---:|"]

    def pct(v):
        return "n/a" if v is None else f"{100 * v:.1f} %"

    for r in strikes_rows(doc):
        s, raw = r["smoothed"], r["raw"]
        head = ("| **overall** | | | " if r["overall"] else
                f"| {r['name']} | {r['azimuth_deg']:g} | {r['elevation_deg']:g} | {r['background']} ")
        lines.append(f"{head}| {r['action_video_frames']} | {pct(s['punch_fraction'])} | {pct(s['kick_fraction'])} | "
                     f"{pct(s['punch_share_of_strikes'])} | {pct(raw['punch_fraction'])} |")
    return "\n".join(lines)
