"""What every artifact owner module shares: the error, the ``kind`` + ``schema_version`` header, strict JSON
reading, and field checks that name the file and the field.

An owner module (``vidstyle/formats/<artifact>.py``) defines a typed object and ``read_<artifact>`` /
``write_<artifact>``. Its reader validates every field and raises :class:`FormatError`
(``"<file>: <field>: <problem>"``), and nothing else, whatever the bytes; its writer validates the object
first and writes atomically (temporary file + rename), so an invalid object never reaches disk.
"""

from __future__ import annotations

import json
import math
import os
import threading
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from ..errors import FormatError
from ..fileio import json_default, read_json_document, write_text

__all__ = ["FormatError", "read_json_document"]  # re-exported: formats' readers raise and use them


def check_header(
    doc: Any, path: str | os.PathLike | None, kind: str, versions: Iterable[int], legacy: bool = False
) -> int:
    """Check ``doc`` is an object of ``kind`` at a supported ``schema_version``; return the version.

    ``legacy``: a document without ``kind`` and ``schema_version`` is schema 1 (files written before
    headers existed)."""
    versions = tuple(versions)
    if not isinstance(doc, dict):
        raise FormatError(path, None, f"expected a JSON object ({kind}), got {_type(doc)}")
    if legacy and "kind" not in doc and "schema_version" not in doc:
        return 1
    got = doc.get("kind")
    if got != kind:
        raise FormatError(path, "kind", f"expected {kind!r}, got {got!r}")
    v = doc.get("schema_version")
    if not (isinstance(v, int) and not isinstance(v, bool)) or v not in versions:
        raise FormatError(path, "schema_version", f"{v!r} is not supported (expected {', '.join(map(str, versions))})")
    return v


def header(kind: str, version: int) -> dict[str, Any]:
    return {"kind": kind, "schema_version": version}


def write_json_document(path: str | os.PathLike, doc: Any) -> None:
    """Atomic, UTF-8, finite numbers only (``allow_nan=False``), newline at the end."""
    write_text(path, json.dumps(doc, indent=2, allow_nan=False, default=json_default) + "\n")


def write_checked(path: str | os.PathLike, doc: dict, parse, what: str) -> None:
    """Write ``doc`` (built in memory) after ``parse(doc, path)`` accepts it, as its reader would. A document
    the reader would refuse is a programming error, so it raises ``ValueError`` ("invalid <what>: ...")."""
    try:
        parse(doc, path)
    except FormatError as e:
        raise ValueError(f"invalid {what}: {e.field}: {e.problem}") from None
    write_json_document(path, doc)


def _type(x: Any) -> str:
    return {dict: "an object", list: "a list", str: "a string", bool: "a boolean", type(None): "null",
            int: "an integer", float: "a number"}.get(type(x), type(x).__name__)


