"""Synthetic performers with known action chains (tests, benchmarks; no video needed).

Writes the same files as ``vidstyle demo make-dataset`` for the parts the style stage reads: a
``dataset.json`` manifest with each performer's true chain, and per-video label files; optionally a
second directory of "recognised" label files with recognition errors and confidences.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..fileio import write_json

ACTIONS = ("Jab", "Hook", "Uppercut", "Defense", "LowKick", "RoundhouseKick")
CLASSES = ACTIONS + ("Guard", "Step")


def random_chain(rng: np.random.Generator, n_actions: int = len(ACTIONS), concentration: float = 0.35,
                 floor: float = 0.2) -> dict:
    """A random ergodic chain: sparse Dirichlet rows (so performers differ clearly) mixed with a
    uniform ``floor`` (so no action is nearly absorbing and every row is learnable from data)."""
    trans = (1 - floor) * rng.dirichlet(np.full(n_actions, concentration), size=n_actions) + floor / n_actions
    start = rng.dirichlet(np.ones(n_actions))
    return {"start": start, "transition": trans}


def sample_chain(start: np.ndarray, trans: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    out = np.empty(n, dtype=np.int64)
    out[0] = rng.choice(len(start), p=start)
    for t in range(1, n):
        out[t] = rng.choice(len(start), p=trans[out[t - 1]])
    return out


def render_frames(actions: np.ndarray, durations: np.ndarray, rng: np.random.Generator,
                  names: tuple[str, ...] = ACTIONS, gap_prob: float = 1.0,
                  gap_frames: tuple[int, int] = (3, 7), step_prob: float = 0.2) -> list[str]:
    """Frame labels: each event's frames, with a Guard (or Step) gap after an event with ``gap_prob``."""
    labels: list[str] = ["Guard"] * int(rng.integers(*gap_frames))
    for a, d in zip(actions.tolist(), durations.tolist()):
        labels += [names[a]] * int(d)
        if rng.random() < gap_prob:
            filler = "Step" if rng.random() < step_prob else "Guard"
            labels += [filler] * int(rng.integers(*gap_frames))
    return labels


def corrupt_frames(labels: list[str], rng: np.random.Generator, frame_noise: float = 0.1,
                   event_swap: float = 0.05, classes: tuple[str, ...] = CLASSES,
                   actions: tuple[str, ...] = ACTIONS) -> tuple[list[str], list[float]]:
    """Recognition-like errors: whole runs swapped with a fixed confusion partner (prob ``event_swap``),
    isolated frames replaced by a random class (prob ``frame_noise``, low confidence)."""
    out = list(labels)
    conf = list(np.round(rng.uniform(0.6, 1.0, len(out)), 3))
    partner = {a: actions[(i + 1) % len(actions)] for i, a in enumerate(actions)}
    i = 0
    while i < len(out):
        j = i
        while j < len(out) and labels[j] == labels[i]:
            j += 1
        if labels[i] in partner and rng.random() < event_swap:
            out[i:j] = [partner[labels[i]]] * (j - i)
        i = j
    flip = np.flatnonzero(rng.random(len(out)) < frame_noise)
    for k in flip.tolist():
        out[k] = classes[int(rng.integers(len(classes)))]
        conf[k] = float(np.round(rng.uniform(0.2, 0.7), 3))
    return out, [float(c) for c in conf]


def write_fake_dataset(
    root: str | os.PathLike,
    n_performers: int = 6,
    n_videos: int = 3,
    events_per_video: int = 100,
    seed: int = 0,
    fps: int = 20,
    gap_prob: float = 1.0,
    recognised_dir: str | os.PathLike | None = None,
    frame_noise: float = 0.1,
    event_swap: float = 0.05,
    n_single: int = 1,
) -> Path:
    """Write ``root/dataset.json`` + ``root/labels/*.json``; with ``recognised_dir`` also noisy labels.

    Returns the manifest path. Every performer gets its own random chain and duration means.
    """
    root = Path(root)
    rng = np.random.default_rng(seed)
    performers, videos = [], []
    A = len(ACTIONS)
    for p in range(n_performers):
        pid = f"p{p:02d}"
        chain = random_chain(rng)
        dur_mean = rng.uniform(8, 20, A)
        dur_sd = 0.15 * dur_mean
        performers.append({
            "id": pid,
            "chain": {
                "actions": list(ACTIONS),
                "start": chain["start"].tolist(),
                "transition": chain["transition"].tolist(),
                "duration_frames": {a: [float(m), float(s)] for a, m, s in zip(ACTIONS, dur_mean, dur_sd)},
            },
        })
        clips = [("performance", f"{pid}_perf{v}") for v in range(n_videos)]
        clips += [("single", f"{pid}_single{v}") for v in range(n_single)]
        for kind, vid in clips:
            if kind == "performance":
                acts = sample_chain(chain["start"], chain["transition"], events_per_video, rng)
            else:
                acts = np.full(5, int(rng.integers(A)))
            durs = np.maximum(2, np.rint(rng.normal(dur_mean[acts], dur_sd[acts]))).astype(int)
            frames = render_frames(acts, durs, rng, gap_prob=gap_prob)
            doc = {"video": f"videos/{vid}.mp4", "fps": fps, "classes": list(CLASSES), "labels": frames,
                   "performer": pid}
            write_json(root / "labels" / f"{vid}.json", doc)
            if recognised_dir is not None:
                noisy, conf = corrupt_frames(frames, rng, frame_noise, event_swap)
                write_json(Path(recognised_dir) / f"{vid}.json", {**doc, "labels": noisy, "confidence": conf})
            videos.append({"id": vid, "performer": pid, "kind": kind, "view": "front",
                           "video": f"videos/{vid}.mp4", "labels": f"labels/{vid}.json",
                           "bvh": f"mocap/{vid}.bvh"})
    manifest = {"seed": seed, "fps": fps, "actions": list(ACTIONS), "classes": list(CLASSES),
                "performers": performers, "videos": videos}
    write_json(root / "dataset.json", manifest)
    return root / "dataset.json"
