"""BVH reader/writer: channel orders against scipy, layout variants, round trips, malformed input."""

from __future__ import annotations

import itertools
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from bvh_samples import TWO_JOINT
from vidstyle.mocap import BVHError, Motion, format_bvh, global_positions, parse_bvh, read_bvh, write_bvh

ORDERS = ["".join(p) for p in itertools.permutations("XYZ")]


def _chain_bvh(orders: list[str], values: np.ndarray, frame_time: float = 0.05, root_pos: bool = True) -> str:
    """A chain of len(orders) joints, joint k rotating in orders[k]; values (F, C) in file layout."""
    lines = ["HIERARCHY"]
    for k, order in enumerate(orders):
        ind = "  " * k
        lines.append(f"{ind}{'ROOT' if k == 0 else 'JOINT'} J{k}")
        lines.append(f"{ind}{{")
        lines.append(f"{ind}  OFFSET {0.5 * k} {1.0 + k} {-0.25 * k}")
        chans = [f"{a}rotation" for a in order]
        if k == 0 and root_pos:
            chans = ["Xposition", "Yposition", "Zposition"] + chans
        lines.append(f"{ind}  CHANNELS {len(chans)} {' '.join(chans)}")
    lines.append("  " * len(orders) + "End Site")
    lines.append("  " * len(orders) + "{ OFFSET 0 1 0 }")
    for k in reversed(range(len(orders))):
        lines.append("  " * k + "}")
    lines += ["MOTION", f"Frames: {len(values)}", f"Frame Time: {frame_time}"]
    lines += [" ".join(f"{v:.9f}" for v in row) for row in values]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("order", ORDERS)
def test_each_rotation_order_matches_scipy(order, rng):
    angles = rng.uniform(-180, 180, size=(20, 3))
    values = np.concatenate([rng.normal(size=(20, 3)), angles], axis=1)
    motion = parse_bvh(_chain_bvh([order], values))
    expected = Rotation.from_euler(order, angles, degrees=True)  # upper case = intrinsic, as BVH
    got = Rotation.from_quat(motion.rotations[:, 0])
    assert np.allclose((expected.inv() * got).magnitude(), 0, atol=1e-9)
    assert np.allclose(motion.root_positions, values[:, :3])


def test_mixed_orders_in_one_file_and_fk_against_scipy_composition(rng):
    orders = ORDERS  # six joints, one of each order
    angles = rng.uniform(-170, 170, size=(7, 6, 3))
    values = np.concatenate([rng.normal(size=(7, 3)), angles.reshape(7, -1)], axis=1)
    motion = parse_bvh(_chain_bvh(orders, values))
    pos = global_positions(motion)
    # independent composition with scipy Rotation objects
    for f in range(7):
        R = Rotation.identity()
        p = values[f, :3].copy()
        for k, order in enumerate(orders):
            if k > 0:
                p = p + R.apply([0.5 * k, 1.0 + k, -0.25 * k])
            R = R * Rotation.from_euler(order, angles[f, k], degrees=True)
            assert np.allclose(pos[f, k], p, atol=1e-9)


def test_hand_written_sample_structure_and_end_sites():
    m = parse_bvh(TWO_JOINT)
    assert m.skeleton.names == ["Hips", "Chest", "LeftLeg", "RightLeg"]
    assert list(m.skeleton.parents) == [-1, 0, 0, 0]
    assert sorted(m.skeleton.end_sites) == [1, 2, 3]
    assert np.allclose(m.skeleton.end_sites[2], [0, -3, 0])
    assert m.n_frames == 3 and m.fps == 30.0
    assert m.skeleton.channels[2] == ("Xrotation", "Yrotation", "Zrotation")


def test_frame_rates_other_than_integer():
    m = parse_bvh(_chain_bvh(["ZYX"], np.zeros((2, 6)), frame_time=0.0123))
    assert m.fps == pytest.approx(1 / 0.0123)
    m = parse_bvh(_chain_bvh(["ZYX"], np.zeros((2, 6)), frame_time=0.0416667))
    assert m.fps == 24.0


