"""Transition styles: a performer's own way of getting from one action to another.

A plain motion graph blends straight from the end of one action into the start of the next. Real
performers often pass through a distinctive pose instead (thesis 5.2: "a walking to jumping transition
will involve stopping and slightly crouching"). Each demo performer gets such a habit for a few action
pairs, drawn from their seed; the guard pause between those two actions is then animated as the
transition movement, and the ground truth records its exact frames (the 3D motion is the take's BVH).

Three kinds, written for an orthodox fighter as ``(phase, pose)`` keys like :mod:`.actions`:

- ``crouch``: the fighter sinks deep into the knees, leans forward, fists lowered to the chin line;
- ``hop``: a small hop to a square stance (both feet side by side, in the air) and back;
- ``step_back``: a step back with the guard dropped to the waist, leaning away, then back in.

The mocap library of :mod:`vidstyle.demo.library` holds the same poses in *other* contexts (a dodge,
a double stance switch, a stop), never between the two actions of a performer's transition.
"""

from __future__ import annotations

import numpy as np

from .actions import ACTIONS, ANKLE, Key

TRANSITION_KINDS: tuple[str, ...] = ("crouch", "hop", "step_back")

CROUCH_POSE = {"py": -0.095, "pitch": 20.0, "cpitch": 12.0, "hpitch": -14.0, "cyaw": -2.0,
               "lh": (-0.26, 0.02, 0.42), "le": (0.3, -1.0, 0.2), "rh": (0.30, 0.00, 0.34),
               "re": (-0.3, -1.0, 0.2), "lk": (0.2, 0.0, 1.0), "rk": (-0.4, 0.0, 1.0)}
HOP_POSE = {"py": 0.035, "yaw": 0.0, "cyaw": 0.0, "lf": (0.11, ANKLE + 0.06, 0.01), "lfyaw": 0.0,
            "rf": (-0.11, ANKLE + 0.06, -0.01), "rfyaw": 0.0, "lk": (0.1, 0.0, 1.0), "rk": (-0.1, 0.0, 1.0),
            "lh": (-0.22, 0.30, 0.36), "rh": (0.22, 0.30, 0.36), "lfpitch": 15.0, "rfpitch": 15.0}
STEP_BACK_POSE = {"pz": -0.10, "lf": (0.07, ANKLE, 0.15 - 0.07), "rf": (-0.09, ANKLE, -0.15 - 0.12),
                  "pitch": -9.0, "cpitch": -8.0, "hpitch": 10.0, "lh": (-0.20, -0.34, 0.26),
                  "le": (0.4, -1.0, -0.1), "rh": (0.26, -0.36, 0.18), "re": (-0.4, -1.0, -0.1)}
_POSES = {"crouch": CROUCH_POSE, "hop": HOP_POSE, "step_back": STEP_BACK_POSE}
_LIFT = {"hop": {"lf": (0.08, ANKLE + 0.03, 0.09), "rf": (-0.10, ANKLE + 0.03, -0.09), "py": 0.01}}

MIN_FRAMES = 9
"""Video frames (at 20 fps) a styled transition takes at least; shorter guard pauses are lengthened."""

KEY_PHASES = (0.40, 0.60)
"""The transition pose is held between these phases of the pause; its middle is the *key frame*."""


def transition_keys(kind: str) -> list[Key]:
    """The keys of one transition movement over the whole guard pause (phase 0 and 1: the guard)."""
    pose = _POSES[kind]
    keys: list[Key] = [(0.0, {})]
    if kind in _LIFT:
        keys.append((0.2, _LIFT[kind]))
    keys += [(KEY_PHASES[0], pose), (KEY_PHASES[1], pose)]
    if kind in _LIFT:
        keys.append((0.8, _LIFT[kind]))
    keys.append((1.0, {}))
    return keys


def draw_transition_styles(rng: np.random.Generator, transition: np.ndarray, n_pairs: int = 3
                           ) -> tuple[tuple[str, str, str], ...]:
    """``n_pairs`` distinct (from, to, kind) habits between *different* actions; pairs the performer's
    chain visits often are likelier, so the habit shows in their performances."""
    A = len(ACTIONS)
    w = np.asarray(transition, dtype=np.float64).copy()
    np.fill_diagonal(w, 0.0)
    flat = w.ravel() / w.sum()
    picks = rng.choice(A * A, size=n_pairs, replace=False, p=flat)
    kinds = rng.choice(len(TRANSITION_KINDS), size=n_pairs)
    return tuple((ACTIONS[p // A], ACTIONS[p % A], TRANSITION_KINDS[k]) for p, k in zip(picks, kinds))
