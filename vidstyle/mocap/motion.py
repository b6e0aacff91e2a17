"""Motion: a skeleton animated over frames, and pure operations on motions.

Shapes (F frames, J joints):

- ``rotations``: ``(F, J, 4)`` local joint rotations as unit quaternions, scalar-last ``(x, y, z, w)``
  (scipy's :class:`~scipy.spatial.transform.Rotation` convention);
- ``translations``: ``(F, J, 3)`` local joint translations: the root's position, and for every other joint
  its rest offset unless the file animates it with position channels (then the channel values replace
  the offset, as most BVH readers do);
- ``fps``: frames per second.

The vertical axis is +Y and a character at facing angle 0 looks along +Z (the BVH convention). Every
operation returns a new :class:`Motion`; none modifies its input.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from .quat import slerp
from .skeleton import Skeleton

UP = np.array([0.0, 1.0, 0.0])


class Motion:
    """An animated skeleton. See the module docstring for array shapes and conventions."""

    def __init__(
        self,
        skeleton: Skeleton,
        rotations: np.ndarray,
        translations: np.ndarray | None = None,
        fps: float = 30.0,
        root_positions: np.ndarray | None = None,
    ) -> None:
        rotations = np.asarray(rotations, dtype=np.float64)
        J = skeleton.n_joints
        if rotations.ndim != 3 or rotations.shape[1:] != (J, 4):
            raise ValueError(f"rotations must be (frames, {J}, 4), got {rotations.shape}")
        F = rotations.shape[0]
        if translations is None:
            translations = np.broadcast_to(skeleton.offsets, (F, J, 3)).copy()
        translations = np.asarray(translations, dtype=np.float64)
        if translations.shape != (F, J, 3):
            raise ValueError(f"translations must be ({F}, {J}, 3), got {translations.shape}")
        if root_positions is not None:
            root_positions = np.asarray(root_positions, dtype=np.float64)
            if root_positions.shape != (F, 3):
                raise ValueError(f"root_positions must be ({F}, 3), got {root_positions.shape}")
            translations = translations.copy()
            translations[:, 0] = root_positions
        if not fps > 0:
            raise ValueError(f"fps must be positive, got {fps}")
        # np.linalg.norm(rotations, axis=-1, keepdims=True) to the bit (its reduction over the 4 components
        # adds them in order), without a reduction over a length-4 axis
        x, y, z, w = (rotations[..., k] for k in range(4))
        norms = np.sqrt(x * x + y * y + z * z + w * w)[..., None]
        if F and not np.all(norms > 0):
            raise ValueError("rotations contain a zero quaternion")
        self.skeleton = skeleton
        self.rotations = rotations / np.where(norms > 0, norms, 1.0)
        self.translations = translations
        self.fps = float(fps)

    # ------------------------------------------------------------------ basics
    @property
    def n_frames(self) -> int:
        return self.rotations.shape[0]

    @property
    def n_joints(self) -> int:
        return self.skeleton.n_joints

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame."""
        return max(self.n_frames - 1, 0) / self.fps

    @property
    def root_positions(self) -> np.ndarray:
        """(F, 3) position of the first root joint."""
        return self.translations[:, 0]

    def __len__(self) -> int:
        return self.n_frames

    def __repr__(self) -> str:
        return f"Motion({self.n_frames} frames, {self.n_joints} joints, {self.fps:g} fps)"

    def __getitem__(self, index: slice | int | np.ndarray) -> "Motion":
        """Frame slicing; an int gives a one-frame motion."""
        if isinstance(index, (int, np.integer)):
            index = slice(int(index), int(index) + 1 if int(index) != -1 else None)
        return Motion(self.skeleton, self.rotations[index], self.translations[index], self.fps)

    def copy(self) -> "Motion":
        return Motion(self.skeleton.copy(), self.rotations.copy(), self.translations.copy(), self.fps)

    def rotation(self, joint: int | str) -> Rotation:
        """scipy Rotation of one joint over all frames."""
        j = self.skeleton.index(joint) if isinstance(joint, str) else joint
        return Rotation.from_quat(self.rotations[:, j])

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_euler(
        cls,
        skeleton: Skeleton,
        angles_deg: np.ndarray,
        root_positions: np.ndarray,
        fps: float,
        order: str = "ZYX",
    ) -> "Motion":
        """Build from intrinsic Euler angles ``(F, J, 3)`` in degrees, in the given axis order."""
        angles_deg = np.asarray(angles_deg, dtype=np.float64)
        F, J, _ = angles_deg.shape
        quats = Rotation.from_euler(order, angles_deg.reshape(-1, 3), degrees=True).as_quat()
        return cls(skeleton, quats.reshape(F, J, 4), None, fps, root_positions=root_positions)

    # ------------------------------------------------------------------ operations
    @staticmethod
    def concatenate(motions: Sequence["Motion"]) -> "Motion":
        """Frames of all motions one after another (same hierarchy and fps required)."""
        if not motions:
            raise ValueError("nothing to concatenate")
        first = motions[0]
        for m in motions[1:]:
            if not first.skeleton.same_hierarchy(m.skeleton):
                raise ValueError("cannot concatenate motions with different skeletons")
            if abs(m.fps - first.fps) > 1e-9 * first.fps:
                raise ValueError(f"cannot concatenate motions at {first.fps:g} and {m.fps:g} fps")
        return Motion(
            first.skeleton,
            np.concatenate([m.rotations for m in motions]),
            np.concatenate([m.translations for m in motions]),
            first.fps,
        )

    def resample(self, fps: float) -> "Motion":
        """The same motion sampled at ``fps``: joint rotations by slerp, translations linearly.

        New frames are at times 0, 1/fps, ... up to the last original frame's time.
        """
        if not fps > 0:
            raise ValueError(f"fps must be positive, got {fps}")
        F = self.n_frames
        if F < 2:
            return Motion(self.skeleton, self.rotations, self.translations, fps)
        t_old = np.arange(F) / self.fps
        n_new = int(np.floor(self.duration * fps + 1e-9)) + 1
        t_new = np.arange(n_new) / fps
        t_new = np.minimum(t_new, t_old[-1])
        # scipy's Slerp per joint, to the last bit, at a third of its time (quat.slerp)
        rots = slerp(t_old, self.rotations, t_new)
        flat = self.translations.reshape(F, -1)
        trans = np.empty((n_new, flat.shape[1]))
        for c in range(flat.shape[1]):
            trans[:, c] = np.interp(t_new, t_old, flat[:, c])
        return Motion(self.skeleton, rots, trans.reshape(n_new, self.n_joints, 3), fps)

    def mirror(self, axis: int = 0) -> "Motion":
        """Left/right mirror image: reflect the world through the plane normal to ``axis`` (default X,
        the lateral axis of a character facing +Z) and swap left and right joints.

        For the reflection M = diag(±1), a rotation R becomes M R M; for a quaternion that keeps the
        component along ``axis`` and the scalar, and negates the other two vector components.
        """
        mm = self.skeleton.mirror_map()
        sign = np.ones(3)
        sign[axis] = -1.0
        qsign = np.append(-sign, 1.0)  # quaternion vector part transforms as a pseudo-vector
        sk = self.skeleton
        end_sites = {}
        for j in range(sk.n_joints):
            if int(mm[j]) in sk.end_sites:
                end_sites[j] = sk.end_sites[int(mm[j])] * sign
        skeleton = Skeleton(list(sk.names), sk.parents.copy(), sk.offsets[mm] * sign, list(sk.channels), end_sites)
        # the swap must map the hierarchy onto itself: parent(mirror(j)) == mirror(parent(j))
        mapped_parents = np.where(sk.parents >= 0, mm[np.maximum(sk.parents, 0)], -1)
        if not np.array_equal(sk.parents[mm], mapped_parents):
            raise ValueError("left/right joint names do not form a symmetric hierarchy")
        rotations = self.rotations[:, mm] * qsign
        translations = self.translations[:, mm] * sign
        return Motion(skeleton, rotations, translations, self.fps)

    def rotate_about_vertical(self, angle: float | np.ndarray, pivot: np.ndarray | None = None) -> "Motion":
        """Rotate the whole motion by ``angle`` radians about the vertical (+Y) axis through ``pivot``
        (default the world origin). ``angle`` may be a scalar or ``(F,)``. The rotation is that of
        :class:`~vidstyle.mocap.placement.Placement` (turns +Z towards +X)."""
        from .placement import yaw_quat
        from .quat import qmul

        angle = np.broadcast_to(np.asarray(angle, dtype=np.float64), (self.n_frames,))
        pivot = np.zeros(3) if pivot is None else np.asarray(pivot, dtype=np.float64)
        c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
        rotations = self.rotations.copy()
        translations = self.translations.copy()
        for r in np.flatnonzero(self.skeleton.parents < 0):
            rotations[:, r] = qmul(yaw_quat(angle), self.rotations[:, r])
            p = self.translations[:, r] - pivot
            translations[:, r, 0] = (c * p[:, [0]] + s * p[:, [2]])[:, 0] + pivot[0]
            translations[:, r, 2] = (-s * p[:, [0]] + c * p[:, [2]])[:, 0] + pivot[2]
        return Motion(self.skeleton, rotations, translations, self.fps)

    def place(self, placement) -> "Motion":
        """Every root moved by a :class:`~vidstyle.mocap.placement.Placement` (yaw, then floor offset)."""
        out = self.rotate_about_vertical(placement.theta)
        return out.translate(np.array([placement.x0, 0.0, placement.z0]))

    def translate(self, offset: np.ndarray) -> "Motion":
        """Move every root by ``offset`` ((3,) or (F, 3))."""
        translations = self.translations.copy()
        roots = np.flatnonzero(self.skeleton.parents < 0)
        translations[:, roots] += np.asarray(offset, dtype=np.float64)[..., None, :] if np.ndim(offset) == 2 else offset
        return Motion(self.skeleton, self.rotations.copy(), translations, self.fps)

    def facing_angles(self) -> np.ndarray:
        """(F,) facing angle in radians about +Y; 0 = looking along +Z, pi/2 = along +X."""
        d = facing_directions(self)
        return np.arctan2(d[:, 0], d[:, 2])

    def normalize_facing(self, frame: int = 0, angle: float = 0.0, origin: bool = True) -> "Motion":
        """Rotate about the vertical axis so that the character faces ``angle`` (0 = +Z) at ``frame``,
        and (``origin``) move it so that its root is above the world origin at that frame
        (:meth:`~vidstyle.mocap.placement.Placement.facing`)."""
        from .placement import Placement

        P = Placement.facing(float(self.facing_angles()[frame]), self.root_positions[frame], angle, origin)
        return self.place(P)


