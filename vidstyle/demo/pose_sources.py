"""The demo performers as a training source of the pose model: ``"demo:<i>"`` specs of
:func:`vidstyle.pose.data.make_specs` render performer ``p<i>`` (:class:`vidstyle.demo.Performer`, seeded by
``(seed, i)``) doing a random performance plan. Registered with :func:`vidstyle.pose.data.register_source`
when :mod:`vidstyle.demo` is imported (the pose package never imports the demo)."""

from __future__ import annotations

import numpy as np

from ..pose.data import register_source

SOURCE = "demo"


def demo_motion(index: int, seconds: float, seed: int):
    """Motion of demo performer ``index`` (20 fps video rate), at least ``seconds`` long."""
    from .performer import Performer
    from .timeline import build_take, performance_plan

    rng = np.random.default_rng(np.random.SeedSequence([seed, index]))
    p = Performer.random(f"p{index:02d}", rng, video_fps=20)
    take = build_take(p, performance_plan(p, round(seconds * 20) + 4, rng), rng, video_fps=20)
    return take.motion


register_source(SOURCE, demo_motion)
