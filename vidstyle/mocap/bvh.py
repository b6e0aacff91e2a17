"""BVH (Biovision Hierarchy) reading and writing.

Reader: any per-joint channel order and subset (3 rotations, 6 channels, positions on any joint), End
Sites, any frame rate, tabs / CRLF / CR / odd whitespace, several ROOTs. Rotation channels compose as
intrinsic rotations in the order listed (``Zrotation Yrotation Xrotation`` means ``R = Rz Ry Rx``), which
is scipy's upper-case Euler sequence. Position channels replace the joint's OFFSET (the convention of
most readers; for the usual root with a zero OFFSET the two conventions agree).

A MOTION block with more frame lines than its ``Frames:`` header is read whole, with a warning naming
the file and both counts: Blender's importer (``io_anim_bvh/import_bvh.py``) reads every frame line to
the end of the file and ignores the count, so files it writes or accepts with a stale header keep all
their frames here too (assimp instead stops after ``Frames:`` lines and drops the rest). Fewer lines
than the header promises is an error (a truncated file).

Every problem with the file raises :class:`BVHError` naming the file and line. The MOTION block is
parsed by a vectorised reader of plain decimals (``_decimal_values``: the exact values strtod gives,
about twice as fast as loadtxt), else with ``numpy.loadtxt`` (C speed); only when that fails too is it
rescanned line by line to name the offending line precisely.
"""

from __future__ import annotations

import io
import logging
import math
import os
import re
import warnings
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import VidstyleError
from ..fileio import atomic_path
from .motion import Motion
from .quat import intrinsic_euler_parts
from .skeleton import ALL_CHANNELS, POSITION_CHANNELS, ROTATION_CHANNELS, Skeleton

_AXIS = {"X": 0, "Y": 1, "Z": 2}
log = logging.getLogger(__name__)


class BVHError(VidstyleError):
    """A malformed BVH file. ``str(err)`` is ``"<file>:<line>: <problem>"``."""

    def __init__(self, path: str | os.PathLike | None, line: int | None, problem: str) -> None:
        self.path = str(path) if path is not None else "<bvh>"
        self.line = line
        self.problem = problem
        where = f"{self.path}:{line}" if line else self.path
        super().__init__(f"{where}: {problem}")

    def __reduce__(self):  # picklable (a worker process's error reaches the parent intact)
        return type(self), (self.path, self.line, self.problem)