def _find(names: list[str], candidates: Sequence[str]) -> int | None:
    lower = [n.lower() for n in names]
    for c in candidates:
        if c.lower() in lower:
            return lower.index(c.lower())
    return None


def facing_directions(motion: Motion) -> np.ndarray:
    """(F, 3) horizontal unit vector the character faces, per frame.

    From the left-right axis of hips and shoulders when the skeleton names them (robust to a
    bent spine); otherwise from the root joint's local +Z axis.
    """
    from .kinematics import forward_kinematics

    names = motion.skeleton.names
    pairs = [
        (("LeftUpLeg", "LHip", "LeftHip", "l_hip", "LThigh"), ("RightUpLeg", "RHip", "RightHip", "r_hip", "RThigh")),
        (("LeftArm", "LShoulder", "LeftShoulder", "l_shoulder"), ("RightArm", "RShoulder", "RightShoulder", "r_shoulder")),
    ]
    found = [(_find(names, left), _find(names, right)) for left, right in pairs]
    found = [(a, b) for a, b in found if a is not None and b is not None]
    if found:
        pos, _ = forward_kinematics(motion)
        across = sum(pos[:, a] - pos[:, b] for a, b in found)
        fwd = np.cross(across, UP)
    else:
        fwd = Rotation.from_quat(motion.rotations[:, 0]).apply([0.0, 0.0, 1.0])
    fwd[:, 1] = 0.0
    n = np.linalg.norm(fwd, axis=1, keepdims=True)
    return fwd / np.where(n > 1e-12, n, 1.0)
