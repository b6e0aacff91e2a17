"""Model files: one persistence policy for every fitted model vidstyle writes (recognizer, pose model, ...).

A model file is a joblib pickle of ``{"header": <JSON text>, "model": <fitted estimator>}``. The header is a
JSON object with ``kind`` + ``schema_version`` (as every artifact has, :mod:`vidstyle.formats._base`) and
what the model kind records about itself (params, seed, classes, training files, library versions). An
owner per model kind calls :func:`write_model_file` / :func:`read_model_file` with its own ``kind``,
versions and expected class; the reader checks the header as the JSON owners do and raises
:class:`FormatError` naming the file for anything else: a missing file, bytes joblib cannot read, another
kind or version, a model object of the wrong class.

Pickles run code when loaded: open model files you trust (your own, or ones shipped in the package).
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ..fileio import atomic_path, json_default
from ._base import FormatError, check_header


def write_model_file(path: str | os.PathLike, kind: str, version: int, header: dict[str, Any],
                     model: Any, compress: int = 3) -> dict[str, Any]:
    """Write ``model`` with ``header`` (``kind``/``schema_version`` are set here) atomically; return the header."""
    import joblib

    doc = {**header, "kind": kind, "schema_version": int(version)}
    text = json.dumps(doc, default=json_default, allow_nan=False)
    with atomic_path(Path(path)) as tmp:
        joblib.dump({"header": text, "model": model}, tmp, compress=compress)
    return json.loads(text)


def read_model_header_and_object(path: str | os.PathLike) -> tuple[Any, Any]:
    """The raw ``(header document, model object)`` of a model file, without checks on either."""
    import joblib

    path = Path(path)
    if path.is_dir():
        raise FormatError(path, None, "is a directory, not a model file")
    if not path.is_file():
        raise FormatError(path, None, "model file not found")
    try:
        obj = joblib.load(path)
    except Exception as exc:  # noqa: BLE001 - any unpickling failure is a bad model file
        raise FormatError(path, None, f"not a readable model file ({type(exc).__name__})") from None
    if not isinstance(obj, dict) or not isinstance(obj.get("header"), str) or "model" not in obj:
        raise FormatError(path, None, "not a vidstyle model file (no header)")
    try:
        doc = json.loads(obj["header"])
    except ValueError:
        raise FormatError(path, "header", "not valid JSON") from None
    return doc, obj["model"]


def read_model_file(path: str | os.PathLike, kind: str, versions: Iterable[int],
                    model_type: type | tuple[type, ...]) -> tuple[Any, dict[str, Any]]:
    """``(model, header)`` of a model file of ``kind`` at one of ``versions`` whose model is a ``model_type``."""
    doc, model = read_model_header_and_object(path)
    check_header(doc, path, kind, versions)
    if not isinstance(model, model_type):
        names = ", ".join(t.__name__ for t in (model_type if isinstance(model_type, tuple) else (model_type,)))
        raise FormatError(path, "model", f"expected a {names}, got {type(model).__name__}")
    return model, doc
