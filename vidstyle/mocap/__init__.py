"""Mocap core: BVH I/O, skeleton, motion data model and forward kinematics.

>>> from vidstyle.mocap import read_bvh, forward_kinematics
>>> motion = read_bvh("walk.bvh")                      # doctest: +SKIP
>>> positions, rotations = forward_kinematics(motion)   # (F, J, 3), (F, J, 3, 3)  # doctest: +SKIP
"""

from .bvh import BVHError, format_bvh, parse_bvh, read_bvh, write_bvh
from .kinematics import end_site_positions, forward_kinematics, global_positions
from .motion import Motion, facing_directions
from .skeleton import Skeleton, mirror_name

__all__ = [
    "BVHError",
    "Motion",
    "Skeleton",
    "end_site_positions",
    "facing_directions",
    "format_bvh",
    "forward_kinematics",
    "global_positions",
    "mirror_name",
    "parse_bvh",
    "read_bvh",
    "write_bvh",
]
