"""Following one performer among several people, scored against truth (the ``demo make-crowd`` take).

Per view: every frame's pose from a backend, alone (``naive``: the backend's own choice of person each
frame) or followed (:class:`vidstyle.pose.people.PerformerTracker`). Each estimated pose is assigned the
identity of the true person whose keypoints it lies closest to (mean distance over the keypoints the
backend found); an *identity switch* is a frame whose identity differs from the previous estimated
frame's. PCK@0.2 (torso-normalised, true torso) is scored against the person the pose stage chose in its
first frame with a pose; frames without a pose count as misses.

:func:`follow_everyone` follows each person of each view in turn (chosen by pixel) with given tracker
settings, the protocol of ``scripts/validate_people.py``, which chose the tracker's defaults on crowds of
other seeds than the committed result's.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..formats.keypoints import KEYPOINTS

NECK, PELVIS = KEYPOINTS.index("neck"), KEYPOINTS.index("pelvis")


def identities(estimates: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """(F,) index of the true person nearest each estimate, -1 where there is none.

    ``estimates`` (F, 15, 3) x, y, score (NaN rows: no pose); ``truth`` (P, F, 15, 2)."""
    F = estimates.shape[0]
    out = np.full(F, -1, dtype=np.int64)
    for f in range(F):
        ok = np.isfinite(estimates[f, :, 0]) & (np.nan_to_num(estimates[f, :, 2]) > 0)
        if ok.sum() < 3:
            continue
        d = [np.linalg.norm(truth[p, f, ok] - estimates[f, ok, :2], axis=-1).mean() for p in range(truth.shape[0])]
        out[f] = int(np.argmin(d))
    return out


def switches(ids: np.ndarray) -> int:
    seen = ids[ids >= 0]
    return int(np.sum(seen[1:] != seen[:-1]))


def pck(estimates: np.ndarray, truth_person: np.ndarray, threshold: float = 0.2) -> float:
    """PCK over every keypoint of every frame (missing poses / keypoints are misses)."""
    torso = np.linalg.norm(truth_person[:, NECK] - truth_person[:, PELVIS], axis=-1)
    d = np.linalg.norm(estimates[..., :2] - truth_person, axis=-1) / torso[:, None]
    found = np.isfinite(d) & (np.nan_to_num(estimates[..., 2]) > 0)
    return float(np.mean(found & (np.nan_to_num(d, nan=np.inf) < threshold)))


def score_view(estimates: np.ndarray, truth: np.ndarray) -> dict:
    ids = identities(estimates, truth)
    first = ids[ids >= 0]
    chosen = int(first[0]) if len(first) else -1
    F, n = len(ids), switches(ids)
    return {"frames": F, "found": int((ids >= 0).sum()), "chosen": chosen,
            "identity_switches": n, "switches_per_100_frames": 100.0 * n / max(F, 1),
            "pck@0.2": pck(estimates, truth[chosen]) if chosen >= 0 else 0.0,
            "frames_on_chosen": float(np.mean(ids == chosen)) if chosen >= 0 else 0.0}


def run_view(video: str | Path, backend: str, tracked: bool, model_path=None) -> np.ndarray:
    """(F, 15, 3) poses of every frame of ``video`` from ``vidstyle pose``'s path
    (:func:`vidstyle.pose.run.estimate_video`, followed or not), NaN rows where there is none."""
    from ..pose.run import estimate_video

    poses = estimate_video(video, backend, model_path, jobs=1, track=tracked)
    return np.stack([pf.points for pf in poses.frames])


def follow_person(video: str | Path, pixel: tuple[float, float], estimator, params: dict | None = None) -> np.ndarray:
    """(F, 15, 3) poses of the person at ``pixel`` (the input video's pixels) of the first frame with people,
    followed through ``video`` by :class:`vidstyle.pose.people.PerformerTracker` (``params``: its settings)
    on ``estimator`` (a :class:`vidstyle.pose.interfaces.PoseBackend`), through ``vidstyle pose``'s own
    path (:func:`vidstyle.pose.run.estimate_frames`); NaN rows where the performer is missing."""
    from ..pose.run import estimate_frames
    from ..video import VideoReader

    with VideoReader(video) as probe:
        n = len(probe)
    poses = estimate_frames(video, estimator, list(range(n)), True, person=pixel, tracker_params=params)
    return np.stack([pf.points if pf.found else np.full((len(KEYPOINTS), 3), np.nan) for pf in poses])


def follow_everyone(crowd_dir: str | Path, estimator, params: dict | None = None) -> dict:
    """Every person of a crowd take followed in turn in every view (chosen by the pixel halfway between
    their true neck and pelvis in the first frame), each run scored by :func:`score_view` (against the
    person the tracker took first, which is another one when the asked-for person is hidden there); totals
    over the runs: identity switches per 100 frames, mean PCK@0.2, missing frames."""
    crowd_dir = Path(crowd_dir)
    truth = np.load(crowd_dir / "truth.npz")
    kp2 = truth["keypoints2d"].astype(np.float64)
    views = [str(v) for v in truth["views"]]
    runs = []
    for v, name in enumerate(views):
        for p in range(kp2.shape[1]):
            pixel = tuple(float(x) for x in (kp2[v, p, 0, NECK] + kp2[v, p, 0, PELVIS]) / 2)
            est = follow_person(crowd_dir / f"{name}.mp4", pixel, estimator, params)
            s = score_view(est, kp2[v])
            s.update(view=name, person=p, missing=int(np.isnan(est[:, 0, 0]).sum()))
            runs.append(s)
    return {"crowd": str(crowd_dir), "views": views, "people": int(kp2.shape[1]), "runs": runs, **totals(runs)}


def totals(runs: list[dict]) -> dict:
    """Identity switches (count and per 100 frames), mean PCK@0.2 and missing frames over ``runs``."""
    n = sum(r["identity_switches"] for r in runs)
    frames = sum(r["frames"] for r in runs)
    return {"frames": frames, "identity_switches": n, "identity_switches_per_100_frames": 100.0 * n / max(frames, 1),
            "pck@0.2": float(np.mean([r["pck@0.2"] for r in runs])) if runs else 0.0,
            "missing_frames": sum(r.get("missing", 0) for r in runs)}


def evaluate_crowd(crowd_dir: str | Path, backend: str = "blazepose", model_path=None,
                   modes=("naive", "tracked")) -> dict:
    """Scores of every mode on every view of a crowd take, and the multi-view PCK of each mode's poses."""
    from ..formats.calibration import read_calibration
    from ..formats.keypoints import KEYPOINTS as NAMES
    from .multiview import leave_one_view_out, summarise

    crowd_dir = Path(crowd_dir)
    truth = np.load(crowd_dir / "truth.npz")
    kp2 = truth["keypoints2d"].astype(np.float64)
    views = [str(v) for v in truth["views"]]
    calib = read_calibration(crowd_dir / "calibration.toml")
    result = {"views": views, "people": int(kp2.shape[1]), "frames": int(kp2.shape[2]), "modes": {}}
    for mode in modes:
        per_view, poses = {}, []
        for v, name in enumerate(views):
            est = run_view(crowd_dir / f"{name}.mp4", backend, mode == "tracked", model_path)
            per_view[name] = score_view(est, kp2[v])
            poses.append(est)
        errors, _ = leave_one_view_out(calib.cameras, np.stack(poses), (NECK, PELVIS))
        mv = summarise(errors, views, NAMES)["overall"]
        total_sw = sum(p["identity_switches"] for p in per_view.values())
        total_f = sum(p["frames"] for p in per_view.values())
        result["modes"][mode] = {
            "per_view": per_view,
            "identity_switches_per_100_frames": 100.0 * total_sw / max(total_f, 1),
            "pck@0.2": float(np.mean([p["pck@0.2"] for p in per_view.values()])),
            "same_person_in_every_view": len({p["chosen"] for p in per_view.values()}) == 1,
            "multiview_pck@0.2": mv["pck@0.2"],
        }
    return result


def format_table(metrics: dict) -> str:
    lines = [f"{metrics['people']} people, {metrics['frames']} frames x {len(metrics['views'])} views",
             f"  {'mode':<8} {'switches/100 frames':>20} {'PCK@0.2':>8} {'multi-view PCK@0.2':>19} {'same person':>12}"]
    def f(x):
        return "-" if x is None else f"{x:.3f}"

    for mode, m in metrics["modes"].items():
        lines.append(f"  {mode:<8} {m['identity_switches_per_100_frames']:>20.2f} {f(m['pck@0.2']):>8} "
                     f"{f(m['multiview_pck@0.2']):>19} {m['same_person_in_every_view']!s:>12}")
    return "\n".join(lines)
