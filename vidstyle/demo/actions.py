"""Keyframes of the guard stance, the six kickboxing actions of the thesis' database, and steps.

Every action is written for an orthodox fighter (left side forward, left lead hand, right rear leg)
facing an opponent along +Z, as a list of ``(phase, pose)`` keys, phase 0..1 over the action's
duration; a pose lists only the channels (:data:`vidstyle.demo.rig.CHANNELS`) that leave the guard, with
grouped shorthands (``lh`` = ``lhx, lhy, lhz``; see :data:`GROUPS`). Every action begins and ends
at phase 0 / 1 in the guard, so actions chain in any order. A performer applies its style to the
*difference* from the reference guard (amplitude scales it), so the shapes stay recognisable while
reach, height and rhythm differ between performers. Southpaws are mirror images.

What makes each action distinct in any view (the recogniser sees 160x120 video):
Jab - the lead arm straightens forward at shoulder height, fast, little else moves.
Hook - the lead elbow rises to shoulder height and the fist sweeps sideways across, the chest and
pelvis twist hard and the lead foot pivots.
Uppercut - a knee dip, the rear fist drops to the waist and drives up in front of the chin.
Defense - both forearms up in front of the face, body leaning back, held.
LowKick - the rear shin swings across at thigh height with the hips turned 50 degrees.
RoundhouseKick - the rear knee chambers high, the leg whips out above hip height with the pelvis
turned sideways and tilted, the support foot pivoting 90 degrees, the rear arm swinging down.
"""

from __future__ import annotations

import numpy as np

from .rig import CH, CHANNELS

ACTIONS: tuple[str, ...] = ("Jab", "Hook", "Uppercut", "Defense", "LowKick", "RoundhouseKick")
CLASSES: tuple[str, ...] = ACTIONS + ("Guard", "Step")

GROUPS = {
    "lh": ("lhx", "lhy", "lhz"), "le": ("lex", "ley", "lez"),
    "rh": ("rhx", "rhy", "rhz"), "re": ("rex", "rey", "rez"),
    "lf": ("lfx", "lfy", "lfz"), "lk": ("lkx", "lky", "lkz"),
    "rf": ("rfx", "rfy", "rfz"), "rk": ("rkx", "rky", "rkz"),
}

ANKLE = 0.039  # flat-foot ankle height, statures (vidstyle.demo.skeleton.Body.ankle_height / H)

GUARD: dict[str, float | tuple[float, ...]] = {
    "px": 0.0, "py": 0.0, "pz": 0.0, "yaw": -22.0, "pitch": 4.0, "roll": 0.0,
    "cyaw": -8.0, "cpitch": 6.0, "croll": 0.0, "hpitch": 6.0,
    "lh": (-0.30, 0.20, 0.42), "le": (0.25, -1.0, -0.35),
    "rh": (0.36, 0.17, 0.32), "re": (-0.25, -1.0, -0.35),
    "lf": (0.07, ANKLE, 0.15), "lfyaw": -12.0, "lfpitch": 0.0, "lk": (0.1, 0.0, 1.0),
    "rf": (-0.09, ANKLE, -0.15), "rfyaw": -40.0, "rfpitch": 0.0, "rk": (-0.55, 0.0, 0.85),
}

Key = tuple[float, dict[str, float | tuple[float, ...]]]

_JAB_OUT = {"lh": (-0.28, 0.10, 1.0), "le": (0.6, -1.0, 0.0), "cyaw": -20.0, "yaw": -26.0, "pz": 0.012,
            "rh": (0.34, 0.16, 0.26)}
_HOOK_HIT = {"lh": (-0.70, 0.12, 0.55), "le": (0.6, 1.0, -0.2), "cyaw": -38.0, "yaw": -38.0,
             "lfyaw": -45.0, "croll": -6.0, "rh": (0.36, 0.20, 0.30)}
_UPPER_HIT = {"rh": (0.50, 0.22, 0.50), "re": (0.0, -1.0, 0.3), "cyaw": 14.0, "yaw": 2.0, "py": 0.004,
              "cpitch": -4.0, "rfyaw": -15.0, "croll": 5.0}
_COVER = {"lh": (-0.32, 0.48, 0.30), "le": (0.15, -1.0, 0.9), "rh": (0.34, 0.48, 0.30),
          "re": (-0.15, -1.0, 0.9), "cpitch": -14.0, "pitch": -6.0, "hpitch": 18.0, "py": -0.015,
          "pz": -0.02, "cyaw": 4.0}
_LOW_HIT = {"rf": (0.20, 0.21, 0.40), "rk": (-0.1, 0.9, 0.6), "rfpitch": 35.0, "rfyaw": 20.0,
            "yaw": 32.0, "cyaw": -30.0, "roll": -6.0, "lfyaw": 25.0, "px": 0.035, "pz": 0.05,
            "rh": (0.30, 0.05, 0.30), "lh": (-0.28, 0.26, 0.40)}
