"""The visual vocabulary file (``vidstyle vocabulary --out vocab.npz``): owner of its reading and writing.

Schema ``kind = "vidstyle.vocabulary"``, ``schema_version = 1`` (a ``.npz``, no pickles):

====================  ===============  =====================================================================
``kind``              str (0-d)        "vidstyle.vocabulary"
``schema_version``    int64 (0-d)      1
``centres``           float (W, D)     the word centres (k-means)
``method``            str (0-d)        minibatch | hierarchical | kmeans
``params``            str (0-d)        JSON object: the vocabulary's constructor parameters
``dim``               int (0-d)        descriptor dimension D
``descriptor_dtype``  str (0-d)        dtype of the descriptors it was fitted on
``training_files``    str (0-d)        JSON list of the features files of set A
``n_descriptors``     int (0-d)        descriptors the centres were fitted on
``seed``              int (0-d)        random_state (-1: None)
``extra``             str (0-d)        JSON object (e.g. the split), optional
``tree_<name>``       arrays           the hierarchical tree (method ``hierarchical``), optional
====================  ===============  =====================================================================

Files written before the header (no ``kind``/``schema_version``) are schema 1 and still load. The reader
returns a plain :class:`VocabularyRecord`; :class:`vidstyle.recognition.Vocabulary` builds itself from it.
Every problem is a :class:`FormatError` naming the file and field.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..fileio import write_npz
from ._base import FormatError, load_npz, npz_json, npz_scalar, npz_version

KIND = "vidstyle.vocabulary"
SCHEMA_VERSION = 1
VERSIONS = (1,)


@dataclass
class VocabularyRecord:
    """What a vocabulary file holds."""

    centres: np.ndarray
    params: dict[str, Any]
    dim: int
    descriptor_dtype: str
    n_descriptors: int
    training_files: list[str] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)
    seed: int | None = None
    tree: dict[str, np.ndarray] | None = None
    method: str = ""
    schema_version: int = SCHEMA_VERSION


def write_vocabulary(path: str | os.PathLike, record: VocabularyRecord) -> None:
    """Write ``record`` atomically (with the current ``kind`` and ``schema_version``)."""
    arrays = dict(
        kind=np.array(KIND),
        schema_version=np.int64(SCHEMA_VERSION),
        centres=np.asarray(record.centres),
        method=np.array(record.method or str(record.params.get("method", ""))),
        params=np.array(json.dumps(record.params, sort_keys=True)),
        dim=np.array(int(record.dim)),
        descriptor_dtype=np.array(str(record.descriptor_dtype)),
        training_files=np.array(json.dumps([str(f) for f in record.training_files])),
        n_descriptors=np.array(int(record.n_descriptors)),
        seed=np.array(-1 if record.seed is None else int(record.seed)),
        extra=np.array(json.dumps(record.extra or {}, sort_keys=True, default=str)),
    )
    if record.tree is not None:
        arrays.update({f"tree_{k}": v for k, v in record.tree.items()})
    write_npz(path, **arrays)



def read_vocabulary(path: str | os.PathLike) -> VocabularyRecord:
    """Read and check a vocabulary ``.npz`` (with or without the schema header)."""
    path = Path(path)
    z = load_npz(path, "vocabulary")
    version = npz_version(z, path, KIND, VERSIONS)
    if "centres" not in z:
        raise FormatError(path, "centres", "missing")
    centres = z["centres"]
    if centres.dtype.kind not in "iuf" or centres.ndim != 2 or centres.shape[0] < 1:
        raise FormatError(path, "centres", f"expected a non-empty numeric (words, dim) array, got "
                                           f"{centres.dtype} {centres.shape}")
    if not np.isfinite(centres).all():
        raise FormatError(path, "centres", "not finite")
    dim = npz_scalar(z, path, "dim", "int")
    if centres.shape[1] != dim:
        raise FormatError(path, "centres", f"has shape {centres.shape}, but dim is {dim}")
    params = npz_json(z, path, "params", dict)
    files = npz_json(z, path, "training_files", list)
    if not all(isinstance(f, str) for f in files):
        raise FormatError(path, "training_files", "expected a list of strings")
    n_desc = npz_scalar(z, path, "n_descriptors", "int")
    if n_desc < 0:
        raise FormatError(path, "n_descriptors", f"must be >= 0, got {n_desc}")
    seed = npz_scalar(z, path, "seed", "int", required=False)
    tree = {k[5:]: z[k] for k in z if k.startswith("tree_")}
    if tree:
        _check_tree(path, tree, dim, centres.shape[0])
    return VocabularyRecord(
        centres=centres.astype(np.float32), params=params, dim=dim,
        descriptor_dtype=npz_scalar(z, path, "descriptor_dtype", "str"), n_descriptors=n_desc,
        training_files=files, extra=npz_json(z, path, "extra", dict, required=False),
        seed=None if seed is None or seed < 0 else seed, tree=tree or None,
        method=npz_scalar(z, path, "method", "str", required=False) or str(params.get("method", "")),
        schema_version=version,
    )


TREE_KEYS = ("centres", "child_start", "child_count", "word")


def _check_tree(path: Path, tree: dict[str, np.ndarray], dim: int, n_words: int) -> None:
    """A hierarchical tree that descends: every inner node's children come after it, inside the tree,
    and every leaf is a word (so assigning a descriptor always ends, at a word of the vocabulary)."""
    for k in TREE_KEYS:
        if k not in tree:
            raise FormatError(path, f"tree_{k}", "missing (the tree is incomplete)")
    c = tree["centres"]
    if c.dtype.kind not in "iuf" or c.ndim != 2 or c.shape[1] != dim or c.shape[0] < 1 or not np.isfinite(c).all():
        raise FormatError(path, "tree_centres", f"expected finite (nodes, {dim}) numbers, got {c.dtype} {c.shape}")
    n = c.shape[0]
    for k in TREE_KEYS[1:]:
        a = tree[k]
        if a.dtype.kind not in "iu" or a.shape != (n,):
            raise FormatError(path, f"tree_{k}", f"expected ({n},) integers, got {a.dtype} {a.shape}")
    start, count, word = (tree[k].astype(np.int64) for k in TREE_KEYS[1:])
    inner = word < 0
    node = np.arange(n)
    if np.any(inner & ((count < 1) | (start <= node) | (start + count > n))):
        raise FormatError(path, "tree_child_start", "an inner node's children are not after it inside the tree")
    if np.any(~inner & (word >= n_words)):
        raise FormatError(path, "tree_word", f"a leaf names a word >= {n_words}")
