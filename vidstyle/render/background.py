"""Static backgrounds: a plain colour, or a tinted crop of a scikit-image sample texture.

The textures (``brick``, ``grass``, ``gravel``) ship inside the scikit-image wheel, so they work
offline.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np

TEXTURES = ("brick", "grass", "gravel")  # what "texture" draws from
# only by name ("texture:moon"): backgrounds no "texture" video shows; moon is the unseen-camera test set's,
# coins the validation camera's (scripts/validate_recognition.py --camera-dataset)
HELDOUT_TEXTURES = ("moon", "coins")
PLAIN_COLOURS = [(205, 205, 200), (180, 190, 195), (150, 160, 150), (215, 200, 185), (120, 125, 130), (190, 175, 160)]


@functools.cache
def _texture(name: str) -> np.ndarray:
    import skimage.data

    img = getattr(skimage.data, name)()
    if img.ndim == 3:
        img = cv2.cvtColor(img[..., :3], cv2.COLOR_RGB2GRAY)
    img = img.astype(np.float32) / 255.0
    img.setflags(write=False)
    return img


def parse_background(spec) -> tuple[str, object]:
    """``"plain"``, ``"plain:B,G,R"``, ``"texture"``, ``"texture:<name>"`` or an (H, W, 3) uint8 image."""
    if isinstance(spec, np.ndarray):
        if spec.ndim != 3 or spec.shape[2] != 3:
            raise ValueError(f"background image must be (H, W, 3), got {spec.shape}")
        return "image", spec
    s = str(spec).strip().lower()
    kind, _, arg = s.partition(":")
    if kind == "plain":
        if arg:
            try:
                col = tuple(int(v) for v in arg.split(","))
            except ValueError:
                col = ()
            if len(col) != 3 or not all(0 <= v <= 255 for v in col):
                raise ValueError(f"plain background colour must be B,G,R in 0..255, got {arg!r}")
            return "plain", col
        return "plain", None
    if kind == "texture":
        if arg and arg not in TEXTURES + HELDOUT_TEXTURES:
            raise ValueError(f"unknown texture {arg!r}; choose from {', '.join(TEXTURES + HELDOUT_TEXTURES)}")
        return "texture", arg or None
    raise ValueError(f"background must be 'plain' or 'texture' (optionally ':<colour|name>'), got {spec!r}")


def make_background(spec, size: tuple[int, int], rng: np.random.Generator) -> tuple[np.ndarray, str]:
    """(H, W, 3) float32 BGR background and a description of what was chosen."""
    W, H = size
    kind, arg = parse_background(spec)
    if kind == "image":
        img = cv2.resize(np.ascontiguousarray(arg), (W, H), interpolation=cv2.INTER_AREA)
        return img.astype(np.float32), "image"
    if kind == "plain":
        col = arg if arg is not None else PLAIN_COLOURS[int(rng.integers(len(PLAIN_COLOURS)))]
        bg = np.empty((H, W, 3), dtype=np.float32)
        bg[:] = np.asarray(col, dtype=np.float32)
        return bg, "plain:" + ",".join(str(int(v)) for v in col)
    name = arg if arg is not None else TEXTURES[int(rng.integers(len(TEXTURES)))]
    tex = _texture(name)
    th, tw = tex.shape
    # random crop with the image's aspect ratio, 40-100 % of the texture's size
    scale = rng.uniform(0.4, 1.0)
    cw = min(tw, max(8, int(round(scale * min(tw, th * W / H)))))
    ch = min(th, max(8, int(round(cw * H / W))))
    x0 = int(rng.integers(0, tw - cw + 1))
    y0 = int(rng.integers(0, th - ch + 1))
    crop = cv2.resize(tex[y0 : y0 + ch, x0 : x0 + cw], (W, H), interpolation=cv2.INTER_AREA)
    # muted contrast so the figure stands out, tinted with a random colour
    crop = 0.55 + 0.45 * (crop - crop.mean())
    tint = np.asarray(PLAIN_COLOURS[int(rng.integers(len(PLAIN_COLOURS)))], dtype=np.float32)
    bg = np.clip(crop[..., None] * tint, 0, 255).astype(np.float32)
    return bg, f"texture:{name}"


class NoiseBank:
    """Seeded Gaussian sensor noise. A few full-size noise fields are drawn once; each frame takes a
    random one at a random offset, which is as good as fresh i.i.d. noise per pixel and frame for the
    purpose (mild noise), at a fraction of the cost of drawing new normals for every frame."""

    def __init__(self, size: tuple[int, int], sigma: float, rng: np.random.Generator, n_fields: int = 8,
                 pad: int = 16) -> None:
        W, H = size
        self.sigma = float(sigma)
        self.pad = pad
        self.size = (W, H)
        self.rng = rng
        if self.sigma > 0:
            self.fields = rng.standard_normal((n_fields, H + pad, W + pad, 3), dtype=np.float32)
            self.fields *= self.sigma
        else:
            self.fields = None

    def pick(self) -> tuple[np.ndarray | None, int, int]:
        """The next frame's noise: ``(field, oy, ox)``, the frame's noise being
        ``field[oy:oy + H, ox:ox + W]`` (one draw of the generator per frame), or ``(None, 0, 0)`` without noise."""
        if self.fields is None:
            return None, 0, 0
        k, oy, ox = (int(v) for v in self.rng.integers(0, [len(self.fields), self.pad + 1, self.pad + 1]))
        return self.fields[k], oy, ox

    def add(self, img: np.ndarray) -> None:
        """Add the next frame's noise (:meth:`pick`) to ``img`` ((H, W, 3) float32) in place."""
        field, oy, ox = self.pick()
        if field is None:
            return
        W, H = self.size
        img += field[oy : oy + H, ox : ox + W]