class Fields:
    """Checks on one JSON object that raise :class:`FormatError` naming ``path`` and the dotted field."""

    def __init__(self, obj: Any, path: str | os.PathLike | None, prefix: str = "") -> None:
        self.path = path
        self.prefix = prefix
        if not isinstance(obj, dict):
            raise FormatError(path, prefix or None, f"expected an object, got {_type(obj)}")
        self.obj = obj

    def name(self, key: str | int) -> str:
        if isinstance(key, int):
            return f"{self.prefix}[{key}]"
        return f"{self.prefix}.{key}" if self.prefix else key

    def fail(self, key: str | int | None, problem: str) -> FormatError:
        return FormatError(self.path, self.prefix if key is None else self.name(key), problem)

    def has(self, key: str) -> bool:
        return key in self.obj

    def get(self, key: str, required: bool = True) -> Any:
        if key not in self.obj:
            if required:
                raise FormatError(self.path, self.name(key), "missing")
            return None
        return self.obj[key]

    def str(self, key: str, required: bool = True, default: str | None = None, choices: Sequence[str] | None = None,
            nonempty: bool = False) -> str | None:
        v = self.get(key, required)
        if v is None and not required:
            return default
        if not isinstance(v, str):
            raise self.fail(key, f"expected a string, got {_type(v)}")
        if nonempty and not v:
            raise self.fail(key, "must not be empty")
        if choices is not None and v not in choices:
            raise self.fail(key, f"{v!r} is not one of {', '.join(map(repr, choices))}")
        return v

    def int(self, key: str, required: bool = True, default: int | None = None, min: int | None = None,
            max: int | None = None) -> int | None:
        v = self.get(key, required)
        if v is None and not required:
            return default
        return check_int(v, self.path, self.name(key), min, max)

    def number(self, key: str, required: bool = True, default: float | None = None, min: float | None = None,
               max: float | None = None, positive: bool = False) -> float | None:
        v = self.get(key, required)
        if v is None and not required:
            return default
        return check_number(v, self.path, self.name(key), min, max, positive)

    def bool(self, key: str, required: bool = True, default: bool | None = None) -> bool | None:
        v = self.get(key, required)
        if v is None and not required:
            return default
        if not isinstance(v, bool):
            raise self.fail(key, f"expected true or false, got {_type(v)}")
        return v

    def list(self, key: str, required: bool = True, default: list | None = None, min_len: int = 0,
             max_len: int | None = None) -> list | None:
        v = self.get(key, required)
        if v is None and not required:
            return default
        if not isinstance(v, list):
            raise self.fail(key, f"expected a list, got {_type(v)}")
        if len(v) < min_len:
            raise self.fail(key, f"expected at least {min_len} item(s), got {len(v)}")
        if max_len is not None and len(v) > max_len:
            raise self.fail(key, f"expected at most {max_len} item(s), got {len(v)}")
        return v

    def str_list(self, key: str, required: bool = True, unique: bool = False, min_len: int = 0,
                 nonempty_items: bool = True) -> list[str] | None:
        v = self.list(key, required, min_len=min_len)
        if v is None:
            return None
        for i, s in enumerate(v):
            if not isinstance(s, str) or (nonempty_items and not s):
                raise FormatError(self.path, f"{self.name(key)}[{i}]", f"expected a non-empty string, got {s!r}"[:200])
        if unique and len(set(v)) != len(v):
            seen: set[str] = set()
            dup = next(s for s in v if s in seen or seen.add(s))  # linear: a set, not a count per name
            raise self.fail(key, f"{dup!r} appears more than once"[:200])
        return v

    def sub(self, key: str, required: bool = True) -> Fields | None:
        v = self.get(key, required)
        if v is None and not required:
            return None
        return Fields(v, self.path, self.name(key))

    def array(self, key: str, shape: tuple[int | None, ...] | None = None, dtype=np.float64,
              required: bool = True, finite: bool = True) -> np.ndarray | None:
        v = self.get(key, required)
        if v is None and not required:
            return None
        return check_array(v, self.path, self.name(key), shape, dtype, finite)


def check_int(v: Any, path, field: str, min: int | None = None, max: int | None = None) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
        if isinstance(v, float) and v.is_integer() and abs(v) < 2**53:
            v = int(v)
        else:
            raise FormatError(path, field, f"expected an integer, got {_type(v)} {v!r}"[:200])
    v = int(v)
    if min is not None and v < min:
        raise FormatError(path, field, f"must be at least {min}, got {v}")
    if max is not None and v > max:
        raise FormatError(path, field, f"must be at most {max}, got {v}")
    return v


def check_leaves(v: Any, path, name: str, depth: int = 0) -> None:
    """``v`` is plain JSON data whose leaves are finite numbers, null, booleans or strings (nested objects
    and lists allowed, at most 20 deep)."""
    if depth > 20:
        raise FormatError(path, name, "nested too deeply")
    if isinstance(v, dict):
        for k, x in v.items():
            check_leaves(x, path, f"{name}.{k}", depth + 1)
    elif isinstance(v, list):
        for i, x in enumerate(v):
            check_leaves(x, path, f"{name}[{i}]", depth + 1)
    elif v is not None and not isinstance(v, (bool, str)):
        check_number(v, path, name)


def check_number(v: Any, path, field: str, min: float | None = None, max: float | None = None,
                 positive: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.number)):
        raise FormatError(path, field, f"expected a number, got {_type(v)}")
    v = float(v)
    if not math.isfinite(v):
        raise FormatError(path, field, f"must be a finite number, got {v}")
    if positive and not v > 0:
        raise FormatError(path, field, f"must be positive, got {v}")
    if min is not None and v < min:
        raise FormatError(path, field, f"must be at least {min}, got {v}")
    if max is not None and v > max:
        raise FormatError(path, field, f"must be at most {max}, got {v}")
    return v


def check_array(v: Any, path, field: str, shape: tuple[int | None, ...] | None = None, dtype=np.float64,
                finite: bool = True) -> np.ndarray:
    """``v`` (a nested list, or an array read from an .npz) as an array of ``shape`` (``None`` = any
    length on that axis), all finite when ``finite``."""
    try:
        a = np.asarray(v)
        if a.dtype == object or a.dtype.kind in "USV":
            raise ValueError("not numeric")
        a = a.astype(dtype, copy=False)
    except (ValueError, TypeError, OverflowError):
        raise FormatError(path, field, "expected a numeric array (ragged, or not numbers)") from None
    if shape is not None:
        if a.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, a.shape)):
            want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
            raise FormatError(path, field, f"expected shape {want}, got {tuple(a.shape)}")
    if finite and a.dtype.kind == "f" and a.size and not np.isfinite(a).all():
        bad = int(np.flatnonzero(~np.isfinite(a.ravel()))[0])
        raise FormatError(path, field, f"contains a non-finite value (NaN or inf) at flat index {bad}")
    return a


