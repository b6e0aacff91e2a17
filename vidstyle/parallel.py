"""One code path for per-item work (per video, per tile): joblib on this machine, Dask on a cluster.

``parallel_map(fn, items, jobs=-1, scheduler=None)`` returns ``[fn(x) for x in items]`` in order.
With ``scheduler="tcp://host:port"`` the calls run on that Dask cluster (``dask.distributed.Client``);
otherwise through joblib's loky backend with ``jobs`` workers (all cores for -1). ``fn`` must be a
module-level function (picklable). OpenCV and BLAS are limited to one thread inside each worker, so
``jobs`` workers never oversubscribe the cores.

Local workers die with the process that started them (:func:`loky_backend`): killed with ``kill -9``, a
run leaves no worker behind that goes on computing and writing outputs. A Dask cluster's workers are not
this process's to kill; there the scheduler drops the queued calls of a client that is gone, and a call
already running is stopped (:func:`dask_task`).
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import sys
import threading
import time
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


#: how often a local worker checks that the process that started it is still alive (seconds)
WATCH_INTERVAL = 0.5


def loky_backend(**kwargs):
    """joblib's loky backend whose workers die with this process (the one way vidstyle starts local
    workers; ``kwargs`` go to the backend, e.g. ``max_nbytes``). Each worker, when it starts
    (:func:`_die_with_parent`), asks Linux to SIGKILL it when the thread that forked it ends
    (``PR_SET_PDEATHSIG``; only when that is this process's main thread, which lives as long as the
    process) and watches its parent's pid from a thread every :data:`WATCH_INTERVAL` seconds, so it exits
    once its parent is gone also where the signal is not available or not safe."""
    from joblib.parallel import BACKENDS

    main = threading.current_thread() is threading.main_thread()
    return BACKENDS["loky"](initializer=_die_with_parent, initargs=(os.getpid(), main), **kwargs)


def _die_with_parent(parent: int, pdeathsig: bool) -> None:
    """Worker initializer of :func:`loky_backend`: die when the process ``parent`` does."""
    if pdeathsig:
        set_parent_death_signal()
    if os.getppid() != parent:  # the parent died before this worker got here
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent,), name="vidstyle-parent-watch", daemon=True).start()


def set_parent_death_signal(sig: int = signal.SIGKILL) -> bool:
    """Linux: have the kernel send ``sig`` to this process when the thread that forked it ends
    (``prctl(PR_SET_PDEATHSIG)``); False where that is not available."""
    if not sys.platform.startswith("linux"):
        return False
    import ctypes

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(1, int(sig), 0, 0, 0) == 0  # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return False


def _watch_parent(parent: int) -> None:
    while True:
        time.sleep(WATCH_INTERVAL)
        if os.getppid() != parent:  # reparented (to init or a subreaper): the parent is gone
            os.kill(os.getpid(), signal.SIGKILL)


def _single_threaded(fn: Callable[[T], R], item: T) -> R:
    with limit_threads(1):
        return fn(item)


class TaskCancelled(BaseException):
    """Raised inside a Dask call whose client is gone (:func:`dask_task`). A ``BaseException``, as
    ``KeyboardInterrupt``, so that no ``except Exception`` in the work swallows it; atomic writers remove
    their temporary file on it."""


def dask_task(fn: Callable[..., R], *args) -> R:
    """``fn(*args)`` inside a Dask task (submit ``dask_task, fn, *args``), stopped once the scheduler has
    cancelled the task: a client killed with ``kill -9`` wants it no more, but Dask cannot stop a running
    call, which would go on computing and writing its outputs. A thread checks the task's state on this
    worker every :data:`WATCH_INTERVAL` seconds and, once it is cancelled, raises :class:`TaskCancelled`
    in the task's thread at its next Python instruction; and every :func:`~vidstyle.fileio.atomic_path` write
    of the call checks the state once more before it renames its output into place, so an output finished
    between the cancellation and the next look is not written either. Outside a Dask worker it is just
    ``fn(*args)``."""
    try:
        from distributed import get_worker
        from distributed.worker import thread_state

        worker, key = get_worker(), thread_state.key
    except (ImportError, ValueError, AttributeError):
        return fn(*args)
    from .fileio import commit_check

    lock, done, tid = threading.Lock(), threading.Event(), threading.get_ident()

    def cancelled() -> bool:
        ts = worker.state.tasks.get(key)
        return ts is None or ts.state in ("cancelled", "released", "forgotten")

    def watch() -> None:
        while not done.wait(WATCH_INTERVAL):
            if cancelled():
                with lock:
                    if not done.is_set():
                        _raise_in_thread(tid, TaskCancelled)
                return

    def before_rename() -> None:  # the watch looks every WATCH_INTERVAL; an output is checked as it lands
        if cancelled():
            raise TaskCancelled(f"task {key} was cancelled (its client is gone): its output is not written")

    threading.Thread(target=watch, name=f"vidstyle-cancel-watch-{key}", daemon=True).start()
    try:
        with commit_check(before_rename):
            return fn(*args)
    finally:
        with lock:
            done.set()


def _raise_in_thread(tid: int, exc: type[BaseException]) -> None:
    import ctypes

    ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(tid), ctypes.py_object(exc))


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
    it = Parallel(n_jobs=workers, backend=loky_backend(), return_as="generator")(
        delayed(_single_threaded)(fn, x) for x in items
    )
    return list(progress(it, description, total=len(items)))


def _dask_map(fn: Callable[[T], R], items: Sequence[T], scheduler: str, description: str) -> list[R]:
    from .logutil import progress

    with dask_client(scheduler) as client:
        log.info("%s: %d items on Dask cluster %s", description, len(items), scheduler)
        futures = client.map(dask_task, [_single_threaded] * len(items), [fn] * len(items), items, pure=False)
        return [f.result() for f in progress(futures, description, total=len(futures))]
