"""The action-model file (``vidstyle fit-actions --out model.npz``): owner of its reading and writing.

Schema ``kind = "vidstyle.actionmodel"``, ``schema_version = 1``; one ``.npz`` without pickles (strings
are 0-d unicode arrays, JSON where structured):

=========================  ==============  ===========================================================
``kind``                   str             "vidstyle.actionmodel"
``schema_version``         int             1
``params``                 str (JSON)      the estimator's constructor parameters (``get_params()``)
``fps``                    float           frame rate of the source clips (> 0)
``contact_height``         float           planted ankle height, source units
``skeleton_names``         str (JSON)      J unique joint names (file order)
``skeleton_parents``       int (J,)        parent index (< own index) or -1
``skeleton_offsets``       float (J, 3)    rest offsets
``skeleton_channels``      str (JSON)      J lists of BVH channel names
``skeleton_end_sites``     str (JSON)      {joint index: [x, y, z]}
``reach``                  float (J,)      joint weights of the spatial features (> 0)
``labels``                 str (JSON)      the modelled labels, L >= 1, unique
``sources``                str (JSON)      the clips it was fitted on
``skipped``                str (JSON)      {label: why it has no model}
``label_meta``             str (JSON)      L objects: n_instances, n_other_signature, medoid, fit_seconds,
                                           spatial/temporal_variance_kept, mean_frames, covariance_type
``m{i}_<array>``           arrays          per label ``i`` (order of ``labels``): ``ref_rotations``
                                           (M, J, 4) unit quaternions, ``ref_root`` (M, 3),
                                           ``keyframes`` (K,) increasing from 0, < M, ``states`` (K, 2)
                                           bool, ``spatial_mean`` (M(3+3J),), ``spatial_components``
                                           (ks, M(3+3J)), ``spatial_std`` (ks,) > 0, ``temporal_mean``
                                           (M-1,), ``temporal_components`` (kt, M-1), ``temporal_std``
                                           (kt,) > 0, ``gmm_weights`` (G,) > 0 summing to 1,
                                           ``gmm_means`` (G, ks+kt), ``gmm_covariances`` (G, k, k)
                                           symmetric positive definite, ``bic`` (>= 1,)
=========================  ==============  ===========================================================

:func:`read_actionmodel` checks every field and returns an :class:`ActionModelRecord` (plain arrays;
:meth:`vidstyle.actionmodel.ActionModel.from_record` builds the fitted model, ``ActionModel.load`` does
both); anything else is a :class:`FormatError` naming the file and field. :func:`write_actionmodel`
validates the record the same way before writing atomically.
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

KIND = "vidstyle.actionmodel"
SCHEMA_VERSION = 1
VERSIONS = (1,)
LABEL_ARRAYS = ("ref_rotations", "ref_root", "keyframes", "states", "spatial_mean", "spatial_components",
                "spatial_std", "temporal_mean", "temporal_components", "temporal_std", "gmm_weights", "gmm_means",
                "gmm_covariances", "bic")
META_NUMBERS = ("fit_seconds", "spatial_variance_kept", "temporal_variance_kept", "mean_frames")
#: the estimator's parameters and what each must be ("int>=k", "fraction": in (0, 1], a choice tuple,
#: "labels": null or a list of names, "seed": null or an integer >= 0)
PARAMS = {"variance": "fraction", "slope_limit": "int>=1", "max_components": "int>=1",
          "covariance_type": ("full", "diag"), "min_frames": "int>=2", "min_run": "int>=1", "min_primitive": "int>=2",
          "min_instances": "int>=2", "medoid_candidates": "int>=2", "blend_frames": "int>=0", "labels": "labels",
          "warp_smoothing": "nonnegative",
          "random_state": "seed"}


@dataclass
class ActionModelRecord:
    """What an action-model file holds (module text); ``models`` maps each label to its arrays
    (:data:`LABEL_ARRAYS`) and metadata (``meta``)."""

    params: dict[str, Any]
    fps: float
    contact_height: float
    skeleton: dict[str, Any]  # names, parents, offsets, channels, end_sites
    reach: np.ndarray
    labels: list[str]
    models: dict[str, dict[str, Any]]
    sources: list[str] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)
    schema_version: int = SCHEMA_VERSION


def _arrays(rec: ActionModelRecord) -> dict[str, np.ndarray]:
    sk = rec.skeleton
    out = dict(
        kind=np.array(KIND), schema_version=np.int64(SCHEMA_VERSION),
        params=np.array(json.dumps(rec.params, sort_keys=True, default=_jsonable)),
        fps=np.float64(rec.fps), contact_height=np.float64(rec.contact_height),
        skeleton_names=np.array(json.dumps(list(sk["names"]))),
        skeleton_parents=np.asarray(sk["parents"], dtype=np.int64),
        skeleton_offsets=np.asarray(sk["offsets"], dtype=np.float64),
        skeleton_channels=np.array(json.dumps([list(c) for c in sk["channels"]])),
        skeleton_end_sites=np.array(json.dumps({str(k): [float(x) for x in v] for k, v in sk["end_sites"].items()})),
        reach=np.asarray(rec.reach, dtype=np.float64),
        labels=np.array(json.dumps(list(rec.labels))),
        sources=np.array(json.dumps([str(s) for s in rec.sources])),
        skipped=np.array(json.dumps({str(k): str(v) for k, v in rec.skipped.items()})),
    )
    meta = []
    for i, label in enumerate(rec.labels):
        lm = rec.models[label]
        for k in LABEL_ARRAYS:
            out[f"m{i}_{k}"] = np.asarray(lm[k])
        meta.append({k: lm["meta"][k] for k in ("n_instances", "n_other_signature", "medoid", "covariance_type",
                                                *META_NUMBERS)})
    out["label_meta"] = np.array(json.dumps(meta, default=_jsonable))
    return out


def _jsonable(o: Any):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, tuple):
        return list(o)
    raise TypeError(type(o).__name__)


def write_actionmodel(path: str | os.PathLike, record: ActionModelRecord) -> None:
    """Write ``record`` atomically, after checking it as the reader would (ValueError: a record the
    reader would refuse is a programming error)."""
    arrays = _arrays(record)
    try:
        parse_actionmodel(arrays, path)
    except FormatError as e:
        raise ValueError(f"invalid action model: {e.field}: {e.problem}") from None
    write_npz(path, **arrays)


def read_actionmodel(path: str | os.PathLike) -> ActionModelRecord:
    """Read and check an action-model ``.npz``."""
    path = Path(path)
    return parse_actionmodel(load_npz(path, "action model"), path)



def _arr(z: dict, path, key: str, shape: tuple, kind: str = "f") -> np.ndarray:
    if key not in z:
        raise FormatError(path, key, "missing")
    a = z[key]
    kinds = {"f": "iuf", "i": "iu", "b": "b"}[kind]
    if a.dtype.kind not in kinds:
        raise FormatError(path, key, f"expected dtype kind {kind}, got {a.dtype}")
    if a.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, a.shape)):
        want = "(" + ", ".join("*" if s is None else str(s) for s in shape) + ")"
        raise FormatError(path, key, f"expected shape {want}, got {a.shape}")
    if kind == "f":
        a = a.astype(np.float64)
        if not np.isfinite(a).all():
            raise FormatError(path, key, "not finite")
    return a


def _check_params(params: dict, path) -> dict:
    unknown = sorted(set(params) - set(PARAMS))
    if unknown:
        raise FormatError(path, "params", f"unknown parameter {unknown[0]!r}")
    missing = sorted(set(PARAMS) - set(params))
    if missing:
        raise FormatError(path, f"params.{missing[0]}", "missing")
    for k, rule in PARAMS.items():
        v = params[k]
        bad = FormatError(path, f"params.{k}", f"invalid value {v!r}")
        is_int = isinstance(v, int) and not isinstance(v, bool)
        if isinstance(rule, tuple):
            if v not in rule:
                raise bad
        elif rule == "fraction":
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v <= 1:
                raise bad
        elif rule == "nonnegative":
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 <= v < 1e3:
                raise bad
        elif rule.startswith("int>="):
            if not is_int or v < int(rule[5:]):
                raise bad
        elif rule == "labels":
            if v is not None and not (isinstance(v, list) and all(isinstance(x, str) for x in v)):
                raise bad
        elif rule == "seed":
            if v is not None and not (is_int and v >= 0):
                raise bad
    return dict(params, labels=None if params["labels"] is None else tuple(params["labels"]))


def parse_actionmodel(z: dict, path=None) -> ActionModelRecord:
    """Check the arrays of an action-model file (module text)."""
    npz_version(z, path, KIND, VERSIONS)
    if "kind" not in z:
        raise FormatError(path, "kind", "missing")
    params = _check_params(npz_json(z, path, "params", dict), path)
    fps = npz_scalar(z, path, "fps", "float")
    if fps <= 0:
        raise FormatError(path, "fps", f"must be > 0, got {fps}")
    contact_height = npz_scalar(z, path, "contact_height", "float")
    names = npz_json(z, path, "skeleton_names", list)
    if not names or not all(isinstance(n, str) for n in names):
        raise FormatError(path, "skeleton_names", "expected a non-empty list of strings")
    J = len(names)
    parents = _arr(z, path, "skeleton_parents", (J,), "i").astype(np.int64)
    offsets = _arr(z, path, "skeleton_offsets", (J, 3))
    channels = npz_json(z, path, "skeleton_channels", list)
    if len(channels) != J or not all(isinstance(c, list) and all(isinstance(x, str) for x in c) for c in channels):
        raise FormatError(path, "skeleton_channels", f"expected {J} lists of channel names")
    ends = npz_json(z, path, "skeleton_end_sites", dict)
    end_sites = {}
    for k, v in ends.items():
        if not (k.isdigit() and int(k) < J and isinstance(v, list) and len(v) == 3
                and all(isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x) for x in v)):
            raise FormatError(path, "skeleton_end_sites", f"entry {k!r}: expected a joint index and 3 numbers")
        end_sites[int(k)] = np.array(v, dtype=np.float64)
    if np.any(parents < -1) or np.any(parents >= np.arange(J)):
        raise FormatError(path, "skeleton_parents", "a parent is not -1 or a joint before its child")
    if len(set(names)) != J:
        raise FormatError(path, "skeleton_names", "joint names are not unique")
    skeleton = {"names": names, "parents": parents, "offsets": offsets, "channels": [tuple(c) for c in channels],
                "end_sites": end_sites}
    reach = _arr(z, path, "reach", (J,))
    if np.any(reach <= 0):
        raise FormatError(path, "reach", "must be > 0")
    labels = npz_json(z, path, "labels", list)
    if not labels or not all(isinstance(x, str) and x for x in labels) or len(set(labels)) != len(labels):
        raise FormatError(path, "labels", "expected a non-empty list of unique names")
    sources = npz_json(z, path, "sources", list)
    if not all(isinstance(s, str) for s in sources):
        raise FormatError(path, "sources", "expected a list of strings")
    skipped = npz_json(z, path, "skipped", dict)
    if not all(isinstance(v, str) for v in skipped.values()):
        raise FormatError(path, "skipped", "expected an object of strings")
    meta = npz_json(z, path, "label_meta", list)
    if len(meta) != len(labels):
        raise FormatError(path, "label_meta", f"expected {len(labels)} objects, got {len(meta)}")
    models = {}
    D = 3 + 3 * J
    for i, label in enumerate(labels):
        mt = meta[i]
        where = f"label_meta[{i}]"
        if not isinstance(mt, dict):
            raise FormatError(path, where, "expected an object")
        for k in ("n_instances", "n_other_signature"):
            v = mt.get(k)
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise FormatError(path, f"{where}.{k}", f"expected an integer >= 0, got {v!r}")
        for k in META_NUMBERS:
            v = mt.get(k)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v) or v < 0:
                raise FormatError(path, f"{where}.{k}", f"expected a number >= 0, got {v!r}")
        if not isinstance(mt.get("medoid"), str):
            raise FormatError(path, f"{where}.medoid", "expected a string")
        if mt.get("covariance_type") not in ("full", "diag"):
            raise FormatError(path, f"{where}.covariance_type", "expected full or diag")
        p = f"m{i}_"
        rot = _arr(z, path, p + "ref_rotations", (None, J, 4))
        M = rot.shape[0]
        if M < 2:
            raise FormatError(path, p + "ref_rotations", f"expected at least 2 aligned frames, got {M}")
        if np.any(np.abs(np.linalg.norm(rot, axis=-1) - 1) > 1e-6):
            raise FormatError(path, p + "ref_rotations", "not unit quaternions")
        root = _arr(z, path, p + "ref_root", (M, 3))
        keys = _arr(z, path, p + "keyframes", (None,), "i").astype(np.int64)
        K = len(keys)
        if K < 1 or keys[0] != 0 or np.any(np.diff(keys) <= 0) or keys[-1] >= M - 1:
            raise FormatError(path, p + "keyframes", f"expected increasing frames from 0, below {M - 1}")
        states = _arr(z, path, p + "states", (K, 2), "b")
        sm = _arr(z, path, p + "spatial_mean", (M * D,))
        sc = _arr(z, path, p + "spatial_components", (None, M * D))
        ss = _arr(z, path, p + "spatial_std", (sc.shape[0],))
        tm = _arr(z, path, p + "temporal_mean", (M - 1,))
        tc = _arr(z, path, p + "temporal_components", (None, M - 1))
        ts = _arr(z, path, p + "temporal_std", (tc.shape[0],))
        for key, s in ((p + "spatial_std", ss), (p + "temporal_std", ts)):
            if np.any(s <= 0):
                raise FormatError(path, key, "must be > 0")
        k = sc.shape[0] + tc.shape[0]
        if k < 1:
            raise FormatError(path, p + "spatial_components", "no coefficient at all")
        gw = _arr(z, path, p + "gmm_weights", (None,))
        G = len(gw)
        if G < 1 or np.any(gw <= 0) or abs(gw.sum() - 1) > 1e-6:
            raise FormatError(path, p + "gmm_weights", "expected positive weights summing to 1")
        gm = _arr(z, path, p + "gmm_means", (G, k))
        gc = _arr(z, path, p + "gmm_covariances", (G, k, k))
        if not np.allclose(gc, np.swapaxes(gc, 1, 2), rtol=1e-8, atol=1e-10):
            raise FormatError(path, p + "gmm_covariances", "not symmetric")
        try:
            np.linalg.cholesky(gc)
        except np.linalg.LinAlgError:
            raise FormatError(path, p + "gmm_covariances", "not positive definite") from None
        bic = _arr(z, path, p + "bic", (None,))
        if len(bic) < 1:
            raise FormatError(path, p + "bic", "empty")
        models[label] = {"ref_rotations": rot, "ref_root": root, "keyframes": keys, "states": states.astype(bool),
                         "spatial_mean": sm, "spatial_components": sc, "spatial_std": ss, "temporal_mean": tm,
                         "temporal_components": tc, "temporal_std": ts, "gmm_weights": gw, "gmm_means": gm,
                         "gmm_covariances": gc, "bic": bic,
                         "meta": {"n_instances": mt["n_instances"], "n_other_signature": mt["n_other_signature"],
                                  "medoid": mt["medoid"], "covariance_type": mt["covariance_type"],
                                  **{k2: float(mt[k2]) for k2 in META_NUMBERS}}}
    return ActionModelRecord(params, float(fps), float(contact_height), skeleton, reach, list(labels), models,
                             list(sources), dict(skipped))
