"""Motion operations: slicing, concatenation, resampling, mirroring, facing normalisation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

from vidstyle.mocap import Motion, Skeleton, global_positions, mirror_name


def _humanoid() -> Skeleton:
    names = ["Hips", "LeftUpLeg", "LeftLeg", "RightUpLeg", "RightLeg", "Spine", "LeftArm", "LeftForeArm",
             "RightArm", "RightForeArm", "Head"]
    parents = [-1, 0, 1, 0, 3, 0, 5, 6, 5, 8, 5]
    offsets = [[0, 0, 0], [1, -0.5, 0], [0, -4, 0], [-1, -0.5, 0], [0, -4, 0], [0, 3, 0], [1.5, 1, 0], [2.5, 0, 0],
               [-1.5, 1, 0], [-2.5, 0, 0], [0, 2, 0]]
    return Skeleton(names, np.array(parents), np.array(offsets, float))


def _motion(rng, F=40, fps=30.0) -> Motion:
    sk = _humanoid()
    rv = np.cumsum(rng.normal(scale=0.05, size=(F, sk.n_joints, 3)), axis=0)
    quats = Rotation.from_rotvec(rv.reshape(-1, 3)).as_quat().reshape(F, sk.n_joints, 4)
    root = np.cumsum(rng.normal(size=(F, 3)), axis=0) + [0, 9, 0]
    return Motion(sk, quats, None, fps, root_positions=root)


def test_slicing_and_concatenation(rng):
    m = _motion(rng)
    a, b = m[:15], m[15:]
    assert (a.n_frames, b.n_frames) == (15, 25)
    c = Motion.concatenate([a, b])
    assert np.array_equal(c.rotations, m.rotations) and np.array_equal(c.translations, m.translations)
    assert m[3].n_frames == 1 and np.array_equal(m[3].rotations[0], m.rotations[3])
    with pytest.raises(ValueError):
        Motion.concatenate([m, m.resample(60)])


def test_resample_to_half_rate_keeps_every_other_frame(rng):
    m = _motion(rng, F=41, fps=60.0)
    h = m.resample(30.0)
    assert h.n_frames == 21 and h.fps == 30.0
    assert np.allclose(global_positions(h), global_positions(m)[::2], atol=1e-9)


def test_resample_upsampling_is_slerp(rng):
    m = _motion(rng, F=10, fps=10.0)
    u = m.resample(40.0)
    assert u.n_frames == 37
    j = 6
    ref = Slerp(np.arange(10) / 10.0, Rotation.from_quat(m.rotations[:, j]))(np.arange(37) / 40.0)
    assert np.allclose((ref.inv() * Rotation.from_quat(u.rotations[:, j])).magnitude(), 0, atol=1e-9)
    # constant angular velocity: the midpoint of a 0->80 degree turn is 40 degrees
    sk = m.skeleton
    quats = np.tile([0, 0, 0, 1.0], (2, sk.n_joints, 1))
    quats[1, 5] = Rotation.from_euler("y", 80, degrees=True).as_quat()
    two = Motion(sk, quats, None, 1.0)
    mid = two.resample(2.0).rotation(5)[1]
    assert np.isclose(mid.magnitude(), np.deg2rad(40))
    assert np.allclose(two.resample(2.0).root_positions[1], 0)


def test_mirror_reflects_world_and_swaps_sides(rng):
    m = _motion(rng)
    mm = m.mirror()
    p, q = global_positions(m), global_positions(mm)
    swap = m.skeleton.mirror_map()
    assert m.skeleton.names[swap[1]] == "RightUpLeg"
    assert np.allclose(q, p[:, swap] * [-1, 1, 1], atol=1e-9)
    back = mm.mirror()
    assert np.allclose(global_positions(back), p, atol=1e-9)


def test_mirror_names():
    assert mirror_name("LeftArm") == "RightArm"
    assert mirror_name("RHipJoint") == "LHipJoint"
    assert mirror_name("LThumb") == "RThumb"
    assert mirror_name("Hips") == "Hips"
    assert mirror_name("LowerBack") == "LowerBack"  # "L" followed by lower case is not a side marker


def test_facing_normalisation(rng):
    m = _motion(rng)
    for target in (0.0, 1.0, -2.5):
        n = m.normalize_facing(frame=5, angle=target)
        assert np.isclose(np.angle(np.exp(1j * (n.facing_angles()[5] - target))), 0, atol=1e-9)
        assert np.allclose(n.root_positions[5, [0, 2]], 0, atol=1e-9)
        assert np.isclose(n.root_positions[5, 1], m.root_positions[5, 1])
    # rotation about the vertical preserves poses: all pairwise joint distances per frame unchanged
    r = m.rotate_about_vertical(0.7)
    d0 = np.linalg.norm(global_positions(m)[:, :, None] - global_positions(m)[:, None], axis=-1)
    d1 = np.linalg.norm(global_positions(r)[:, :, None] - global_positions(r)[:, None], axis=-1)
    assert np.allclose(d0, d1)
    delta = np.angle(np.exp(1j * (r.facing_angles() - m.facing_angles())))
    assert np.allclose(delta, 0.7)


def test_facing_angle_convention():
    sk = _humanoid()
    rest = Motion(sk, np.tile([0, 0, 0, 1.0], (1, sk.n_joints, 1)), None, 30.0)
    # rest pose: left side (+X) , so the character faces +Z
    assert np.isclose(rest.facing_angles()[0], 0.0)
    turned = rest.rotate_about_vertical(np.pi / 2)  # +Z turns to +X
    assert np.isclose(turned.facing_angles()[0], np.pi / 2)


@pytest.mark.parametrize("new", ["down3", "up", "random", "keys"])
def test_quat_slerp_is_scipys_slerp_to_the_last_bit(rng, new):
    """vidstyle.mocap.quat.slerp against scipy's Slerp joint by joint, bit for bit: resampling down (a third
    of the intervals used), up (every interval used several times), at random times, and at the keys."""
    from vidstyle.mocap.quat import slerp

    F, J = 31, 5
    times = np.cumsum(rng.uniform(0.5, 1.5, F))
    quats = rng.standard_normal((F, J, 4))
    new_times = {"down3": times[::3], "up": np.linspace(times[0], times[-1], 4 * F),
                 "random": np.sort(rng.uniform(times[0], times[-1], 17)), "keys": times}[new]
    got = slerp(times, quats, new_times)
    for j in range(J):
        want = Slerp(times, Rotation.from_quat(quats[:, j]))(new_times).as_quat()
        assert np.array_equal(got[:, j], want), j
