"""Videos that show their own frame number, to test frame exactness (decoders, seeking, annotation).

Frame ``i`` carries ``i`` as 16 bits in a row of black/white blocks (robust to lossy codecs and to
resizing), plus the decimal number drawn for a person to read. :func:`read_number` decodes it.
"""

from __future__ import annotations

import numpy as np

BITS = 16


def numbered_frame(index: int, width: int = 160, height: int = 120) -> np.ndarray:
    """(height, width, 3) uint8 BGR frame showing ``index``."""
    import cv2

    if not 0 <= index < 2**BITS:
        raise ValueError(f"index must be in 0..{2**BITS - 1}")
    img = np.full((height, width, 3), 96, np.uint8)
    bw = width / BITS
    bh = max(4, height // 6)
    for b in range(BITS):
        on = (index >> (BITS - 1 - b)) & 1
        x0, x1 = int(round(b * bw)), int(round((b + 1) * bw))
        img[:bh, x0:x1] = 255 if on else 0
    scale = max(0.4, height / 160)
    cv2.putText(img, str(index), (4, min(height - 4, bh + int(30 * scale))), cv2.FONT_HERSHEY_SIMPLEX,
                scale, (255, 255, 255), max(1, int(round(2 * scale))), cv2.LINE_AA)
    return img


def read_number(img: np.ndarray) -> int:
    """The frame number shown by a (possibly resized or re-encoded) :func:`numbered_frame`."""
    img = np.asarray(img)
    gray = img.mean(axis=2) if img.ndim == 3 else img.astype(np.float64)
    h, w = gray.shape
    bh = max(4, round(h * (1 / 6)))
    band = gray[max(0, bh // 4): max(1, (3 * bh) // 4)]
    value = 0
    for b in range(BITS):
        x0, x1 = int(b * w / BITS), int((b + 1) * w / BITS)
        cell = band[:, x0 + (x1 - x0) // 4: x1 - (x1 - x0) // 4 or x1]
        value = (value << 1) | int(cell.mean() > 128)
    return value
