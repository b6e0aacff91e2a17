"""The demo dataset: procedural performers rendered to video with exact per-frame ground truth.

Layout of ``DIR`` (paths in the manifest are relative to ``DIR``)::

    dataset.json                      manifest (vidstyle.formats.dataset): params, performers with their true
                                      chains, one entry per video
    videos/<id>.mp4                   160x120 at 20 fps; <id> = <performer>_<take>_<view>
    videos/<id>.truth.npz             renderer sidecar (2D/3D joints, camera, labels per frame)
    labels/<id>.json                  (vidstyle.formats.labels) per video frame: labels, transitions, events, chain
    mocap/<take>.bvh                  the motion the take's videos were rendered from (60 fps)
    mocap/<take>.labels.json          the same labels per mocap frame

Both labels files carry ``styled_transitions``: the performer's own transition movements
(:mod:`.transitions`) as ``{"from", "to", "kind", "start", "end", "key"}`` in that file's frames (``end``
exclusive, ``key`` the middle of the held transition pose); their 3D motion is the take's BVH over
those frames. The frames keep the label ``Guard`` (a transition is the pause between two actions).

Takes: ``<performer>_<action>`` (single-action takes, e.g. ``p00_jab``) and ``<performer>_perf<k>``
(performances). Every random draw comes from ``numpy.random.SeedSequence([seed, performer, take])``,
so a take does not depend on which worker ran it or on the other takes: the same seed gives
byte-identical JSON and BVH files and identical video frames.

The dataset is written into a hidden sibling directory and renamed onto ``DIR`` only when complete.
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import ParameterError
from ..fileio import staged_dir
from ..formats.dataset import write_dataset
from ..formats.labels import write_labels
from .actions import ACTIONS, CLASSES
from .performer import Performer
from .skeleton import UNIT_M
from .timeline import Take, build_take, performance_plan, single_action_plan

log = logging.getLogger(__name__)

VIEW_NAMES = ("front", "left", "right", "back")
_PERF_TAKE_BASE = 100  # take numbers of performances (single-action takes are 0..5)


@dataclass(frozen=True)
class DatasetParams:
    seed: int = 0
    performers: int = 10
    views: tuple[str, ...] = ("front", "left", "right")
    single_seconds: float = 16.0
    performances: int = 2
    performance_seconds: float = 60.0
    performance_views: tuple[str, ...] | None = None  # views of the performances (None: ``views``)
    fps: int = 20
    mocap_fps: int = 60
    size: tuple[int, int] = (160, 120)
    elevation_deg: float = 10.0
    background: str = "texture"
    noise_sigma: float = 2.0
    render: bool = True
    only_performers: tuple[str, ...] | None = None  # render only these performer ids (None: all)
    # punches with footwork (MovementTraits.footwork): each performer's amount drawn in [footwork / 2, footwork]
    # from a stream of its own, so the performers are otherwise those of the same seed without it (0: none)
    footwork: float = 0.0

    @classmethod
    def small(cls, seed: int = 0, **overrides) -> DatasetParams:
        """Small enough for CI: 4 performers (one per recognition set: A, B, validation, test), 2 views,
        4 s clips, one 8 s performance each."""
        base = dict(seed=seed, performers=4, views=("front", "left"), single_seconds=4.0, performances=1,
                    performance_seconds=8.0)
        return cls(**{**base, **overrides})

    def validate(self) -> DatasetParams:
        if self.performers < 1:
            raise ParameterError("performers", f"must be at least 1, got {self.performers}")
        validate_views(self.views)
        if self.performance_views is not None:
            try:
                validate_views(self.performance_views)
            except ParameterError as e:
                raise ParameterError("performance_views", e.problem) from None
        if self.single_seconds < 1.5:
            raise ParameterError("single_seconds", f"must be at least 1.5, got {self.single_seconds}")
        if self.performances < 0:
            raise ParameterError("performances", f"must be >= 0, got {self.performances}")
        if self.performances and self.performance_seconds < 3:
            raise ParameterError("performance_seconds", f"must be at least 3, got {self.performance_seconds}")
        if not 0.0 <= self.footwork <= 1.0:
            raise ParameterError("footwork", f"must be in 0..1, got {self.footwork}")
        if self.fps <= 0 or self.mocap_fps % self.fps:
            raise ParameterError("fps", f"the mocap rate {self.mocap_fps} must be a multiple of the video rate {self.fps}")
        return self

    def to_dict(self) -> dict:
        d = asdict(self)
        d["views"] = list(self.views)
        d["performance_views"] = None if self.performance_views is None else list(self.performance_views)
        d["size"] = list(self.size)
        d["only_performers"] = None if self.only_performers is None else list(self.only_performers)
        if not self.footwork:
            del d["footwork"]  # the documents of datasets made without footwork stay as they were
        return d

    @classmethod
    def unseen_camera(cls, base: DatasetParams, split_seed: int | None = None) -> DatasetParams:
        """``base`` filmed from cameras and a background that no dataset made with the defaults uses
        (:data:`UNSEEN_CAMERA`), with one performance per performer. With ``split_seed``, only the test
        performers of the recognition split of that seed (``vidstyle.recognition.splits``) are rendered:
        the only ones an unseen-camera evaluation scores."""
        only = None
        if split_seed is not None:
            from ..recognition.splits import performer_groups

            only = tuple(performer_groups([f"p{i:02d}" for i in range(base.performers)], split_seed)["T"])
        return replace(base, views=UNSEEN_CAMERA["views"], performance_views=None,
                       elevation_deg=UNSEEN_CAMERA["elevation_deg"], background=UNSEEN_CAMERA["background"],
                       performances=min(base.performances, 1), only_performers=only)


# Cameras of `vidstyle demo make-dataset --unseen-camera`: azimuths between the front and side views the
# default dataset uses, from higher up, in front of a texture the default backgrounds never draw.
UNSEEN_CAMERA = {"views": ("30", "150"), "elevation_deg": 30.0, "background": "texture:moon"}


def validate_views(views) -> None:
    """``--views``: at least one, each a view name or an azimuth in degrees, none repeated."""
    if not views:
        raise ParameterError("views", "give at least one view")
    for v in views:
        try:
            float(v)
        except ValueError:
            if v not in VIEW_NAMES:
                raise ParameterError("views", f"unknown view {v!r} (front, left, right, back or degrees)") from None
    if len(set(views)) != len(views):
        raise ParameterError("views", f"repeated view in {','.join(views)}")


# --------------------------------------------------------------------------- performers and takes
def make_performer(params: DatasetParams, index: int) -> Performer:
    rng = np.random.default_rng(np.random.SeedSequence([params.seed, index]))
    performer = Performer.random(f"p{index:02d}", rng, video_fps=params.fps)
    if params.footwork > 0:
        u = np.random.default_rng(np.random.SeedSequence([params.seed, index, 2])).uniform(0.5, 1.0)
        performer = replace(performer, style=replace(performer.style, footwork=float(params.footwork * u)))
    return performer


def _take_rng(params: DatasetParams, performer: int, take: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence([params.seed, performer, take, 1]))


def make_take(params: DatasetParams, performer: Performer, index: int, take: int) -> Take:
    """Single-action take ``take`` (0..5, an action index) or performance ``take - 100``."""
    rng = _take_rng(params, index, take)
    ratio = params.mocap_fps // params.fps
    if take < _PERF_TAKE_BASE:
        plan = single_action_plan(performer, ACTIONS[take], int(round(params.single_seconds * params.fps)), rng)
    else:
        plan = performance_plan(performer, int(round(params.performance_seconds * params.fps)), rng)
    return build_take(performer, plan, rng, video_fps=params.fps, ratio=ratio)


def take_name(performer: Performer, take: int) -> str:
    if take < _PERF_TAKE_BASE:
        return f"{performer.id}_{ACTIONS[take].lower()}"
    return f"{performer.id}_perf{take - _PERF_TAKE_BASE}"


def label_document(labels: list[str], fps: float, chain: list[str], **meta) -> dict:
    """The labels JSON: per-frame labels, transitions (frames whose label differs from the previous
    frame's), events (runs of the six actions, ``end`` exclusive) and the chain performed."""
    transitions = [i for i in range(1, len(labels)) if labels[i] != labels[i - 1]]
    bounds = [0] + transitions + [len(labels)]
    segments = [{"label": labels[s], "start": s, "end": e} for s, e in zip(bounds[:-1], bounds[1:]) if e > s]
    events = [seg for seg in segments if seg["label"] in ACTIONS]
    return {**meta, "fps": fps, "classes": list(CLASSES), "labels": list(labels), "transitions": transitions,
            "events": events, "chain": list(chain), "segments": segments}


def video_transitions(tk: Take) -> list[dict]:
    """The take's styled transitions in video frames (their boundaries fall on video frames)."""
    return [{**t, "start": t["start"] // tk.ratio, "end": t["end"] // tk.ratio, "key": t["key"] // tk.ratio}
            for t in tk.transitions]


def _render_seed(params: DatasetParams, index: int, take: int, view_index: int) -> int:
    return int(np.random.SeedSequence([params.seed, index, take, 2, view_index]).generate_state(1)[0])


def _appearance_seed(params: DatasetParams, index: int) -> int:
    return int(np.random.SeedSequence([params.seed, index, 3]).generate_state(1)[0])


def _view_slug(view: str) -> str:
    return view if view in VIEW_NAMES else f"az{float(view):g}".replace("-", "m").replace(".", "p")


def generate_take(job: tuple[DatasetParams, int, int, str]) -> list[dict]:
    """Write one take (BVH, mocap labels, and per view: video, sidecar, video labels) under ``root``;
    return its manifest video entries. Module level so joblib/Dask can ship it to workers."""
    from ..mocap import write_bvh

    params, index, take, root_str = job
    root = Path(root_str)
    performer = make_performer(params, index)
    tk = make_take(params, performer, index, take)
    name = take_name(performer, take)
    kind = "single" if take < _PERF_TAKE_BASE else "performance"
    bvh_rel = f"mocap/{name}.bvh"
    bvh_labels_rel = f"mocap/{name}.labels.json"
    write_bvh(tk.motion, root / bvh_rel)
    write_labels(root / bvh_labels_rel, label_document(tk.labels, float(params.mocap_fps), tk.chain,
                                                    bvh=bvh_rel, performer=performer.id,
                                                    styled_transitions=tk.transitions))
    video_labels = tk.video_labels
    is_transition = np.zeros(len(tk.labels), dtype=bool)
    is_transition[1:] = np.array(tk.labels[1:]) != np.array(tk.labels[:-1])
    entries = []
    views = params.views if kind == "single" or params.performance_views is None else params.performance_views
    for vi, view in enumerate(views):
        vid = f"{name}_{_view_slug(view)}"
        video_rel, labels_rel = f"videos/{vid}.mp4", f"labels/{vid}.json"
        truth_rel = f"videos/{vid}.truth.npz"
        azimuth = _azimuth(view)
        if params.render:
            from ..render import Appearance, render_to_file

            render_to_file(tk.motion, root / video_rel, view=azimuth, size=tuple(params.size), fps=params.fps,
                           elevation_deg=params.elevation_deg, appearance=Appearance.random(_appearance_seed(params, index)),
                           background=params.background, noise_sigma=params.noise_sigma,
                           seed=_render_seed(params, index, take, vi), labels=tk.labels, transitions=is_transition)
        write_labels(root / labels_rel, label_document(video_labels, float(params.fps), tk.chain, video=video_rel,
                                                     performer=performer.id, view=view,
                                                     styled_transitions=video_transitions(tk)))
        entry = {"id": vid, "performer": performer.id, "kind": kind}
        if kind == "single":
            entry["action"] = ACTIONS[take]
        entry.update({"view": view, "azimuth_deg": azimuth, "elevation_deg": float(params.elevation_deg),
                      "background": str(params.background), "video": video_rel, "labels": labels_rel,
                      "truth": truth_rel, "bvh": bvh_rel, "bvh_labels": bvh_labels_rel,
                      "frames": len(video_labels)})
        entries.append(entry)
    return entries


def _azimuth(view: str) -> float:
    from ..render.camera import parse_view

    return float(parse_view(view))


def dataset_jobs(params: DatasetParams, root: str) -> list[tuple[DatasetParams, int, int, str]]:
    takes = list(range(len(ACTIONS))) + [_PERF_TAKE_BASE + k for k in range(params.performances)]
    # performances first: they are the longest, so the pool's tail is short
    takes.sort(key=lambda t: t < _PERF_TAKE_BASE)
    only = None if params.only_performers is None else set(params.only_performers)
    return [(params, i, t, root) for t in takes for i in range(params.performers) if only is None or f"p{i:02d}" in only]


def make_dataset(out: str | os.PathLike, params: DatasetParams, overwrite: bool = False, jobs: int = -1,
                 scheduler: str | None = None) -> Path:
    """Generate the dataset into ``out`` (see the module docstring). An existing non-empty ``out`` is
    refused unless ``overwrite`` (then it is replaced only once the new dataset is complete)."""
    from ..parallel import parallel_map

    params.validate()
    out = Path(out)
    with staged_dir(out, overwrite) as tmp:
        for sub in ("videos", "labels", "mocap"):
            (tmp / sub).mkdir()
        t0 = time.perf_counter()
        performers = [make_performer(params, i) for i in range(params.performers)]
        if params.only_performers is not None:
            unknown = sorted(set(params.only_performers) - {p.id for p in performers})
            if unknown:
                raise ParameterError("only_performers", f"no such performer {unknown[0]!r} among {params.performers}")
            performers = [p for p in performers if p.id in set(params.only_performers)]
        results = parallel_map(generate_take, dataset_jobs(params, str(tmp)), jobs=jobs, scheduler=scheduler,
                               description="demo takes")
        videos = sorted((e for entries in results for e in entries), key=lambda e: e["id"])
        manifest = {
            "seed": params.seed,
            "fps": params.fps,
            "mocap_fps": params.mocap_fps,
            "mocap_unit_m": UNIT_M,  # metres per BVH length unit (CMU units): evaluations report mm
            "size": list(params.size),
            "actions": list(ACTIONS),
            "classes": list(CLASSES),
            "params": params.to_dict(),
            "performers": [p.to_dict() for p in performers],
            "videos": videos,
        }
        write_dataset(tmp / "dataset.json", manifest)
    log.info("wrote %s: %d performers, %d videos (%d frames) in %.1f s", out, len(performers), len(videos),
             sum(v["frames"] for v in videos), time.perf_counter() - t0)
    return out / "dataset.json"


def with_overrides(params: DatasetParams, **kw) -> DatasetParams:
    return replace(params, **{k: v for k, v in kw.items() if v is not None})
