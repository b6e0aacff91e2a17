"""Quality of synthesised motion: seams, foot skid, label fidelity, transitions used.

* **velocity jump** at frame t: ``|v(t+1) - v(t)| * fps`` per joint (``v`` in length unit per second), the
  mean over joints; **jerk**: ``|third difference| * fps^3``, mean over joints.
* **seam frames**: output frames of a transition blend and one frame either side; statistics there are
  compared with every frame inside the original clips of the graph (same measure, same frame rate).
* **foot skid**: horizontal speed of a foot joint while it is low (within ``foot_height`` of the lowest
  foot height of that motion, default 5 % of the body height) and moving little vertically: the foot
  should be planted. Reported at seams and inside the original clips.
* **label fidelity**: fraction of output frames whose source label equals the requested label.

The protocol of ``vidstyle evaluate motion`` is :func:`evaluate` (the command writes its result through
:mod:`vidstyle.formats.metrics` and prints a table).
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import ParameterError
from ..formats.walk import read_walk_labels
from ..mocap import Motion, global_positions, read_bvh
from ..motiongraph import MotionGraph, Step, defaults, plan_walk, read_sequence, render_walk, walk_labels
from ..motiongraph.pipeline import labels_path

FOOT_NAMES = ("toe", "foot", "ankle")


def _kinematics(pos: np.ndarray, fps: float, valid: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Per-frame (velocity jump, jerk), NaN where the stencil leaves ``valid`` frames (clip boundaries)."""
    T = len(pos)
    vj = np.full(T, np.nan)
    jerk = np.full(T, np.nan)
    if T >= 3:
        a = pos[2:] - 2 * pos[1:-1] + pos[:-2]
        vj[1:-1] = np.linalg.norm(a, axis=-1).mean(-1) * fps * fps
    if T >= 4:
        j3 = pos[3:] - 3 * pos[2:-1] + 3 * pos[1:-2] - pos[:-3]
        jerk[1:-2] = np.linalg.norm(j3, axis=-1).mean(-1) * fps**3
    if valid is not None:
        v = valid.astype(bool)
        ok3 = np.zeros(T, bool)
        ok3[1:-1] = v[:-2] & v[1:-1] & v[2:]
        ok4 = np.zeros(T, bool)
        ok4[1:-2] = v[:-3] & v[1:-2] & v[2:-1] & v[3:]
        vj[~ok3] = np.nan
        jerk[~ok4] = np.nan
    return vj, jerk


def foot_joints(names: list[str]) -> list[int]:
    return [i for i, n in enumerate(names) if any(f in n.lower() for f in FOOT_NAMES)]


def _skid(pos: np.ndarray, fps: float, feet: list[int], height: float) -> tuple[np.ndarray, np.ndarray]:
    """(T, F) horizontal foot speed and a mask of frames where that foot should be planted."""
    p = pos[:, feet]
    v = np.zeros_like(p)
    v[1:] = (p[1:] - p[:-1]) * fps
    v[0] = v[1] if len(p) > 1 else 0
    h_speed = np.linalg.norm(v[..., [0, 2]], axis=-1)
    low = p[..., 1] < p[..., 1].min(axis=0, keepdims=True) + height
    still = np.abs(v[..., 1]) < height * fps * 0.2
    return h_speed, low & still


def _stats(x: np.ndarray) -> dict:
    x = x[np.isfinite(x)]
    if not len(x):
        return {"n": 0, "mean": None, "median": None, "p95": None}
    return {"n": int(len(x)), "mean": float(x.mean()), "median": float(np.median(x)), "p95": float(np.percentile(x, 95))}


