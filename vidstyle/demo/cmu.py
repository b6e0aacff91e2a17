"""A recognition dataset rendered from the CMU mocap clips in ``../shared`` (issue 4, item 5b).

Same layout and manifest schema as the demo dataset (:mod:`vidstyle.demo.dataset`), so ``vidstyle
features`` and ``vidstyle evaluate recognition`` run on it unchanged; the "performer" of a video is its
CMU subject (``s05`` = subject 05), so an unseen-performer split tests on unseen subjects::

    dataset.json                  manifest (vidstyle.formats.dataset)
    videos/<id>.mp4 (+ .truth.npz) 160x120 at 20 fps; <id> = s<subject>_<trial>_w<window>_<view>
    labels/<id>.json              one label per video frame (the whole window is its clip's action)

Each clip whose description maps to a chosen action (:func:`vidstyle.motiongraph.labels.cmu_action`)
loses its frame 0 (a T-pose), is resampled to the video rate and cut into non-overlapping windows of
``segment_seconds`` (centred in the clip, so the lead-in and lead-out are what is dropped), which makes
videos from clips of very different lengths comparable. A clip shorter than one window but at least
``min_seconds`` long gives one window of its own length (most CMU walks last 2-4 s; dropping them would
remove five of the six walking subjects). ``max_per_subject`` caps the windows of one subject and one
source action (a seeded draw), because subjects 05 (dance) and 06 (basketball) each recorded minutes of
one action and would otherwise dominate their class.

Actions: ``walk,run,jump`` uses the CMU actions as classes; ``walk,nonwalk=run+jump+punch`` merges source
actions into one class (needed on this subset, where only walking was recorded by three or more
subjects). Every random draw comes from ``numpy.random.SeedSequence`` keyed by the seed and the clip, never
by the class a clip is merged into, so the same window renders to identical frames under any grouping
and features extracted for one grouping serve the others.
"""

from __future__ import annotations

import csv
import logging
import os
import time
from collections import defaultdict
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError, ParameterError
from ..fileio import staged_dir
from ..formats.dataset import write_dataset
from ..formats.labels import write_labels
from .dataset import VIEW_NAMES, validate_views

log = logging.getLogger(__name__)

DEFAULT_ACTIONS = "walk,run,jump,punch,dance,basketball"
_MIN_SUBJECTS = 3  # an unseen-subject split needs the action from a test subject and >= 2 training subjects


@dataclass(frozen=True)
class CMUParams:
    seed: int = 0
    #: class name -> CMU source actions merged into it (keys of CMU_KEYWORDS)
    classes: tuple[tuple[str, tuple[str, ...]], ...] = ()
    views: tuple[str, ...] = ("front", "left", "right")
    segment_seconds: float = 4.0
    min_seconds: float = 1.0
    max_per_subject: int = 12
    fps: int = 20
    size: tuple[int, int] = (160, 120)
    elevation_deg: float = 10.0
    background: str = "texture"
    noise_sigma: float = 2.0
    #: "fit": a static camera framing the whole window (a walker crossing 5 m is drawn far smaller than a
    #: dancer turning on the spot, so figure size gives the class away); "follow": the root's horizontal
    #: drift (its 1 s moving average) is removed, as a camera operator panning with the performer would,
    #: so every action is framed at about the same size and only the body's own motion tells them apart
    camera: str = "fit"
    #: CMU subjects whose clips are used ("03", ...); empty = every subject. A training set of real motion
    #: for another dataset's recognizer keeps the subjects of its validation and test clips out
    subjects: tuple[str, ...] = ()

    @property
    def class_names(self) -> list[str]:
        return [c for c, _ in self.classes]

    def source_to_class(self) -> dict[str, str]:
        return {src: c for c, srcs in self.classes for src in srcs}

    def validate(self) -> CMUParams:
        if not self.classes:
            raise ParameterError("actions", "give at least one action")
        validate_views(self.views)
        if self.segment_seconds < 1.0:
            raise ParameterError("segment_seconds", f"must be at least 1, got {self.segment_seconds}")
        if not 0.5 <= self.min_seconds <= self.segment_seconds:
            raise ParameterError("min_seconds", f"must be between 0.5 and --segment-seconds, got {self.min_seconds}")
        if self.max_per_subject < 0:
            raise ParameterError("max_per_subject", f"must be >= 0 (0 = no cap), got {self.max_per_subject}")
        if self.camera not in ("fit", "follow"):
            raise ParameterError("camera", f"must be fit or follow, got {self.camera!r}")
        if self.background not in ("plain", "texture"):
            raise ParameterError("background", f"must be plain or texture, got {self.background!r}")
        bad = [s for s in self.subjects if not (s.isdigit() and len(s) == 2)]
        if bad:
            raise ParameterError("subjects", f"CMU subjects are two digits (03, 12), got {', '.join(map(repr, bad))}")
        return self

    def to_dict(self) -> dict:
        d = asdict(self)
        d["classes"] = {c: list(srcs) for c, srcs in self.classes}
        d["views"] = list(self.views)
        d["size"] = list(self.size)
        if self.subjects:
            d["subjects"] = list(self.subjects)
        else:  # documents of datasets made before the option stay as they were
            del d["subjects"]
        return d


