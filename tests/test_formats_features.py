"""vidstyle.formats.features: the one owner of the features file (round trip, validation, schema 1,
fuzzing: nothing but FormatError escapes the reader)."""

from __future__ import annotations

import io
import zipfile

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vidstyle.formats import FormatError
from vidstyle.formats.features import Features, read_features, write_features


def sample(rng, n=12, variant="scovanner2007") -> Features:
    frames = np.sort(rng.integers(0, 8, n))
    pts = np.column_stack([frames, rng.integers(0, 60, n), rng.integers(0, 80, n)]).astype(np.int32)
    desc = rng.integers(0, 256, (n, 640)).astype(np.uint8) if variant == "scovanner2007" else \
        rng.random((n, 256)).astype(np.float32)
    return Features(descriptors=desc, frame_index=pts[:, 0], n_frames=8, points=pts, height=60, width=80,
                    fps=20.0, variant=variant, params={"variant": variant, "salient": {"n_points": 10}},
                    video="v.mp4", source_index=np.arange(0, 24, 3), source_frames=24, source_fps=60.0,
                    source_width=160, source_height=120)


def arrays_of(path) -> dict[str, np.ndarray]:
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


@pytest.mark.parametrize("variant", ["scovanner2007", "thesis"])
def test_round_trip(tmp_path, rng, variant):
    f = sample(rng, variant=variant)
    write_features(tmp_path / "f.npz", f)
    g = read_features(tmp_path / "f.npz")
    for k in ("points", "descriptors", "frame_index", "source_index"):
        assert np.array_equal(getattr(f, k), getattr(g, k)) and getattr(f, k).dtype == getattr(g, k).dtype
    for k in ("n_frames", "height", "width", "fps", "variant", "params", "video", "source_frames",
              "source_fps", "source_width", "source_height"):
        assert getattr(f, k) == getattr(g, k), k
    assert g.schema_version == 2 and g.path == str(tmp_path / "f.npz")
    assert g.source_frame(np.array([0, 7])).tolist() == [0, 21]
    z = arrays_of(tmp_path / "f.npz")
    assert str(z["kind"]) == "vidstyle.features" and int(z["schema_version"]) == 2


def test_schema_1_still_loads(tmp_path, rng):
    f = sample(rng)
    old = {k: v for k, v in f.to_arrays().items() if not k.startswith("source") and k not in ("kind", "schema_version")}
    np.savez(tmp_path / "old.npz", **old)
    g = read_features(tmp_path / "old.npz")
    assert g.schema_version == 1 and np.array_equal(g.source_index, np.arange(8))
    assert (g.source_frames, g.source_fps, g.source_width, g.source_height) == (8, 20.0, 80, 60)
    np.savez(tmp_path / "min.npz", descriptors=np.ones((3, 4), np.float32), frame_index=np.array([0, 1, 1]),
             n_frames=2)
    assert read_features(tmp_path / "min.npz").points is None


@pytest.mark.parametrize(
    "change, field",
    [
        (lambda z: z.pop("descriptors"), "descriptors: missing"),
        (lambda z: z.pop("source_index"), "source_index: missing"),
        (lambda z: z.__setitem__("descriptors", z["descriptors"].astype(np.float64)), "descriptors: must be uint8 or float32"),
        (lambda z: z.__setitem__("points", z["points"].astype(np.float32)), "points: must be an (n, 3) integer"),
        (lambda z: z.__setitem__("frame_index", z["frame_index"] + 100), "frame_index"),
        (lambda z: z.__setitem__("source_index", z["source_index"][::-1].copy()), "source_index: must be non-negative and increasing"),
        (lambda z: z.__setitem__("source_index", z["source_index"] + 100), "source_index: frame"),
        (lambda z: z.__setitem__("n_frames", np.array("eight")), "n_frames: must be an integer"),
        (lambda z: z.__setitem__("kind", np.array("vidstyle.labels")), "kind: expected"),
        (lambda z: z.__setitem__("schema_version", np.int64(9)), "schema_version: unsupported"),
        (lambda z: z.__setitem__("params", np.array("{not json")), "params: not JSON"),
        (lambda z: z.__setitem__("fps", np.float64("nan")), "fps: must be finite"),
        (lambda z: z.__setitem__("points", z["points"] + np.array([0, 1000, 0], np.int32)), "points: row"),
    ],
)
def test_each_bad_field_is_named(tmp_path, rng, change, field):
    write_features(tmp_path / "f.npz", sample(rng, variant="thesis"))
    z = arrays_of(tmp_path / "f.npz")
    change(z)
    np.savez(tmp_path / "bad.npz", **z)
    with pytest.raises(FormatError, match=f"bad.npz: {field}".replace("(", r"\(").replace(")", r"\)")):
        read_features(tmp_path / "bad.npz")


