"""Atomic file writing and small JSON/NPZ helpers used by every stage.

Every writer in vidstyle writes to a temporary file in the destination directory and renames it into
place, so an interrupted run never leaves a half-written artifact (``os.replace`` is atomic on POSIX
within one filesystem).
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import tempfile
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import FormatError, InputError

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np


#: a writer's temporary file beside ``<stem><suffix>`` is ``.<stem>.<pid>-<8 random characters>.tmp<suffix>``
#: (:func:`tempfile.mkstemp`'s names, prefixed with the writing process's id so that a later write of the
#: same file can tell a dead writer's leftover from a live one's work); staging directories and older
#: temporaries have no ``<pid>-``
_TEMP = r"\.{stem}\.(?:[0-9]+-)?[a-z0-9_]{{8}}\.tmp{suffix}"


_commit = threading.local()


@contextlib.contextmanager
def commit_check(check: Callable[[], None]) -> Iterator[None]:
    """While the block runs, every :func:`atomic_path` of this thread calls ``check()`` just before it renames
    its finished temporary onto the destination; ``check`` raises to stop the write (the temporary is removed
    and the destination left as it was). A Dask task uses it (:func:`vidstyle.parallel.dask_task`): an output
    finished after the client was killed is not written."""
    prev = getattr(_commit, "check", None)
    _commit.check = check
    try:
        yield
    finally:
        _commit.check = prev


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` only if the block succeeds (the
    temporary file is removed if it fails).

    ``suffix`` defaults to the destination's own suffix so that libraries which pick a format from the
    extension (OpenCV's VideoWriter, ``np.save``) behave as they would for the real name. A ``path`` that
    is a symlink stays one: the file it points to is replaced. An existing file keeps its permission bits
    (a 0600 file stays 0600); a new one gets those a plain ``open()`` would give.
    """
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path}: is a directory, cannot write a file there")
    suffix = path.suffix if suffix is None else suffix
    target = Path(os.path.realpath(path)) if path.is_symlink() else path  # a link: replace what it points to
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        try:
            mode = os.stat(target).st_mode & 0o777
        except (FileNotFoundError, NotADirectoryError):
            mode = 0o666 & ~_umask()
        sweep_dead_writers(target, suffix)
        fd, tmp = tempfile.mkstemp(prefix=f".{target.stem}.{os.getpid()}-", suffix=f".tmp{suffix}",
                                   dir=target.parent)
    except OSError as e:  # a parent that is a file, or cannot be made (/proc/nope), or not writable
        raise InputError(f"{path}: cannot write ({os_reason(e)})") from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.chmod(tmp_path, mode)  # mkstemp makes the file owner-only (0600)
        check = getattr(_commit, "check", None)
        if check is not None:
            check()
        os.replace(tmp_path, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


def os_reason(e: OSError) -> str:
    """The one-line reason of an OS error (``No such file or directory: '/proc/nope'``)."""
    where = f": {e.filename!r}" if getattr(e, "filename", None) else ""
    return f"{e.strerror or type(e).__name__}{where}"


def check_writable(path: str | os.PathLike) -> Path:
    """Refuse, before any work, an output ``path`` that cannot be written: a directory, or whose nearest
    existing ancestor is not a writable directory (``/proc/nope/p.json``); nothing is created."""
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path}: is a directory, cannot write a file there")
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"{path}: cannot write ({parent} is not a directory)")
    try:  # the one sure test (permissions, read-only or pseudo file systems such as /proc): a file made there
        with tempfile.TemporaryFile(dir=parent):
            pass
    except OSError as e:
        raise InputError(f"{path}: cannot write in {parent} ({e.strerror or type(e).__name__})") from None
    return path


