"""Evaluation of a performer's action-level style fitted from 2D (``scripts/eval_action_style.py``,
``scripts/validate_action_style.py``; :mod:`vidstyle.actionmodel.stylefit`).

* :func:`orthodox_model`: one :class:`~vidstyle.actionmodel.ActionModel` on every take of the given
  (training) performers, southpaws' clips mirrored to orthodox (their lead is the dataset's truth: the
  training performers' mocap is labelled data).
* :func:`performer_videos`: a performer's videos as ``(xy, labels, view)`` for an input ``kind``:
  ``true`` (true 2D keypoints projected from the truth sidecar), ``noisy`` (true 2D plus Gaussian noise of
  5 % of the torso and 5 % outliers, seeded), ``estimated`` (``<poses_dir>/<id>.poses.json``), with the
  true labels or the recognised ones (``labels_dir``).
* :func:`generated_mpjpe`: per label, the MPJPE (mm) of a generated instance against each of the
  performer's true instances of that label (retargeted onto the model's skeleton, canonical frame) after
  slope-limited DTW alignment of the joint positions (the generated instance decoded at the true
  instance's length, then aligned frame to frame); mean over instances.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)


def demo_truth(dataset: str | Path) -> dict:
    """What the action-style scripts read of a demo dataset: its ``manifest``, the ``dataset`` record, the
    mocap unit in millimetres (``unit_mm``), the ``actions`` and each performer's true ``style``."""
    from ..formats.dataset import read_dataset
    from .actionmodel import read_manifest

    manifest = read_manifest(dataset)
    return {"manifest": manifest, "dataset": read_dataset(Path(dataset) / "dataset.json"),
            "unit_mm": float(manifest["mocap_unit_m"]) * 1000.0, "actions": list(manifest["actions"]),
            "style": {p["id"]: p["style"] for p in manifest["performers"]}}


def southpaws(manifest: dict) -> set[str]:
    return {p["id"] for p in manifest["performers"] if p["style"]["lead"] == "southpaw"}


def orthodox_model(dataset: str | Path, manifest: dict, performers: list[str], seed: int = 0, params: dict | None = None):
    from ..actionmodel import ActionModel, cut_instances, load_labelled
    from ..actionmodel.stylefit import orthodox_clips
    from .actionmodel import performer_takes

    paths = []
    for p in performers:
        s, pf = performer_takes(dataset, p)
        paths += s + pf
    clips = orthodox_clips(load_labelled(paths), southpaws(manifest))
    return ActionModel(**{**(params or {}), "random_state": seed}).fit(cut_instances(clips))


def performer_videos(ds, manifest: dict, performer: str, kind: str = "true", poses_dir: Path | None = None,
                     labels_dir: Path | None = None, rng: np.random.Generator | None = None,
                     cache: dict | None = None) -> list:
    """``[(xy, labels, view)]`` of ``performer``'s videos (module text); a video without a pose file is
    left out for ``estimated``."""
    from ..actionmodel.stylefit import noisy_track
    from ..formats.poses import read_poses
    from ..recognition.posefeatures import track_from_poses
    from .poserecognition import true_keypoints

    root = Path(ds.root)
    out = []
    for v in manifest["videos"]:
        if v["performer"] != performer:
            continue
        if labels_dir is not None:
            f = Path(labels_dir) / f"{v['id']}.json"
            if not f.is_file():
                continue
            labels = json.loads(f.read_text())["labels"]
        else:
            labels = json.loads((root / v["labels"]).read_text())["labels"]
        if kind in ("true", "noisy"):
            key = ("true", v["id"])
            if cache is not None and key in cache:
                xy = cache[key]
            else:
                xy = true_keypoints(ds, v["id"])
                if cache is not None:
                    cache[key] = xy
            if kind == "noisy":
                xy = noisy_track(xy, rng if rng is not None else np.random.default_rng(0))
        elif kind == "estimated":
            f = Path(poses_dir) / f"{v['id']}.poses.json"
            if not f.is_file():
                continue
            xy = track_from_poses(read_poses(f), float(manifest["fps"]), int(v["frames"])).xy
        else:
            raise ValueError(f"unknown input kind {kind!r}")
        out.append((xy, labels, v["view"]))
    return out


