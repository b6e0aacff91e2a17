"""One code path for per-item work (per video, per tile): joblib on this machine, Dask on a cluster.

``parallel_map(fn, items, jobs=-1, scheduler=None)`` returns ``[fn(x) for x in items]`` in order.
With ``scheduler="tcp://host:port"`` the calls run on that Dask cluster (``dask.distributed.Client``);
otherwise through joblib's loky backend with ``jobs`` workers (all cores for -1). ``fn`` must be a
module-level function (picklable). OpenCV and BLAS are limited to one thread inside each worker, so
``jobs`` workers never oversubscribe the cores.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Iterator
from typing import Callable, Iterable, Sequence, TypeVar

from .errors import InputError

log = logging.getLogger(__name__)

T = TypeVar("T")
R = TypeVar("R")


@contextlib.contextmanager
def limit_threads(n: int = 1) -> Iterator[None]:
    """OpenCV and BLAS/OpenMP on ``n`` threads inside the block (the one thread-limit helper): work is
    parallel across items, and the per-item matrix products are too small to gain from threads."""
    import cv2
    from threadpoolctl import threadpool_limits

    before = cv2.getNumThreads()
    cv2.setNumThreads(n)
    try:
        with threadpool_limits(limits=n):
            yield
    finally:
        cv2.setNumThreads(before)


def _single_threaded(fn: Callable[[T], R], item: T) -> R:
    with limit_threads(1):
        return fn(item)


@contextlib.contextmanager
def dask_client(scheduler: str) -> Iterator["object"]:
    """A ``dask.distributed.Client`` connected to ``scheduler`` (the one Dask client helper); closed on
    exit. Errors name the ``scheduler`` parameter."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise InputError("scheduler: dask[distributed] is not installed (pip install 'vidstyle[dask]')") from None
    try:
        client = Client(scheduler, timeout="10s")
    except (OSError, TimeoutError, ValueError) as e:
        raise InputError(f"scheduler {scheduler}: cannot connect ({e})") from None
    try:
        yield client
    finally:
        client.close()


def parallel_map(
    fn: Callable[[T], R],
    items: Iterable[T],
    jobs: int = -1,
    scheduler: str | None = None,
    description: str = "working",
) -> list[R]:
    """Apply ``fn`` to every item, in parallel, preserving order, with a progress bar. See the module
    docstring. An exception raised by ``fn`` propagates unchanged (the first one, in item order)."""
    from .logutil import progress

    items = list(items)
    if not items:
        return []
    if jobs == 0:
        raise InputError("jobs: must be a positive number of workers or -1 for all cores")
    if scheduler:
        return _dask_map(fn, items, scheduler, description)
    n = os.cpu_count() or 1
    workers = n if jobs is None or jobs < 0 else jobs
    workers = min(workers, len(items))
    if workers == 1:
        # one thread here too, as in the workers: BLAS and OpenCV round differently on several threads, and
        # a file must not depend on how many workers made it
        return list(progress((_single_threaded(fn, x) for x in items), description, total=len(items)))
    from joblib import Parallel, delayed

    log.info("%s: %d items on %d local workers", description, len(items), workers)
    it = Parallel(n_jobs=workers, backend="loky", return_as="generator")(
        delayed(_single_threaded)(fn, x) for x in items
    )
    return list(progress(it, description, total=len(items)))


def _dask_map(fn: Callable[[T], R], items: Sequence[T], scheduler: str, description: str) -> list[R]:
    from .logutil import progress

    with dask_client(scheduler) as client:
        log.info("%s: %d items on Dask cluster %s", description, len(items), scheduler)
        futures = client.map(_single_threaded, [fn] * len(items), items, pure=False)
        return [f.result() for f in progress(futures, description, total=len(futures))]
