"""The recognizer model file (``vidstyle train-recognizer --out model.joblib``): owner of its reading and
writing, on the one model-file machinery of :mod:`vidstyle.formats.models`.

A joblib pickle of ``{"header": <JSON text>, "model": <fitted ActionRecognizer>}``. The header holds
``kind`` ("vidstyle.recognizer"), ``schema_version`` (1), ``params``, ``seed``, ``classes``,
``training_files`` (features and labels of set B), ``vocabulary`` (its params and training files = set A),
``summary``, ``sklearn`` and ``vidstyle`` versions, and what the trainer adds (``split``,
``features_params``, ``vocabulary_file``).

This module does not import the recognition package: the caller passes the class the model must be
(``model_type``), and builds the header from its fitted model. Pickles run code when loaded: open model
files you trust.
"""

from __future__ import annotations

import os
from typing import Any

from .models import read_model_file, write_model_file

KIND = "vidstyle.recognizer"
SCHEMA_VERSION = 1
VERSIONS = (1,)


def write_recognizer_model(path: str | os.PathLike, model: Any, header: dict[str, Any]) -> dict[str, Any]:
    """Write the fitted recognizer ``model`` with ``header`` atomically; return the header as written.
    Not compressed: the float64 support vectors deflate only from 35 to 32 MB on the demo, at 1.3 s to
    write and 0.2 s more to every read."""
    return write_model_file(path, KIND, SCHEMA_VERSION, header, model, compress=0)


def read_recognizer_model(path: str | os.PathLike, model_type: type | tuple[type, ...] = object) -> tuple[Any, dict[str, Any]]:
    """``(model, header)`` of a recognizer model file; the model must be a ``model_type``."""
    return read_model_file(path, KIND, VERSIONS, model_type)