def make_dir(path: str | os.PathLike) -> Path:
    """``mkdir -p path``; a path that is a file, or that cannot be made, is an :class:`InputError`."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError(f"{path}: exists and is not a directory")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(f"{path}: cannot make the directory ({os_reason(e)})") from None
    return path


def sweep_temporaries(out_dir: str | os.PathLike, names, before: float | None = None) -> list[Path]:
    """Remove the temporary files :func:`atomic_path` left in ``out_dir`` for the outputs ``names`` (file
    names or paths) when a run was killed before it could remove them: only names of the writer's own
    pattern (``.<stem>.<8 random characters>.tmp<suffix>``), only regular files, and only those last
    modified before ``before`` (default: now), so a concurrent writer's fresh file is left alone. Returns
    the removed paths. One pass over the directory, however many names."""
    import re

    wanted = {(Path(n).stem, Path(n).suffix) for n in names}
    any_temp = re.compile(_TEMP.format(stem="(.+)", suffix="(.*)"))

    def match(name: str) -> bool:
        m = any_temp.fullmatch(name)
        return m is not None and (m.group(1), m.group(2)) in wanted

    return _sweep(out_dir, match, before, dirs=False)


def sweep_dead_writers(path: str | os.PathLike, suffix: str | None = None) -> list[Path]:
    """Remove the temporaries :func:`atomic_path` left beside ``path`` (``.<stem>.<pid>-<8 chars>.tmp<suffix>``,
    regular files only) whose writing process no longer exists; a live writer's file is left alone,
    however old. Returns the removed paths."""
    import re

    path = Path(path)
    suffix = path.suffix if suffix is None else suffix
    mine = re.compile(rf"\.{re.escape(path.stem)}\.([0-9]+)-[a-z0-9_]{{8}}\.tmp{re.escape(suffix)}")
    removed: list[Path] = []
    try:
        entries = list(os.scandir(path.parent))
    except (FileNotFoundError, NotADirectoryError):
        return removed
    for e in entries:
        m = mine.fullmatch(e.name) if e.name.startswith(".") else None
        if m is None or _process_alive(int(m.group(1))):
            continue
        try:
            if e.is_file(follow_symlinks=False):
                os.unlink(e.path)
                removed.append(Path(e.path))
        except FileNotFoundError:
            pass
    if removed:
        import logging

        logging.getLogger(__name__).info("%s: removed %d temporary file(s) a killed run left", path, len(removed))
    return removed


def sweep_staging(out: str | os.PathLike, before: float | None = None) -> list[Path]:
    """Remove the staging directories (:func:`staging_dir`: ``.<name>.<8 random characters>.tmp`` beside
    ``out``) a killed run left, only those last modified before ``before`` (default: now), and settle a
    replacement a kill interrupted (:func:`replace_dir`'s ``.<name>.old-<pid>`` of a process that is gone):
    put back as ``out`` when ``out`` is missing (the kill came between the two renames), else removed.
    Returns the removed paths."""
    import re
    import shutil

    out = Path(out)
    removed = _sweep(out.parent, re.compile(_TEMP.format(stem=re.escape(out.name), suffix="")).fullmatch, before,
                     dirs=True)
    old = re.compile(rf"\.{re.escape(out.name)}\.old-([0-9]+)")
    try:
        entries = list(os.scandir(out.parent))
    except (FileNotFoundError, NotADirectoryError):
        return removed
    for e in entries:
        m = old.fullmatch(e.name)
        if not m or not e.is_dir(follow_symlinks=False) or _process_alive(int(m.group(1))):
            continue
        if not out.exists() and not out.is_symlink():
            os.replace(e.path, out)
        else:
            shutil.rmtree(e.path, ignore_errors=True)
            removed.append(Path(e.path))
    return removed


def _sweep(parent: str | os.PathLike, match, before: float | None, dirs: bool) -> list[Path]:
    """Remove the entries of ``parent`` whose name ``match`` accepts (hidden names only), regular files (``dirs`` False) or directories (True, with their content; never a symlink), last
    modified before ``before`` (default: now)."""
    import shutil
    import time

    before = time.time() if before is None else before
    removed: list[Path] = []
    try:
        entries = list(os.scandir(parent))
    except (FileNotFoundError, NotADirectoryError):
        return removed
    for e in entries:
        if not e.name.startswith(".") or not match(e.name):
            continue
        try:
            kind = e.is_dir(follow_symlinks=False) if dirs else e.is_file(follow_symlinks=False)
            if kind and e.stat(follow_symlinks=False).st_mtime < before:
                if dirs:
                    shutil.rmtree(e.path)
                else:
                    os.unlink(e.path)
                removed.append(Path(e.path))
        except FileNotFoundError:
            pass
    return removed


def _process_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def _missing_dirs(path: Path) -> list[Path]:
    """``path`` and its ancestors that do not exist yet, deepest first."""
    created = []
    p = path
    while not p.exists() and not p.is_symlink() and p != p.parent:
        created.append(p)
        p = p.parent
    return created


def _remove_empty(created: list[Path]) -> None:
    """Remove the directories ``created`` (deepest first) while they are empty."""
    for d in created:
        try:
            d.rmdir()  # only an empty directory goes
        except OSError:
            break


@contextlib.contextmanager
def output_dir(out_dir: str | os.PathLike, names=()) -> Iterator[Path]:
    """The output directory of a stage's run: created (with its parents) if missing, with the temporaries
    a killed earlier run left for the outputs ``names`` swept (:func:`sweep_temporaries`, those older than
    this run's start). If the block fails, the directories this run created are removed again when they
    are empty (a failed run leaves no empty output directory). An ``out_dir`` that is a file is an
    :class:`InputError`."""
    import time

    start = time.time()
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"{out_dir}: exists and is not a directory")
    created = _missing_dirs(out_dir)
    make_dir(out_dir)
    swept = sweep_temporaries(out_dir, names, before=start)
    if swept:
        import logging

        logging.getLogger(__name__).info("%s: removed %d temporary file(s) a killed run left", out_dir, len(swept))
    try:
        yield out_dir
    except BaseException:
        _remove_empty(created)
        raise


def outputs_by_stem(inputs, out_dir: str | os.PathLike, ext: str) -> list[Path]:
    """``<out_dir>/<input stem><ext>`` per input; two inputs with the same stem are an :class:`InputError`
    (one output would overwrite the other)."""
    out_dir = Path(out_dir)
    seen: dict[str, str] = {}
    paths = []
    for item in inputs:
        stem = Path(item).stem
        if stem in seen:
            raise InputError(f"{item}: same output name {stem}{ext} as {seen[stem]}; rename one of them")
        seen[stem] = str(item)
        paths.append(out_dir / f"{stem}{ext}")
    return paths


@contextlib.contextmanager
def staged_dir(out: str | os.PathLike, overwrite: bool = False) -> Iterator[Path]:
    """Build the directory ``out`` in a fresh hidden sibling (:func:`staging_dir`, which first sweeps what a
    killed earlier run left there) and put it at ``out`` (:func:`replace_dir`) only when the block
    succeeds. If it fails, the staging directory is removed, and so are the parents of ``out`` this call
    created, when empty."""
    out = Path(out)
    created = _missing_dirs(out.parent)
    try:
        tmp = staging_dir(out, overwrite)
    except BaseException:
        _remove_empty(created)
        raise
    try:
        yield tmp
        replace_dir(tmp, out)
    except BaseException:
        import shutil

        shutil.rmtree(tmp, ignore_errors=True)
        _remove_empty(created)
        raise


def staging_dir(out: str | os.PathLike, overwrite: bool = False) -> Path:
    """A fresh hidden directory beside ``out`` to build it in (finish with :func:`replace_dir`; prefer
    :func:`staged_dir`, which also cleans up after a failure). What a killed earlier run left beside
    ``out`` is swept first (:func:`sweep_staging`: staging directories older than this call). An ``out``
    that is a file, or a non-empty directory without ``overwrite``, is an :class:`InputError`."""
    import time

    start = time.time()
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out}: exists and is not a directory")
    swept = sweep_staging(out, before=start)
    if swept:
        import logging

        logging.getLogger(__name__).info("%s: removed %d staging director(ies) a killed run left", out, len(swept))
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        raise InputError(f"{out}: directory is not empty (use --overwrite to replace it)")
    make_dir(out.parent)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent))
    os.chmod(tmp, 0o777 & ~_umask())  # mkdtemp makes it owner-only (0700); ``out`` gets a plain mkdir's mode
    return tmp


def replace_dir(tmp: str | os.PathLike, out: str | os.PathLike) -> None:
    """Put the finished directory ``tmp`` at ``out``, replacing an existing ``out`` only now (two renames on
    one filesystem: a reader sees the old or the new directory, never a mix)."""
    import shutil

    tmp, out = Path(tmp), Path(out)
    if out.exists():
        old = out.parent / f".{out.name}.old-{os.getpid()}"
        os.replace(out, old)
        os.replace(tmp, out)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(tmp, out)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text(path: str | os.PathLike, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def write_json(path: str | os.PathLike, obj: Any) -> None:
    write_text(path, json.dumps(obj, indent=2, default=json_default) + "\n")


def read_json_document(path: str | os.PathLike, max_bytes: int = 1 << 30) -> Any:
    """Parse ``path`` as UTF-8 JSON (a BOM is tolerated; UTF-16, binary, a directory are errors)."""
    path = Path(path)
    if path.is_dir():
        raise FormatError(path, None, "is a directory, not a file")
    return parse_json_bytes(read_bytes(path, max_bytes), path)


def parse_json_bytes(raw: bytes, path: str | os.PathLike | None) -> Any:
    """Parse ``raw`` as strict UTF-8 JSON (as :func:`read_json_document`); errors name ``path``."""
    if raw.startswith(b"\xef\xbb\xbf"):
        raw = raw[3:]
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff") or (len(raw) > 1 and raw[1:2] == b"\x00"):
        raise FormatError(path, None, "is UTF-16 text; save it as UTF-8")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise FormatError(path, None, f"not UTF-8 text (a binary file?) at byte {e.start}") from None
    try:
        return json.loads(text, parse_constant=_reject_constant)
    except json.JSONDecodeError as e:
        raise FormatError(path, None, f"not valid JSON ({e.msg} at line {e.lineno} column {e.colno})") from None
    except (ValueError, RecursionError) as e:
        raise FormatError(path, None, f"not valid JSON ({e})") from None


def _reject_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a JSON number")


def read_bytes(path: str | os.PathLike, max_bytes: int) -> bytes:
    """The bytes of the file ``path``, at most ``max_bytes`` of them; :class:`FormatError` naming the file
    when it is missing, unreadable or larger."""
    try:
        with open(path, "rb") as f:
            raw = f.read(max_bytes + 1)
    except FileNotFoundError:
        raise FormatError(path, None, "file not found") from None
    except OSError as e:
        raise FormatError(path, None, f"cannot be read ({e.strerror or e})") from None
    if len(raw) > max_bytes:
        raise FormatError(path, None, f"larger than {max_bytes} bytes")
    return raw


def read_json(path: str | os.PathLike) -> Any:
    """Strict UTF-8 JSON (:func:`read_json_document`): every problem is one :class:`FormatError` naming
    the file. Artifacts have owner readers in :mod:`vidstyle.formats`; this is for the few inputs without
    one (e.g. an appearance)."""
    return read_json_document(path)


def write_npz(path: str | os.PathLike, *, compressed: bool = True, **arrays: Any) -> None:
    """``arrays`` to the ``.npz`` ``path`` atomically: deflated (``np.savez_compressed``), or stored as they
    are with ``compressed=False`` (``np.savez``: for arrays that barely compress, where deflate would cost
    more time than it saves space, e.g. 3D SIFT descriptors)."""
    import numpy as np  # here, not at the top: the CLI imports this module at start-up

    with atomic_path(path, suffix=".npz") as tmp:
        (np.savez_compressed if compressed else np.savez)(tmp, **arrays)


def write_npy(path: str | os.PathLike, array: np.ndarray) -> None:
    import numpy as np

    with atomic_path(path, suffix=".npy") as tmp:
        np.save(tmp, array)


def json_default(o: Any) -> Any:
    np = sys.modules.get("numpy")  # a numpy value exists only once numpy is imported (not at CLI start-up)
    if np is not None and isinstance(o, np.generic):
        return o.item()
    if np is not None and isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")
