"""Fuzzing every reader of :mod:`vidstyle.formats`: mutated bytes and mutated JSON structure (dropped,
retyped, NaN, wrong-length, empty and nested-garbage fields). Nothing but FormatError may escape, the
message names the file, and whatever is accepted writes back and reads again to the same document."""

from __future__ import annotations

import io
import json
import math
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vidstyle.formats import FormatError
from vidstyle.formats.dataset import parse_dataset, read_dataset, write_dataset
from vidstyle.formats.labels import FrameLabels, parse_labels, read_labels, write_labels
from vidstyle.formats.library import parse_library, read_library, write_library
from vidstyle.formats.metrics import parse_metrics, read_metrics, write_metrics
from vidstyle.formats.poses import parse_poses, read_poses, write_poses
from vidstyle.formats.recognised import RecognisedLabels, parse_recognised, read_recognised, write_recognised
from vidstyle.formats.reconstruction import parse_reconstruction, read_reconstruction, write_reconstruction
from vidstyle.formats.runrecord import parse_run_record, read_run_record, write_run_record
from vidstyle.formats.sequence import ActionSequence, parse_sequence, read_sequence, write_sequence
from vidstyle.formats.style import StyleRecord, parse_style, read_style, style_to_dict, write_style
from vidstyle.formats.truth import parse_truth, read_truth, write_truth
from vidstyle.formats.walk import parse_walk_labels, read_walk_labels, write_walk_labels

CLASSES = ["Jab", "Hook", "Guard"]


def _labels_doc() -> dict:
    labels = ["Guard", "Jab", "Jab", "Hook", "Guard", "Guard"]
    return FrameLabels(labels, CLASSES, 20.0, video="v.mp4", performer="p00", confidence=np.linspace(0, 1, 6),
                       transitions=[1, 3, 4], events=None, chain=["Jab", "Hook"]).to_dict() | {
        "events": [{"label": "Jab", "start": 1, "end": 3}, {"label": "Hook", "start": 3, "end": 4}]}


def _recognised_doc() -> dict:
    labels = ["Guard", "Jab", "Jab", "Hook"]
    return RecognisedLabels(labels, CLASSES, 20.0, video="v.mp4", confidence=np.array([0.5, 0.9, 0.8, 0.7]),
                            raw=["Jab", "Jab", "Hook", "Hook"], raw_confidence=np.array([0.4, 0.6, 0.5, 0.9]),
                            smoothing="viterbi", smoothing_window=6, model="m.joblib", features="f.npz").to_dict()


def _dataset_doc() -> dict:
    chain = {"actions": ["Jab", "Hook"], "start": [0.5, 0.5], "transition": [[0.2, 0.8], [0.6, 0.4]],
             "duration_frames": {"Jab": [8.0, 1.0], "Hook": [10.0, 2.0]}}
    videos = [{"id": f"p0{p}_{k}", "performer": f"p0{p}", "kind": k, "action": "Jab" if k == "single" else None,
               "view": "front", "azimuth_deg": 0.0, "video": f"videos/p0{p}_{k}.mp4", "labels": f"labels/p0{p}_{k}.json",
               "frames": 6} for p in range(2) for k in ("single", "performance")]
    return {"kind": "vidstyle.dataset", "schema_version": 2, "seed": 0, "fps": 20, "actions": ["Jab", "Hook"],
            "classes": CLASSES, "performers": [{"id": "p00", "chain": chain}, {"id": "p01", "chain": chain}],
            "videos": videos}


def _reconstruction_doc() -> dict:
    frames = [{"frame": i, "observed": i != 1, "azimuth_deg": 10.0 * i, "label": "Jab" if i else "",
               "contacts": [True, i == 2],
               "neighbours": [] if i == 1 else [{"clip": 0, "frame": 3 + i, "weight": 0.75},
                                                {"clip": 1, "frame": 9, "weight": 0.25}]} for i in range(3)]
    return {"kind": "vidstyle.reconstruction", "schema_version": 1, "video": "v.mp4", "poses": "v.poses.json",
            "bvh": "v.bvh", "fps": 20.0, "size": [160, 120], "library": ["a.bvh", "b.bvh"], "params": {"k": 32},
            "camera": {"K": [[150.0, 0.0, 79.5], [0.0, 150.0, 59.5], [0.0, 0.0, 1.0]], "elevation_deg": 10.0,
                       "height": 20.0}, "frames": frames}