_RH_CHAMBER = {"rf": (-0.10, 0.42, 0.12), "rk": (0.3, 0.5, 1.0), "rfpitch": 55.0, "rfyaw": 0.0,
               "yaw": 35.0, "cyaw": -30.0, "roll": -10.0, "lfyaw": 30.0, "px": 0.05, "pz": 0.04,
               "py": -0.008, "rh": (0.30, 0.0, 0.20)}
_RH_HIT = {"rf": (0.10, 0.76, 0.52), "rk": (0.8, 0.5, 0.0), "rfpitch": 70.0, "rfyaw": 80.0,
           "yaw": 85.0, "cyaw": -40.0, "roll": -28.0, "croll": 18.0, "cpitch": -6.0, "lfyaw": 80.0,
           "px": 0.06, "pz": 0.045, "py": -0.01, "rh": (0.10, -0.55, -0.15), "re": (-0.5, 0.0, -1.0),
           "lh": (-0.20, 0.30, 0.40)}

ACTION_KEYS: dict[str, list[Key]] = {
    "Jab": [(0.0, {}), (0.38, _JAB_OUT), (0.52, _JAB_OUT), (1.0, {})],
    "Hook": [
        (0.0, {}),
        (0.22, {"lh": (-0.02, 0.16, 0.48), "le": (1.0, 0.2, -0.6), "cyaw": 2.0, "yaw": -16.0}),
        (0.50, _HOOK_HIT),
        (0.62, {**_HOOK_HIT, "lh": (-0.78, 0.12, 0.45)}),
        # the elbow comes back down round the outside, never through the shoulder-fist line
        (0.82, {"lh": (-0.50, 0.18, 0.44), "le": (0.4, -0.4, -1.0), "cyaw": -18.0, "yaw": -28.0, "lfyaw": -25.0}),
        (1.0, {}),
    ],
    "Uppercut": [
        (0.0, {}),
        (0.30, {"rh": (0.30, -0.32, 0.30), "re": (-0.3, -1.0, -0.4), "py": -0.035, "cyaw": -18.0,
                "croll": -8.0, "cpitch": 12.0}),
        (0.55, _UPPER_HIT),
        (0.68, _UPPER_HIT),
        (1.0, {}),
    ],
    "Defense": [(0.0, {}), (0.22, _COVER), (0.78, {**_COVER, "cpitch": -16.0, "py": -0.02}), (1.0, {})],
    "LowKick": [
        (0.0, {}),
        (0.22, {"rf": (-0.05, 0.10, -0.06), "rk": (-0.2, 0.5, 1.0), "rfpitch": 12.0, "yaw": 5.0,
                "cyaw": -16.0, "px": 0.025, "pz": 0.03, "lfyaw": 5.0}),
        (0.48, _LOW_HIT),
        (0.60, {**_LOW_HIT, "rf": (0.28, 0.19, 0.32)}),
        (0.82, {"rf": (-0.06, 0.09, -0.08), "rk": (-0.3, 0.4, 1.0), "rfpitch": 10.0, "yaw": 0.0,
                "cyaw": -14.0, "px": 0.02, "pz": 0.02}),
        (1.0, {}),
    ],
    "RoundhouseKick": [
        (0.0, {}),
        (0.24, _RH_CHAMBER),
        (0.46, _RH_HIT),
        (0.58, {**_RH_HIT, "rf": (0.16, 0.74, 0.46)}),
        (0.80, {**_RH_CHAMBER, "yaw": 25.0, "lfyaw": 15.0}),
        (1.0, {}),
    ],
}

# Footwork of the punches (MovementTraits.footwork, off by default): what a real fighter's lower body does while
# an arm strikes, which the keys above leave in the guard (the strikes diagnostics found the recognizer learned
# punches by that still lower body, and read real punches, with their weight shift, as kicks). Channel deltas
# at full footwork for an orthodox fighter (statures, degrees), added to each key of the punch in proportion
# to how far the striking hands are out of the guard at that key, so the action still starts and ends in it:
# Jab - the weight goes onto the lead leg, the rear foot turns in; the lead foot steps in (PUNCH_STEP) and back;
# Hook - the weight shifts over the lead leg and the rear foot pivots;
# Uppercut - a deeper dip, the hips drive forward, the rear foot pivots.
# (The rig turns a foot about its ankle, so a heel lifted off a planted ball is not drawn.)
PUNCH_FOOTWORK: dict[str, dict[str, float]] = {
    "Jab": {"pz": 0.04, "py": -0.006, "rfyaw": 10.0, "pitch": 4.0},
    "Hook": {"px": -0.03, "pz": 0.015, "py": -0.01, "rfyaw": 25.0, "yaw": -8.0},
    "Uppercut": {"pz": 0.025, "px": -0.015, "py": -0.012, "rfyaw": 35.0},
}
#: the lead foot's step in (statures forward at full footwork) and its lift on the way there and back
PUNCH_STEP: dict[str, float] = {"Jab": 0.07}
STEP_LIFT = 0.025