def parse_actions(spec: str) -> tuple[tuple[str, tuple[str, ...]], ...]:
    """``"walk,run,nonwalk=jump+punch"`` -> ``(("walk", ("walk",)), ("run", ("run",)), ("nonwalk", ("jump",
    "punch")))``. A source action is a key of ``CMU_KEYWORDS`` or one of its keywords (``jog`` = run,
    ``dribble`` = basketball, ``strike`` = punch)."""
    from ..motiongraph.labels import CMU_KEYWORDS

    alias = {a: a for a in CMU_KEYWORDS}
    alias.update({w: a for a, words in CMU_KEYWORDS.items() for w in words})
    out: list[tuple[str, tuple[str, ...]]] = []
    seen: dict[str, str] = {}
    for item in (s.strip() for s in spec.split(",")):
        if not item:
            continue
        name, _, rhs = item.partition("=")
        name = name.strip()  # a class keeps the case it is given in (Step=walk: another dataset's class)
        sources = [s.strip().lower() for s in (rhs.split("+") if rhs else [name])]
        if not name or not all(sources):
            raise ParameterError("actions", f"malformed item {item!r} (use ACTION or CLASS=ACTION+ACTION)")
        resolved = []
        for s in sources:
            if s not in alias:
                raise ParameterError("actions", f"unknown action {s!r} (one of {', '.join(CMU_KEYWORDS)})")
            a = alias[s]
            if a in seen:
                raise ParameterError("actions", f"action {a!r} given twice (in {seen[a]!r} and {name!r})")
            seen[a] = name
            resolved.append(a)
        if name in (c for c, _ in out):
            raise ParameterError("actions", f"class {name!r} given twice")
        out.append((name, tuple(resolved)))
    if not out:
        raise ParameterError("actions", "give at least one action")
    return tuple(out)


# --------------------------------------------------------------------------- planning
@dataclass(frozen=True)
class CmuClip:
    file: str
    subject: str
    trial: str
    description: str
    frames: int  # BVH frames including the T-pose frame 0
    fps: float
    source_action: str


@dataclass(frozen=True)
class ClipWindow:
    """One window of one clip, in video frames of the clip resampled to ``fps`` after dropping frame 0."""

    clip: CmuClip
    window: int
    start: int  # video frame (inclusive)
    end: int  # video frame (exclusive)
    label: str  # class after merging

    @property
    def performer(self) -> str:
        return f"s{self.clip.subject}"

    @property
    def stem(self) -> str:
        return f"{self.performer}_{self.clip.trial}_w{self.window}"


