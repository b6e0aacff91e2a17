"""The motion graph file (vidstyle.formats.motiongraph): v2 round trip with segments and enhancement
edges, v1 files, and bad files - truncated, corrupted, structurally wrong - raise FormatError only."""

from __future__ import annotations

import io
import json
import zipfile

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vidstyle.cli import main
from vidstyle.formats import FormatError
from vidstyle.formats.motiongraph import MotionGraphRecord, read_graph, write_graph
from vidstyle.motiongraph import EdgeKind, MotionGraph, Step, plan_walk

from test_motiongraph_open import _segment_from, _tiny_graph


@pytest.fixture(scope="module")
def graph():
    g = _tiny_graph()
    k = g.window
    sid = g.add_segment(*_segment_from(g, 6, bend=0.5), source="walk.bvh@0.2s", label="crouch")
    # a second, anchored segment with a hold (its node windows either side of the centre)
    f = np.arange(3, 3 + 2 * k + 3)
    g.add_segment(g.rotations_[f], g.root_positions_[f], centre=k + 1, anchors=(k, k + 2), hold=0.25,
                  source="walk.bvh@0.1s", label="hop")
    kept = np.flatnonzero(g.scc_)
    src = next(f for f in kept if g.frame_clip_[f + k] == g.frame_clip_[f])
    dst = next(f for f in kept[::-1] if g.frame_clip_[f - k + 1] == g.frame_clip_[f])
    g.add_edges(src, dst, EdgeKind.ENHANCEMENT, segment=sid)
    g.prune()
    return g


@pytest.fixture(scope="module")
def good_bytes(graph, tmp_path_factory):
    p = tmp_path_factory.mktemp("g") / "g.npz"
    write_graph(p, graph.to_record())
    return p.read_bytes()