def test_whitespace_variants_parse_identically():
    base = parse_bvh(TWO_JOINT)
    variants = [
        TWO_JOINT.replace("\n", "\r\n"),
        TWO_JOINT.replace("\n", "\r"),
        TWO_JOINT.replace("  ", "\t"),
        re.sub(r" ", "   \t ", TWO_JOINT.replace("Frame Time:", "FRAMETIME_").replace("End Site", "ENDSITE_"))
        .replace("FRAMETIME_", "Frame Time:")
        .replace("ENDSITE_", "End Site"),
        "\ufeff" + TWO_JOINT + "\n\n\n",
        TWO_JOINT.replace("{\n    OFFSET 0 1 0\n    }", "{ OFFSET 0 1 0 }"),
    ]
    for text in variants:
        m = parse_bvh(text)
        assert m.skeleton.names == base.skeleton.names
        assert np.allclose(m.rotations, base.rotations) and np.allclose(m.translations, base.translations)


def test_six_channel_non_root_joint_replaces_offset():
    text = TWO_JOINT.replace(
        "OFFSET 0 2 0\n    CHANNELS 3 Zrotation Yrotation Xrotation",
        "OFFSET 0 2 0\n    CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation",
    )
    lines = text.split("\n")
    start = lines.index("Frame Time: 0.033333") + 1
    for i in range(start, start + 3):
        v = lines[i].split()
        lines[i] = " ".join(v[:6] + ["0.5", "3", "0"] + v[6:])
    m = parse_bvh("\n".join(lines))
    assert np.allclose(m.translations[:, 1], [0.5, 3, 0])
    assert np.allclose(global_positions(m)[0, 1], [0.5, 13, 0])


def test_round_trip_read_write_read(tmp_path, rng):
    values = np.concatenate([rng.normal(size=(30, 3)) * 10, rng.uniform(-179, 179, size=(30, 18))], axis=1)
    m1 = parse_bvh(_chain_bvh(ORDERS, values))
    path = tmp_path / "rt.bvh"
    write_bvh(m1, path)
    m2 = read_bvh(path)
    assert m2.skeleton.names == m1.skeleton.names and m2.skeleton.channels == m1.skeleton.channels
    assert np.allclose(m2.skeleton.offsets, m1.skeleton.offsets, atol=1e-6)
    assert m2.fps == pytest.approx(m1.fps, rel=1e-6)
    dots = np.abs(np.sum(m1.rotations * m2.rotations, axis=-1))  # q and -q are the same rotation
    assert np.all(1 - dots < 1e-6)
    assert np.allclose(global_positions(m1), global_positions(m2), atol=1e-6)
    # and the text is stable: write -> read -> write gives the same bytes
    assert format_bvh(read_bvh(path)) == path.read_text()


def test_write_is_atomic_on_failure(tmp_path, monkeypatch):
    m = parse_bvh(TWO_JOINT)
    out = tmp_path / "out.bvh"
    import vidstyle.mocap.bvh as bvh_mod

    def boom(*a, **k):
        raise RuntimeError("disk full")

    monkeypatch.setattr(bvh_mod, "format_bvh", boom)
    with pytest.raises(RuntimeError):
        bvh_mod.write_bvh(m, out)
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------ malformed input
def _motion_lines(text):
    lines = text.split("\n")
    return lines, lines.index("MOTION")


# case -> (mutation, message pattern, text of the line the error must point at, or None)
MALFORMED = {
    "truncated": (lambda t: t.rsplit("\n", 2)[0] + "\n", r"truncated MOTION block: 2 of 3 frames", None),
    "wrong_count": (lambda t: t.replace("1 10 0 90 0 0 0 0 0 45", "1 10 0 90 0 0 0 0 45"), r"frame 1 has 14 values, expected 15", "1 10 0 90"),
    "unknown_channel": (lambda t: t.replace("CHANNELS 3 Xrotation Yrotation Zrotation", "CHANNELS 3 Xrotation Yrotation Wrotation", 1), r"unknown channel name 'Wrotation'", "Wrotation"),
    "non_numeric": (lambda t: t.replace("2 10 0 0 90", "2 10 zero 0 90"), r"'zero' is not a number", "2 10 zero"),
    "missing_frame_time": (lambda t: t.replace("Frame Time: 0.033333\n", ""), r"missing 'Frame Time:'", "0 10 0 0"),
    "unbalanced_open": (lambda t: t.replace("  JOINT RightLeg\n  {", "  JOINT RightLeg\n  {\n  {{"), r"unexpected '\{'", "  {{"),
    "unbalanced_close": (lambda t: t.replace("MOTION", "}\nMOTION"), r"unbalanced braces", None),
    "missing_brace": (lambda t: t.replace("}\nMOTION", "MOTION"), r"never closed", None),
    "nan": (lambda t: t.replace("2 10 0 0 90", "2 10 nan 0 90"), r"not finite", "2 10 nan"),
    "no_motion": (lambda t: t.split("MOTION")[0], r"no MOTION section", None),
    "bad_extra_frame": (lambda t: t + "7 10 0 0 0 0 0 0 0 0 0 0 0 0\n", r"frame 3 has 14 values, expected 15", "7 10 0 0"),
    "bad_offset": (lambda t: t.replace("OFFSET 0 2 0", "OFFSET 0 two 0"), r"OFFSET of 'Chest'.*not a number", "two"),
    "bad_frames": (lambda t: t.replace("Frames: 3", "Frames: three"), r"Frames: 'three'", "Frames: three"),
}