def _walk_doc() -> dict:
    labels = ["Jab", "Jab", "Jab", "Hook", "Hook"]
    return {"kind": "vidstyle.labels", "schema_version": 2, "bvh": "w.bvh", "fps": 30, "classes": ["Hook", "Jab"],
            "labels": labels, "events": [{"label": "Jab", "start": 0, "end": 3}, {"label": "Hook", "start": 3, "end": 5}],
            "source_labels": ["Jab", "Jab", "unlabelled", "Hook", "Hook"], "source_clip": ["a", "a", "a", "b", "b"],
            "source_frame": [4, 5, 6, 0, 1], "graph_frame": [4, 5, 6, 40, 41], "transition": [-1, -1, -1, 7, -1],
            "transitions_used": [7], "transition_kinds": ["BLEND"], "transition_segments": [-1], "cost": 1.5,
            "foot_lock": {"enabled": False}, "planner": {"mismatch_penalty": 2.0}}


def _library_doc() -> dict:
    return {"kind": "vidstyle.library", "schema_version": 1,
            "params": {"seed": 0, "performers": 1, "action_seconds": 6.0, "fps": 20, "mocap_fps": 60, "cmu_clips": 1},
            "performers": [{"id": "lib00", "body": {"height": 1.7}, "style": {"amplitude": [1.0, 0.9]}}],
            "clips": [{"name": "lib00_jab", "performer": "lib00", "kind": "action", "holds_pose": None, "frames": 360,
                       "bvh": "clips/lib00_jab.bvh", "labels": "clips/lib00_jab.labels.json"},
                      {"name": "lib00_stop", "performer": "lib00", "kind": "context", "holds_pose": "step_back",
                       "frames": 873, "bvh": "clips/lib00_stop.bvh", "labels": "clips/lib00_stop.labels.json"},
                      {"name": "cmu_02_05", "performer": "cmu02", "kind": "cmu", "holds_pose": None, "frames": 400,
                       "bvh": "clips/cmu_02_05.bvh", "labels": "clips/cmu_02_05.labels.json", "source": "x/02_05.bvh"}]}


def _poses_doc() -> dict:
    """A blazepose poses.json (schema 3): a frame with world keypoints, one without, one with no pose."""
    from vidstyle.formats.poses import PoseFrame, Poses

    rng = np.random.default_rng(1)
    pts = np.column_stack([rng.uniform(0, 160, (15, 2)), rng.uniform(0, 1, 15)]).round(3)
    frames = [PoseFrame(0, "front", pts, {"front": 0.7, "left": 0.1, "right": 0.1, "back": 0.1}, azimuth=-20.0,
                        world=rng.uniform(-0.9, 0.9, (15, 3)).round(5)),
              PoseFrame(1, "left", pts, {"left": 1.0}),
              PoseFrame.none(2, "performer not found")]
    return Poses("v.mp4", "blazepose", frames, params={"smoothed": "one-euro"}).to_document()


def _sequence_doc() -> dict:
    return ActionSequence.from_events([{"action": "Jab", "duration_frames": 5}, {"action": "Hook", "duration_frames": 7}],
                                      20.0, style="s.json", model="a", seed=3).to_dict()


@pytest.fixture(scope="module")
def style_doc():
    from vidstyle.style.artifact import Style, StyleParams
    from vidstyle.style.events import EventParams

    rng = np.random.default_rng(0)
    labels = []
    for _ in range(40):
        labels += [str(rng.choice(["Jab", "Hook", "Cross"]))] * int(rng.integers(4, 8)) + ["Guard"] * 3
    track = FrameLabels(labels, ("Jab", "Hook", "Cross", "Guard"), 20.0, video="v.mp4")
    style = Style.from_tracks([track], StyleParams(events=EventParams(ignore=("Guard",)), n_init=1, k_range=(1, 2)))
    return json.loads(json.dumps(style.to_dict(), default=lambda o: np.asarray(o).tolist()))


