"""Takes: a plan of labelled segments (actions, guard pauses, steps) -> one continuous motion + labels.

PlanStep lengths are whole *video* frames; the mocap runs at an integer multiple of the video rate
(``ratio``), so video frame ``k`` is mocap frame ``ratio * k`` and every label boundary falls exactly on
a video frame. All keys of a take go into one shape-preserving cubic (PCHIP) per channel: C1 motion,
no overshoot past a key (so a fist never flies beyond its target and planted feet never dip below the
floor), and zero velocity at each extreme pose, which reads as the ease-in/ease-out of a strike.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import PchipInterpolator

from ..mocap import Motion
from .actions import (
    ACTION_KEYS,
    ACTIONS,
    BASE_SECONDS,
    GUARD_VECTOR,
    POSITION_X,
    POSITION_Z,
    STEP_KEYS_BACKWARD,
    STEP_KEYS_FORWARD,
    Key,
    pose_vector,
    with_footwork,
)
from .performer import Performer
from .rig import CH, CHANNELS, solve_motion
from .transitions import KEY_PHASES, MIN_FRAMES, transition_keys

_NOISE_SCALE = np.ones(len(CHANNELS))
for _c in ("yaw", "pitch", "roll", "cyaw", "cpitch", "croll", "hpitch", "lfyaw", "lfpitch", "rfyaw", "rfpitch"):
    _NOISE_SCALE[CH[_c]] = 60.0  # degrees per unit of variation
for _c in ("px", "py", "pz"):
    _NOISE_SCALE[CH[_c]] = 0.1
for _c in ("lfx", "lfy", "lfz", "rfx", "rfy", "rfz"):
    _NOISE_SCALE[CH[_c]] = 0.5

_FOOT_POSITIONS = tuple(tuple(CH[f"{f}{a}"] for a in "xyz") for f in ("lf", "rf"))


@dataclass
class PlanStep:
    label: str
    frames: int  # video frames
    step: int = 0  # +1 forward, -1 backward (Step segments)
    keys: list[Key] | None = None  # own keys (a transition style or a library movement), guard to guard
    style: str = ""  # the transition kind animated in this guard pause (:mod:`.transitions`)


@dataclass
class Take:
    """One continuous performance: the motion and a label per mocap frame."""

    motion: Motion
    labels: list[str]
    plan: list[PlanStep]
    ratio: int  # mocap frames per video frame
    chain: list[str] = field(default_factory=list)
    transitions: list[dict] = field(default_factory=list)
    """Styled transitions: ``{"from", "to", "kind", "start", "end", "key"}`` in mocap frames (``end``
    exclusive; ``key`` is the middle of the held transition pose)."""

    @property
    def video_labels(self) -> list[str]:
        return self.labels[:: self.ratio]


def performer_guard(p: Performer) -> np.ndarray:
    """The performer's own guard: the reference guard adjusted by their style."""
    g = GUARD_VECTOR.copy()
    s = p.style
    g[CH["lhy"]] += s.guard_height
    g[CH["rhy"]] += s.guard_height
    for c in ("lfx", "lfz", "rfx", "rfz"):
        g[CH[c]] *= s.stance_width
    g[CH["py"]] -= s.crouch
    return g


def _keys_of(p: Performer, guard: np.ndarray, keys: list[Key], t0: float, duration: float,
             origin: np.ndarray, rng: np.random.Generator, noisy: bool) -> tuple[list[float], list[np.ndarray]]:
    var = p.style.variation if noisy else 0.0
    phases = np.array([ph for ph, _ in keys])
    if var > 0 and len(phases) > 2:
        inner = phases[1:-1] + rng.normal(0.0, 0.25 * var, len(phases) - 2)
        inner = np.clip(np.sort(inner), 0.06, 0.94)
        phases = np.concatenate([[0.0], inner, [1.0]])
        phases[1:] = np.maximum(phases[1:], phases[:-1] + 0.03)  # keep keys strictly ordered
        phases = np.minimum(phases, 1.0)
        phases[-1] = 1.0
    times, values = [], []
    for ph, (_, pose) in zip(phases, keys):
        delta = pose_vector(pose) - GUARD_VECTOR
        v = guard + p.style.amplitude * delta
        moving = np.abs(delta) > 1e-12
        for foot in _FOOT_POSITIONS:  # a foot at the guard's height is planted: its place gets no noise
            if not moving[foot[1]]:
                moving[list(foot)] = False
        if var > 0 and moving.any():
            v = v + moving * rng.normal(0.0, var, len(v)) * _NOISE_SCALE
        v[list(POSITION_X)] += origin[0]
        v[list(POSITION_Z)] += origin[1]
        times.append(t0 + ph * duration)
        values.append(v)
    return times, values