def original_stats(graph, max_frames: int = 20000, seed: int = 0) -> dict:
    """Velocity jump, jerk and foot skid inside the graph's original clips (a seeded subset of clips
    when the graph is large)."""
    rng = np.random.default_rng(seed)
    starts = np.asarray(graph.clips_["start"])
    counts = np.asarray(graph.clips_["frames"])
    order = rng.permutation(len(starts))
    vj_all, jerk_all, skid_all = [], [], []
    total = 0
    feet = foot_joints(graph.skeleton_.names)
    for c in order:
        if total >= max_frames:
            break
        m = graph.motion(slice(int(starts[c]), int(starts[c] + counts[c])))
        pos = global_positions(m)
        vj, jerk = _kinematics(pos, graph.fps)
        vj_all.append(vj)
        jerk_all.append(jerk)
        if feet:
            height = 0.05 * _body_height(pos)
            sp, planted = _skid(pos, graph.fps, feet, height)
            skid_all.append(sp[planted])
        total += counts[c]
    cat = lambda xs: np.concatenate(xs) if xs else np.zeros(0)  # noqa: E731
    return {"velocity_jump": _stats(cat(vj_all)), "jerk": _stats(cat(jerk_all)), "foot_skid": _stats(cat(skid_all))}


def _body_height(pos: np.ndarray) -> float:
    return float(np.median(pos[..., 1].max(axis=1) - pos[..., 1].min(axis=1)))


def evaluate_walk(motion: Motion, labels_doc: dict, original: dict | None = None) -> dict:
    """Metrics of one synthesised motion and its ``labels.json`` document."""
    pos = global_positions(motion)
    fps = motion.fps
    trans = np.asarray(labels_doc.get("transition", [-1] * motion.n_frames))
    seam = trans >= 0
    near = seam.copy()
    near[1:] |= seam[:-1]
    near[:-1] |= seam[1:]
    vj, jerk = _kinematics(pos, fps)
    feet = foot_joints(motion.skeleton.names)
    out: dict = {"frames": motion.n_frames, "fps": fps}
    out["velocity_jump"] = {"seam": _stats(vj[near]), "inside": _stats(vj[~near])}
    out["jerk"] = {"seam": _stats(jerk[near]), "inside": _stats(jerk[~near])}
    if feet:
        sp, planted = _skid(pos, fps, feet, 0.05 * _body_height(pos))
        out["foot_skid"] = {"seam": _stats(sp[near[:, None] & planted]), "inside": _stats(sp[~near[:, None] & planted])}
    req = labels_doc.get("labels", [])
    src = labels_doc.get("source_labels", [])
    out["label_fidelity"] = float(np.mean([a == b for a, b in zip(req, src)])) if req else None
    used = labels_doc.get("transitions_used", [])
    out["transitions_used"] = len(used)
    out["transitions_per_second"] = len(used) / max(motion.duration, 1e-9)
    if labels_doc.get("cost") is not None:
        out["cost"] = float(labels_doc["cost"])
    if labels_doc.get("foot_lock"):
        out["foot_lock"] = labels_doc["foot_lock"]
    if original is not None:
        out["original"] = original
    return out


def summarise(results: list[dict], original: dict) -> dict:
    """Pool per-walk metrics: frame-weighted fidelity, seam / original ratios of medians and p95."""
    def pooled(metric: str, where: str, key: str) -> float | None:
        vals = [r[metric][where][key] for r in results if metric in r and r[metric][where][key] is not None]
        return float(np.mean(vals)) if vals else None

    frames = sum(r["frames"] for r in results)
    summary = {
        "walks": len(results),
        "frames": frames,
        "label_fidelity": sum(r["label_fidelity"] * r["frames"] for r in results) / max(frames, 1),
        "transitions_used": sum(r["transitions_used"] for r in results),
        "transitions_per_second": float(np.mean([r["transitions_per_second"] for r in results])) if results else 0.0,
    }
    if results and all("cost" in r for r in results):
        summary["walk_cost"] = float(sum(r["cost"] for r in results))
    for metric in ("velocity_jump", "jerk", "foot_skid"):
        if metric not in original:
            continue
        row = {}
        for key in ("median", "p95"):
            seam = pooled(metric, "seam", key)
            inside = pooled(metric, "inside", key)
            orig = original[metric][key]
            row[f"seam_{key}"] = seam
            row[f"inside_{key}"] = inside
            row[f"original_{key}"] = orig
            row[f"seam_over_original_{key}"] = seam / orig if seam is not None and orig else None
        summary[metric] = row
    return summary


