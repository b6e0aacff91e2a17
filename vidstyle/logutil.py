"""Logging and progress bars. Configured by the CLI only, never at import time."""

from __future__ import annotations

import logging
from typing import Iterable, Iterator, TypeVar

T = TypeVar("T")


def stderr_console():
    """The console of logs, progress bars and errors: stderr (stdout carries only a command's data)."""
    from rich.console import Console

    return Console(stderr=True)


def configure(verbosity: int = 0) -> None:
    from rich.logging import RichHandler

    import os

    level = logging.WARNING if verbosity < 0 else logging.INFO if verbosity == 0 else logging.DEBUG
    # -vv: native libraries' own log lines (MediaPipe's C++ layer) too; inherited by worker processes
    os.environ["VIDSTYLE_NATIVE_LOGS"] = "1" if verbosity >= 2 else "0"
    logging.basicConfig(
        level=level,
        format="%(message)s",
        datefmt="[%X]",
        handlers=[RichHandler(console=stderr_console(), show_path=False, rich_tracebacks=False)],
        force=True,
    )


def progress(items: Iterable[T], description: str, total: int | None = None) -> Iterator[T]:
    """Iterate with a rich progress bar (on stderr; hidden when stderr is not a terminal)."""
    from rich.progress import track

    console = stderr_console()
    # not even a blank line when stderr is not a terminal (rich's transient bar leaves one there)
    yield from track(items, description=description, total=total, transient=True, console=console,
                     disable=not console.is_terminal)
