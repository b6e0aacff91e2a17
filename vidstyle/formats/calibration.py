"""Camera calibrations of synchronised views: Qualisys ``.qca.txt`` (XML) and OpenCV / Pose2Sim ``.toml``.

Both are read into one record, :class:`Calibration`: per camera its name, image size, intrinsic matrix
``K`` (pixels), OpenCV distortion ``(k1, k2, p1, p2, k3)``, and the world -> camera transform
``X_cam = R @ X_world + t`` (``t`` in millimetres), so a world point projects to pixel
``K @ X_cam`` (after distortion), OpenCV's convention (x right, y down, z forward).

Qualisys (as Pose2Sim reads it): ``focalLengthU/V`` and ``centerPointU/V`` are in 1/64 pixel; the
``transform`` attributes ``r11..r33`` read row by row give a matrix ``M`` whose transpose holds the
camera's axes in the world (the file stores the matrix by column), and ``x, y, z`` are the camera centre
``C`` in mm. World -> camera is then ``M (X - C)`` followed by a rotation of pi about the camera's x axis
(Qualisys cameras look along -z with y up): ``R = diag(1, -1, -1) M``, ``t = -R C``. The image size is
the ``fov_video`` rectangle.

Pose2Sim / OpenCV ``.toml``: one table per camera with ``name``, ``size = [w, h]``,
``matrix`` (3x3), ``distortions`` (4 or 5), ``rotation`` (Rodrigues vector, world -> camera) and
``translation`` in metres (Pose2Sim's unit; converted to mm here); ``[metadata]`` is ignored.
:func:`write_calibration` writes this form.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree

import numpy as np

from ..fileio import read_bytes, write_text
from ._base import FormatError

MAX_BYTES = 4 << 20
MAX_CAMERAS = 256


@dataclass
class CameraCalibration:
    name: str
    size: tuple[int, int]
    """(width, height) in pixels"""
    K: np.ndarray
    """(3, 3) intrinsic matrix, pixels"""
    R: np.ndarray
    """(3, 3) world -> camera rotation"""
    t: np.ndarray
    """(3,) world -> camera translation, millimetres"""
    dist: np.ndarray = field(default_factory=lambda: np.zeros(5))
    """OpenCV distortion (k1, k2, p1, p2, k3)"""

    @property
    def centre(self) -> np.ndarray:
        """the camera centre in the world, mm"""
        return -self.R.T @ self.t

    @property
    def P(self) -> np.ndarray:
        """(3, 4) projection matrix of the undistorted image: K [R | t]"""
        return self.K @ np.hstack([self.R, self.t[:, None]])


@dataclass
class Calibration:
    cameras: list[CameraCalibration]
    source: str = ""

    def names(self) -> list[str]:
        return [c.name for c in self.cameras]

    def camera(self, name: str) -> CameraCalibration:
        for c in self.cameras:
            if c.name == name:
                return c
        raise KeyError(name)


def read_calibration(path: str | os.PathLike) -> Calibration:
    """A ``.qca.txt`` / ``.qca`` (Qualisys XML) or ``.toml`` calibration; :class:`FormatError` otherwise."""
    path = Path(path)
    if path.is_dir():
        raise FormatError(path, None, "is a directory, not a calibration file")
    raw = read_bytes(path, MAX_BYTES)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise FormatError(path, None, f"not UTF-8 text (a binary file?) at byte {e.start}") from None
    if text.lstrip().startswith("<"):
        cams = _parse_qca(text, path)
    elif path.suffix.lower() == ".toml" or "[" in text:
        cams = _parse_toml(text, path)
    else:
        raise FormatError(path, None, "neither Qualisys XML nor TOML calibration")
    if not cams:
        raise FormatError(path, "cameras", "no camera")
    names = [c.name for c in cams]
    if len(set(names)) != len(names):
        raise FormatError(path, "cameras", "camera names are not unique")
    return Calibration(cams, str(path))


def _num(v, path, field: str, positive: bool = False) -> float:
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise FormatError(path, field, f"expected a number, got {v!r}"[:200]) from None
    if not math.isfinite(x):
        raise FormatError(path, field, "must be finite")
    if positive and x <= 0:
        raise FormatError(path, field, "must be positive")
    return x


def _check_rotation(R: np.ndarray, path, field: str) -> np.ndarray:
    if R.shape != (3, 3) or not np.all(np.isfinite(R)):
        raise FormatError(path, field, "expected a finite 3x3 matrix")
    if np.abs(R @ R.T - np.eye(3)).max() > 1e-3 or np.linalg.det(R) < 0:
        raise FormatError(path, field, "is not a rotation matrix")
    return R


def _parse_qca(text: str, path) -> list[CameraCalibration]:
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as e:
        raise FormatError(path, None, f"not valid XML ({e})") from None
    nodes = root.findall("cameras/camera")
    if len(nodes) > MAX_CAMERAS:
        raise FormatError(path, "cameras", f"more than {MAX_CAMERAS} cameras")
    cams = []
    flip = np.diag([1.0, -1.0, -1.0])
    for i, node in enumerate(nodes):
        where = f"cameras[{i}]"
        name = node.get("serial") or f"cam{i + 1:02d}"
        fov, tr, intr = node.find("fov_video"), node.find("transform"), node.find("intrinsic")
        if fov is None or tr is None or intr is None:
            raise FormatError(path, where, "needs fov_video, transform and intrinsic")
        w = _num(fov.get("right"), path, f"{where}.fov_video.right") - _num(fov.get("left"), path, f"{where}.fov_video.left") + 1
        h = _num(fov.get("bottom"), path, f"{where}.fov_video.bottom") - _num(fov.get("top"), path, f"{where}.fov_video.top") + 1
        if not (1 <= w <= 1 << 16 and 1 <= h <= 1 << 16):
            raise FormatError(path, f"{where}.fov_video", f"image size {w} x {h} out of range")
        f = {k: _num(intr.get(k), path, f"{where}.intrinsic.{k}") / 64.0
             for k in ("focalLengthU", "focalLengthV", "centerPointU", "centerPointV")}
        if f["focalLengthU"] <= 0 or f["focalLengthV"] <= 0:
            raise FormatError(path, f"{where}.intrinsic", "focal lengths must be positive")
        skew = _num(intr.get("skew", 0), path, f"{where}.intrinsic.skew")
        K = np.array([[f["focalLengthU"], skew, f["centerPointU"]], [0.0, f["focalLengthV"], f["centerPointV"]],
                      [0.0, 0.0, 1.0]])
        dist = np.array([_num(intr.get(k, 0), path, f"{where}.intrinsic.{k}") for k in
                         ("radialDistortion1", "radialDistortion2", "tangentalDistortion1", "tangentalDistortion2",
                          "radialDistortion3")])
        M = np.array([[_num(tr.get(f"r{a}{b}"), path, f"{where}.transform.r{a}{b}") for b in (1, 2, 3)]
                      for a in (1, 2, 3)])
        C = np.array([_num(tr.get(k), path, f"{where}.transform.{k}") for k in ("x", "y", "z")])
        R = _check_rotation(flip @ M, path, f"{where}.transform")
        cams.append(CameraCalibration(name, (int(w), int(h)), K, R, -R @ C, dist))
    return cams


def _matrix(v, shape, path, field: str) -> np.ndarray:
    try:
        a = np.asarray(v, dtype=np.float64)
    except (TypeError, ValueError):
        raise FormatError(path, field, "expected numbers") from None
    if a.shape != shape or not np.all(np.isfinite(a)):
        raise FormatError(path, field, f"expected finite numbers of shape {shape}")
    return a


def _parse_toml(text: str, path) -> list[CameraCalibration]:
    import cv2

    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise FormatError(path, None, f"not valid TOML ({e})") from None
    cams = []
    tables = [(k, v) for k, v in doc.items() if isinstance(v, dict) and k != "metadata"]
    if len(tables) > MAX_CAMERAS:
        raise FormatError(path, None, f"more than {MAX_CAMERAS} cameras")
    for key, t in tables:
        name = t.get("name", key)
        if not isinstance(name, str) or not name:
            raise FormatError(path, f"{key}.name", "expected a non-empty string")
        size = _matrix(t.get("size"), (2,), path, f"{key}.size")
        if not np.all((size >= 1) & (size <= 1 << 16)):
            raise FormatError(path, f"{key}.size", "out of range")
        K = _matrix(t.get("matrix"), (3, 3), path, f"{key}.matrix")
        if K[0, 0] <= 0 or K[1, 1] <= 0:
            raise FormatError(path, f"{key}.matrix", "focal lengths must be positive")
        d = t.get("distortions", [0.0, 0.0, 0.0, 0.0])
        dist = _matrix(d, (len(d),) if isinstance(d, list) else (4,), path, f"{key}.distortions")
        if len(dist) not in (4, 5):
            raise FormatError(path, f"{key}.distortions", "expected 4 or 5 numbers")
        dist = np.concatenate([dist, np.zeros(5 - len(dist))])
        rvec = _matrix(t.get("rotation"), (3,), path, f"{key}.rotation")
        tvec = _matrix(t.get("translation"), (3,), path, f"{key}.translation")
        if t.get("fisheye", False):
            raise FormatError(path, f"{key}.fisheye", "fisheye cameras are not supported")
        R = cv2.Rodrigues(rvec)[0]
        cams.append(CameraCalibration(name, (int(size[0]), int(size[1])), K, R, tvec * 1000.0, dist))
    return cams


def calibration_toml(calib: Calibration) -> str:
    """The Pose2Sim / OpenCV TOML text of ``calib`` (translation in metres)."""
    import cv2

    def arr(a) -> str:
        return "[ " + ", ".join(repr(float(x)) for x in np.ravel(a)) + ",]"

    lines = []
    for c in calib.cameras:
        rvec = cv2.Rodrigues(np.asarray(c.R, dtype=np.float64))[0].ravel()
        lines += [f"[{_toml_key(c.name)}]", f"name = {_toml_str(c.name)}", f"size = {arr(c.size)}",
                  "matrix = [ " + ", ".join(arr(row) for row in c.K) + ",]",
                  f"distortions = {arr(c.dist[:5])}", f"rotation = {arr(rvec)}",
                  f"translation = {arr(np.asarray(c.t) / 1000.0)}", "fisheye = false", ""]
    return "\n".join(lines)


def _toml_str(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _toml_key(s: str) -> str:
    return s if s.replace("_", "").replace("-", "").isalnum() and s.isascii() else _toml_str(s)


def write_calibration(path: str | os.PathLike, calib: Calibration) -> None:
    """Write ``calib`` as Pose2Sim / OpenCV TOML, atomically."""
    write_text(path, calibration_toml(calib))
