"""The real CMU clips: all parse, metadata agrees with clips.csv, frame 0 is a T-pose."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from vidstyle.mocap import global_positions, read_bvh


def test_all_cmu_clips_parse(cmu_dir):
    rows = {r["file"]: r for r in csv.DictReader(open(cmu_dir / "clips.csv"))}
    files = sorted(cmu_dir.glob("*.bvh"))
    assert len(files) == 86
    for f in files:
        m = read_bvh(f)
        assert m.n_joints == 31, f
        assert m.fps == 120.0, f
        assert m.n_frames == int(rows[f.name]["frames"]), f
        assert np.isfinite(m.rotations).all()


@pytest.mark.parametrize("name", ["01_01.bvh", "02_01.bvh", "05_02.bvh", "08_01.bvh"])
def test_cmu_frame0_is_t_pose_with_horizontal_arms(cmu_dir, name):
    m = read_bvh(cmu_dir / name)
    pos = global_positions(m[0])[0]
    ix = m.skeleton.index
    for side in ("Left", "Right"):
        arm = pos[ix(f"{side}Hand")] - pos[ix(f"{side}Arm")]
        elevation = np.degrees(np.arcsin(abs(arm[1]) / np.linalg.norm(arm)))
        assert elevation < 15, (name, side, elevation)
        assert np.linalg.norm(arm) > 5  # a real arm, not a degenerate one
    # hands far apart, feet below the hips, head above them
    assert np.linalg.norm(pos[ix("LeftHand")] - pos[ix("RightHand")]) > 15
    assert pos[ix("Head")][1] > pos[ix("Hips")][1] > pos[ix("LeftFoot")][1]