def random_sequences(graph: MotionGraph, walks: int, steps: int, actions: str | Sequence[str] | None,
                     min_seconds: float, max_seconds: float, seed: int) -> list[list[Step]]:
    """``walks`` seeded random sequences of ``steps`` steps (no action twice in a row), over ``actions``
    (names, or one comma-separated string; default: every label with at least 2 s of frames in the
    graph's component)."""
    rng = np.random.default_rng(seed)
    lab = graph.labels_[graph.scc_]
    counts = {name: int((lab == i).sum()) for i, name in enumerate(graph.label_names_)}
    if actions:
        pool = [a.strip() for a in actions.split(",") if a.strip()] if isinstance(actions, str) else list(actions)
    else:
        pool = [a for a, c in counts.items() if c >= 2 * graph.fps and a != "unlabelled"]
    if not pool:
        raise ParameterError("actions", f"no action with enough frames in the graph ({counts})")
    out = []
    for _ in range(walks):
        seq, prev = [], None
        for _ in range(steps):
            choices = [a for a in pool if a != prev] or pool
            prev = str(rng.choice(choices))
            seq.append(Step(prev, int(rng.integers(int(min_seconds * graph.fps), int(max_seconds * graph.fps) + 1))))
        out.append(seq)
    return out


def evaluate(
    graph: MotionGraph,
    motions: Sequence[str | os.PathLike] = (),
    *,
    sequence: str | os.PathLike | None = None,
    walks: int = defaults.EVAL_WALKS,
    steps: int = defaults.EVAL_STEPS,
    actions: str | Sequence[str] | None = None,
    min_seconds: float = defaults.EVAL_MIN_SECONDS,
    max_seconds: float = defaults.EVAL_MAX_SECONDS,
    seed: int = 0,
    foot_lock: bool = defaults.FOOT_LOCK,
    max_in_degree: int | None = None,
) -> dict:
    """Seam quality, foot skid, label fidelity and transitions used of synthesised motion: of the given
    BVH ``motions`` (each with ``<stem>.labels.json``), else of ``sequence`` synthesised, else of
    ``walks`` seeded random sequences. Returns the metrics document's content (without the graph's path):
    ``graph_stats``, ``seed``, ``parameters``, ``summary``, ``original`` (the graph's own clips), ``walks``."""
    original = original_stats(graph, seed=seed)
    results = []
    synth_seconds, synth_frames = 0.0, 0

    def walk_of(seq: list[Step], name: str) -> None:
        nonlocal synth_seconds, synth_frames
        t0 = time.perf_counter()
        walk = plan_walk(graph, seq, strict=False, max_in_degree=max_in_degree)
        motion = render_walk(graph, walk, foot_lock=foot_lock)
        synth_seconds += time.perf_counter() - t0
        synth_frames += motion.n_frames
        results.append(evaluate_walk(motion, walk_labels(graph, walk, name)))

    if motions:
        for m in motions:
            motion = read_bvh(m)
            results.append(evaluate_walk(motion, read_walk_labels(labels_path(m), motion.n_frames).doc))
    elif sequence is not None:
        walk_of(read_sequence(sequence, graph.fps), Path(sequence).stem + ".bvh")
    else:
        for w, seq in enumerate(random_sequences(graph, walks, steps, actions, min_seconds, max_seconds, seed)):
            walk_of(seq, f"walk{w}.bvh")
    summary = summarise(results, original)
    if synth_frames:
        summary["synthesis_x_real_time"] = synth_frames / graph.fps / max(synth_seconds, 1e-9)
    return {
        "graph_stats": graph.stats_,
        "seed": seed,
        "parameters": {"walks": walks, "steps": steps, "actions": actions if actions is None or isinstance(actions, str) else ",".join(actions),
                       "min_seconds": min_seconds, "max_seconds": max_seconds, "foot_lock": foot_lock,
                       "sequence": str(sequence) if sequence else None, "max_in_degree": max_in_degree},
        "summary": summary,
        "original": original,
        "walks": results,
    }
