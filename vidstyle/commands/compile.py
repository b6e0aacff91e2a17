"""``vidstyle compile``: compile the numba kernels into numba's cache ahead of use (:mod:`vidstyle.warmup`)."""

from __future__ import annotations

import logging

import typer

from ._numbers import jobs_option

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:
    app.command("compile")(compile_kernels)


def compile_kernels(
    jobs: int = jobs_option(-1, help="Tasks compiled in parallel (-1 = all cores)."),
) -> None:
    """Compile every numba kernel of vidstyle into numba's cache now, so that no stage compiles one.

    numba compiles a kernel the first time a process calls it and caches the machine code beside the
    source (or in NUMBA_CACHE_DIR). This runs each kernel's public path on tiny inputs (about 13 s of
    compilation on one core, split over the workers). `make demo` and `make test` run it as their last
    install step; after an install by pip, run it once. A kernel whose source changed is compiled again at
    its next use."""
    from ..warmup import warm

    seconds = warm(jobs=jobs)
    log.info("kernels compiled into numba's cache: %s",
             ", ".join(f"{name} {s:.1f} s" for name, s in seconds.items()))
