"""Du's (2014, 4.4) naturalness figures of a motion, and reconstruction error, for action models.

For a motion (an action instance, sampled or captured) on a skeleton whose ankles
:func:`vidstyle.mocap.keypoints.keypoint_joints` finds, with planted frames from
:func:`vidstyle.actionmodel.instances.clip_contacts` (the same detector for samples and sources, run on
the instance alone):

* ``slide_mm_per_frame``: mean horizontal displacement of a planted ankle between two planted frames
  (:func:`vidstyle.reconstruct.metrics.foot_skate`), physical correctness.
* ``contact_height_error_mm``: mean ``|ankle height - planted ankle height|`` over planted frames: how far
  a planted foot is from where a planted foot belongs (the model's ``contact_height_``, learned from the
  source clips; Du's distance between contact point and contact plane).
* ``velocity_variance_mm2``: Du's naturalness measure, the variance over frames of the forward difference
  of the joint positions (mm/frame), averaged over joints and axes; natural motion changes smoothly.
* ``acceleration_mm_per_frame2``: mean magnitude of the second difference of joint positions (jerky
  samples show here first).

Everything is in millimetres with ``unit_mm`` millimetres per length unit of the motion.
"""

from __future__ import annotations

import math

import numpy as np

from ..mocap import Motion

FIGURES = ("slide_mm_per_frame", "contact_height_error_mm", "velocity_variance_mm2", "acceleration_mm_per_frame2")


def naturalness(motion: Motion, contact_height: float, unit_mm: float = 1.0, min_run: int = 3) -> dict:
    """The figures of the module text for one motion, plus ``frames`` and ``planted_frames``."""
    from ..mocap.keypoints import keypoint_positions
    from ..reconstruct.metrics import ANKLES, foot_skate
    from .instances import clip_contacts

    pts = keypoint_positions(motion)
    contacts = clip_contacts(motion, min_run)
    slide = foot_skate(pts, contacts) if len(pts) > 1 else math.nan
    ank = pts[:, list(ANKLES), 1]
    err = np.abs(ank[contacts] - contact_height)
    from ..mocap.kinematics import forward_kinematics

    pos = forward_kinematics(motion, return_matrices=False)[0] * unit_mm
    v = np.diff(pos, axis=0)
    a = np.diff(pos, n=2, axis=0)
    return {
        "frames": int(motion.n_frames),
        "planted_frames": int(contacts.any(1).sum()),
        "slide_mm_per_frame": float(slide * unit_mm) if math.isfinite(slide) else None,
        "contact_height_error_mm": float(err.mean() * unit_mm) if err.size else None,
        "velocity_variance_mm2": float(v.var(axis=0).mean()) if len(v) > 1 else None,
        "acceleration_mm_per_frame2": float(np.linalg.norm(a, axis=-1).mean()) if len(a) else None,
    }


def pooled(rows: list[dict]) -> dict:
    """Mean of every figure over ``rows`` (None where no row has it), planted-frame weighted for the two
    contact figures."""
    out = {}
    for k in FIGURES:
        vals = [(r[k], r["planted_frames"] if k in FIGURES[:2] else 1) for r in rows if r.get(k) is not None]
        w = sum(x[1] for x in vals)
        out[k] = float(sum(x * wt for x, wt in vals) / w) if vals and w > 0 else None
    out["instances"] = len(rows)
    return out


def mpjpe(a: Motion, b: Motion, unit_mm: float = 1.0) -> float:
    """Mean per-joint position error (mm) between two motions of one skeleton and length (canonical
    frames, so no alignment)."""
    from ..mocap.kinematics import forward_kinematics

    if a.n_frames != b.n_frames:
        raise ValueError(f"frame counts differ: {a.n_frames} vs {b.n_frames}")
    pa = forward_kinematics(a, return_matrices=False)[0]
    pb = forward_kinematics(b, return_matrices=False)[0]
    return float(np.linalg.norm(pa - pb, axis=-1).mean() * unit_mm)


def time_normalised_positions(motion: Motion, frames: int = 32) -> np.ndarray:
    """(frames, J, 3) joint positions of ``motion`` resampled linearly to ``frames`` frames."""
    from ..mocap.kinematics import forward_kinematics

    pos = forward_kinematics(motion, return_matrices=False)[0]
    t = np.linspace(0, len(pos) - 1, frames)
    i0 = np.floor(t).astype(int)
    i1 = np.minimum(i0 + 1, len(pos) - 1)
    a = (t - i0)[:, None, None]
    return (1 - a) * pos[i0] + a * pos[i1]


def nearest_distances(queries: list[np.ndarray], refs: list[np.ndarray], unit_mm: float = 1.0,
                      leave_one_out: bool = False) -> np.ndarray:
    """Per query, the least mean joint distance (mm) to any of ``refs`` (time-normalised positions,
    :func:`time_normalised_positions`); ``leave_one_out``: queries are the refs, each skips itself.
    Samples as far from their nearest source as a source is from its nearest other source are new
    instances of the same spread, not copies (near 0) nor outliers (far above)."""
    Q = np.stack(queries)
    R = np.stack(refs)
    d = np.linalg.norm(Q[:, None] - R[None], axis=-1).mean(axis=(2, 3)) * unit_mm
    if leave_one_out:
        np.fill_diagonal(d, np.inf)
    return d.min(axis=1)