# --------------------------------------------------------------------------- reading
def read_bvh(path: str | os.PathLike) -> Motion:
    """Read a BVH file into a :class:`Motion`."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise BVHError(path, None, "file not found") from None
    except IsADirectoryError:
        raise BVHError(path, None, "is a directory, not a BVH file") from None
    except OSError as e:
        raise BVHError(path, None, f"cannot be read ({e.strerror})") from None
    return parse_bvh(raw, path)


def parse_bvh(data: str | bytes, path: str | os.PathLike | None = None) -> Motion:
    """Parse BVH text (str or bytes); ``path`` is only used in error messages."""
    if isinstance(data, bytes):
        if b"\x00" in data:
            raise BVHError(path, None, "binary data (NUL bytes), not a BVH text file")
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError:
            text = data.decode("latin-1")
    else:
        text = data
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    if text.startswith("\ufeff"):
        text = text[1:]
    lines = text.split("\n")

    motion_line = None
    for i, line in enumerate(lines):
        if line.strip() == "MOTION":
            motion_line = i
            break
        if line.strip().upper().startswith("MOTION") and line.split()[0].upper() == "MOTION":
            motion_line = i
            break
    if motion_line is None:
        raise BVHError(path, len(lines), "no MOTION section")
    skeleton = _parse_hierarchy(lines[:motion_line], path)
    return _parse_motion(lines, motion_line, skeleton, path)


def _tokens(lines: list[str]) -> list[tuple[str, int]]:
    out = []
    for i, line in enumerate(lines):
        for tok in line.split():
            # braces glued to words ("Hips{") are separate tokens
            for part in re.split(r"([{}])", tok):
                if part:
                    out.append((part, i + 1))
    return out


def _parse_hierarchy(lines: list[str], path) -> Skeleton:
    toks = _tokens(lines)
    pos = 0
    n = len(toks)
    last_line = max(len(lines), 1)

    def peek() -> tuple[str | None, int]:
        return toks[pos] if pos < n else (None, last_line)

    def take(expected: str | None = None, what: str | None = None) -> tuple[str, int]:
        nonlocal pos
        if pos >= n:
            raise BVHError(path, last_line, f"unexpected end of HIERARCHY (expected {expected or what or 'more'})")
        tok, ln = toks[pos]
        if expected is not None and tok.upper() != expected.upper():
            raise BVHError(path, ln, f"expected {expected!r}, found {tok!r}")
        pos += 1
        return tok, ln

    def number(what: str) -> float:
        tok, ln = take()
        try:
            v = float(tok)
        except ValueError:
            raise BVHError(path, ln, f"{what}: {tok!r} is not a number") from None
        if not math.isfinite(v):
            raise BVHError(path, ln, f"{what}: {tok!r} is not finite")
        return v

    names: list[str] = []
    parents: list[int] = []
    offsets: list[list[float]] = []
    channels: list[tuple[str, ...]] = []
    end_sites: dict[int, np.ndarray] = {}

    tok, ln = peek()
    if tok is None or tok.upper() != "HIERARCHY":
        raise BVHError(path, ln, f"file does not start with HIERARCHY (found {tok!r})")
    take()

    def parse_joint(parent: int, keyword_line: int) -> None:
        # name: every token on the keyword's line up to an opening brace
        name_parts = []
        while pos < n and toks[pos][1] == keyword_line and toks[pos][0] != "{":
            name_parts.append(take()[0])
        if not name_parts:
            raise BVHError(path, keyword_line, "joint without a name")
        name = " ".join(name_parts)
        if name in names:
            raise BVHError(path, keyword_line, f"duplicate joint name {name!r}")
        take("{")
        index = len(names)
        names.append(name)
        parents.append(parent)
        offsets.append([0.0, 0.0, 0.0])
        channels.append(())
        seen_offset = False
        while True:
            tok, ln = peek()
            if tok is None:
                raise BVHError(path, ln, f"unbalanced braces: joint {name!r} is never closed")
            key = tok.upper()
            if key == "}":
                take()
                break
            if key == "OFFSET":
                take()
                offsets[index] = [number(f"OFFSET of {name!r}") for _ in range(3)]
                seen_offset = True
            elif key == "CHANNELS":
                take()
                cnt_tok, cnt_ln = take()
                if not cnt_tok.isdigit():
                    raise BVHError(path, cnt_ln, f"CHANNELS of {name!r}: count {cnt_tok!r} is not an integer")
                cnt = int(cnt_tok)
                chans = []
                for _ in range(cnt):
                    c, cln = take(what="a channel name")
                    canon = _canonical_channel(c)
                    if canon is None:
                        raise BVHError(path, cln, f"unknown channel name {c!r} in joint {name!r}")
                    if canon in chans:
                        raise BVHError(path, cln, f"channel {c!r} repeated in joint {name!r}")
                    chans.append(canon)
                channels[index] = tuple(chans)
            elif key == "JOINT":
                _, jl = take()
                parse_joint(index, jl)
            elif key == "END":
                _, el = take()
                take("Site")
                take("{")
                take("OFFSET")
                end_sites[index] = np.array([number(f"End Site OFFSET of {name!r}") for _ in range(3)])
                take("}")
            elif key in ("ROOT", "MOTION", "HIERARCHY", "{"):
                raise BVHError(path, ln, f"unexpected {tok!r} inside joint {name!r} (unbalanced braces?)")
            else:
                raise BVHError(path, ln, f"unexpected token {tok!r} in joint {name!r}")
        if not seen_offset:
            raise BVHError(path, keyword_line, f"joint {name!r} has no OFFSET")

    while pos < n:
        tok, ln = take()
        if tok.upper() == "ROOT":
            parse_joint(-1, ln)
        elif tok == "}":
            raise BVHError(path, ln, "unbalanced braces: '}' without a joint")
        else:
            raise BVHError(path, ln, f"expected ROOT, found {tok!r}")
    if not names:
        raise BVHError(path, 1, "HIERARCHY has no ROOT joint")
    return Skeleton(names, np.array(parents), np.array(offsets), channels, end_sites)


def _canonical_channel(name: str) -> str | None:
    for c in ALL_CHANNELS:
        if c.lower() == name.lower():
            return c
    return None


_FRAMES_RE = re.compile(r"^\s*Frames\s*:\s*(\S*)\s*$", re.IGNORECASE)
_FTIME_RE = re.compile(r"^\s*Frame\s+Time\s*:\s*(\S*)\s*$", re.IGNORECASE)


def _parse_motion(lines: list[str], motion_line: int, skeleton: Skeleton, path) -> Motion:
    i = motion_line + 1

    def next_nonblank(i: int) -> int:
        while i < len(lines) and not lines[i].strip():
            i += 1
        return i

    i = next_nonblank(i)
    m = _FRAMES_RE.match(lines[i]) if i < len(lines) else None
    if not m:
        raise BVHError(path, i + 1, "missing 'Frames:' line after MOTION")
    frames_line = i + 1
    try:
        n_frames = int(m.group(1))
        if n_frames < 0:
            raise ValueError
    except ValueError:
        raise BVHError(path, i + 1, f"Frames: {m.group(1)!r} is not a non-negative integer") from None
    i = next_nonblank(i + 1)
    m = _FTIME_RE.match(lines[i]) if i < len(lines) else None
    if not m:
        raise BVHError(path, i + 1, "missing 'Frame Time:' line")
    try:
        frame_time = float(m.group(1))
        if not (frame_time > 0 and math.isfinite(frame_time)):
            raise ValueError
    except ValueError:
        raise BVHError(path, i + 1, f"Frame Time: {m.group(1)!r} is not a positive number") from None
    data_start = i + 1
    n_channels = sum(len(c) for c in skeleton.channels)
    data_lines = lines[data_start:]
    values = _parse_values(data_lines, data_start, n_frames, n_channels, path)
    if len(values) == 0:
        raise BVHError(path, frames_line, "no motion: 'Frames: 0' and no frame lines (at least one frame is needed)")
    fps = 1.0 / frame_time
    if abs(fps - round(fps)) < 1e-3 * fps and round(fps) > 0:
        fps = float(round(fps))  # ".0083333" means 120 fps: the file rounded 1/120
    return _motion_from_channels(skeleton, values, fps)


_POW10 = np.array([10.0**k for k in range(23)])  # 10**0 .. 10**22: every one an exact double
_MAX_DIGITS = 15  # an integer of at most 15 decimal digits is below 2**53: exact as an int64 and a double
_CHAR_CLASS = np.full(256, 3, dtype=np.uint8)  # 0: separator (space, tab, newline), 1: digit, 2: point, 3: other
_CHAR_CLASS[[32, 9, 10]] = 0
_CHAR_CLASS[48:58] = 1
_CHAR_CLASS[46] = 2


def _decimal_values(text: str, n_rows: int, n_cols: int) -> np.ndarray | None:
    """``(n_rows, n_cols)`` values of ``text`` (lines of plain decimals), or None to leave it to loadtxt:
    :func:`_decimal_values_numpy`'s rule and values, read by a compiled byte-by-byte loop
    (:func:`_decimal_loop`; the numpy version without numba)."""
    kernel = _decimal_kernel()
    if kernel is None:  # pragma: no cover - numba is a dependency
        return _decimal_values_numpy(text, n_rows, n_cols)
    try:
        data = text.encode("ascii")
    except UnicodeEncodeError:
        return None
    out = np.empty(n_rows * n_cols)
    if not kernel(np.frombuffer(data, dtype=np.uint8), _CHAR_CLASS, _POW10, n_rows, n_cols, _MAX_DIGITS, out):
        return None
    return out.reshape(n_rows, n_cols)


def _decimal_loop(b, cls, pow10, n_rows, n_cols, max_digits, out):
    # compiled by numba: _decimal_values_numpy token by token. A token: an optional sign, then digits with at
    # most one point, 1 to max_digits digits, value (digits as an integer) / 10**(digits after the point);
    # space, tab and newline separate tokens, n_cols tokens per line, n_rows lines (no blank one). False:
    # anything else (leave it to loadtxt)
    n = b.shape[0]
    total = n_rows * n_cols
    i = 0
    tok = 0
    line = 0
    col = 0
    while i < n:
        ch = b[i]
        k = cls[ch]
        if k == 0:
            if ch == 10:
                if col != n_cols:
                    return False
                line += 1
                col = 0
            i += 1
            continue
        if tok >= total:
            return False
        neg = False
        if k == 3:
            if ch == 45:
                neg = True
            elif ch != 43:
                return False
            i += 1
        mant = 0
        digits = 0
        frac = 0
        point = False
        while i < n:
            ch = b[i]
            k = cls[ch]
            if k == 0:
                break
            if k == 1:
                digits += 1
                if digits > max_digits:
                    return False
                mant = mant * 10 + (ch - 48)
                if point:
                    frac += 1
            elif k == 2:
                if point:
                    return False
                point = True
            else:
                return False
            i += 1
        if digits == 0:
            return False
        v = np.float64(mant) / pow10[frac]
        out[tok] = -v if neg else v
        tok += 1
        col += 1
    return tok == total and line == n_rows - 1 and col == n_cols


_DECIMAL_KERNEL: list = []


def _decimal_kernel():
    """:func:`_decimal_loop` compiled (:func:`vidstyle.compiled.compile_kernel`), or None without numba."""
    if not _DECIMAL_KERNEL:
        from ..compiled import compile_kernel

        _DECIMAL_KERNEL.append(compile_kernel(_decimal_loop))
    return _DECIMAL_KERNEL[0]


def _decimal_values_numpy(text: str, n_rows: int, n_cols: int) -> np.ndarray | None:
    """``(n_rows, n_cols)`` values of ``text`` (lines of plain decimals), or None to leave it to loadtxt.

    The fast path of the MOTION block, vectorised over all numbers at once. It takes only what it can
    read exactly: ASCII lines (none blank) of ``n_cols`` space / tab separated tokens, each
    ``[+-]?`` digits with at most one ``.``, at least 1 and at most 15 digits. Such a number is the
    integer m of its digits over 10**k (k digits after the point); m < 2**53 and 10**k (k <= 22) are
    exact doubles, so ``m / 10**k`` rounds once, to the nearest double: the value strtod (loadtxt,
    float()) gives, bit for bit (Clinger's fast path). Anything else (exponents, nan/inf, more digits,
    other whitespace, malformed tokens, wrong counts) returns None, and loadtxt and the line-by-line
    check decide as before.
    """
    try:
        data = text.encode("ascii")
    except UnicodeEncodeError:
        return None
    b = np.frombuffer(data + b" ", dtype=np.uint8)  # a separator after the last token
    cls = _CHAR_CLASS[b]
    edge = np.diff((cls == 0).view(np.int8), prepend=np.int8(1))  # -1: a token starts, +1: it ends
    starts = np.flatnonzero(edge == -1)
    ends = np.flatnonzero(edge == 1)
    n = starts.size
    if n != n_rows * n_cols:
        return None
    line_ends = np.flatnonzero(b == 10)
    if line_ends.size != n_rows - 1:
        return None
    # tokens before each line end: n_cols per line, so every line holds exactly n_cols
    if n_rows > 1 and not np.array_equal(np.searchsorted(starts, line_ends), np.arange(1, n_rows) * n_cols):
        return None
    c = b[starts]
    neg = c == 45  # '-'
    signed = neg | (c == 43)  # '+'
    if np.count_nonzero(cls == 3) != np.count_nonzero(signed):
        return None  # a character other than digit, point or separator, or a sign inside a token
    pos = starts + signed
    width = int((ends - pos).max())
    if width > _MAX_DIGITS + 1:  # digits + point
        return None
    mant = np.zeros(n, dtype=np.int64)
    digits = np.zeros(n, dtype=np.uint8)
    frac = np.zeros(n, dtype=np.uint8)
    point = np.zeros(n, dtype=bool)
    for _ in range(width):  # one character of every token per step
        k = cls[pos]  # a finished token stays on the separator after it (class 0)
        is_digit = k == 1
        is_point = k == 2
        if (is_point & point).any():
            return None  # a second point
        mant = np.where(is_digit, mant * 10 + (b[pos] - np.uint8(48)), mant)
        digits += is_digit
        frac += is_digit & point
        point |= is_point
        pos += k != 0
    if not np.array_equal(pos, ends) or not digits.all() or int(digits.max()) > _MAX_DIGITS:
        return None
    values = mant.astype(np.float64) / _POW10[frac]  # both exact: the division rounds once, as strtod does
    np.negative(values, out=values, where=neg)  # "-0" and "-0.000" are -0.0, as strtod reads them
    return values.reshape(n_rows, n_cols)


def _parse_values(data_lines: list[str], first_line: int, n_frames: int, n_channels: int, path) -> np.ndarray:
    """(n_frames, n_channels) float array; ``first_line`` is the 0-based index of data_lines[0]."""
    body = [ln for ln in data_lines if ln.strip()]
    if len(body) > n_frames and n_channels > 0:
        # as Blender reads it: every frame line counts, the header's count does not (module docstring)
        log.warning("%s: %d frame lines but 'Frames: %d'; reading all %d frames (as Blender does)",
                    path if path is not None else "<bvh>", len(body), n_frames, len(body))
        n_frames = len(body)
    if not body:  # no frame lines: 'Frames: 0' (or a count the file does not hold, said below)
        if n_frames == 0:
            return np.zeros((0, n_channels))
    if n_channels == 0:
        if body:
            raise BVHError(path, first_line + 1, "frame values given but the hierarchy has no channels")
        return np.zeros((n_frames, 0))
    if len(body) == n_frames:
        values = _decimal_values("\n".join(body), n_frames, n_channels)
        if values is not None:
            return values
        try:
            values = np.loadtxt(io.StringIO("\n".join(body)), dtype=np.float64, ndmin=2, comments=None)
        except ValueError:
            values = None
        if values is not None and values.shape == (n_frames, n_channels) and np.isfinite(values).all():
            return values
    # slow path: find the first offending line and say what is wrong with it
    frame = 0
    for k, line in enumerate(data_lines):
        if not line.strip():
            continue
        lineno = first_line + k + 1
        if frame >= n_frames:
            raise BVHError(path, lineno, f"more frame lines than 'Frames: {n_frames}'")
        parts = line.split()
        if len(parts) != n_channels:
            raise BVHError(path, lineno, f"frame {frame} has {len(parts)} values, expected {n_channels}")
        for p in parts:
            try:
                v = float(p)
            except ValueError:
                raise BVHError(path, lineno, f"frame {frame}: {p!r} is not a number") from None
            if not math.isfinite(v):
                raise BVHError(path, lineno, f"frame {frame}: {p!r} is not finite")
        frame += 1
    if frame < n_frames:
        raise BVHError(
            path, first_line + len(data_lines), f"truncated MOTION block: {frame} of {n_frames} frames present"
        )
    raise BVHError(path, first_line + 1, "MOTION block could not be parsed")  # pragma: no cover


def _motion_from_channels(skeleton: Skeleton, values: np.ndarray, fps: float) -> Motion:
    F = values.shape[0]
    J = skeleton.n_joints
    quats = np.zeros((F, J, 4))
    quats[..., 3] = 1.0
    translations = np.broadcast_to(skeleton.offsets, (F, J, 3)).copy()
    by_sequence: dict[str, tuple[list[int], list[list[int]]]] = {}
    col = 0
    for j, chans in enumerate(skeleton.channels):
        cols = {c: col + k for k, c in enumerate(chans)}
        col += len(chans)
        if any(c in cols for c in POSITION_CHANNELS):
            for axis, c in enumerate(POSITION_CHANNELS):
                translations[:, j, axis] = values[:, cols[c]] if c in cols else 0.0
        rot = [c for c in chans if c in ROTATION_CHANNELS]
        if rot:
            joints, columns = by_sequence.setdefault("".join(c[0] for c in rot), ([], []))
            joints.append(j)
            columns.append([cols[c] for c in rot])
    # one batched conversion per rotation order (files usually have one or two orders), on contiguous
    # (F, joints) arrays per axis: the numbers of from_intrinsic_euler, bit for bit
    for seq, (joints, columns) in by_sequence.items():
        angles = np.ascontiguousarray(values[:, np.array(columns).T].transpose(1, 0, 2))  # (len(seq), F, joints)
        for i, part in enumerate(intrinsic_euler_parts(seq, angles)):
            quats[:, joints, i] = part
    return Motion(skeleton, quats, translations, fps)


# --------------------------------------------------------------------------- writing
def motion_to_channels(motion: Motion) -> np.ndarray:
    """(F, C) channel values in the skeleton's channel layout (Euler angles in degrees)."""
    sk = motion.skeleton
    cols = []
    for j, chans in enumerate(sk.channels):
        rot = [c for c in chans if c in ROTATION_CHANNELS]
        angles: dict[str, np.ndarray] = {}
        if rot:
            seq = "".join(c[0] for c in rot)
            if len(seq) < 3:  # complete the sequence with the missing axes; they are expected to be ~0
                seq += "".join(a for a in "XYZ" if a not in seq)
            with warnings.catch_warnings():
                # at gimbal lock scipy picks one of the equivalent decompositions: still exact
                warnings.simplefilter("ignore", UserWarning)
                eul = Rotation.from_quat(motion.rotations[:, j]).as_euler(seq, degrees=True)
            for k, c in enumerate(rot):
                angles[c] = eul[:, k]
        for c in chans:
            if c in POSITION_CHANNELS:
                cols.append(motion.translations[:, j, _AXIS[c[0]]])
            else:
                cols.append(angles[c])
    if not cols:
        return np.zeros((motion.n_frames, 0))
    return np.stack(cols, axis=1)


