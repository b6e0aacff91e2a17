"""Dense gradient-orientation cells (HOG-like, Dalal & Triggs) on rotated copies of a frame.

``cell_features(gray)`` -> (H/c, W/c, B): per ``cell`` x ``cell`` pixel cell, the gradient magnitude
histogram over ``B`` unsigned orientation bins (linear soft binning), normalised by the energy of the
3x3 cell neighbourhood (a cheap stand-in for HOG's overlapping 2x2 blocks), then clipped at 0.4 and
square-rooted; plus one channel with the cell's mean normalised gradient energy.

With ``rotate=False`` only the unrotated frame's cells are computed and every orientation reads them:
the per-orientation mixture templates of Yang & Ramanan instead of rotated copies.

``RotatedFeatures`` computes the cells of the frame rotated by each of ``n_orient`` angles so that a
part of orientation ``theta_k`` (direction proximal -> distal, image angle ``atan2(dy, dx)``) points
straight down (+y) in copy ``k``: part templates are then learned and applied upright only (the
"rotated templates" of Andriluka et al.). Copies are drawn on a square canvas of the frame's diagonal,
so nothing is cut off.
"""

from __future__ import annotations

import math

import cv2
import numpy as np


def cell_features(gray: np.ndarray, cell: int = 4, bins: int = 9) -> np.ndarray:
    g = np.asarray(gray, dtype=np.float32)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=1)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=1)
    mag = cv2.magnitude(gx, gy)
    ang = (np.arctan2(gy, gx) % np.pi) * (bins / np.pi)  # [0, bins)
    b0 = np.floor(ang).astype(np.int32) % bins
    frac = ang - np.floor(ang)
    H, W = g.shape
    Hc, Wc = H // cell, W // cell
    g_idx = _cell_index(H, W, cell)  # pixel -> cell (or the overflow cell Hc*Wc)
    m = mag.ravel()
    fr = frac.ravel()
    b = b0.ravel()
    n = (Hc * Wc + 1) * bins
    cells = (np.bincount(g_idx * bins + b, weights=m * (1 - fr), minlength=n)
             + np.bincount(g_idx * bins + (b + 1) % bins, weights=m * fr, minlength=n))
    cells = cells[: Hc * Wc * bins].reshape(Hc, Wc, bins).astype(np.float32)
    energy = (cells ** 2).sum(axis=2)
    norm = cv2.boxFilter(energy, -1, (3, 3), normalize=False, borderType=cv2.BORDER_REFLECT)
    feat = cells / np.sqrt(norm[..., None] + 1e-2 * cell * cell * 255.0)
    np.clip(feat, 0.0, 0.4, out=feat)
    feat = np.sqrt(feat)
    strength = np.sqrt(energy / (energy.mean() + 1e-6))[..., None] * 0.2
    return np.concatenate([feat, np.minimum(strength, 1.0)], axis=2).astype(np.float32)


_INDEX_CACHE: dict = {}


def _cell_index(H: int, W: int, cell: int) -> np.ndarray:
    key = (H, W, cell)
    if key not in _INDEX_CACHE:
        Hc, Wc = H // cell, W // cell
        r, c = np.mgrid[0:H, 0:W]
        idx = (r // cell) * Wc + (c // cell)
        idx[(r >= Hc * cell) | (c >= Wc * cell)] = Hc * Wc
        _INDEX_CACHE[key] = idx.ravel()
    return _INDEX_CACHE[key]


def orientations(n_orient: int) -> np.ndarray:
    """(n,) part orientation bin centres in radians (image angle, 0 = +x, pi/2 = +y)."""
    return np.arange(n_orient) * (2 * math.pi / n_orient)


def orientation_bin(theta: np.ndarray, n_orient: int) -> np.ndarray:
    return np.rint(np.asarray(theta) / (2 * math.pi / n_orient)).astype(np.int64) % n_orient


class RotatedFeatures:
    """Cell features of ``n_orient`` rotated copies of one frame (see the module docstring).

    ``feats[k]`` is (S, S, B+1) on the canvas grid; ``to_canvas(k, xy)`` maps frame pixels to canvas
    pixels of copy ``k``; ``grid`` (Hc, Wc) is the frame's own cell grid used for part states.
    """

    def __init__(self, gray: np.ndarray, n_orient: int, cell: int = 4, rotate: bool = True) -> None:
        H, W = gray.shape
        self.H, self.W, self.cell, self.n_orient, self.rotate = H, W, cell, n_orient, rotate
        S = math.ceil(math.hypot(H, W) / cell) * cell
        self.S = S
        self.mats = []
        self.feats = []
        for th in (orientations(n_orient) if rotate else [math.pi / 2]):
            alpha = math.pi / 2 - th  # rotate direction th onto +y
            c, s = math.cos(alpha), math.sin(alpha)
            # p' = Rot(alpha) (p - centre) + canvas centre  (image axes: x right, y down)
            A = np.array([[c, -s], [s, c]])
            t = np.array([(S - 1) / 2.0, (S - 1) / 2.0]) - A @ np.array([(W - 1) / 2.0, (H - 1) / 2.0])
            M = np.hstack([A, t[:, None]])
            self.mats.append(M)
            rot = cv2.warpAffine(gray, M, (S, S), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            self.feats.append(cell_features(rot, cell))
        self.feats = np.stack(self.feats)  # (K, S/c, S/c, B+1); (1, ...) unrotated when not rotate
        if not rotate:
            self.mats = self.mats * n_orient

    def copy_index(self, k: int) -> int:
        """Which feature copy orientation ``k`` reads (0 for all when the frame is not rotated)."""
        return k if self.rotate else 0

    def to_canvas(self, k: int, xy: np.ndarray) -> np.ndarray:
        M = self.mats[k]
        xy = np.asarray(xy, dtype=np.float64)
        return xy @ M[:, :2].T + M[:, 2]

    def window(self, k: int, centre_xy: np.ndarray, h: int, w: int) -> np.ndarray | None:
        """Cells of the (h, w)-cell window centred on frame point ``centre_xy`` in copy ``k``
        (flattened), or None when it leaves the canvas."""
        cx, cy = (self.to_canvas(k, centre_xy) - (self.cell - 1) / 2.0) / self.cell
        r0 = round(cy - (h - 1) / 2.0)
        c0 = round(cx - (w - 1) / 2.0)
        f = self.feats[self.copy_index(k)]
        if r0 < 0 or c0 < 0 or r0 + h > f.shape[0] or c0 + w > f.shape[1]:
            return None
        return f[r0:r0 + h, c0:c0 + w].ravel()