def with_footwork(action: str, keys: list[Key], amount: float) -> tuple[list[Key], list[tuple[int, int, float]]]:
    """``keys`` of ``action`` with :data:`PUNCH_FOOTWORK` added at ``amount`` (0..1), and for the actions of
    :data:`PUNCH_STEP` the lead foot stepped in while the hand is out; unchanged for 0 and for actions without
    footwork. Also the lifts of the lead foot as ``(first key, last key, height in statures)``: it travels
    between those keys, on its way in and out, and is to be raised by a smooth bump over that span after the keys
    are interpolated (a lift in the keys would get their noise and could put the foot through the floor)."""
    if amount <= 0 or action not in PUNCH_FOOTWORK:
        return keys, []
    hands = [CH[c] for g in ("lh", "rh") for c in GROUPS[g]]
    vecs = [pose_vector(pose) for _, pose in keys]
    reach = np.array([float(np.linalg.norm((v - GUARD_VECTOR)[hands])) for v in vecs])
    if reach.max() <= 0:
        return keys, []
    w = amount * reach / reach.max()
    for v, wk in zip(vecs, w):
        for ch, d in PUNCH_FOOTWORK[action].items():
            v[CH[ch]] += wk * d
    lifts = []
    if action in PUNCH_STEP:
        hold = np.flatnonzero(reach >= 0.999 * reach.max())
        first, last = int(hold[0]), int(hold[-1])  # the strike's hit and the end of its hold
        for i in range(first, last + 1):
            vecs[i][CH["lfz"]] += amount * PUNCH_STEP[action]
        lifts = [(first - 1, first, amount * STEP_LIFT), (last, last + 1, amount * STEP_LIFT)]
    return [(ph, {c: float(v[i]) for i, c in enumerate(CHANNELS) if abs(v[i] - GUARD_VECTOR[i]) > 1e-12})
            for (ph, _), v in zip(keys, vecs)], lifts


# A step is a forward shuffle of STEP_LENGTH statures (lead foot first); backward is the reverse order.
STEP_LENGTH = 0.11
STEP_KEYS_FORWARD: list[Key] = [
    (0.0, {}),
    (0.35, {"lf": (0.07, ANKLE + 0.03, 0.15 + STEP_LENGTH * 0.6), "pz": STEP_LENGTH * 0.45, "lfpitch": -10.0}),
    (0.50, {"lf": (0.07, ANKLE, 0.15 + STEP_LENGTH), "pz": STEP_LENGTH * 0.7}),
    (0.75, {"lf": (0.07, ANKLE, 0.15 + STEP_LENGTH), "rf": (-0.09, ANKLE + 0.03, -0.15 + STEP_LENGTH * 0.6),
            "pz": STEP_LENGTH * 0.9, "rfpitch": 10.0}),
    (1.0, {"lf": (0.07, ANKLE, 0.15 + STEP_LENGTH), "rf": (-0.09, ANKLE, -0.15 + STEP_LENGTH),
           "pz": STEP_LENGTH}),
]
STEP_KEYS_BACKWARD: list[Key] = [
    (0.0, {}),
    (0.35, {"rf": (-0.09, ANKLE + 0.03, -0.15 - STEP_LENGTH * 0.6), "pz": -STEP_LENGTH * 0.45, "rfpitch": 10.0}),
    (0.50, {"rf": (-0.09, ANKLE, -0.15 - STEP_LENGTH), "pz": -STEP_LENGTH * 0.7}),
    (0.75, {"rf": (-0.09, ANKLE, -0.15 - STEP_LENGTH), "lf": (0.07, ANKLE + 0.03, 0.15 - STEP_LENGTH * 0.6),
            "pz": -STEP_LENGTH * 0.9, "lfpitch": -10.0}),
    (1.0, {"rf": (-0.09, ANKLE, -0.15 - STEP_LENGTH), "lf": (0.07, ANKLE, 0.15 - STEP_LENGTH),
           "pz": -STEP_LENGTH}),
]

BASE_SECONDS: dict[str, float] = {
    "Jab": 0.50, "Hook": 0.75, "Uppercut": 0.70, "Defense": 0.95, "LowKick": 0.90, "RoundhouseKick": 1.15,
    "Step": 0.60,
}
"""Duration of each action at speed 1."""


def pose_vector(pose: dict[str, float | tuple[float, ...]], base: np.ndarray | None = None) -> np.ndarray:
    """A full channel vector: ``base`` (default the reference guard) overridden by ``pose``."""
    out = (GUARD_VECTOR if base is None else base).copy()
    for name, value in pose.items():
        if name in GROUPS:
            for ch, v in zip(GROUPS[name], value):  # type: ignore[arg-type]
                out[CH[ch]] = v
        else:
            out[CH[name]] = float(value)  # type: ignore[arg-type]
    return out


GUARD_VECTOR = np.zeros(len(CHANNELS))
GUARD_VECTOR = pose_vector(GUARD, GUARD_VECTOR)

# channels holding world positions: a step moves the stance, these follow the stance origin
POSITION_X = tuple(CH[c] for c in ("px", "lfx", "rfx"))
POSITION_Z = tuple(CH[c] for c in ("pz", "lfz", "rfz"))