@pytest.mark.parametrize("case", sorted(MALFORMED))
def test_malformed_input_names_file_and_line(case):
    mutate, pattern, marker = MALFORMED[case]
    text = mutate(TWO_JOINT)
    with pytest.raises(BVHError) as err:
        parse_bvh(text, path="sample.bvh")
    msg = str(err.value)
    assert msg.startswith("sample.bvh:"), msg
    assert re.search(pattern, msg), msg
    assert "\n" not in msg
    assert err.value.line is not None and err.value.line >= 1
    if marker is not None:
        expected = next(i for i, ln in enumerate(text.split("\n"), 1) if marker in ln)
        assert err.value.line == expected, msg


def test_more_frame_lines_than_the_header_are_read_with_a_warning(tmp_path, caplog):
    """As Blender reads such a file: every frame line is kept (assimp would drop the extra one)."""
    extra = "7 10 0 0 0 0 0 0 0 0 0 0 0 0 0\n"
    p = tmp_path / "extra.bvh"
    p.write_text(TWO_JOINT + extra + "\n")
    with caplog.at_level("WARNING", logger="vidstyle.mocap.bvh"):
        m = read_bvh(p)
    ref = parse_bvh(TWO_JOINT.replace("Frames: 3", "Frames: 4") + extra)
    assert m.n_frames == 4 == ref.n_frames
    np.testing.assert_array_equal(m.translations, ref.translations)
    np.testing.assert_array_equal(m.rotations, ref.rotations)
    assert m.root_positions[3, 0] == 7.0
    [rec] = [r for r in caplog.records if r.levelname == "WARNING"]
    assert str(p) in rec.getMessage() and "4 frame lines" in rec.getMessage() and "Frames: 3" in rec.getMessage()


def test_fewer_frame_lines_than_the_header_stay_an_error():
    text = TWO_JOINT.replace("Frames: 3", "Frames: 5")
    with pytest.raises(BVHError, match=r"truncated MOTION block: 3 of 5 frames"):
        parse_bvh(text, path="short.bvh")


def test_binary_and_missing_files(tmp_path):
    p = tmp_path / "x.bvh"
    p.write_bytes(b"\x00\x01\x02binary")
    with pytest.raises(BVHError, match="binary"):
        read_bvh(p)
    with pytest.raises(BVHError, match="file not found"):
        read_bvh(tmp_path / "missing.bvh")
    with pytest.raises(BVHError, match="directory"):
        read_bvh(tmp_path)


_mutation = st.one_of(
    st.tuples(st.just("delete"), st.integers(0, 10_000), st.integers(1, 40)),
    st.tuples(st.just("insert"), st.integers(0, 10_000), st.text(alphabet="{} \t\n0123456789.-eE+abcXYZrotationMOTIONFrameTim:", max_size=12)),
    st.tuples(st.just("truncate"), st.integers(0, 10_000), st.just(0)),
    st.tuples(st.just("dupline"), st.integers(0, 60), st.just(0)),
    st.tuples(st.just("dropline"), st.integers(0, 60), st.just(0)),
    st.tuples(st.just("swaptok"), st.integers(0, 400), st.integers(0, 400)),
)


def _apply(text: str, muts) -> str:
    for kind, a, b in muts:
        if kind == "delete":
            a %= max(len(text), 1)
            text = text[:a] + text[a + b :]
        elif kind == "insert":
            a %= max(len(text), 1)
            text = text[:a] + b + text[a:]
        elif kind == "truncate":
            text = text[: a % max(len(text), 1)]
        elif kind in ("dupline", "dropline"):
            lines = text.split("\n")
            a %= max(len(lines), 1)
            lines = lines[: a + 1] + lines[a:] if kind == "dupline" else lines[:a] + lines[a + 1 :]
            text = "\n".join(lines)
        else:
            toks = text.split(" ")
            if toks:
                a %= len(toks)
                b %= len(toks)
                toks[a], toks[b] = toks[b], toks[a]
            text = " ".join(toks)
    return text