def _arrays(raw: bytes) -> dict:
    with np.load(io.BytesIO(raw), allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _npz(path, arrays: dict) -> None:
    np.savez(path, **arrays)


def test_v2_round_trip_keeps_edges_and_segments(graph, tmp_path):
    p = tmp_path / "g.npz"
    graph.save(p)
    g = MotionGraph.load(p)
    for name in ("edge_src_", "edge_dst_", "edge_kind_", "edge_segment_", "edge_in_scc_", "scc_", "labels_", "frame_clip_"):
        np.testing.assert_array_equal(getattr(g, name), getattr(graph, name))
    for name in ("edge_cost_", "edge_align_", "root_positions_"):
        np.testing.assert_allclose(getattr(g, name), getattr(graph, name))
    np.testing.assert_allclose(g.edge_align_segment_, graph.edge_align_segment_)  # NaN where not enhancement
    assert len(g.segments_) == 2
    s0, s1 = g.segments_[0], graph.segments_[0]
    assert (s0.centre, s0.source, s0.label, s0.anchors, s0.hold) == (s1.centre, "walk.bvh@0.2s", "crouch", None, 0.0)
    np.testing.assert_allclose(s0.rotations, s1.rotations)
    k = graph.window
    assert (g.segments_[1].anchors, g.segments_[1].hold) == ((k, k + 2), 0.25)
    steps = [Step("walk", 5), Step("run", 4), Step("walk", 4)]
    a, b = plan_walk(graph, steps, strict=False), plan_walk(g, steps, strict=False)
    assert a.cost == pytest.approx(b.cost, abs=1e-6) and a.transitions_used == b.transitions_used


def test_record_round_trip_is_byte_identical_and_field_exact(graph, good_bytes, tmp_path):
    """The owner reads back exactly the record it wrote, writing that record again gives the same bytes,
    and the graph rebuilt from the record gives the same record (MotionGraph.from_record / to_record)."""
    p = tmp_path / "g.npz"
    p.write_bytes(good_bytes)
    rec = read_graph(p)
    assert isinstance(rec, MotionGraphRecord)
    assert rec.params == graph.get_params() and rec.threshold_used == graph.threshold_ and rec.stats == graph.stats_
    assert (rec.window, rec.fps, rec.label_names) == (graph.window, graph.fps, graph.label_names_)
    np.testing.assert_array_equal(rec.edge_in_scc, graph.edge_in_scc_)
    again = tmp_path / "again.npz"
    write_graph(again, rec)
    assert _arrays(again.read_bytes()).keys() == _arrays(good_bytes).keys()
    for key, value in _arrays(good_bytes).items():
        np.testing.assert_array_equal(_arrays(again.read_bytes())[key], value, err_msg=key)
    rebuilt = MotionGraph.from_record(rec).to_record()
    for name, value in vars(rec).items():
        other = getattr(rebuilt, name)
        if isinstance(value, dict) or name == "channels":
            assert other == value, name
        else:
            np.testing.assert_array_equal(np.asarray(other), np.asarray(value), err_msg=name)


def test_an_invalid_record_never_reaches_disk(graph, tmp_path):
    rec = graph.to_record()
    rec.edge_dst = np.asarray(rec.edge_dst).copy()
    rec.edge_dst[0] = 10**6
    p = tmp_path / "bad.npz"
    with pytest.raises(ValueError, match="edge_dst"):
        write_graph(p, rec)
    assert not p.exists() and not list(tmp_path.iterdir())


def test_files_without_segment_anchors_or_holds_load_with_none(good_bytes, tmp_path):
    a = _arrays(good_bytes)
    del a["segment_anchor"], a["segment_hold"]
    p = tmp_path / "older.npz"
    _npz(p, a)
    g = MotionGraph.load(p)
    assert [(s.anchors, s.hold) for s in g.segments_] == [(None, 0.0), (None, 0.0)]


@pytest.mark.parametrize("key,value,problem", [("segment_anchor", [[-1, -1], [0, 5]], "anchor pair"),
                                               ("segment_anchor", [[-1, -1], [5, 3]], "anchor pair"),
                                               ("segment_hold", [0.0, 1.0], "hold outside"),
                                               ("segment_hold", [0.0, np.nan], "NaN")])
def test_bad_segment_anchors_and_holds_are_format_errors(good_bytes, tmp_path, key, value, problem):
    a = _arrays(good_bytes)
    a[key] = np.array(value)
    p = tmp_path / "bad.npz"
    _npz(p, a)
    with pytest.raises(FormatError, match=problem) as e:
        read_graph(p)
    assert str(p) in str(e.value) and key in str(e.value)


def _as_v1(arrays: dict) -> dict:
    """The v1 layout (what MotionGraph.save wrote before schema 2): parallel trans_* arrays, no edge table."""
    out = {k: v for k, v in arrays.items() if not k.startswith(("edge_", "segment_")) and k not in ("kind", "schema_version")}
    blend = arrays["edge_kind"] == EdgeKind.BLEND
    out["schema"] = np.array("vidstyle.motiongraph/1")
    out["trans_from"] = arrays["edge_src"][blend] + 1
    out["trans_to"] = arrays["edge_dst"][blend]
    out["trans_cost"] = arrays["edge_cost"][blend]
    out["trans_theta"], out["trans_x0"], out["trans_z0"] = arrays["edge_align"][blend].T
    out["trans_in_scc"] = arrays["edge_in_scc"][blend]
    return out


def test_v1_files_still_load(graph, good_bytes, tmp_path):
    p = tmp_path / "v1.npz"
    _npz(p, _as_v1(_arrays(good_bytes)))
    g = MotionGraph.load(p)
    plain = graph.edges(kind=EdgeKind.ENHANCEMENT)
    keep = np.setdiff1d(np.arange(graph.n_edges), plain)
    np.testing.assert_array_equal(g.edge_src_, graph.edge_src_[keep])
    np.testing.assert_array_equal(g.edge_dst_, graph.edge_dst_[keep])
    np.testing.assert_array_equal(g.edge_kind_, graph.edge_kind_[keep])
    np.testing.assert_allclose(g.edge_cost_, graph.edge_cost_[keep])
    assert g.segments_ == [] and (g.edge_segment_ == -1).all()


@pytest.mark.parametrize("damage", ["truncated", "garbage", "missing key", "wrong shape", "nan", "index", "empty",
                                    "directory", "kind"])
def test_bad_files_raise_format_error_naming_the_file(good_bytes, tmp_path, damage):
    p = tmp_path / "bad.npz"
    a = _arrays(good_bytes)
    if damage == "truncated":
        p.write_bytes(good_bytes[: len(good_bytes) // 2])
    elif damage == "garbage":
        p.write_bytes(b"PK\x03\x04" + bytes(range(256)) * 4)
    elif damage == "empty":
        p.write_bytes(b"")
    elif damage == "directory":
        p.mkdir()
    else:
        if damage == "missing key":
            del a["edge_cost"]
        elif damage == "wrong shape":
            a["rotations"] = a["rotations"][:, :, :3]
        elif damage == "nan":
            a["root_positions"] = a["root_positions"].copy()
            a["root_positions"][3, 1] = np.nan
        elif damage == "index":
            a["edge_dst"] = a["edge_dst"].copy()
            a["edge_dst"][0] = 10**6
        elif damage == "kind":
            a["kind"] = np.array("vidstyle.labels")
        _npz(p, a)
    with pytest.raises(FormatError) as e:
        read_graph(p)
    assert str(p) in str(e.value)


def test_synthesize_on_a_bad_graph_prints_one_line_and_exits_2(good_bytes, tmp_path, capsys):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(good_bytes[:-100])
    seq = tmp_path / "seq.json"
    seq.write_text(json.dumps(["walk", "run"]))
    out = tmp_path / "o.bvh"
    assert main(["synthesize", "--graph", str(bad), "--sequence", str(seq), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(bad) in err
    assert not out.exists() and not list(tmp_path.glob("o*"))


# ------------------------------------------------------------------------------------------ fuzz
_SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                             HealthCheck.too_slow])


def _read_only_format_errors(path) -> None:
    try:
        MotionGraph.load(path)  # the owner's reader, then the graph built from its record
    except FormatError as e:
        assert str(path) in str(e)


@_SETTINGS
@given(data=st.data())
def test_fuzz_bytes(good_bytes, tmp_path_factory, data):
    raw = bytearray(good_bytes)
    op = data.draw(st.sampled_from(["flip", "truncate", "splice"]))
    if op == "flip":
        for _ in range(data.draw(st.integers(1, 8))):
            i = data.draw(st.integers(0, len(raw) - 1))
            raw[i] = data.draw(st.integers(0, 255))
    elif op == "truncate":
        raw = raw[: data.draw(st.integers(0, len(raw) - 1))]
    else:
        i = data.draw(st.integers(0, len(raw)))
        raw[i:i] = data.draw(st.binary(min_size=1, max_size=64))
    p = tmp_path_factory.mktemp("fz") / "g.npz"
    p.write_bytes(bytes(raw))
    _read_only_format_errors(p)



@_SETTINGS
@given(data=st.data())
def test_fuzz_structure(good_bytes, tmp_path_factory, data):
    a = _arrays(good_bytes)
    if data.draw(st.booleans()):
        a = _as_v1(a)
    keys = sorted(a)
    for _ in range(data.draw(st.integers(1, 3))):
        key = data.draw(st.sampled_from(keys))
        op = data.draw(st.sampled_from(["drop", "scalar", "string", "shape", "nan", "negate", "shuffle", "float", "empty"]))
        v = a.get(key)
        if v is None:
            continue
        if op == "drop":
            del a[key]
            keys.remove(key)
        elif op == "scalar":
            a[key] = np.array(data.draw(st.integers(-5, 10**9)))
        elif op == "string":
            a[key] = np.array(data.draw(st.text(max_size=20)))
        elif op == "shape" and v.size:
            a[key] = v.reshape(-1)[:-1]
        elif op == "nan" and v.size and v.dtype.kind in "iufb":
            w = v.astype(np.float64).copy()
            w.reshape(-1)[data.draw(st.integers(0, w.size - 1))] = np.nan
            a[key] = w
        elif op == "negate" and v.dtype.kind in "iuf":
            a[key] = -v - 1
        elif op == "shuffle" and v.ndim and len(v) > 1:
            a[key] = v[::-1].copy()
        elif op == "float" and v.dtype.kind in "iub":
            a[key] = v.astype(np.float64) + 0.5
        elif op == "empty":
            a[key] = v[:0] if v.ndim else v
    p = tmp_path_factory.mktemp("fz") / "g.npz"
    _npz(p, a)
    _read_only_format_errors(p)


def test_not_a_zip_member_layout(tmp_path):
    """A zip that holds something other than .npy members."""
    p = tmp_path / "z.npz"
    with zipfile.ZipFile(p, "w") as z:
        z.writestr("rotations.npy", b"\x93NUMPY garbage")
    with pytest.raises(FormatError, match="z.npz"):
        read_graph(p)