METRICS = {
    "recognition": {"kind": "vidstyle.metrics.recognition", "schema_version": 1, "seed": 0,
                    "frame_accuracy": {"raw": 0.6, "smoothed": 0.7}, "video_accuracy": None, "n_test_videos": 2,
                    "n_test_frames": 40, "split": {"kind": "unseen-performer", "test": ["a", "b"]},
                    "confusion": {"classes": ["Jab", "Hook"], "smoothed": [[1.0, 0.0], [0.25, 0.75]],
                                  "raw": [[0.5, 0.5], [0.5, 0.5]]},
                    "segments": {"smoothed": {"boundary_tolerant_accuracy": {"1": 0.9, "2": 0.95},
                                              "segmental_f1": {"10": 0.8, "50": None}}}},
    "style": {"kind": "vidstyle.metrics.style", "schema_version": 1, "seed": 0,
              "sources": {"ground_truth": {"summary": {
                  "transition_mae": {"a": 0.04, "bigram": 0.05, "b_implied": None},
                  "identification": {"a": {"accuracy_by_heldout_data": 0.9, "confusion_by_heldout_data": {"p": {"p": 3}}}},
                  "fidelity": {"a": {"jsd_2gram_same": 0.1, "jsd_2gram_other": 0.3}},
                  "heldout_loglik_per_event": {"a": -1.2, "b": -1.1, "bigram": -1.3}}}}},
    "motion": {"kind": "vidstyle.metrics.motion", "schema_version": 1, "seed": 0, "graph_stats": {"frames": 100},
               "summary": {"label_fidelity": 0.9, "transitions_per_second": 0.5,
                           "velocity_jump": {"seam_over_original_median": 1.2, "seam_p95": [1.0, 2.0]}}},
    "augmg": {"kind": "vidstyle.metrics.augmg", "schema_version": 1, "seed": 0,
              "by_source": {"model": {"queries": 17, "retrieval_mpjpe_mm": 61.8, "transition_plain_mm": 169.0,
                                      "transition_augmg_mm": 84.7, "recall_at_1": 0.76, "recall_at_10": 1.0,
                                      "transition_reduction_ci95": [0.41, 0.58]}},
              "headline": {"augmg.transition_error_augmg": 84.7}},
    "reconstruct": {"kind": "vidstyle.metrics.reconstruct", "schema_version": 1, "seed": 0,
                    "runs": [{"data": "demo:p02", "source": "ps", "method": "olng", "skeleton": "library", "frames": 200,
                              "mpjpe_mm": 120.0, "mpjpe_root_relative_mm": 98.0, "pa_mpjpe_mm": 51.0,
                              "acceleration_error_mm_per_frame2": 12.0, "foot_skate_mm_per_frame": None}],
                    "params": {"k": 32}, "headline": {"reconstruct": {"mpjpe_mm": 98.0}}},
    "headline": {"kind": "vidstyle.metrics.headline", "schema_version": 1, "seed": 0,
                 "recognition": {"frame_accuracy_raw": 0.5, "video_accuracy": None},
                 "style": {"transition_mae_truth": 0.05}, "motion": {"label_fidelity": 0.8}},
    "timing": {"kind": "vidstyle.metrics.timing", "schema_version": 1, "records_dir": "out/timings", "recorded": True,
               "dvc_file": "dvc.yaml", "started": 100.0, "finished": 160.5, "run_wall_seconds": 70.0,
               "stages_wall_seconds": 60.5, "cpu_seconds": 90.25, "unreadable_records": 0,
               "stages": [{"stage": "features", "status": "ran", "invocations": 2, "failed": 0, "wall_seconds": 60.5,
                           "cpu_seconds": 90.25, "peak_rss_mb": 512.0, "commands": ["features"]},
                          {"stage": "report", "status": "skipped", "invocations": 0, "failed": 0,
                           "wall_seconds": None, "cpu_seconds": None, "peak_rss_mb": None, "commands": []}]},
}


def _run_record_doc() -> dict:
    return {"kind": "vidstyle.run_record", "schema_version": 1, "command": "demo make-dataset",
            "argv": ["demo", "make-dataset", "--out", "d"], "stage": "make_dataset", "pid": 42, "start_time": 100.0,
            "end_time": 102.5, "wall_seconds": 2.5, "cpu_seconds": 1.25, "children_cpu_seconds": 3.0,
            "peak_rss_mb": 120.5, "children_peak_rss_mb": 80.0, "exit_status": 0}


def _truth_arrays() -> dict:
    F, J = 3, 2
    rng = np.random.default_rng(0)
    return {
        "joints2d": rng.random((F, J, 2)).astype(np.float32), "joints3d": rng.random((F, J, 3)).astype(np.float32),
        "visible": np.ones((F, J), bool), "depth": rng.random((F, J)).astype(np.float32),
        "joint_names": np.array(["Hips", "Head"]), "parents": np.array([-1, 0]), "K": np.eye(3), "R": np.eye(3),
        "t": np.zeros(3), "azimuth_deg": np.float64(0), "elevation_deg": np.float64(10), "facing_deg": np.float64(0),
        "fps": np.float64(20), "size": np.array([160, 120]), "labels": np.array(["Jab", "Jab", ""]),
        "transition": np.zeros(F, bool), "source_time": np.arange(F) / 20.0, "part_owner": np.array([0, 1, 1]),
        "appearance": np.array("{}"), "background": np.array("plain"), "seed": np.int64(0),
        "noise_sigma": np.float64(2.0),
    }