def build_take(p: Performer, plan: list[PlanStep], rng: np.random.Generator, video_fps: float = 20.0,
               ratio: int = 3) -> Take:
    """Animate ``plan``; orthodox keys are mirrored for a southpaw."""
    mocap_fps = video_fps * ratio
    guard = performer_guard(p)
    origin = np.zeros(2)
    times: list[float] = [0.0]
    values: list[np.ndarray] = [guard.copy()]
    frame = 0
    bounce_windows: list[tuple[float, float]] = []
    lift_windows: list[tuple[float, float, float]] = []  # the lead foot's lifts of punches with footwork
    labels: list[str] = []
    for seg in plan:
        t0, dur = frame / video_fps, seg.frames / video_fps
        if seg.keys is not None:  # deterministic: the take's random stream stays that of a plain take
            tk, vk = _keys_of(p, guard, seg.keys, t0, dur, origin, rng, noisy=False)
        elif seg.label == "Guard":
            bounce_windows.append((t0, dur))
            tk, vk = [t0 + dur], [values[-1].copy()]
        elif seg.label == "Step":
            keys = STEP_KEYS_FORWARD if seg.step > 0 else STEP_KEYS_BACKWARD
            tk, vk = _keys_of(p, guard, keys, t0, dur, origin, rng, noisy=False)
            origin = origin + np.array([0.0, p.style.amplitude * float(keys[-1][1]["pz"])])
        else:
            keys, lifts = with_footwork(seg.label, ACTION_KEYS[seg.label], p.style.footwork)
            tk, vk = _keys_of(p, guard, keys, t0, dur, origin, rng, noisy=True)
            lift_windows += [(tk[a], tk[b] - tk[a], p.style.amplitude * h) for a, b, h in lifts]
        # the segment's first key repeats the previous segment's last one (both are the guard)
        held = seg.label == "Guard" and seg.keys is None
        times += tk if held else tk[1:]
        values += vk if held else vk[1:]
        labels += [seg.label] * (seg.frames * ratio)
        frame += seg.frames
    n = frame * ratio
    t = np.arange(n) / mocap_fps
    T = np.asarray(times)
    V = np.stack(values)
    keep = np.concatenate([[True], np.diff(T) > 1e-9])
    channels = PchipInterpolator(T[keep], V[keep], axis=0, extrapolate=True)(t)
    for t0, dur in bounce_windows:
        inside = (t >= t0) & (t < t0 + dur)
        cycles = max(1, int(round(dur * p.style.bounce_hz)))
        wave = np.sin(np.pi * cycles * (t[inside] - t0) / dur) ** 2
        channels[inside, CH["py"]] -= p.style.bounce * wave
        channels[inside, CH["lhy"]] -= 0.6 * p.style.bounce * wave
        channels[inside, CH["rhy"]] -= 0.6 * p.style.bounce * wave
    for t0, dur, height in lift_windows:
        inside = (t >= t0) & (t < t0 + dur)
        channels[inside, CH["lfy"]] += height * np.sin(np.pi * (t[inside] - t0) / dur) ** 2
    motion = solve_motion(channels, p.body, mocap_fps)
    if p.style.lead == "southpaw":
        motion = motion.mirror()
    chain = [s.label for s in plan if s.label in ACTIONS]
    transitions, frame = [], 0
    for i, seg in enumerate(plan):
        if seg.style:
            start, end = frame * ratio, (frame + seg.frames) * ratio
            key = start + int(round(0.5 * (KEY_PHASES[0] + KEY_PHASES[1]) * (end - start)))
            transitions.append({"from": plan[i - 1].label, "to": plan[i + 1].label, "kind": seg.style,
                                "start": start, "end": end, "key": key})
        frame += seg.frames
    return Take(motion, labels, plan, ratio, chain, transitions)


