"""The motion graph file (``.npz``): owner of its schema, reader and writer.

``kind`` = ``vidstyle.motiongraph``, ``schema_version`` 2 (version 1 files, ``schema`` =
``"vidstyle.motiongraph/1"`` with parallel ``trans_*`` arrays, still load: their transitions become BLEND
edges and playback edges are derived from the clips). ``N`` frames, ``J`` joints, ``C`` clips, ``L``
labels, ``E`` edges, ``S`` segments holding ``F_S`` frames in all. Edge semantics:
:mod:`vidstyle.motiongraph.graph`.

==========================  ==============  ==============================================================
key                         shape / type    meaning
==========================  ==============  ==============================================================
kind, schema_version        str, int        ``vidstyle.motiongraph``, 2
params_json                 str             JSON: every estimator parameter, the seed, ``threshold_used``,
                                            ``stats``
fps, window                 float, int      frame rate of the graph; blend window ``k``
clip_names, clip_paths      (C,) str        clip name (file stem) and source BVH path
clip_sha256                 (C,) str        SHA-256 of each source BVH
clip_start, clip_frames     (C,) int        first global frame and frame count of each clip (contiguous)
clip_src_first              (C,) int        first source-file frame used (1 when a T-pose frame 0 was dropped)
clip_src_fps, clip_scale    (C,) float      source frame rate; root-translation scale of the retargeting
joint_names, parents        (J,) str, int   hierarchy shared by all clips (the reference skeleton's)
offsets                     (J, 3)          rest offsets of the reference skeleton
channels_json               str             BVH channels per joint
end_sites                   (J, 3)          End Site offset, NaN where a joint has none
rotations                   (N, J, 4) f32   local joint rotations (x, y, z, w)
root_positions              (N, 3)          root translation (retargeted)
frame_clip                  (N,) int        clip index of every frame
label_names, labels         (L,), (N,)      action names; label index of every frame
joint_weights               (J,)            weights of the frame distance
scc                         (N,) bool       frame is in the largest strongly connected component
edge_src, edge_dst          (E,) int        edge ``src -> dst`` (graph frames)
edge_kind                   (E,) int8       0 PLAYBACK, 1 BLEND, 2 ENHANCEMENT
edge_cost                   (E,)            planner cost (>= 0)
edge_segment                (E,) int        segment id of an enhancement, else -1
edge_align                  (E, 3)          (theta, x0, z0) placing ``dst``'s clip into ``src``'s coordinates
edge_align_segment          (E, 3)          placement of the segment into ``src``'s coordinates (NaN unless
                                            ENHANCEMENT)
edge_in_scc                 (E,) bool       both ends in the component
segment_rotations           (F_S, J, 4)     frames of all segments, one after another
segment_root_positions      (F_S, 3)
segment_start, _frames      (S,) int        first row and frame count of each segment
segment_centre              (S,) int        index of the middle pose ``w_z`` inside its segment
segment_source, _label      (S,) str        where the segment came from; its label
segment_anchor              (S, 2) int      optional: the segment's enhancement nodes ``(a_in, a_out)``,
                                            ``k-1 <= a_in <= centre <= a_out <= frames-k``; ``(-1, -1)``
                                            (and files without the key): none
segment_hold                (S,)            optional: fraction in [0, 1) of an enhancement shown with the
                                            segment's full weight (files without the key: 0)
==========================  ==============  ==============================================================

A truncated or corrupted file, a missing key, a wrong shape or type, an index out of range or a
non-finite number raises :class:`FormatError` naming the file and the key.

The owner reads and writes a :class:`MotionGraphRecord` (the file's keys as typed fields);
:class:`vidstyle.motiongraph.MotionGraph` builds itself from one (``MotionGraph.from_record``) and
returns one (``graph.to_record()``).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..fileio import write_npz
from ._base import NPZ_LOCK, FormatError

KIND = "vidstyle.motiongraph"
SCHEMA_VERSION = 2
LEGACY_SCHEMA = "vidstyle.motiongraph/1"

_CLIP_KEYS = ("clip_names", "clip_paths", "clip_sha256", "clip_start", "clip_frames", "clip_src_first",
              "clip_src_fps", "clip_scale")
_CORE = ("params_json", "fps", "window", *_CLIP_KEYS, "joint_names", "parents", "offsets", "channels_json",
         "end_sites", "rotations", "root_positions", "frame_clip", "label_names", "labels", "joint_weights", "scc")
_V2 = ("edge_src", "edge_dst", "edge_kind", "edge_cost", "edge_segment", "edge_align", "edge_align_segment",
       "edge_in_scc", "segment_rotations", "segment_root_positions", "segment_start", "segment_frames",
       "segment_centre", "segment_source", "segment_label")
_V1 = ("trans_from", "trans_to", "trans_cost", "trans_theta", "trans_x0", "trans_z0")


@dataclass
class MotionGraphRecord:
    """The content of a graph file, one field per key of the table above (``params_json`` split into
    ``params``, ``threshold_used`` and ``stats``; ``channels_json`` as ``channels``). Lists or arrays are
    accepted when writing; the reader returns checked arrays (float64, int64, bool) and lists of str.
    ``edge_in_scc`` as read is derived from ``scc`` (both ends in the component)."""

    params: dict[str, Any]
    threshold_used: float | None
    stats: dict[str, Any]
    fps: float
    window: int
    clip_names: Any
    clip_paths: Any
    clip_sha256: Any
    clip_start: Any
    clip_frames: Any
    clip_src_first: Any
    clip_src_fps: Any
    clip_scale: Any
    joint_names: Any
    parents: Any
    offsets: Any
    channels: list
    end_sites: Any
    rotations: Any
    root_positions: Any
    frame_clip: Any
    label_names: Any
    labels: Any
    joint_weights: Any
    scc: Any
    edge_src: Any
    edge_dst: Any
    edge_kind: Any
    edge_cost: Any
    edge_segment: Any
    edge_align: Any
    edge_align_segment: Any
    edge_in_scc: Any
    segment_rotations: Any
    segment_root_positions: Any
    segment_start: Any
    segment_frames: Any
    segment_centre: Any
    segment_source: Any
    segment_label: Any
    segment_anchor: Any
    segment_hold: Any


# ---------------------------------------------------------------------------------------------- write
def write_graph(path: str | os.PathLike, rec: MotionGraphRecord) -> None:
    """Write ``rec`` (schema version 2) atomically; the arrays are checked first, so an invalid graph
    never reaches disk (``ValueError``)."""
    arrays = dict(
        kind=np.array(KIND),
        schema_version=np.array(SCHEMA_VERSION),
        params_json=np.array(json.dumps(dict(rec.params, threshold_used=rec.threshold_used, stats=rec.stats),
                                        default=str, allow_nan=False)),
        fps=np.array(float(rec.fps)),
        window=np.array(int(rec.window)),
        clip_names=np.array(rec.clip_names, dtype=str),
        clip_paths=np.array(rec.clip_paths, dtype=str),
        clip_sha256=np.array(rec.clip_sha256, dtype=str),
        clip_start=np.array(rec.clip_start, dtype=np.int64),
        clip_frames=np.array(rec.clip_frames, dtype=np.int64),
        clip_src_first=np.array(rec.clip_src_first, dtype=np.int64),
        clip_src_fps=np.array(rec.clip_src_fps, dtype=np.float64),
        clip_scale=np.array(rec.clip_scale, dtype=np.float64),
        joint_names=np.array(rec.joint_names, dtype=str),
        parents=np.asarray(rec.parents),
        offsets=np.asarray(rec.offsets),
        channels_json=np.array(json.dumps([list(c) for c in rec.channels])),
        end_sites=np.asarray(rec.end_sites),
        rotations=np.asarray(rec.rotations).astype(np.float32),
        root_positions=np.asarray(rec.root_positions),
        frame_clip=np.asarray(rec.frame_clip),
        label_names=np.array(rec.label_names, dtype=str),
        labels=np.asarray(rec.labels),
        joint_weights=np.asarray(rec.joint_weights),
        scc=np.asarray(rec.scc),
        edge_src=np.asarray(rec.edge_src),
        edge_dst=np.asarray(rec.edge_dst),
        edge_kind=np.asarray(rec.edge_kind).astype(np.int8),
        edge_cost=np.asarray(rec.edge_cost),
        edge_segment=np.asarray(rec.edge_segment),
        edge_align=np.asarray(rec.edge_align),
        edge_align_segment=np.asarray(rec.edge_align_segment),
        edge_in_scc=np.asarray(rec.edge_in_scc),
        segment_rotations=np.asarray(rec.segment_rotations),
        segment_root_positions=np.asarray(rec.segment_root_positions),
        segment_start=np.asarray(rec.segment_start),
        segment_frames=np.asarray(rec.segment_frames),
        segment_centre=np.asarray(rec.segment_centre),
        segment_source=np.array(rec.segment_source, dtype=str),
        segment_label=np.array(rec.segment_label, dtype=str),
        segment_anchor=np.asarray(rec.segment_anchor),
        segment_hold=np.asarray(rec.segment_hold),
    )
    try:
        _validate(arrays, None, SCHEMA_VERSION)
    except FormatError as e:
        raise ValueError(f"graph is not valid: {e.field}: {e.problem}") from None
    write_npz(path, **arrays)


# ---------------------------------------------------------------------------------------------- read
def read_graph(path: str | os.PathLike) -> MotionGraphRecord:
    """Read a graph file (schema version 1 or 2) into a checked :class:`MotionGraphRecord`
    (:meth:`vidstyle.motiongraph.MotionGraph.load` builds the graph from it)."""
    path = Path(path)
    d = _load_arrays(path)
    version = _version(d, path)
    if version == 1:
        _require(d, path, _CORE + _V1)
        _convert_v1(d, path)
    else:
        _require(d, path, _CORE + _V2)
    checked = _validate(d, path, version)
    try:
        return _record(checked, path)
    except (ValueError, TypeError, IndexError, KeyError) as e:  # what the checks above could not foresee
        raise FormatError(path, None, f"not a consistent motion graph ({e})") from None


def _load_arrays(path: Path) -> dict[str, np.ndarray]:
    if path.is_dir():
        raise FormatError(path, None, "is a directory, not a graph file")
    if not path.exists():
        raise FormatError(path, None, "graph file not found")
    try:
        with NPZ_LOCK, np.load(path, allow_pickle=False) as z:
            out = {}
            for key in z.files:
                out[key] = z[key]
            return out
    except MemoryError:
        raise FormatError(path, None, "not a motion graph .npz (an array header claims more memory than there is)") from None
    except Exception as e:
        if isinstance(e, FormatError):
            raise
        reason = f"{type(e).__name__}: {e}" if str(e) else type(e).__name__
        raise FormatError(path, None, f"not a readable .npz (truncated or corrupted? {reason})"[:300]) from None


def _version(d: dict, path: Path) -> int:
    if "kind" in d:
        kind = _scalar_str(d, "kind", path)
        if kind != KIND:
            raise FormatError(path, "kind", f"expected {KIND!r}, got {kind!r}")
        v = d.get("schema_version")
        if v is None or v.shape != () or v.dtype.kind not in "iu" or int(v) != SCHEMA_VERSION:
            raise FormatError(path, "schema_version", f"{v!r} is not supported (expected 1 or {SCHEMA_VERSION})")
        return SCHEMA_VERSION
    if "schema" in d and _scalar_str(d, "schema", path) == LEGACY_SCHEMA:
        return 1
    raise FormatError(path, "kind", f"not a motion graph (no kind {KIND!r} and no schema {LEGACY_SCHEMA!r})")


def _require(d: dict, path: Path, keys) -> None:
    for key in keys:
        if key not in d:
            raise FormatError(path, key, "missing (truncated or not a motion graph file)")


def _scalar_str(d: dict, key: str, path) -> str:
    a = d.get(key)
    if a is None:
        raise FormatError(path, key, "missing")
    if a.shape != () or a.dtype.kind != "U":
        raise FormatError(path, key, f"expected a string, got a {a.dtype} array of shape {a.shape}")
    return str(a)


def _arr(d: dict, key: str, path, shape: tuple, kind: str, finite: bool = True) -> np.ndarray:
    """``d[key]`` with numpy dtype kind in ``kind`` ('i' int, 'f' float, 'b' bool, 'U' str) and ``shape``
    (ints or None)."""
    a = d[key]
    ok_kind = a.dtype.kind in kind or (kind == "f" and a.dtype.kind in "iu") or (kind == "i" and a.dtype.kind == "u")
    if not ok_kind:
        raise FormatError(path, key, f"expected {dict(i='integers', f='numbers', b='booleans', U='strings')[kind[0]]}, got dtype {a.dtype}")
    if a.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, a.shape)):
        want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
        raise FormatError(path, key, f"expected shape {want}, got {tuple(a.shape)}")
    if kind == "f":
        a = a.astype(np.float64)
        if finite and a.size and not np.isfinite(a).all():
            raise FormatError(path, key, "contains NaN or inf")
    elif kind == "i":
        a = a.astype(np.int64)
    return a


def _in_range(a: np.ndarray, key: str, path, lo: int, hi: int) -> None:
    if a.size and (a.min() < lo or a.max() >= hi):
        bad = a[(a < lo) | (a >= hi)][0]
        raise FormatError(path, key, f"value {int(bad)} outside [{lo}, {hi})")


def _convert_v1(d: dict, path: Path) -> None:
    """Turn the v1 parallel transition arrays into the v2 edge table (in place)."""
    N = d["frame_clip"].shape[0] if d["frame_clip"].ndim == 1 else 0
    fc = _arr(d, "frame_clip", path, (None,), "i")
    E1 = d["trans_from"].shape[0] if d["trans_from"].ndim == 1 else -1
    tf = _arr(d, "trans_from", path, (None,), "i")
    tt = _arr(d, "trans_to", path, (E1,), "i")
    tc = _arr(d, "trans_cost", path, (E1,), "f")
    al = np.stack([_arr(d, f"trans_{k}", path, (E1,), "f") for k in ("theta", "x0", "z0")], 1)
    f = np.arange(max(N - 1, 0))
    play = f[fc[f] == fc[f + 1]]
    P = len(play)
    d["edge_src"] = np.concatenate([play, tf - 1])
    d["edge_dst"] = np.concatenate([play + 1, tt])
    d["edge_kind"] = np.concatenate([np.zeros(P, np.int8), np.ones(E1, np.int8)])
    d["edge_cost"] = np.concatenate([np.zeros(P), tc])
    d["edge_segment"] = np.full(P + E1, -1, np.int64)
    d["edge_align"] = np.concatenate([np.zeros((P, 3)), al])
    d["edge_align_segment"] = np.full((P + E1, 3), np.nan)
    d["edge_in_scc"] = np.zeros(P + E1, bool)  # recomputed from scc
    J = d["parents"].shape[0] if d["parents"].ndim == 1 else 0
    d["segment_rotations"] = np.zeros((0, J, 4))
    d["segment_root_positions"] = np.zeros((0, 3))
    for key in ("segment_start", "segment_frames", "segment_centre"):
        d[key] = np.zeros(0, np.int64)
    d["segment_source"] = d["segment_label"] = np.zeros(0, dtype="<U1")


def _validate(d: dict, path, version: int) -> dict[str, Any]:
    """Every key checked (types, shapes, ranges, finite); returns the values as the builder needs them."""
    out: dict[str, Any] = {}
    try:
        params = json.loads(_scalar_str(d, "params_json", path))
    except json.JSONDecodeError as e:
        raise FormatError(path, "params_json", f"not valid JSON ({e.msg})") from None
    if not isinstance(params, dict):
        raise FormatError(path, "params_json", "expected a JSON object")
    out["params"] = params
    fps = _arr(d, "fps", path, (), "f")
    if not fps > 0:
        raise FormatError(path, "fps", f"must be positive, got {float(fps)}")
    window = _arr(d, "window", path, (), "i")
    if not window >= 2:
        raise FormatError(path, "window", f"must be at least 2, got {int(window)}")
    out["fps"], out["window"] = float(fps), int(window)
    C = d["clip_names"].shape[0] if d["clip_names"].ndim == 1 else -1
    out["clip_names"] = _arr(d, "clip_names", path, (None,), "U")
    out["clip_paths"] = _arr(d, "clip_paths", path, (C,), "U")
    out["clip_sha256"] = _arr(d, "clip_sha256", path, (C,), "U")
    for key in ("clip_start", "clip_frames", "clip_src_first"):
        out[key] = _arr(d, key, path, (C,), "i")
    for key in ("clip_src_fps", "clip_scale"):
        out[key] = _arr(d, key, path, (C,), "f")
    J = d["joint_names"].shape[0] if d["joint_names"].ndim == 1 else -1
    out["joint_names"] = _arr(d, "joint_names", path, (None,), "U")
    out["parents"] = _arr(d, "parents", path, (J,), "i")
    out["offsets"] = _arr(d, "offsets", path, (J, 3), "f")
    out["end_sites"] = _arr(d, "end_sites", path, (J, 3), "f", finite=False)
    try:
        ch = json.loads(_scalar_str(d, "channels_json", path))
    except json.JSONDecodeError as e:
        raise FormatError(path, "channels_json", f"not valid JSON ({e.msg})") from None
    if not (isinstance(ch, list) and len(ch) == J and all(isinstance(c, list) and all(isinstance(x, str) for x in c) for c in ch)):
        raise FormatError(path, "channels_json", f"expected {J} lists of channel names")
    out["channels"] = ch
    N = d["rotations"].shape[0] if d["rotations"].ndim == 3 else -1
    rot = _arr(d, "rotations", path, (N, J, 4), "f")
    if rot.size and not (np.linalg.norm(rot, axis=-1) > 1e-6).all():
        raise FormatError(path, "rotations", "contains a zero quaternion")
    out["rotations"] = rot
    out["root_positions"] = _arr(d, "root_positions", path, (N, 3), "f")
    fc = out["frame_clip"] = _arr(d, "frame_clip", path, (N,), "i")
    _in_range(fc, "frame_clip", path, 0, max(C, 0))
    start, count = out["clip_start"], out["clip_frames"]
    if count.size and (count.min() < 0 or start.min() < 0 or int(count.sum()) != N):
        raise FormatError(path, "clip_frames", f"clip frame counts do not add up to the {N} frames")
    if C > 0 and N > 0 and not np.array_equal(fc, np.repeat(np.arange(C), count)):
        raise FormatError(path, "frame_clip", "does not match clip_start / clip_frames (clips must be contiguous, in order)")
    if C > 0 and not np.array_equal(start, np.concatenate([[0], np.cumsum(count)[:-1]])):
        raise FormatError(path, "clip_start", "does not match clip_frames")
    L = d["label_names"].shape[0] if d["label_names"].ndim == 1 else -1
    out["label_names"] = _arr(d, "label_names", path, (None,), "U")
    lab = out["labels"] = _arr(d, "labels", path, (N,), "i")
    _in_range(lab, "labels", path, 0, max(L, 0))
    out["joint_weights"] = _arr(d, "joint_weights", path, (J,), "f")
    scc = out["scc"] = _arr(d, "scc", path, (N,), "b")
    E = d["edge_src"].shape[0] if d["edge_src"].ndim == 1 else -1
    src = out["edge_src"] = _arr(d, "edge_src", path, (None,), "i")
    dst = out["edge_dst"] = _arr(d, "edge_dst", path, (E,), "i")
    _in_range(src, "edge_src", path, 0, N)
    _in_range(dst, "edge_dst", path, 0, N)
    kind = out["edge_kind"] = _arr(d, "edge_kind", path, (E,), "i")
    _in_range(kind, "edge_kind", path, 0, 3)
    cost = out["edge_cost"] = _arr(d, "edge_cost", path, (E,), "f")
    if cost.size and cost.min() < 0:
        raise FormatError(path, "edge_cost", "contains a negative cost")
    out["edge_align"] = _arr(d, "edge_align", path, (E, 3), "f")
    aseg = out["edge_align_segment"] = _arr(d, "edge_align_segment", path, (E, 3), "f", finite=False)
    seg = out["edge_segment"] = _arr(d, "edge_segment", path, (E,), "i")
    _arr(d, "edge_in_scc", path, (E,), "b")
    S = d["segment_frames"].shape[0] if d["segment_frames"].ndim == 1 else -1
    enh = kind == 2
    _in_range(seg[enh], "edge_segment", path, 0, max(S, 0))
    if (seg[~enh] != -1).any():
        raise FormatError(path, "edge_segment", "only ENHANCEMENT edges (kind 2) may name a segment")
    if not np.isfinite(aseg[enh]).all():
        raise FormatError(path, "edge_align_segment", "contains NaN or inf for an ENHANCEMENT edge")
    k = out["window"]
    play = kind == 0
    if E > 0:
        if ((dst[play] != src[play] + 1) | (fc[np.minimum(src[play] + 1, N - 1)] != fc[src[play]])).any():
            raise FormatError(path, "edge_dst", "a PLAYBACK edge does not go to the next frame of its clip")
        s, t = src[~play], dst[~play]
        if ((s + k >= N) | (t - k + 1 < 0)).any() or (fc[np.minimum(s + k, N - 1)] != fc[s]).any() or (fc[np.maximum(t - k + 1, 0)] != fc[t]).any():
            raise FormatError(path, "edge_src", f"a BLEND/ENHANCEMENT edge's {k}-frame windows leave their clips")
    sf = out["segment_frames"] = _arr(d, "segment_frames", path, (None,), "i")
    ss = out["segment_start"] = _arr(d, "segment_start", path, (S,), "i")
    sc = out["segment_centre"] = _arr(d, "segment_centre", path, (S,), "i")
    out["segment_source"] = _arr(d, "segment_source", path, (S,), "U")
    out["segment_label"] = _arr(d, "segment_label", path, (S,), "U")
    FS = d["segment_rotations"].shape[0] if d["segment_rotations"].ndim == 3 else -1
    srot = out["segment_rotations"] = _arr(d, "segment_rotations", path, (FS, J, 4), "f")
    if srot.size and not (np.linalg.norm(srot, axis=-1) > 1e-6).all():
        raise FormatError(path, "segment_rotations", "contains a zero quaternion")
    out["segment_root_positions"] = _arr(d, "segment_root_positions", path, (FS, 3), "f")
    if S > 0:
        if sf.min() < 1 or not np.array_equal(ss, np.concatenate([[0], np.cumsum(sf)[:-1]])) or int(sf.sum()) != FS:
            raise FormatError(path, "segment_start", "segment_start / segment_frames do not tile segment_rotations")
        if ((sc < k - 1) | (sc > sf - k)).any():
            raise FormatError(path, "segment_centre", f"a centre leaves fewer than window - 1 = {k - 1} frames on one side")
    # optional keys (files written before they existed have neither)
    anc = out["segment_anchor"] = (_arr(d, "segment_anchor", path, (max(S, 0), 2), "i") if "segment_anchor" in d
                                   else np.full((max(S, 0), 2), -1, np.int64))
    none = (anc == -1).all(axis=1)
    if S > 0 and not none.all():
        a_in, a_out, c, n = anc[~none, 0], anc[~none, 1], sc[~none], sf[~none]
        if ((a_in < k - 1) | (a_in > c) | (a_out < c) | (a_out > n - k)).any():
            raise FormatError(path, "segment_anchor", f"an anchor pair is not window - 1 = {k - 1} <= a_in <= centre "
                                                      "<= a_out <= frames - window (nor -1, -1)")
    hold = out["segment_hold"] = (_arr(d, "segment_hold", path, (max(S, 0),), "f") if "segment_hold" in d
                                  else np.zeros(max(S, 0)))
    if hold.size and ((hold < 0) | (hold >= 1)).any():
        raise FormatError(path, "segment_hold", "a hold outside [0, 1)")
    del scc
    return out


def _record(c: dict[str, Any], path: Path) -> MotionGraphRecord:
    params = dict(c["params"])
    stats = params.pop("stats", {})
    thr = params.pop("threshold_used", None)
    if thr is not None and not (isinstance(thr, (int, float)) and not isinstance(thr, bool) and np.isfinite(thr) and thr > 0):
        raise FormatError(path, "params_json.threshold_used", f"expected a positive number, got {thr!r}")
    scc = c["scc"].astype(bool)
    return MotionGraphRecord(
        params=params, threshold_used=thr, stats=stats if isinstance(stats, dict) else {},
        fps=c["fps"], window=c["window"],
        clip_names=[str(x) for x in c["clip_names"]], clip_paths=[str(x) for x in c["clip_paths"]],
        clip_sha256=[str(x) for x in c["clip_sha256"]], clip_start=c["clip_start"], clip_frames=c["clip_frames"],
        clip_src_first=c["clip_src_first"], clip_src_fps=c["clip_src_fps"], clip_scale=c["clip_scale"],
        joint_names=[str(x) for x in c["joint_names"]], parents=c["parents"], offsets=c["offsets"],
        channels=c["channels"], end_sites=c["end_sites"],
        rotations=c["rotations"], root_positions=c["root_positions"], frame_clip=c["frame_clip"],
        label_names=[str(x) for x in c["label_names"]], labels=c["labels"], joint_weights=c["joint_weights"],
        scc=scc,
        edge_src=c["edge_src"], edge_dst=c["edge_dst"], edge_kind=c["edge_kind"].astype(np.int8),
        edge_cost=c["edge_cost"], edge_segment=c["edge_segment"], edge_align=c["edge_align"],
        edge_align_segment=c["edge_align_segment"], edge_in_scc=scc[c["edge_src"]] & scc[c["edge_dst"]],
        segment_rotations=c["segment_rotations"], segment_root_positions=c["segment_root_positions"],
        segment_start=c["segment_start"], segment_frames=c["segment_frames"], segment_centre=c["segment_centre"],
        segment_source=[str(x) for x in c["segment_source"]], segment_label=[str(x) for x in c["segment_label"]],
        segment_anchor=c["segment_anchor"], segment_hold=c["segment_hold"],
    )
