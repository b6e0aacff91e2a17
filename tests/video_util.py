"""Lossless test videos (PNG frames in a MOV), optionally with a display matrix as phones write it."""

from __future__ import annotations

import av
import numpy as np


def write_lossless(path, images, deg: float = 0, hflip: bool = False, vflip: bool = False):
    """Write BGR ``images`` to ``path`` at 20 fps; ``deg``/``hflip``/``vflip``: PyAV's
    ``set_display_rotation`` (shown rotated ``deg`` counter-clockwise, then mirrored). Returns ``path``."""
    c = av.open(str(path), "w")
    st = c.add_stream("png", rate=20)
    st.height, st.width = images[0].shape[:2]
    st.pix_fmt = "rgb24"
    if deg or hflip or vflip:
        st.set_display_rotation(deg, hflip=hflip, vflip=vflip)
    for im in images:
        for p in st.encode(av.VideoFrame.from_ndarray(np.ascontiguousarray(im), format="bgr24")):
            c.mux(p)
    for p in st.encode():
        c.mux(p)
    c.close()
    return path
