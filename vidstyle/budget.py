"""A memory budget checked before the work that would need it.

Work whose size follows from the input and the options (the library projected at ``--views`` azimuths,
the motion graph over every clip frame, the pose-sequence training set, a video's frame window) estimates
the memory it will need *before it allocates*, and :func:`require` refuses it with one line naming the
option (or the input) and both figures, exit status 2, when the estimate does not fit what the machine
has free. Without the check, such a run grows until the kernel kills it, taking the machine with it.

What the machine has: the smallest of ``MemAvailable`` (``/proc/meminfo``), the free part of the
process's cgroup limit (v2 ``memory.max - memory.current``; v1 ``memory.limit_in_bytes - usage``) and the
address-space limit (``ulimit -v``). ``VIDSTYLE_MEMORY_LIMIT`` (bytes, or with a ``K``/``M``/``G``
suffix) lowers it, e.g. to share a machine with other jobs. Estimates are upper-side approximations of
the allocations (arrays, trees, buffers), not measurements; :data:`HEADROOM` of what is free is allowed.
"""

from __future__ import annotations

import logging
import os
import resource

from .errors import InputError, ParameterError

log = logging.getLogger(__name__)

#: the part of the free memory one run may plan to use (the interpreter, libraries and the OS need the rest)
HEADROOM = 0.85

_UNITS = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}


def parse_size(text: str) -> int:
    """``"512M"`` -> 536870912; a plain number is bytes. Raises ValueError for anything else."""
    t = text.strip().upper().removesuffix("B").removesuffix("I")
    unit = t[-1:] if t[-1:] in _UNITS and t[-1:] else ""
    number = float(t[: len(t) - len(unit)])
    if not number >= 0 or number == float("inf"):
        raise ValueError(text)
    return int(number * _UNITS[unit])


def _read_int(path: str) -> int | None:
    try:
        with open(path, encoding="ascii") as f:
            text = f.read().strip()
    except (OSError, UnicodeDecodeError):
        return None
    return int(text) if text.isdigit() else None  # "max" (no limit) -> None


def _meminfo_available() -> int | None:
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def _cgroup_free() -> int | None:
    free = []
    for limit, usage in (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                         ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes")):
        lim, use = _read_int(limit), _read_int(usage)
        if lim is not None and use is not None and lim < 1 << 60:  # v1 reports "no limit" as a huge number
            free.append(max(lim - use, 0))
    return min(free) if free else None


def available_bytes() -> int | None:
    """Memory this process may still use (see the module's text); None when nothing tells."""
    found = [x for x in (_meminfo_available(), _cgroup_free()) if x is not None]
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft != resource.RLIM_INFINITY:
        try:
            with open("/proc/self/statm", encoding="ascii") as f:
                used = int(f.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        except (OSError, ValueError, IndexError):
            used = 0
        found.append(max(soft - used, 0))
    env = os.environ.get("VIDSTYLE_MEMORY_LIMIT")
    if env:
        try:
            found.append(parse_size(env))
        except ValueError:
            raise InputError(f"VIDSTYLE_MEMORY_LIMIT: expected bytes or a size such as 4G, got {env!r}") from None
    return min(found) if found else None


def human(nbytes: float) -> str:
    """``1536 * 2**20`` -> ``"1.5 GB"`` (binary units, as ``free -h`` shows them)."""
    for unit, size in (("TB", 1 << 40), ("GB", 1 << 30), ("MB", 1 << 20), ("KB", 1 << 10)):
        if nbytes >= size:
            return f"{nbytes / size:.3g} {unit}"
    return f"{int(nbytes)} B"


def require(nbytes: float, what: str, param: str | None = None, advice: str = "") -> None:
    """Refuse work estimated at ``nbytes`` when it does not fit :data:`HEADROOM` of the free memory:
    :class:`ParameterError` naming ``param`` (the CLI shows its flag) or, when the input alone is too
    large, :class:`InputError`; exit status 2 either way. ``what`` says what the memory is for, ``advice``
    how to make it fit."""
    free = available_bytes()
    log.debug("%s: about %s needed, %s free", what, human(nbytes), "?" if free is None else human(free))
    if free is None or nbytes <= HEADROOM * free:
        return
    problem = f"{what} would need about {human(nbytes)}, more than the {human(HEADROOM * free)} this machine can give it"
    if advice:
        problem += f" ({advice})"
    if param:
        raise ParameterError(param, problem)
    raise InputError(problem)
