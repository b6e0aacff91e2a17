"""The pose model file (``vidstyle train-pose`` -> ``pose.joblib``), through the one model-file policy of
:mod:`vidstyle.formats.models`: a joblib pickle of ``{"header": <JSON text>, "model": <fitted pose model>}``.

Header (``kind`` ``"vidstyle.pose-model"``, ``schema_version`` 1): ``params`` (the model's
``get_params()``), ``seed``, ``n_train_frames``, ``parts`` (the part names, in the model's order) and what
the trainer adds (``training``: the training set). This module knows nothing of the pose package: the
caller passes the header it records and the model class(es) it expects back (:func:`read_pose_model`), so
formats never imports the domain above it.

Pickles run code when loaded: open pose models you trust.
"""

from __future__ import annotations

import os
from typing import Any

from ._base import FormatError
from .models import read_model_file, write_model_file

KIND = "vidstyle.pose-model"
VERSION = 1
VERSIONS = (1,)


def check_pose_header(doc: dict[str, Any], path: str | os.PathLike | None) -> dict[str, Any]:
    """The recorded fields of a pose model header (after its kind and version): ``params`` an object,
    ``seed`` and ``n_train_frames`` integers (the latter >= 0), ``parts`` a list of names."""
    def _int(x) -> bool:
        return isinstance(x, int) and not isinstance(x, bool)

    if not isinstance(doc.get("params"), dict):
        raise FormatError(path, "params", f"expected an object, got {type(doc.get('params')).__name__}")
    if "seed" in doc and not _int(doc["seed"]):
        raise FormatError(path, "seed", f"expected an integer, got {doc['seed']!r}")
    n = doc.get("n_train_frames", 0)
    if not _int(n) or n < 0:
        raise FormatError(path, "n_train_frames", f"expected an integer >= 0, got {n!r}")
    parts = doc.get("parts", [])
    if not isinstance(parts, list) or not all(isinstance(p, str) for p in parts):
        raise FormatError(path, "parts", "expected a list of part names")
    return doc


def write_pose_model(path: str | os.PathLike, model: Any, header: dict[str, Any]) -> dict[str, Any]:
    """Write ``model`` with ``header`` (``kind``/``schema_version`` set here), atomically; return the header."""
    check_pose_header(header, path)
    return write_model_file(path, KIND, VERSION, header, model)


def read_pose_model(path: str | os.PathLike, model_type: type | tuple[type, ...]) -> tuple[Any, dict[str, Any]]:
    """``(model, header)`` of a pose model file whose model is a ``model_type``; :class:`FormatError`
    naming the file for a missing or unreadable file, another kind or version, a bad header field or a
    model of another class."""
    model, doc = read_model_file(path, KIND, VERSIONS, model_type)
    return model, check_pose_header(doc, path)
