"""Synthetic feature files with known per-frame labels, for tests and benchmarks of the recognition stage.

Descriptors of a frame of class c are drawn from a mixture over *prototypes*: each class owns a few
prototypes and shares others with every class (so single descriptors are ambiguous and only their
statistics over a frame context tell classes apart). A performer shifts every prototype a little and a
view shifts it more, so "unseen performer" and "unseen view" are harder than the training data, as in
real video. The files follow the features / labels / ``dataset.json`` contracts of :mod:`.io`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .io import VideoFeatures

ACTIONS = ["Jab", "Hook", "Uppercut", "Defense", "LowKick", "RoundhouseKick"]
CLASSES = ACTIONS + ["Guard", "Step"]


@dataclass
class SyntheticWorld:
    """The generative model: prototypes, class mixtures, performer and view shifts."""

    classes: list[str]
    prototypes: np.ndarray  # (P, d)
    weights: np.ndarray  # (K, P) mixture weights per class
    performer_shift: dict[str, np.ndarray]
    view_shift: dict[str, np.ndarray]
    noise: float
    n_points: float
    dtype: str = "float32"

    @classmethod
    def make(
        cls,
        rng: np.random.Generator,
        dim: int = 64,
        classes: list[str] | None = None,
        own: int = 4,
        shared: int = 8,
        own_weight: float = 0.5,
        performers: list[str] = (),
        views: list[str] = (),
        performer_scale: float = 0.25,
        view_scale: float = 0.35,
        noise: float = 0.6,
        n_points: float = 10,
        dtype: str = "float32",
    ) -> "SyntheticWorld":
        classes = list(classes or CLASSES)
        K = len(classes)
        P = K * own + shared
        protos = rng.normal(size=(P, dim))
        W = np.zeros((K, P))
        for k in range(K):
            W[k, k * own : (k + 1) * own] = own_weight / own
            W[k, K * own :] = (1 - own_weight) / shared
        return cls(
            classes,
            protos,
            W,
            {p: performer_scale * rng.normal(size=(P, dim)) for p in performers},
            {v: view_scale * rng.normal(size=(P, dim)) for v in views},
            noise,
            n_points,
            dtype,
        )

    def video(self, rng: np.random.Generator, labels: list[str], performer: str, view: str, name: str = "") -> VideoFeatures:
        idx = {c: i for i, c in enumerate(self.classes)}
        n = len(labels)
        counts = rng.poisson(self.n_points, size=n)
        counts[rng.random(n) < 0.03] = 0  # frames without motion have no points
        frame_index = np.repeat(np.arange(n), counts)
        k = np.array([idx[labels[f]] for f in frame_index], np.int64)
        cum = np.cumsum(self.weights[k], axis=1)
        proto = (rng.random(len(k))[:, None] > cum).sum(axis=1)
        proto = np.minimum(proto, self.prototypes.shape[0] - 1)
        shift = self.performer_shift.get(performer, 0.0) + self.view_shift.get(view, 0.0)
        base = self.prototypes + shift
        desc = base[proto] + self.noise * rng.normal(size=(len(k), self.prototypes.shape[1]))
        if self.dtype == "uint8":
            desc = np.clip(desc * 32 + 128, 0, 255).astype(np.uint8)
        else:
            desc = desc.astype(np.float32)
        return VideoFeatures(desc, frame_index, n, video=name)


def single_sequence(rng: np.random.Generator, action: str, reps: tuple[int, int] = (3, 5)) -> list[str]:
    seq = ["Guard"] * int(rng.integers(4, 10))
    for _ in range(int(rng.integers(*reps))):
        seq += [action] * int(rng.integers(8, 15))
        seq += ["Guard"] * int(rng.integers(4, 10))
        if rng.random() < 0.3:
            seq += ["Step"] * int(rng.integers(6, 12))
    return seq


def performance_sequence(rng: np.random.Generator, n_actions: int = 12, actions: list[str] | None = None) -> list[str]:
    actions = actions or ACTIONS
    seq = ["Guard"] * int(rng.integers(4, 10))
    for _ in range(n_actions):
        seq += [str(rng.choice(actions))] * int(rng.integers(8, 15))
        seq += ["Guard"] * int(rng.integers(3, 8))
        if rng.random() < 0.25:
            seq += ["Step"] * int(rng.integers(6, 12))
    return seq


def write_features(path: Path, v: VideoFeatures) -> None:
    from ..fileio import write_npz

    n = v.descriptors.shape[0]
    rng = np.random.default_rng(n)
    points = np.stack([v.frame_index, rng.integers(0, 120, n), rng.integers(0, 160, n)], axis=1).astype(np.int32)
    write_npz(
        path,
        points=points,
        descriptors=v.descriptors,
        frame_index=v.frame_index.astype(np.int32),
        n_frames=np.int64(v.n_frames),
        height=np.int64(120),
        width=np.int64(160),
        video=np.array(v.video),
        params=np.array(json.dumps({"synthetic": True})),
    )


def make_dataset(
    root: str | Path,
    n_performers: int = 6,
    views: tuple[str, ...] = ("front", "left", "right"),
    seed: int = 0,
    dim: int = 64,
    performances: int = 1,
    reps: tuple[int, int] = (3, 5),
    n_actions: int = 12,
    world: dict | None = None,
) -> dict:
    """Write ``root/dataset.json``, ``root/labels/<id>.json`` and ``root/features/<id>.npz``."""
    from ..fileio import write_json

    root = Path(root)
    rng = np.random.default_rng(seed)
    performers = [f"p{i:02d}" for i in range(n_performers)]
    w = SyntheticWorld.make(rng, dim=dim, performers=performers, views=list(views), **(world or {}))
    azimuth = {v: a for v, a in zip(views, (0, 90, -90, 180, 45, -45))}
    videos = []
    for p in performers:
        items = [(a, "single", single_sequence(rng, a, reps)) for a in ACTIONS]
        items += [(None, "performance", performance_sequence(rng, n_actions)) for _ in range(performances)]
        for view in views:
            for i, (action, kind, seq) in enumerate(items):
                vid = f"{p}_{(action or f'perf{i}').lower()}_{view}"
                feats = w.video(rng, seq, p, view, name=f"videos/{vid}.mp4")
                write_features(root / "features" / f"{vid}.npz", feats)
                write_json(
                    root / "labels" / f"{vid}.json",
                    {"video": f"videos/{vid}.mp4", "fps": 20, "classes": CLASSES, "labels": seq, "performer": p},
                )
                videos.append(
                    {"id": vid, "performer": p, "kind": kind, "action": action, "view": view,
                     "azimuth_deg": azimuth[view], "video": f"videos/{vid}.mp4", "labels": f"labels/{vid}.json"}
                )
    manifest = {
        "seed": seed, "fps": 20, "actions": ACTIONS, "classes": CLASSES,
        "performers": [{"id": p} for p in performers], "videos": videos, "synthetic": True,
    }
    write_json(root / "dataset.json", manifest)
    return manifest