def true_instances(dataset: str | Path, performer: str, model, max_per_label: int = 8, seed: int = 0) -> dict:
    """label -> up to ``max_per_label`` true instances (seeded choice) of ``performer`` on the model's skeleton."""
    from ..actionmodel import cut_instances, load_labelled
    from .actionmodel import performer_takes

    s, pf = performer_takes(dataset, performer)
    iset = cut_instances(load_labelled(s + pf), reference=model.skeleton_)
    rng = np.random.default_rng(seed)
    out = {}
    for label in model.labels_:
        insts = iset.of(label)
        if len(insts) > max_per_label:
            insts = [insts[i] for i in sorted(rng.choice(len(insts), max_per_label, replace=False))]
        if insts:
            out[label] = [i.motion for i in insts]
    return out


def dtw_mpjpe(gen_pos: np.ndarray, true_pos: np.ndarray, slope_limit: int = 5) -> float:
    """Mean joint distance along the slope-limited DTW path between two (F, J, 3) position sequences."""
    from ..actionmodel.dtw import dtw

    a = gen_pos.reshape(len(gen_pos), -1)
    b = true_pos.reshape(len(true_pos), -1)
    C = np.linalg.norm((gen_pos[:, None] - true_pos[None]), axis=-1).mean(-1)
    _, path = dtw(C, slope_limit)
    path = np.asarray(path)
    del a, b
    return float(C[path[:, 0], path[:, 1]].mean())


def generated_mpjpe(make, truth: list, unit_mm: float) -> float:
    """Mean over ``truth`` motions of :func:`dtw_mpjpe` of ``make(n_frames)`` (a Motion) against each."""
    from ..mocap.kinematics import forward_kinematics

    errs = []
    for m in truth:
        g = make(m.n_frames)
        pg = forward_kinematics(g, return_matrices=False)[0]
        pt = forward_kinematics(m, return_matrices=False)[0]
        errs.append(dtw_mpjpe(pg, pt) * unit_mm)
    return float(np.mean(errs)) if errs else float("nan")


def pearson(x, y) -> float | None:
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 3 or np.std(x[ok]) == 0 or np.std(y[ok]) == 0:
        return None
    return float(np.corrcoef(x[ok], y[ok])[0, 1])