def test_nan_descriptors_are_an_error_naming_the_file(tmp_path, rng):
    f = sample(rng, variant="thesis")
    z = f.to_arrays()
    z["descriptors"][3, 5] = np.nan
    np.savez(tmp_path / "nan.npz", **z)
    with pytest.raises(FormatError, match=r"nan.npz: descriptors: 1 row\(s\) hold NaN"):
        read_features(tmp_path / "nan.npz")
    f.descriptors[0, 0] = np.inf
    with pytest.raises(FormatError, match="descriptors"):
        write_features(tmp_path / "w.npz", f)
    assert not (tmp_path / "w.npz").exists()


def test_not_a_file(tmp_path):
    with pytest.raises(FormatError, match="not found"):
        read_features(tmp_path / "none.npz")
    (tmp_path / "d.npz").mkdir()
    with pytest.raises(FormatError, match="d.npz: is a directory"):
        read_features(tmp_path / "d.npz")
    np.save(tmp_path / "single.npy", np.zeros(3))
    with pytest.raises(FormatError, match="single"):
        read_features(tmp_path / "single.npy")


def _valid_bytes() -> bytes:
    rng = np.random.default_rng(0)
    buf = io.BytesIO()
    np.savez(buf, **sample(rng, n=4, variant="thesis").to_arrays())
    return buf.getvalue()


VALID = _valid_bytes()


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.integers(0, len(VALID) - 1), st.integers(0, 255)), min_size=1, max_size=8),
       st.integers(0, len(VALID)))
def test_fuzz_bytes(tmp_path, edits, cut):
    data = bytearray(VALID)
    for pos, val in edits:
        data[pos] = val
    p = tmp_path / "fuzz.npz"
    p.write_bytes(bytes(data[:cut] if cut < len(VALID) and cut % 3 == 0 else data))
    try:
        f = read_features(p)
    except FormatError as e:
        assert "fuzz.npz" in str(e)
    else:
        assert np.isfinite(f.descriptors).all() and f.frame_index.max() < f.n_frames


KEYS = sorted(np.load(io.BytesIO(VALID)).files)
VALUES = st.one_of(
    st.just(np.array(np.nan)), st.just(np.array("text")), st.just(np.zeros((2, 2, 2))), st.just(np.array(-1)),
    st.just(np.zeros(0)), st.just(np.full((4, 256), np.nan, np.float32)), st.just(np.array([1.5, 2.5])),
    st.just(np.ones((4, 3), bool)), st.just(np.array(10**12)), st.just(np.array("[]")), st.just(np.array('{"a": NaN}')),
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.sampled_from(KEYS), st.one_of(st.none(), VALUES)), min_size=1, max_size=4))
def test_fuzz_structure(tmp_path, changes):
    z = dict(np.load(io.BytesIO(VALID)))
    for key, value in changes:
        if value is None:
            z.pop(key, None)
        else:
            z[key] = value
    p = tmp_path / "s.npz"
    np.savez(p, **z)
    try:
        read_features(p)
    except FormatError as e:
        assert "s.npz" in str(e)


def test_zip_members_damaged(tmp_path):
    p = tmp_path / "z.npz"
    with zipfile.ZipFile(p, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("descriptors.npy", b"\x93NUMPY garbage")
    with pytest.raises(FormatError, match="z.npz"):
        read_features(p)


def test_directory_params_reads_the_recorded_extraction(tmp_path, rng):
    from dataclasses import replace

    from vidstyle.formats.features import directory_params

    f = sample(rng)
    write_features(tmp_path / "b.npz", f)
    write_features(tmp_path / "a.npz", replace(f, params={"variant": "thesis", "salient": {"n_points": 20}}))
    assert directory_params(tmp_path) == {"variant": "thesis", "salient": {"n_points": 20}}  # the first file
    with pytest.raises(FormatError, match="no features files"):
        directory_params(tmp_path / "missing")
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "x.npz").write_bytes(b"not a zip")
    with pytest.raises(FormatError, match="not a readable"):
        directory_params(tmp_path / "bad")
