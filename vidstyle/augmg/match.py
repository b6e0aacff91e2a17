"""``vidstyle match-pose`` as a library call: each frame's 2D pose matched against the library projected at
the frame's viewpoint (:class:`.index.PoseIndex`), the top-k library frames per frame."""

from __future__ import annotations

import logging
import os
from collections.abc import Sequence

import numpy as np

from ..errors import InputError, ParameterError
from . import defaults as D

log = logging.getLogger(__name__)


def view_spread(viewpoint: str) -> int:
    """Neighbouring projected views searched either side of a pose's viewpoint: 0 for an azimuth in
    degrees, 1 for a named viewpoint (front / left / right: a class, so its neighbours too)."""
    try:
        float(viewpoint)
        return 0
    except ValueError:
        return 1


def match_poses(poses: str | os.PathLike, library: Sequence[str | os.PathLike], k: int = D.K,
                views: int = D.N_VIEWS, elevation: float = D.ELEVATION_DEG, stride: int = D.STRIDE,
                coherence: bool = False, fps: float = D.VIDEO_FPS, jobs: int = 1, scheduler: str | None = None):
    """The :class:`vidstyle.formats.matches.Matches` of ``poses`` (a poses.json of the pose stage) against
    the library clips / directories ``library``: per frame the top-``k`` library frames ({"clip", "time",
    "cost"}, best first) at the frame's viewpoint relative to the character's facing (joint-angle
    features, kd-tree kNN over ``views`` azimuths at ``elevation`` degrees, every ``stride``-th library
    frame). ``coherence``: re-rank consecutive frames' candidates by temporal coherence
    (:func:`.index.coherent_ranking`, frames numbered at ``fps``). Parameters are checked before any work
    (:class:`~vidstyle.errors.ParameterError`)."""
    from ..formats.matches import Candidate, FrameMatches, Matches
    from ..render.camera import parse_view
    from .index import PoseIndex, coherent_ranking, library_clips, query_views
    from .poses_io import read_frame_poses

    if not 1 <= k <= D.MAX_K:
        raise ParameterError("k", f"must be in 1..{D.MAX_K}, got {k}")
    if not 1 <= views <= D.MAX_VIEWS:
        raise ParameterError("views", f"must be in 1..{D.MAX_VIEWS}, got {views}")
    if not 1 <= stride <= D.MAX_STRIDE:
        raise ParameterError("stride", f"must be in 1..{D.MAX_STRIDE}, got {stride}")
    if not (fps > 0 and np.isfinite(fps)):
        raise ParameterError("fps", f"must be a finite number > 0, got {fps}")
    video, frames = read_frame_poses(poses)
    if not frames:
        raise InputError(f"{poses}: no frames to match")
    clips = library_clips(list(library))
    index = PoseIndex(n_views=views, elevation_deg=elevation, stride=stride, jobs=jobs, scheduler=scheduler).fit(clips)
    ids, costs, azs = [], [], []
    for f in frames:
        try:
            az = parse_view(f.viewpoint)
        except ValueError as e:
            raise InputError(f"{poses}: frame {f.frame}: {e}") from None
        i, c = query_views(index, f.points, az, k, view_spread(f.viewpoint))
        ids.append(i[0])
        costs.append(c[0])
        azs.append(az)
    kk = min(len(x) for x in ids)
    I, C = np.stack([x[:kk] for x in ids]), np.stack([x[:kk] for x in costs])
    if coherence:
        I, C = coherent_ranking(index, I, C, np.array([f.frame for f in frames]), fps)
    times = index.time_of(I)
    out_frames = [FrameMatches(f.frame, float(az), [Candidate(index.paths_[int(index.clip_[j])], float(t), float(c))
                                                    for j, t, c in zip(I[q], times[q], C[q])])
                  for q, (f, az) in enumerate(zip(frames, azs))]
    log.info("%d frames x %d candidates over %d library frames", len(frames), kk, index.n_frames)
    return Matches(str(poses), video, index.paths_, {**index.get_params(), "k": k, "coherence": coherence},
                   out_frames)

