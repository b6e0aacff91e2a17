"""Person prior from a video: a static-camera background (per-pixel median of frames spread over the
video) and each frame's foreground map, turned into a per-part bonus for pictorial structures.

``part_coverage`` gives, for every part, orientation and cell of the frame's state grid, the mean
foreground of the part's template window (the window the detector reads, in the same rotated copy
of the frame); :meth:`PoseModel.estimate` adds ``fg_weight`` times it to the part's log-odds. Only
the relative bonus matters: a constant per part would not change the optimum.
"""

from __future__ import annotations

import cv2
import numpy as np

FG_LOW, FG_HIGH = 8.0, 30.0  # grey-level difference mapped to foreground 0 .. 1


def background_model(frames) -> np.ndarray:
    """Per-pixel median of a few frames (any iterable of equally sized uint8 images)."""
    stack = np.stack([np.asarray(f) for f in frames])
    if len(stack) < 3:
        raise ValueError("background_model needs at least 3 frames")
    return np.median(stack, axis=0).astype(np.float32)


def foreground(frame: np.ndarray, background: np.ndarray) -> np.ndarray:
    """(H, W) float32 in [0, 1]: largest channel difference to the background, blurred, ramped
    from FG_LOW (0) to FG_HIGH (1) grey levels."""
    d = np.abs(np.asarray(frame, np.float32) - background)
    if d.ndim == 3:
        d = d.max(axis=2)
    d = cv2.GaussianBlur(d, (5, 5), 1.0)
    return np.clip((d - FG_LOW) / (FG_HIGH - FG_LOW), 0.0, 1.0).astype(np.float32)


def part_coverage(model, f, fg: np.ndarray) -> np.ndarray:
    """(10, K, Hc, Wc) mean foreground of each part's window at every state (``model`` a
    :class:`~vidstyle.pose.model.PictorialStructures`, ``f`` the frame's RotatedFeatures, ``fg`` the
    frame's foreground at the working size)."""
    from .model import N_PARTS, canvas_maps

    cell = model.cell
    Hc, Wc, maps = canvas_maps(f, cell)
    K = f.n_orient
    Sc = f.S // cell
    copies = {}
    for k in range(K):
        c = f.copy_index(k)
        if c not in copies:
            rot = cv2.warpAffine(fg, f.mats[k], (f.S, f.S), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                                 borderValue=0.0)
            copies[c] = cv2.resize(rot, (Sc, Sc), interpolation=cv2.INTER_AREA)
    out = np.zeros((N_PARTS, K, Hc, Wc), np.float32)
    for j in range(N_PARTS):
        h, w = model.sizes_[j]
        boxed = {c: cv2.boxFilter(img, -1, (w, h), normalize=True, borderType=cv2.BORDER_CONSTANT)
                 for c, img in copies.items()}
        for k in range(K):
            mx, my = maps[k]
            out[j, k] = cv2.remap(boxed[f.copy_index(k)], mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                                  borderValue=0.0)
    return out