# ----------------------------------------------------------------------------- structural mutations
_leaf = st.one_of(st.none(), st.booleans(), st.integers(-3, 10**6), st.sampled_from([1e308, -0.0, 0.5, 2**53 + 1.0]),
                  st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=4), st.just([]), st.just({}),
                  st.sampled_from(CLASSES + ["Kick", ""]))
_garbage = st.recursive(_leaf, lambda c: st.lists(c, max_size=3) | st.dictionaries(st.text(max_size=3), c, max_size=3),
                        max_leaves=6)
_op = st.tuples(st.sampled_from(["drop", "replace", "nan", "shorten", "lengthen", "empty", "wrap"]),
                st.integers(0, 10**6), _garbage)


def _slots(doc, out=None, depth=0):
    """(container, key) of every value in ``doc``."""
    out = [] if out is None else out
    if depth > 8:
        return out
    items = doc.items() if isinstance(doc, dict) else enumerate(doc) if isinstance(doc, list) else ()
    for k, v in items:
        out.append((doc, k))
        _slots(v, out, depth + 1)
    return out


def _mutate(doc, ops):
    doc = json.loads(json.dumps(doc))
    for op, where, garbage in ops:
        slots = _slots(doc)
        if not slots:
            return garbage
        box, key = slots[where % len(slots)]
        v = box[key]
        if op == "drop":
            if isinstance(box, dict):
                del box[key]
            else:
                box.pop(key)
        elif op == "replace":
            box[key] = garbage
        elif op == "nan":
            box[key] = float("nan") if not isinstance(v, list) else [float("nan")] + v[1:]
        elif op == "shorten" and isinstance(v, list):
            box[key] = v[:-1]
        elif op == "lengthen" and isinstance(v, list):
            box[key] = v + v[-1:] if v else [garbage]
        elif op == "empty":
            box[key] = [] if isinstance(v, list) else {} if isinstance(v, dict) else ""
        elif op == "wrap":
            box[key] = [v]
    return doc


def _check_structure(parse, write, read, doc, tmp: Path):
    try:
        obj = parse(doc, "fuzz.json")
    except FormatError as e:
        assert str(e).startswith("fuzz.json") and "\n" not in str(e), str(e)
        return
    out = tmp / "again.json"
    write(out, obj)  # what is accepted can be written ...
    again = read(out)  # ... and reads back to the same document
    assert json.loads(out.read_text()) == json.loads(json.dumps(_to_doc(again), default=_np)), "round trip"


def _np(o):
    return np.asarray(o).tolist()


def _to_doc(obj):
    if isinstance(obj, StyleRecord):
        return style_to_dict(obj)
    if hasattr(obj, "to_dict"):
        return obj.to_dict()
    if hasattr(obj, "to_document"):
        return obj.to_document()
    if isinstance(obj, dict):
        return obj
    return obj.doc


_FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                          HealthCheck.function_scoped_fixture],
                 derandomize=True)

READERS = {
    "labels": (parse_labels, write_labels, read_labels, _labels_doc),
    "recognised": (parse_recognised, write_recognised, read_recognised, _recognised_doc),
    "dataset": (parse_dataset, write_dataset, read_dataset, _dataset_doc),
    "sequence": (parse_sequence, write_sequence, read_sequence, _sequence_doc),
    "walk": (parse_walk_labels, write_walk_labels, read_walk_labels, _walk_doc),
    "library": (parse_library, write_library, read_library, _library_doc),
    "run_record": (parse_run_record, write_run_record, read_run_record, _run_record_doc),
    "reconstruction": (parse_reconstruction, write_reconstruction, read_reconstruction, _reconstruction_doc),
    "poses": (parse_poses, write_poses, read_poses, _poses_doc),
    **{f"metrics_{k}": (parse_metrics, write_metrics, read_metrics, (lambda d=d: d)) for k, d in METRICS.items()},
}