def format_bvh(motion: Motion, precision: int = 6) -> str:
    """BVH text of ``motion`` (tab-indented hierarchy, one line per frame)."""
    sk = motion.skeleton
    out = io.StringIO()
    out.write("HIERARCHY\n")
    fmt = f"%.{precision}f"

    def offset_str(v: np.ndarray) -> str:
        return " ".join(fmt % x for x in v)

    children: dict[int, list[int]] = {j: [] for j in range(sk.n_joints)}
    for j, p in enumerate(sk.parents):
        if p >= 0:
            children[int(p)].append(j)

    def write_joint(j: int, depth: int) -> None:
        ind = "\t" * depth
        kw = "ROOT" if sk.parents[j] < 0 else "JOINT"
        out.write(f"{ind}{kw} {sk.names[j]}\n{ind}{{\n")
        out.write(f"{ind}\tOFFSET {offset_str(sk.offsets[j])}\n")
        chans = sk.channels[j]
        out.write(f"{ind}\tCHANNELS {len(chans)}{''.join(' ' + c for c in chans)}\n")
        for c in children[j]:
            write_joint(c, depth + 1)
        if j in sk.end_sites:
            out.write(f"{ind}\tEnd Site\n{ind}\t{{\n{ind}\t\tOFFSET {offset_str(sk.end_sites[j])}\n{ind}\t}}\n")
        out.write(f"{ind}}}\n")

    for r in np.flatnonzero(sk.parents < 0):
        write_joint(int(r), 0)
    out.write("MOTION\n")
    out.write(f"Frames: {motion.n_frames}\n")
    out.write(f"Frame Time: {1.0 / motion.fps:.8f}\n")
    values = motion_to_channels(motion)
    if values.shape[1]:
        values = np.where(np.abs(values) < 0.5 * 10.0**-precision, 0.0, values)  # no "-0.000000"
        np.savetxt(out, values, fmt=fmt, delimiter=" ")
    else:
        out.write("\n" * motion.n_frames)
    return out.getvalue()


def write_bvh(motion: Motion, path: str | os.PathLike, precision: int = 6) -> None:
    """Write ``motion`` as BVH (atomically: temporary file, then rename)."""
    text = format_bvh(motion, precision)
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