@settings(max_examples=2500, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
@given(st.lists(_mutation, min_size=1, max_size=4))
def test_fuzzed_files_raise_only_bvherror(muts):
    text = _apply(TWO_JOINT, muts)
    try:
        m = parse_bvh(text, path="fuzz.bvh")
    except BVHError as e:
        assert str(e).startswith("fuzz.bvh") and "\n" not in str(e)
        return
    # whatever parses must be a consistent motion
    assert isinstance(m, Motion)
    assert np.isfinite(m.rotations).all() and np.isfinite(m.translations).all()
    global_positions(m)


# ------------------------------------------------------------------ the MOTION block's fast path
def _loadtxt(text: str) -> np.ndarray:
    import io

    return np.loadtxt(io.StringIO(text), dtype=np.float64, ndmin=2, comments=None)


_DECIMAL = st.builds(
    lambda sign, whole, point, frac: sign + whole + point + frac,
    st.sampled_from(["", "-", "+"]), st.text("0123456789", max_size=7), st.sampled_from(["", "."]),
    st.text("0123456789", max_size=8),
).filter(lambda t: any(ch.isdigit() for ch in t))  # "5.", ".5", "-0", "007": all plain decimals


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(1, 4), st.integers(1, 5), st.data())
def test_decimal_fast_path_gives_loadtxt_values_bit_for_bit(rows, cols, data):
    from vidstyle.mocap.bvh import _decimal_values

    toks = [[data.draw(_DECIMAL) for _ in range(cols)] for _ in range(rows)]
    seps = data.draw(st.sampled_from([" ", "\t", "  ", " \t "]))
    text = "\n".join(data.draw(st.sampled_from(["", " ", "\t"])) + seps.join(r) + data.draw(st.sampled_from(["", " "]))
                     for r in toks)
    ours = _decimal_values(text, rows, cols)
    ref = _loadtxt(text)
    assert ours is not None and ours.shape == ref.shape
    assert ours.tobytes() == ref.tobytes()  # same bits, signed zeros included


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(1, 3), st.integers(1, 4), st.text("0123456789.+-eE \t\n\x0b,x\u00b9", max_size=40), st.data())
def test_compiled_decimal_reader_equals_the_numpy_reference(rows, cols, noise, data):
    # the compiled reader replaces the vectorised one on the promise of the same values and the same
    # refusals: well-formed tables, and arbitrary text of digits, points, signs, exponents and separators
    from vidstyle.mocap.bvh import _decimal_values, _decimal_values_numpy

    toks = [[data.draw(_DECIMAL) for _ in range(cols)] for _ in range(rows)]
    table = "\n".join(" ".join(r) for r in toks)
    for text, r in ((table, rows), (noise, rows), (table + data.draw(st.sampled_from(["", " ", "\n", "x", "\n1"])), rows)):
        ours, ref = _decimal_values(text, r, cols), _decimal_values_numpy(text, r, cols)
        assert (ours is None) == (ref is None), repr(text)
        if ref is not None:
            assert ours.tobytes() == ref.tobytes()


def test_decimal_fast_path_values_over_the_whole_double_range_of_plain_decimals(rng):
    from vidstyle.mocap.bvh import _decimal_values

    vals = np.concatenate([rng.uniform(-1e3, 1e3, 500), rng.uniform(-1, 1, 500) * 10.0 ** rng.integers(-9, 9, 500)])
    for fmt in ("%.6f", "%.4f", "%.9f", "%.15g", "%.1f"):
        text = "\n".join(" ".join(fmt % v for v in row) for row in vals.reshape(100, 10))
        ours = _decimal_values(text, 100, 10)
        if ours is None:  # e.g. %.15g wrote an exponent or > 15 digits: loadtxt's job
            continue
        assert ours.tobytes() == _loadtxt(text).tobytes()


@pytest.mark.parametrize("text", ["1 2 3-", "1 2 1.2.3", "1 2 -", "1 2 .", "1 2 --1", "1 2 1e5", "1 2 nan",
                                  "1 2 inf", "1 2 0x1", "1 2 1,5", "1 2 3 4", "1 2", "1 2 3\n4 5", "1 2 3\n\n4 5 6",
                                  "1 2 1234567890123456", "1 2 \u00b9", "1 2 3\x0b"])
def test_decimal_fast_path_leaves_everything_else_to_loadtxt(text):
    from vidstyle.mocap.bvh import _decimal_values

    rows = 2 if "\n" in text else 1
    assert _decimal_values(text, rows, 3) is None
