"""Stick-figure contact sheets of a motion (for looking at what the generator makes, without the
renderer): each cell is one frame seen from one camera azimuth, orthographic, the floor as a line."""

from __future__ import annotations

import os

import numpy as np

from ..mocap import Motion, global_positions

_LIMB_COLOURS = {"Left": (60, 60, 230), "Right": (230, 90, 40)}  # BGR: left red, right blue
_VIEWS = {"front": 0.0, "left": 90.0, "right": -90.0}


def contact_sheet(motion: Motion, frames: list[int], views: list[str | float], cell: int = 160,
                  facing: float | None = None) -> np.ndarray:
    """(rows = views, columns = frames) BGR image. A view is an azimuth in degrees relative to the
    character's facing (0 = camera in front, 90 = camera on the character's left), or a name."""
    import cv2

    pos = global_positions(motion)
    if facing is None:
        facing = float(np.median(motion.facing_angles()))
    sk = motion.skeleton
    lo_y, hi_y = 0.0, max(pos[..., 1].max(), 1e-6)
    span = hi_y * 1.15
    img = np.full((cell * len(views), cell * len(frames), 3), 245, np.uint8)
    centre = pos[:, 0, [0, 2]].mean(axis=0)
    for r, view in enumerate(views):
        az = np.deg2rad(_VIEWS.get(view, view) if isinstance(view, str) else view) + facing
        # camera on the unit circle at azimuth az (0 = along +Z), looking at the centre
        right = np.array([np.cos(az), 0.0, -np.sin(az)])
        for k, f in enumerate(frames):
            p = pos[f].copy()
            p[:, [0, 2]] -= centre
            u = p @ right
            v = p[:, 1]
            px = (cell * (k + 0.5) + u / span * cell).astype(int)
            py = (cell * (r + 1) - 6 - (v - lo_y) / span * (cell - 12)).astype(int)
            cv2.line(img, (cell * k, cell * (r + 1) - 6), (cell * (k + 1), cell * (r + 1) - 6), (150, 150, 150), 1)
            for j, parent in enumerate(sk.parents):
                if parent < 0:
                    continue
                name = sk.names[j]
                side = "Left" if name.startswith(("Left", "LH", "LT")) else "Right" if name.startswith(
                    ("Right", "RH", "RT")) else None
                colour = _LIMB_COLOURS.get(side, (40, 40, 40))
                cv2.line(img, (px[parent], py[parent]), (px[j], py[j]), colour, 2, cv2.LINE_AA)
            cv2.putText(img, f"{f}", (cell * k + 3, cell * r + 12), cv2.FONT_HERSHEY_PLAIN, 0.8, (0, 0, 0), 1)
    return img


def write_contact_sheet(motion: Motion, frames: list[int], views: list[str | float], path: str | os.PathLike,
                        cell: int = 160) -> None:
    import cv2

    from ..fileio import atomic_path

    img = contact_sheet(motion, frames, views, cell)
    with atomic_path(path) as tmp:
        if not cv2.imwrite(str(tmp), img):
            raise OSError(f"{path}: could not write image")