def read_clips(cmu_dir: Path) -> list[CmuClip]:
    """The clips of ``clips.csv`` in ``cmu_dir`` (with their CMU action), checked against the files."""
    from ..motiongraph.labels import cmu_action

    if not cmu_dir.is_dir():
        raise InputError(f"{cmu_dir}: CMU directory not found")
    index = cmu_dir / "clips.csv"
    if not index.is_file():
        raise InputError(f"{index}: clip index not found (file,subject,trial,description,frames,fps)")
    clips = []
    with open(index, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        need = {"file", "subject", "trial", "description", "frames", "fps"}
        if not need <= set(reader.fieldnames or ()):
            raise InputError(f"{index}: needs columns {', '.join(sorted(need))}")
        for line, row in enumerate(reader, start=2):
            try:
                frames, fps = int(row["frames"]), float(row["fps"])
            except ValueError:
                raise InputError(f"{index}: line {line}: frames/fps are not numbers") from None
            if not (cmu_dir / row["file"]).is_file():
                raise InputError(f"{index}: line {line}: {row['file']} not found in {cmu_dir}")
            clips.append(CmuClip(row["file"], row["subject"].zfill(2), row["trial"].zfill(2), row["description"],
                              frames, fps, cmu_action(row["description"])))
    return sorted(clips, key=lambda c: c.file)


def video_frames(clip: CmuClip, fps: float) -> int:
    """Frames of the clip without its T-pose, resampled to ``fps`` (as :meth:`Motion.resample` counts)."""
    duration = (clip.frames - 2) / clip.fps
    return int(np.floor(duration * fps + 1e-9)) + 1 if clip.frames > 2 else max(clip.frames - 1, 0)


def clip_windows(n: int, window: int, min_frames: int) -> list[tuple[int, int]]:
    """Non-overlapping windows of ``window`` frames centred in ``n`` frames; one window of ``n`` frames when
    ``min_frames <= n < window``; none when ``n < min_frames``."""
    if n < min_frames:
        return []
    if n < window:
        return [(0, n)]
    k = n // window
    off = (n - k * window) // 2
    return [(off + i * window, off + (i + 1) * window) for i in range(k)]


def plan_segments(clips: list[CmuClip], params: CMUParams) -> tuple[list[ClipWindow], dict]:
    """Windows of the chosen actions (capped per subject and source action) and statistics of the plan."""
    to_class = params.source_to_class()
    window = int(round(params.segment_seconds * params.fps))
    min_frames = int(round(params.min_seconds * params.fps))
    pools: dict[tuple[str, str], list[ClipWindow]] = defaultdict(list)
    dropped_short = []
    if params.subjects:
        keep = set(params.subjects)
        clips = [c for c in clips if c.subject in keep]
    for clip in clips:
        if clip.source_action not in to_class:
            continue
        wins = clip_windows(video_frames(clip, params.fps), window, min_frames)
        if not wins:
            dropped_short.append(clip.file)
        for w, (s, e) in enumerate(wins):
            pools[(clip.subject, clip.source_action)].append(ClipWindow(clip, w, s, e, to_class[clip.source_action]))
    chosen: list[ClipWindow] = []
    for (subject, source), pool in sorted(pools.items()):
        if params.max_per_subject and len(pool) > params.max_per_subject:
            # keyed by subject and source action only, so the draw is the same under any class grouping
            rng = np.random.default_rng(np.random.SeedSequence([params.seed, int(subject), _key(source), 7]))
            keep = np.sort(rng.choice(len(pool), params.max_per_subject, replace=False))
            pool = [pool[i] for i in keep]
        chosen.extend(pool)
    chosen.sort(key=lambda s: s.stem)
    stats = plan_stats(clips, chosen, params)
    stats["dropped_short_clips"] = dropped_short
    return chosen, stats


def plan_stats(clips: list[CmuClip], segments: list[ClipWindow], params: CMUParams) -> dict:
    """Per class: subjects, clips and windows per subject (before/after the cap), and seconds."""
    to_class = params.source_to_class()
    out: dict[str, dict] = {}
    for name in params.class_names:
        cl = [c for c in clips if to_class.get(c.source_action) == name]
        segs = [s for s in segments if s.label == name]
        per_subject: dict[str, dict] = {}
        for subj in sorted({c.subject for c in cl}):
            mine = [s for s in segs if s.clip.subject == subj]
            per_subject[f"s{subj}"] = {
                "clips": sum(c.subject == subj for c in cl),
                "clips_used": len({s.clip.file for s in mine}),
                "segments": len(mine),
                "seconds": round(sum(s.end - s.start for s in mine) / params.fps, 2),
                "source_actions": sorted({s.clip.source_action for s in mine}),
            }
        out[name] = {
            "sources": [list(srcs) for c, srcs in params.classes if c == name][0],
            "clips": len(cl),
            "subjects": sorted({s.performer for s in segs}),
            "segments": len(segs),
            "per_subject": per_subject,
        }
    return {"classes": out}


def _key(text: str) -> int:
    return int.from_bytes(text.encode("utf-8")[:8].ljust(8, b"\0"), "little")


def _render_seed(seed: int, seg: ClipWindow, view_index: int) -> int:
    ss = np.random.SeedSequence([seed, int(seg.clip.subject), int(seg.clip.trial), seg.window, view_index, 2])
    return int(ss.generate_state(1)[0])


def appearance_seed(seed: int, subject: str) -> int:
    """One appearance per subject (clothes and build stay with the person, as in real footage)."""
    return int(np.random.SeedSequence([seed, int(subject), 3]).generate_state(1)[0])


def _view_slug(view: str) -> str:
    return view if view in VIEW_NAMES else f"az{float(view):g}".replace("-", "m").replace(".", "p")


# --------------------------------------------------------------------------- per segment work
def follow_offset(root: np.ndarray, fps: float, seconds: float = 1.0) -> np.ndarray:
    """(F, 3) horizontal drift of ``root`` (F, 3): its centred moving average over ``seconds`` in X and Z,
    zero in Y (+Y is up, so jumps and crouches stay). Subtracting it keeps the sway of steps and turns."""
    from scipy.ndimage import uniform_filter1d

    size = max(1, int(round(seconds * fps)))
    drift = uniform_filter1d(np.asarray(root, dtype=np.float64), size=size, axis=0, mode="nearest")
    drift[:, 1] = 0.0
    return drift



@dataclass
class _Job:
    params: CMUParams
    seg: ClipWindow
    cmu_dir: str
    root: str
    classes: list[str] = field(default_factory=list)


def label_document(label: str, n: int, fps: float, classes: list[str], **meta) -> dict:
    """The labels JSON of a single-action window: every frame is ``label``, one event covering it all."""
    return {**meta, "fps": fps, "classes": list(classes), "labels": [label] * n, "transitions": [],
            "events": [{"label": label, "start": 0, "end": n}],
            "segments": [{"label": label, "start": 0, "end": n}]}


def render_segment(job: _Job) -> list[dict]:
    """Render one window in every view; return its manifest entries. Module level for joblib/Dask."""
    from ..mocap import read_bvh
    from ..render import Appearance, parse_view, render_to_file

    p, seg, root = job.params, job.seg, Path(job.root)
    bvh = Path(job.cmu_dir) / seg.clip.file
    motion = read_bvh(bvh)
    if motion.n_frames != seg.clip.frames:
        raise InputError(f"{bvh}: {motion.n_frames} frames but clips.csv says {seg.clip.frames}")
    # frame 0 is the calibration T-pose; resample the whole clip so every window sees the same samples
    video_motion = motion[1:].resample(p.fps)[seg.start:seg.end]
    if p.camera == "follow":
        video_motion = video_motion.translate(-follow_offset(video_motion.root_positions, p.fps))
    n = video_motion.n_frames
    if n != seg.end - seg.start:
        raise AssertionError(f"{bvh}: window {seg.start}:{seg.end} gave {n} frames")
    labels = [seg.label] * n
    ratio = seg.clip.fps / p.fps
    entries = []
    for vi, view in enumerate(p.views):
        vid = f"{seg.stem}_{_view_slug(view)}"
        video_rel, labels_rel, truth_rel = f"videos/{vid}.mp4", f"labels/{vid}.json", f"videos/{vid}.truth.npz"
        azimuth = float(parse_view(view))
        render_to_file(video_motion, root / video_rel, view=azimuth, size=tuple(p.size), fps=p.fps,
                       elevation_deg=p.elevation_deg,
                       appearance=Appearance.random(appearance_seed(p.seed, seg.clip.subject)),
                       background=p.background, noise_sigma=p.noise_sigma, seed=_render_seed(p.seed, seg, vi),
                       labels=labels, transitions=np.zeros(n, dtype=bool))
        source = {"bvh": str(bvh), "clip": seg.clip.file, "description": seg.clip.description,
                  "source_action": seg.clip.source_action,
                  # BVH frame numbers (frame 0 = the T-pose) of the first and one past the last shown frame
                  "bvh_start": 1 + int(round(seg.start * ratio)), "bvh_end": 1 + int(round((seg.end - 1) * ratio)) + 1}
        write_labels(root / labels_rel, label_document(seg.label, n, float(p.fps), job.classes, video=video_rel,
                                                     performer=seg.performer, view=view, **source))
        entries.append({"id": vid, "performer": seg.performer, "kind": "single", "action": seg.label,
                        "view": view, "azimuth_deg": azimuth, "video": video_rel, "labels": labels_rel,
                        "truth": truth_rel, "bvh": str(bvh), "frames": n, "cmu_subject": seg.clip.subject,
                        "window": seg.window, **{k: v for k, v in source.items() if k != "bvh"}})
    return entries


# --------------------------------------------------------------------------- the dataset
def make_cmu_dataset(cmu_dir: str | os.PathLike, out: str | os.PathLike, params: CMUParams,
                     overwrite: bool = False, jobs: int = -1, scheduler: str | None = None) -> Path:
    """Build the dataset into ``out`` (see the module docstring); returns the manifest path. Written in a
    hidden sibling directory, renamed onto ``out`` only when complete."""
    from ..parallel import parallel_map

    params.validate()
    cmu_dir, out = Path(cmu_dir), Path(out)
    clips = read_clips(cmu_dir)
    missing = sorted(set(params.subjects) - {c.subject for c in clips})
    if missing:
        raise InputError(f"{cmu_dir / 'clips.csv'}: no clip of subject(s) {', '.join(missing)}")
    segments, stats = plan_segments(clips, params)
    log_stats(stats)
    if not segments:
        raise InputError(f"{cmu_dir}: no clip of the actions {', '.join(params.class_names)} is long enough")
    with staged_dir(out, overwrite) as tmp:
        for sub in ("videos", "labels"):
            (tmp / sub).mkdir()
        t0 = time.perf_counter()
        # longest windows first so the pool's tail is short
        order = sorted(segments, key=lambda s: (-(s.end - s.start), s.stem))
        work = [_Job(params, s, str(cmu_dir.resolve()), str(tmp), params.class_names) for s in order]
        results = parallel_map(render_segment, work, jobs=jobs, scheduler=scheduler, description="CMU windows")
        videos = sorted((e for entries in results for e in entries), key=lambda e: e["id"])
        performers = []
        for subj in sorted({s.clip.subject for s in segments}):
            mine = [s for s in segments if s.clip.subject == subj]
            performers.append({"id": f"s{subj}", "cmu_subject": subj,
                               "appearance_seed": appearance_seed(params.seed, subj),
                               "actions": sorted({s.label for s in mine}),
                               "clips": sorted({s.clip.file for s in mine}), "segments": len(mine)})
        manifest = {
            "source": "cmu",
            "seed": params.seed,
            "fps": params.fps,
            "size": list(params.size),
            "actions": params.class_names,
            "classes": params.class_names,
            "params": {**params.to_dict(), "cmu_dir": str(cmu_dir.resolve())},
            "performers": performers,
            "stats": stats,
            "videos": videos,
        }
        write_dataset(tmp / "dataset.json", manifest)
    log.info("wrote %s: %d subjects, %d windows, %d videos (%d frames) in %.1f s", out, len(performers),
             len(segments), len(videos), sum(v["frames"] for v in videos), time.perf_counter() - t0)
    return out / "dataset.json"


def log_stats(stats: dict) -> None:
    """Clips and windows per class and subject; warns about classes an unseen-subject split cannot test."""
    for name, c in stats["classes"].items():
        per = ", ".join(f"{s} {d['segments']}w/{d['clips_used']}c" for s, d in c["per_subject"].items())
        log.info("%-12s %2d clips, %3d windows, %d subjects: %s", name, c["clips"], c["segments"],
                 len(c["subjects"]), per or "-")
        if len(c["subjects"]) < _MIN_SUBJECTS:
            log.warning("%s: windows from %d subject(s) only (%s); an unseen-subject split cannot both train and "
                        "test it -- drop it or merge it into another class (CLASS=A+B)", name,
                        len(c["subjects"]), ", ".join(c["subjects"]) or "none")
    if stats.get("dropped_short_clips"):
        log.info("clips shorter than --min-seconds, dropped: %s", ", ".join(stats["dropped_short_clips"]))