def npz_scalar(z: dict, path, key: str, kind: str, required: bool = True):
    """The scalar array ``z[key]`` of an ``.npz`` owner's file as ``kind`` ("int", "float": finite, "str");
    :class:`FormatError` naming the key for a missing (``required``), non-scalar or mistyped one."""
    if key not in z:
        if required:
            raise FormatError(path, key, "missing")
        return None
    a = z[key]
    if a.ndim != 0 and a.shape != (1,):
        raise FormatError(path, key, f"must be a scalar, got shape {a.shape}")
    v = a.reshape(())[()]
    if kind == "int":
        if a.dtype.kind not in "iu":
            raise FormatError(path, key, f"must be an integer, got dtype {a.dtype}")
        return int(v)
    if kind == "float":
        if a.dtype.kind not in "iuf":
            raise FormatError(path, key, f"must be a number, got dtype {a.dtype}")
        v = float(v)
        if not np.isfinite(v):
            raise FormatError(path, key, f"must be finite, got {v}")
        return v
    if a.dtype.kind != "U":
        raise FormatError(path, key, f"must be a string, got dtype {a.dtype}")
    return str(v)


def npz_json(z: dict, path, key: str, typ: type, required: bool = True) -> Any:
    """The JSON text stored as the string scalar ``z[key]`` of an ``.npz`` owner's file, parsed and checked
    to be a ``typ`` (dict, list, ...); a missing optional key gives ``typ()``. :class:`FormatError` naming
    the key for a missing (``required``), non-JSON or mistyped one."""
    text = npz_scalar(z, path, key, "str", required)
    if text is None:
        return typ()
    try:
        v = json.loads(text)
    except ValueError:
        raise FormatError(path, key, "not valid JSON") from None
    if not isinstance(v, typ):
        raise FormatError(path, key, f"expected a JSON {typ.__name__}, got {type(v).__name__}")
    return v


#: Serialises np.load's .npy header parsing across threads: numpy parses each header with
#: ``ast.literal_eval``, and CPython 3.11's AST construction is not thread-safe (python/cpython#106905:
#: a spurious "SystemError: AST constructor recursion depth mismatch" when threads parse at once, seen
#: in CI when the recognizer loads features files on joblib threads). Held while a file's arrays are read.
NPZ_LOCK = threading.Lock()


def load_npz(path, what: str) -> dict:
    """Every array of the ``.npz`` file ``path`` (``what``: the artifact, for messages), read without
    pickles; any damaged, missing or non-archive file is a :class:`FormatError` naming it."""
    import zipfile
    from pathlib import Path

    path = Path(path)
    if path.is_dir():
        raise FormatError(path, None, f"is a directory, not a {what} .npz")
    if not path.is_file():
        raise FormatError(path, None, f"{what} file not found")
    try:
        with NPZ_LOCK, np.load(path, allow_pickle=False) as z:
            if not hasattr(z, "files"):
                raise FormatError(path, None, f"not a {what} .npz (a single array, not an archive)")
            return {k: z[k] for k in z.files}
    except FormatError:
        raise
    except MemoryError:
        raise FormatError(path, None, "not a readable .npz (an array's declared size is too large)") from None
    except (zipfile.BadZipFile, zipfile.LargeZipFile) as e:
        raise FormatError(path, None, f"not a readable .npz ({type(e).__name__})") from None
    except Exception as e:
        raise FormatError(path, None, f"not a readable .npz ({type(e).__name__}: {' '.join(str(e).split())[:200]})") from None


def npz_version(z: dict, path, kind: str, versions) -> int:
    """The schema version of an ``.npz`` owner's file: 1 without a ``kind`` array (written before headers
    existed), else ``schema_version`` after checking ``kind``."""
    found = npz_scalar(z, path, "kind", "str", required=False)
    if found is None:
        return 1
    if found != kind:
        raise FormatError(path, "kind", f"expected {kind!r}, got {found!r}")
    version = npz_scalar(z, path, "schema_version", "int")
    if version not in versions:
        raise FormatError(path, "schema_version", f"unsupported version {version} (this vidstyle reads "
                          f"{', '.join(map(str, versions))})")
    return version
