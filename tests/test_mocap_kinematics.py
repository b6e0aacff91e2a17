"""Forward kinematics against an independent per-joint 4x4 reference and hand-computed poses."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from bvh_samples import TWO_JOINT
from vidstyle.mocap import Motion, Skeleton, end_site_positions, forward_kinematics, parse_bvh
from vidstyle.mocap.kinematics import quat_to_matrix
from vidstyle.mocap.quat import from_intrinsic_euler, qmul


def _reference_fk(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    """Slow, obviously-correct FK: a 4x4 homogeneous matrix per joint and frame, built with scipy."""
    F, J = motion.n_frames, motion.n_joints
    pos = np.zeros((F, J, 3))
    rot = np.zeros((F, J, 3, 3))
    for f in range(F):
        world = [None] * J
        for j in range(J):
            local = np.eye(4)
            local[:3, :3] = Rotation.from_quat(motion.rotations[f, j]).as_matrix()
            local[:3, 3] = motion.translations[f, j]
            p = motion.skeleton.parents[j]
            world[j] = local if p < 0 else world[p] @ local
            pos[f, j] = world[j][:3, 3]
            rot[f, j] = world[j][:3, :3]
    return pos, rot


def _random_motion(rng, J=12, F=9) -> Motion:
    parents = np.array([-1] + [int(rng.integers(0, j)) for j in range(1, J)])
    sk = Skeleton([f"j{j}" for j in range(J)], parents, rng.normal(size=(J, 3)))
    rots = Rotation.random(F * J, random_state=int(rng.integers(1 << 30))).as_quat().reshape(F, J, 4)
    return Motion(sk, rots, None, 30.0, root_positions=rng.normal(size=(F, 3)))


def test_fk_matches_reference(rng):
    m = _random_motion(rng)
    pos, rot = forward_kinematics(m)
    ref_pos, ref_rot = _reference_fk(m)
    assert np.allclose(pos, ref_pos, atol=1e-10)
    assert np.allclose(rot, ref_rot, atol=1e-10)


def test_compiled_fk_equals_numpy_reference_to_the_bit(rng):
    # forward_kinematics (the compiled loop) replaces the vectorised numpy version on the promise of the same
    # bits: positions and rotations, with and without matrices, several roots, one frame and none
    from vidstyle.mocap.kinematics import forward_kinematics_numpy

    for J, F in ((12, 9), (31, 200), (5, 1), (4, 0)):
        m = _random_motion(rng, J, max(F, 1))
        if F == 0:
            m = m[:0]
        for want in (True, False):
            pos, rot = forward_kinematics(m, return_matrices=want)
            ref_pos, ref_rot = forward_kinematics_numpy(m, return_matrices=want)
            assert pos.shape == (F, J, 3) and np.array_equal(pos, ref_pos)
            assert (rot is None) == (ref_rot is None) == (not want)
            if want:
                assert rot.shape == (F, J, 3, 3) and np.array_equal(rot, ref_rot)
    # two roots (a second hierarchy in the same file)
    sk = Skeleton(["a", "b", "c", "d"], np.array([-1, 0, -1, 2]), rng.normal(size=(4, 3)))
    rots = Rotation.random(3 * 4, random_state=3).as_quat().reshape(3, 4, 4)
    m = Motion(sk, rots, np.broadcast_to(sk.offsets, (3, 4, 3)) + rng.normal(size=(3, 4, 3)), 30.0)
    assert np.array_equal(forward_kinematics(m)[0], forward_kinematics_numpy(m)[0])
    assert np.allclose(forward_kinematics(m)[0], _reference_fk(m)[0], atol=1e-10)


def test_fk_hand_computed_pose():
    m = parse_bvh(TWO_JOINT)
    pos, _ = forward_kinematics(m)
    # frame 0: rest pose, root at (0, 10, 0)
    assert np.allclose(pos[0], [[0, 10, 0], [0, 12, 0], [1, 9, 0], [-1, 9, 0]])
    # frame 1: root at x=1 rotated 90 deg about Z: local +Y -> world -X, local +X -> world +Y
    assert np.allclose(pos[1, 1], [1 - 2, 10, 0])
    assert np.allclose(pos[1, 2], [1 + 1, 10 + 1, 0])
    owners, ends = end_site_positions(m)
    assert owners == [1, 2, 3]
    # frame 1 left leg: Xrotation 45 then root Z 90: end offset (0,-3,0) -> local Rx45 -> (0,-2.121,-2.121)
    # then Rz90 maps (x, y, z) -> (-y, x, z)
    c = 3 / np.sqrt(2)
    assert np.allclose(ends[1, 1], pos[1, 2] + np.array([c, 0, -c]))
    # frame 2: root yaw 90 about Y maps local +X -> world -Z; chest rotated about Z by 30 (then Y 0, X 0)
    assert np.allclose(pos[2, 2], [2, 9, -1])


def test_quaternion_helpers_match_scipy(rng):
    a = Rotation.random(50, random_state=1)
    b = Rotation.random(50, random_state=2)
    prod = qmul(a.as_quat(), b.as_quat())
    assert np.allclose(Rotation.from_quat(prod).as_matrix(), (a * b).as_matrix(), atol=1e-12)
    assert np.allclose(quat_to_matrix(a.as_quat()), a.as_matrix(), atol=1e-12)
    for seq in ("ZYX", "XYZ", "YXZ", "ZXY", "XZY", "YZX"):
        ang = rng.uniform(-180, 180, size=(40, 3))
        q = from_intrinsic_euler(seq, ang)
        assert np.allclose(Rotation.from_quat(q).as_matrix(), Rotation.from_euler(seq, ang, degrees=True).as_matrix(), atol=1e-12)


def test_compose_and_normalise_equal_scipy_to_the_bit(rng):
    # compose replaces Rotation.__mul__ in hot loops on the promise that outputs stay byte-identical:
    # every component must equal scipy's exactly (not approximately), broadcasting included
    from vidstyle.mocap.quat import compose, normalise

    a = Rotation.random(5000, random_state=int(rng.integers(1 << 30)))
    b = Rotation.random(5000, random_state=int(rng.integers(1 << 30)))
    assert np.array_equal(compose(a.as_quat(), b.as_quat()), (a * b).as_quat())
    assert np.array_equal(compose(a.as_quat()[:1], b.as_quat()), (a[0] * b).as_quat())
    grid = compose(a.as_quat()[:7, None], b.as_quat()[None, :3])
    assert grid.shape == (7, 3, 4)
    assert np.array_equal(grid[4], (a[4] * b[:3]).as_quat())
    raw = rng.normal(size=(2000, 4)) * rng.uniform(0.1, 10, size=(2000, 1))
    assert np.array_equal(normalise(raw), Rotation.from_quat(raw).as_quat())
    # the product is the rotation of b followed by a (independent truth: the matrices)
    assert np.allclose(Rotation.from_quat(compose(a.as_quat(), b.as_quat())).as_matrix(),
                       a.as_matrix() @ b.as_matrix(), atol=1e-12)
