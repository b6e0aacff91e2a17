"""Skeleton: the joint hierarchy of a motion (names, parents, rest offsets, BVH channels).

Shapes: ``parents`` is ``(J,)`` int with ``-1`` for a root; ``offsets`` is ``(J, 3)`` in the file's
length unit. Joints are stored in file (depth-first) order, so ``parents[j] < j`` for every non-root
joint; forward kinematics relies on that.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

POSITION_CHANNELS = ("Xposition", "Yposition", "Zposition")
ROTATION_CHANNELS = ("Xrotation", "Yrotation", "Zrotation")
ALL_CHANNELS = POSITION_CHANNELS + ROTATION_CHANNELS

_SIDE_PATTERNS = (
    (re.compile(r"^Left(?=[A-Z_])"), "Right"),
    (re.compile(r"^Right(?=[A-Z_])"), "Left"),
    (re.compile(r"^left(?=[A-Z_])"), "right"),
    (re.compile(r"^right(?=[A-Z_])"), "left"),
    (re.compile(r"^L(?=[A-Z_])"), "R"),
    (re.compile(r"^R(?=[A-Z_])"), "L"),
    (re.compile(r"^l_"), "r_"),
    (re.compile(r"^r_"), "l_"),
    (re.compile(r"(?<=[a-z_])Left$"), "Right"),
    (re.compile(r"(?<=[a-z_])Right$"), "Left"),
    (re.compile(r"_L$"), "_R"),
    (re.compile(r"_R$"), "_L"),
)


def mirror_name(name: str) -> str:
    """The name of the joint on the other side (``LeftArm`` -> ``RightArm``, ``LHipJoint`` ->
    ``RHipJoint``); a name with no side marker maps to itself."""
    for pattern, repl in _SIDE_PATTERNS:
        if pattern.search(name):
            return pattern.sub(repl, name, count=1)
    return name


@dataclass(eq=False)
class Skeleton:
    """Joint hierarchy.

    Attributes
    ----------
    names : list of J joint names, file order.
    parents : (J,) int array, parent index or -1 for a root.
    offsets : (J, 3) float array, rest translation of each joint relative to its parent.
    channels : list of J tuples of BVH channel names (e.g. ``("Zrotation", "Yrotation", "Xrotation")``).
    end_sites : dict joint index -> (3,) offset of that joint's End Site (BVH leaf markers).
    """

    names: list[str]
    parents: np.ndarray
    offsets: np.ndarray
    channels: list[tuple[str, ...]] = field(default_factory=list)
    end_sites: dict[int, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.names = list(self.names)
        self.parents = np.asarray(self.parents, dtype=np.int64)
        self.offsets = np.asarray(self.offsets, dtype=np.float64).reshape(-1, 3)
        n = len(self.names)
        if self.parents.shape != (n,) or self.offsets.shape != (n, 3):
            raise ValueError(
                f"skeleton arrays disagree: {n} names, parents {self.parents.shape}, offsets {self.offsets.shape}"
            )
        if not self.channels:
            self.channels = [
                (POSITION_CHANNELS + ("Zrotation", "Yrotation", "Xrotation"))
                if p < 0
                else ("Zrotation", "Yrotation", "Xrotation")
                for p in self.parents
            ]
        self.channels = [tuple(c) for c in self.channels]
        if len(self.channels) != n:
            raise ValueError(f"{len(self.channels)} channel lists for {n} joints")
        for j, p in enumerate(self.parents):
            if p >= j:
                raise ValueError(f"joint {self.names[j]!r}: parent index {p} is not before it (file order)")
        if len(set(self.names)) != n:
            raise ValueError("joint names are not unique")
        self.end_sites = {int(k): np.asarray(v, dtype=np.float64).reshape(3) for k, v in self.end_sites.items()}

    @property
    def n_joints(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(f"no joint named {name!r}") from None

    def children(self, j: int) -> list[int]:
        return [int(c) for c in np.flatnonzero(self.parents == j)]

    def has_position_channels(self) -> np.ndarray:
        """(J,) bool: joints whose BVH channels include positions (their offset is animated)."""
        return np.array([any(c in POSITION_CHANNELS for c in ch) for ch in self.channels])

    def mirror_map(self) -> np.ndarray:
        """(J,) int: index of each joint's left/right counterpart (itself for central joints)."""
        lookup = {n: i for i, n in enumerate(self.names)}
        return np.array([lookup.get(mirror_name(n), i) for i, n in enumerate(self.names)])

    def same_hierarchy(self, other: "Skeleton") -> bool:
        return self.names == other.names and np.array_equal(self.parents, other.parents)

    def copy(self) -> "Skeleton":
        return Skeleton(
            list(self.names),
            self.parents.copy(),
            self.offsets.copy(),
            list(self.channels),
            {k: v.copy() for k, v in self.end_sites.items()},
        )