def evaluate_performer(model, estimator, videos, truth_style: dict, truth: dict, actions: list[str], unit_mm: float,
                       params: dict | None = None, max_segments: int | None = None, seed: int = 0) -> dict:
    """Fit ``videos`` and score against the performer's ``truth_style`` (dataset ``style``) and true
    instances ``truth`` (label -> motions): global figures, and per label the MPJPE (mm) of the fitted
    mean, a sample of the fitted per-performer Gaussian, the unfitted pooled model's mean and a sample of
    it (orthodox: the unfitted model knows no lead), and the pooled mean given the true lead."""
    import time

    from ..actionmodel import defaults as D
    from ..actionmodel.stylefit import fit_action_style

    t0 = time.perf_counter()
    style = fit_action_style(model, estimator, videos, params,
                             D.STYLE_MAX_SEGMENTS if max_segments is None else max_segments, seed)
    fit_s = time.perf_counter() - t0
    gs = style.global_style
    ts = truth_style
    row = {"lead_true": ts["lead"], "lead": gs.lead, "lead_score": gs.lead_score,
           "guard_height_true": ts["guard_height"], "guard_height": gs.guard_height,
           "stance_width_true": ts["stance_width"], "stance_width": gs.stance_width,
           "crouch_true": ts["crouch"], "crouch": gs.crouch,
           "tempo_true": {a: ts["tempo"][k] for k, a in enumerate(actions)},
           "duration_factor_true": {a: ts["tempo"][k] / ts["speed"] for k, a in enumerate(actions)},
           "tempo": gs.tempo, "relative_tempo": gs.relative_tempo,
           "videos": len(videos), "fit_seconds": fit_s, "segments": dict(style.counts), "labels": {}}
    rng = np.random.default_rng(seed)
    true_south = ts["lead"] == "southpaw"
    for label, motions in truth.items():
        if label not in style.coefficients:
            continue
        lm = model.models_[label]
        mu = lm.gmm_means[int(np.argmax(lm.gmm_weights))]
        zs = model.sample_coefficients(label, 1, rng)[0]
        r = {"instances": len(motions), "segments": style.counts[label]}
        r["fitted_mean_mm"] = generated_mpjpe(lambda n: style.realise(model, label, n), motions, unit_mm)
        r["fitted_sample_mm"] = generated_mpjpe(
            lambda n: style.realise(model, label, n, sample=True, random_state=int(rng.integers(2**31))), motions, unit_mm)
        r["unfitted_mean_mm"] = generated_mpjpe(lambda n: model.decode(mu, label, n_frames=n), motions, unit_mm)
        r["unfitted_sample_mm"] = generated_mpjpe(lambda n: model.decode(zs, label, n_frames=n), motions, unit_mm)
        r["unfitted_mean_true_lead_mm"] = generated_mpjpe(
            lambda n: (lambda m: m.mirror() if true_south else m)(model.decode(mu, label, n_frames=n)), motions, unit_mm)
        row["labels"][label] = r
    row["style"] = style
    return row


def summarise(rows: list[dict], actions: list[str]) -> dict:
    """Lead accuracy, Pearson correlations over performers (tempo: over performer x action pairs) and the
    MPJPE means (instance-free: per performer and label, then averaged) of ``rows``."""
    out = {"performers": len(rows)}
    if not rows:
        return out
    out["lead_accuracy"] = float(np.mean([r["lead"] == r["lead_true"] for r in rows]))
    for k in ("guard_height", "stance_width", "crouch"):
        out[f"{k}_r"] = pearson([r[f"{k}_true"] for r in rows], [r[k] for r in rows])
    tt, te, dt, rt, rte = [], [], [], [], []
    for r in rows:
        mt = np.mean(list(r["tempo_true"].values()))
        for a in actions:
            if a in r["tempo"]:
                tt.append(r["tempo_true"][a])
                dt.append(r["duration_factor_true"][a])
                te.append(r["tempo"][a])
                rt.append(r["tempo_true"][a] / mt)
                rte.append(r["relative_tempo"][a])
    out["duration_factor_r"] = pearson(dt, te)  # tempo / speed: what durations show
    out["tempo_r"] = pearson(tt, te)  # the raw per-action tempo parameter against the duration factor
    out["relative_tempo_r"] = pearson(rt, rte)  # tempo / the performer's mean tempo
    keys = ("fitted_mean_mm", "fitted_sample_mm", "unfitted_mean_mm", "unfitted_sample_mm", "unfitted_mean_true_lead_mm")
    vals = {k: [lr[k] for r in rows for lr in r["labels"].values() if np.isfinite(lr[k])] for k in keys}
    for k in keys:
        out[k] = float(np.mean(vals[k])) if vals[k] else None
    if out.get("unfitted_mean_mm"):
        out["mpjpe_reduction"] = 1 - out["fitted_mean_mm"] / out["unfitted_mean_mm"]
        out["mpjpe_reduction_sample"] = 1 - out["fitted_sample_mm"] / out["unfitted_sample_mm"]
        out["mpjpe_reduction_vs_true_lead"] = 1 - out["fitted_mean_mm"] / out["unfitted_mean_true_lead_mm"]
    return out


def row_json(r: dict) -> dict:
    return {k: v for k, v in r.items() if k != "style"}