@pytest.mark.parametrize("name", list(READERS))
def test_valid_documents_are_accepted_and_round_trip(name, tmp_path):
    parse, write, read, make = READERS[name]
    _check_structure(parse, write, read, make(), tmp_path)
    parse(make(), "ok.json")  # (and it did parse)


@pytest.mark.parametrize("name", list(READERS))
@_FUZZ
@given(ops=st.lists(_op, min_size=1, max_size=3))
def test_structure_mutations_raise_only_formaterror(name, ops, tmp_path):
    parse, write, read, make = READERS[name]
    _check_structure(parse, write, read, _mutate(make(), ops), tmp_path)


def _style_parse(doc, path):
    from vidstyle.style.artifact import Style

    return Style.from_dict(doc, path)


def _style_write(path, style):
    style.save(path)


def _style_read(path):
    from vidstyle.style.artifact import Style

    return Style.load(path)


# the owner's record functions, and the Style built from the record (whose parameter ranges the domain checks)
STYLE_LEVELS = {"record": (parse_style, write_style, read_style), "style": (_style_parse, _style_write, _style_read)}


@pytest.mark.parametrize("level", list(STYLE_LEVELS))
@_FUZZ
@given(ops=st.lists(_op, min_size=1, max_size=3))
def test_style_structure_mutations_raise_only_formaterror(style_doc, level, ops, tmp_path):
    _check_structure(*STYLE_LEVELS[level], _mutate(style_doc, ops), tmp_path)


@pytest.mark.parametrize("level", list(STYLE_LEVELS))
def test_style_document_round_trips(style_doc, level, tmp_path):
    _check_structure(*STYLE_LEVELS[level], style_doc, tmp_path)
    assert isinstance(parse_style(style_doc), StyleRecord)


def test_style_record_round_trip_rebuilds_the_same_style(style_doc, tmp_path):
    """Style -> record -> file -> record -> Style keeps every model array and the generated sequences."""
    from vidstyle.style.artifact import Style

    style = Style.from_dict(style_doc, "s.json")
    p = tmp_path / "s.json"
    write_style(p, style.to_record())
    back = Style.from_record(read_style(p), p)
    assert back.params == style.params and back.actions == style.actions
    for m in ("model_a", "model_b", "bigram"):
        for attr in ("start_", "transition_"):
            np.testing.assert_array_equal(getattr(getattr(back, m), attr), getattr(getattr(style, m), attr))
    np.testing.assert_array_equal(back.durations.mu_, style.durations.mu_)
    assert json.dumps(back.to_dict(), default=_np) == json.dumps(style.to_dict(), default=_np)
    for model in ("a", "b", "bigram"):
        assert back.generate(30, seed=4, model=model) == style.generate(30, seed=4, model=model)


def test_style_parameter_out_of_range_is_a_format_error_naming_params(style_doc):
    from vidstyle.style.artifact import Style

    doc = json.loads(json.dumps(style_doc))
    doc["params"]["alpha"] = -1.0
    assert parse_style(doc, "s.json").params["alpha"] == -1.0  # the owner checks types; the range is the domain's
    with pytest.raises(FormatError, match=r"^s\.json: params") as e:
        Style.from_dict(doc, "s.json")
    assert "alpha" in str(e.value)


# ----------------------------------------------------------------------------- byte mutations
_bytes_op = st.one_of(
    st.tuples(st.just("delete"), st.integers(0, 10**6), st.integers(1, 30)),
    st.tuples(st.just("insert"), st.integers(0, 10**6), st.binary(max_size=8)),
    st.tuples(st.just("truncate"), st.integers(0, 10**6), st.just(b"")),
    st.tuples(st.just("flip"), st.integers(0, 10**6), st.integers(0, 255)),
    st.tuples(st.just("text"), st.integers(0, 10**6), st.sampled_from([b"NaN", b"-Infinity", b"[]", b"{", b'"', b"\xff\xfe",
                                                                      b"\x00", b"1e999", b",", b"null"])),
)


def _apply_bytes(data: bytes, ops) -> bytes:
    for kind, a, b in ops:
        a %= max(len(data), 1)
        if kind == "delete":
            data = data[:a] + data[a + b:]
        elif kind in ("insert", "text"):
            data = data[:a] + b + data[a:]
        elif kind == "truncate":
            data = data[:a]
        elif data:
            data = data[:a] + bytes([data[a] ^ (b or 1)]) + data[a + 1:]
    return data


