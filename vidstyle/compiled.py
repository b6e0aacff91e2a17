"""numba kernels compiled the one way the project compiles them.

:func:`compile_kernel` returns ``loop`` compiled with ``njit(cache=True, nogil=True)`` (cached per
installation; no fast-math, so every floating-point operation rounds as numpy's and the C library's do
and a kernel can be tested bit for bit against its numpy reference), or ``fallback`` when numba cannot
be imported. Used by the 3D SIFT histograms, the motion graph's distance tail, the renderer and forward
kinematics.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


def compile_kernel(loop: Callable[..., Any], fallback: Callable[..., Any] | None = None) -> Callable[..., Any] | None:
    """``loop`` compiled by numba, or ``fallback`` (its numpy / Python reference, or None) without numba."""
    try:
        from numba import njit
    except ImportError:  # pragma: no cover - numba is a dependency
        return fallback
    return njit(cache=True, nogil=True)(loop)
