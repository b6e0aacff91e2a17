"""Compile every numba kernel into numba's cache ahead of use (``vidstyle compile``).

numba compiles a kernel (:func:`vidstyle.compiled.compile_kernel`) the first time a process calls it and
keeps the machine code in its cache (``__pycache__`` beside the source, or ``NUMBA_CACHE_DIR``), keyed by
the source file and the argument types. The package has 23 kernels, 0.2 to 2 s each to compile, 13 s
in all on one core. Without this, a fresh install pays that inside its first pipeline run, one stage at a
time, often in two workers at once. ``make demo`` and ``make test`` run ``vidstyle compile`` as the last
install step, so the pipeline loads the kernels from the cache.

Each task calls the public functions the pipeline calls, on tiny inputs: BVH write and read, forward
kinematics, the renderer as the demo's dataset writer calls it, feature extraction from a video file, the
motion graph, and the array kernels of pose, reconstruction, in-betweening and action models. The functions cast their arguments
before the kernel call, so the signature compiled here is the pipeline's. ``tests/test_warmup.py`` checks
that every kernel the package compiles is cached, and that a run afterwards compiles nothing. The tasks run
in parallel through :func:`vidstyle.parallel.parallel_map`. A kernel whose source file changed since is
compiled again at its next use, as numba always does.
"""

from __future__ import annotations

import logging
import tempfile
import time
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)


def _render(tmp: Path) -> None:
    """A short take written and read back as BVH, forward kinematics, and rendered to a video file as the
    demo's dataset writer renders one (appearance, labels, transitions): the BVH number, forward
    kinematics and raster kernels."""
    from .mocap import forward_kinematics, read_bvh, write_bvh
    from .render import Appearance, render_to_file
    from .render.samples import sample_motion

    write_bvh(sample_motion(60, fps=60.0), tmp / "walk.bvh")
    motion = read_bvh(tmp / "walk.bvh")
    forward_kinematics(motion)
    labels = ["Guard"] * 30 + ["Jab"] * 30
    transitions = np.zeros(60, dtype=bool)
    transitions[30] = True
    render_to_file(motion, tmp / "walk.mp4", view=0.0, size=(160, 120), fps=20, appearance=Appearance.random(0),
                   seed=0, labels=labels, transitions=transitions)


def _features(tmp: Path) -> None:
    """Salient points and 3D SIFT of a short synthetic video, read back from its file as ``vidstyle
    features`` reads one: the salient-point and descriptor kernels."""
    from .features.extract import process_video
    from .video.writer import VideoWriter

    rng = np.random.default_rng(0)
    background = rng.integers(0, 60, size=(120, 160, 3), dtype=np.uint8)
    patch = rng.integers(120, 256, size=(24, 24, 3), dtype=np.uint8)
    video = tmp / "moving.mp4"
    with VideoWriter(video, fps=20) as writer:
        for k in range(24):
            frame = background.copy()
            x, y = 20 + 4 * k, 40 + (k % 6) * 3
            frame[y:y + 24, x:x + 24] = patch
            writer.write(frame)
    summary = process_video(video, tmp / "moving.npz")
    if not summary["points"]:
        raise RuntimeError("the warm-up video gave no salient points, so the descriptor kernels were not compiled")


def _graph(tmp: Path) -> None:
    """A motion graph of two short clips (the distance kernels)."""
    from .motiongraph import MotionGraph
    from .motiongraph.graph import Clip
    from .render.samples import sample_motion

    clips = [Clip(name=f"walk{k}", motion=sample_motion(120, fps=60.0, speed=speed), labels=["Walk"] * 120)
             for k, speed in enumerate((0.8, 1.2))]
    MotionGraph(window=10, fps=30).fit(clips)


def _arrays(tmp: Path) -> None:
    """The array kernels: pose distance transforms, subsequence DTW, the Markov in-betweener's segment
    search, the action models' DTW, and the descriptor's reference top-3 / pow kernels."""
    from .actionmodel.dtw import dtw
    from .features.scovanner2007 import assign_bins_numpy
    from .inbetween.markov import segment_path
    from .pose.dt import dt2d, min_plus
    from .reconstruct.subsequence import accumulated_cost, subsequence_dtw, warping_positions

    rng = np.random.default_rng(0)
    D, _, _ = dt2d(rng.random((2, 8, 9)), 0.5, 0.7)
    min_plus(D, rng.random((3, 2)))

    library, query = rng.random((30, 4)), rng.random((6, 4))
    first = np.zeros(30, dtype=np.int64)
    Dq, steps = subsequence_dtw(query, library, first)
    warping_positions(steps, int(np.argmin(Dq[-1])))
    Dc, steps_c = accumulated_cost(rng.random((6, 30)), first)
    warping_positions(steps_c, int(np.argmin(Dc[-1])))

    dtw(rng.random((7, 9)))

    labels = np.array([0, 0, 1, 1, 2, 2, 0, 1], dtype=np.int64)
    cont = np.array([False, True, True, True, False, True, True, True])
    segment_path(labels, cont, np.array([0, 1, 2, 1], dtype=np.int64), rng.random(8), rng.random(8), 1.0, 0.5,
                 emission=rng.random((8, 3)), warp_cost=0.2)

    assign_bins_numpy(*rng.standard_normal((3, 20)))


#: the warm-up tasks, by name
TASKS = {"render": _render, "features": _features, "graph": _graph, "arrays": _arrays}


def _run(name: str) -> tuple[str, float]:
    t = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix=f"vidstyle-compile-{name}-") as tmp:
        TASKS[name](Path(tmp))
    return name, time.perf_counter() - t


def warm(jobs: int = -1) -> dict[str, float]:
    """Run every task (in parallel over ``jobs`` workers); return each task's seconds."""
    from .parallel import parallel_map

    # the slowest first, so that two workers finish together
    order = ["render", "features", "arrays", "graph"]
    return dict(parallel_map(_run, order, jobs=jobs, description="compiling kernels"))


__all__ = ["TASKS", "warm"]