# --------------------------------------------------------------------------- plans
def _gap(rng: np.random.Generator, lo: int, hi: int) -> int:
    return int(rng.integers(lo, hi + 1))


def single_action_plan(p: Performer, action: str, n_frames: int, rng: np.random.Generator) -> list[PlanStep]:
    """One action repeated with short guard pauses, filling ``n_frames`` video frames (the layout of
    the thesis' database: one action per video). Pauses stay short so the action is the majority."""
    fps = p.chain.video_fps
    plan = [PlanStep("Guard", _gap(rng, int(0.2 * fps), int(0.5 * fps)))]
    used = plan[0].frames
    while True:
        d = p.chain.sample_duration(action, rng)
        g = _gap(rng, max(2, int(0.12 * fps)), max(3, int(0.3 * fps)))
        if used + d + 2 > n_frames:
            break
        plan.append(PlanStep(action, d))
        plan.append(PlanStep("Guard", min(g, n_frames - used - d)))
        used += d + plan[-1].frames
    if used < n_frames:
        if plan[-1].label == "Guard":
            plan[-1].frames += n_frames - used
        else:
            plan.append(PlanStep("Guard", n_frames - used))
    return plan


def performance_plan(p: Performer, n_frames: int, rng: np.random.Generator) -> list[PlanStep]:
    """The performer following their own chain for ``n_frames`` video frames: actions separated by
    guard pauses of their habitual length, some pauses containing a step (forward or back, chosen to
    drift back towards the start so the performer stays in the camera's field)."""
    fps = p.chain.video_fps
    s = p.style
    plan = [PlanStep("Guard", _gap(rng, int(0.3 * fps), int(0.8 * fps)))]
    used = plan[0].frames
    prev: int | None = None
    position = 0
    step_frames = int(round(BASE_SECONDS["Step"] / s.speed * fps))
    while True:
        probs = p.chain.start if prev is None else p.chain.transition[prev]
        a = int(rng.choice(len(ACTIONS), p=probs))
        d = p.chain.sample_duration(ACTIONS[a], rng)
        gap = max(3, int(round(rng.normal(s.gap_seconds * fps, 0.3 * s.gap_seconds * fps))))
        take_step = rng.random() < s.step_prob
        extra = (step_frames + 3) if take_step else 0
        if used + d + gap + extra > n_frames:
            break
        plan.append(PlanStep(ACTIONS[a], d))
        if take_step:
            direction = -1 if position > 0 else 1 if position < 0 else (1 if rng.random() < 0.5 else -1)
            position += direction
            first = max(2, gap // 2)
            plan += [PlanStep("Guard", first), PlanStep("Step", step_frames, direction),
                     PlanStep("Guard", max(3, gap - first))]
            used += d + step_frames + first + max(3, gap - first)
        else:
            plan.append(PlanStep("Guard", gap))
            used += d + gap
        prev = a
    plan[-1].frames += n_frames - used  # the last segment is always a guard pause
    return apply_transition_styles(p, plan, n_frames)


def apply_transition_styles(p: Performer, plan: list[PlanStep], n_frames: int) -> list[PlanStep]:
    """Animate every guard pause between two actions the performer has a transition habit for as that
    transition (lengthened to :data:`MIN_FRAMES` where shorter). If lengthening overruns ``n_frames``,
    trailing segments are dropped and the final guard pause absorbs the rest. Plans without such a
    pair come back unchanged."""
    min_frames = int(round(MIN_FRAMES * p.chain.video_fps / 20.0))
    out = [PlanStep(s.label, s.frames, s.step, s.keys, s.style) for s in plan]
    for i in range(1, len(out) - 1):
        a, g, b = out[i - 1], out[i], out[i + 1]
        kind = p.transition_kind(a.label, b.label) if g.label == "Guard" else None
        if kind and a.label in ACTIONS and b.label in ACTIONS:
            g.keys, g.style, g.frames = transition_keys(kind), kind, max(g.frames, min_frames)
    if all(not s.style for s in out):
        return out
    while sum(s.frames for s in out) > n_frames or out[-1].label != "Guard" or out[-1].style:
        out.pop()  # the first segment is a plain guard pause, so this stops
    out[-1].frames += n_frames - sum(s.frames for s in out)
    return out