def _check_bytes(read, data: bytes, tmp: Path):
    path = tmp / "fuzz.json"
    path.write_bytes(data)
    try:
        read(path)
    except FormatError as e:
        assert str(e).startswith(str(path)) and "\n" not in str(e), str(e)


@pytest.mark.parametrize("name", list(READERS))
@_FUZZ
@given(ops=st.lists(_bytes_op, min_size=1, max_size=4))
def test_byte_mutations_raise_only_formaterror(name, ops, tmp_path):
    _, _, read, make = READERS[name]
    data = json.dumps(make(), indent=1).encode()
    _check_bytes(read, _apply_bytes(data, ops), tmp_path)


@_FUZZ
@given(ops=st.lists(_bytes_op, min_size=1, max_size=4))
def test_style_byte_mutations_raise_only_formaterror(style_doc, ops, tmp_path):
    _check_bytes(read_style, _apply_bytes(json.dumps(style_doc).encode(), ops), tmp_path)


# ----------------------------------------------------------------------------- the render-truth .npz
def _npz_bytes(arrays: dict) -> bytes:
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    return buf.getvalue()


def test_truth_round_trip_and_header(tmp_path):
    arrays = _truth_arrays()
    write_truth(tmp_path / "a.truth.npz", arrays)
    t = read_truth(tmp_path / "a.mp4")  # the video's path finds its sidecar
    assert t.n_frames == 3 and list(t.labels) == ["Jab", "Jab", ""]
    for k, v in arrays.items():
        assert np.array_equal(t.to_arrays()[k], v), k
    with np.load(tmp_path / "a.truth.npz") as z:
        assert str(z["kind"]) == "vidstyle.render_truth" and int(z["schema_version"]) == 2
    parse_truth(arrays)  # schema 1 (no header) still loads


_array_op = st.tuples(st.sampled_from(["drop", "nan", "reshape", "retype", "shorten", "scalar"]),
                      st.integers(0, 10**6))


@_FUZZ
@given(ops=st.lists(_array_op, min_size=1, max_size=3))
def test_truth_array_mutations_raise_only_formaterror(ops, tmp_path):
    arrays = _truth_arrays()
    for op, where in ops:
        keys = sorted(arrays)
        if not keys:
            break
        k = keys[where % len(keys)]
        a = arrays[k]
        if op == "drop":
            del arrays[k]
        elif op == "nan" and a.dtype.kind == "f":
            a = a.copy()
            a.reshape(-1)[where % max(a.size, 1)] = np.nan
            arrays[k] = a
        elif op == "reshape":
            arrays[k] = a.reshape(-1)[: max(a.size - 1, 0)] if a.ndim else np.array([a, a])
        elif op == "retype":
            arrays[k] = a.astype(str) if a.dtype.kind != "U" else np.zeros(a.shape)
        elif op == "shorten" and a.ndim:
            arrays[k] = a[:-1]
        elif op == "scalar":
            arrays[k] = np.float64(where)
    try:
        parse_truth(arrays, "fuzz.truth.npz")
    except FormatError as e:
        assert str(e).startswith("fuzz.truth.npz") and "\n" not in str(e)
        return
    write_truth(tmp_path / "ok.truth.npz", arrays)
    read_truth(tmp_path / "ok.truth.npz")


@_FUZZ
@given(ops=st.lists(_bytes_op, min_size=1, max_size=3))
def test_truth_byte_mutations_raise_only_formaterror(ops, tmp_path):
    path = tmp_path / "x.truth.npz"
    path.write_bytes(_apply_bytes(_npz_bytes(_truth_arrays()), ops))
    try:
        read_truth(path)
    except FormatError as e:
        assert str(e).startswith(str(path)) and "\n" not in str(e)


def test_truth_pickled_member_is_refused(tmp_path):
    path = tmp_path / "p.truth.npz"
    arrays = {**_truth_arrays(), "labels": np.array(["a", None, "b"], dtype=object)}
    np.savez(path, **arrays)
    with pytest.raises(FormatError, match="not a readable .npz"):
        read_truth(path)
    with zipfile.ZipFile(path, "a") as z:  # also a zip with an extra non-npy member
        z.writestr("junk.txt", "x")
    with pytest.raises(FormatError):
        read_truth(path)


def test_nan_is_never_written(tmp_path):
    doc = _labels_doc()
    doc["confidence"][0] = math.nan
    with pytest.raises(FormatError, match=r"confidence: contains a non-finite value"):
        write_labels(tmp_path / "l.json", doc)
    assert not (tmp_path / "l.json").exists()
