"""``vidstyle evaluate pose``: strict PCP per part (thesis Table 5 layout), PCK@0.2 of the torso length
and the viewpoint confusion matrix (Table 6 layout) on held-out renders, for both backends on the same
frames; on real footage (no labels) the agreement of the backends and an overlay image per video.

Held-out renders: performers, CMU subjects and azimuths never used in training (see
:mod:`vidstyle.pose.data`). Strict PCP: a part is correct when both its estimated endpoints lie within
50 % of the true part length of the true endpoints. PCK@0.2: a keypoint is correct within 20 % of the
true torso (neck-pelvis) length.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

import numpy as np

from ..mocap.keypoints import KEYPOINT_INDEX, KEYPOINTS, PART_KEYPOINTS, PART_NAMES
from ..pose.data import BOUNDARY_TOL, VIEW_NAMES, acceptable_views

log = logging.getLogger(__name__)

TABLE5 = (("LLL", "left_lower_leg"), ("LUL", "left_upper_leg"), ("RUL", "right_upper_leg"),
          ("RLL", "right_lower_leg"), ("LFA", "left_forearm"), ("LUA", "left_upper_arm"),
          ("RUA", "right_upper_arm"), ("RFA", "right_forearm"), ("Torso", "torso"), ("Head", "head"))


def strict_pcp(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """(N, 15, >=2) predictions, (N, 15, 2) truth -> (N, 10) bool per part (PART_NAMES order)."""
    a, b = PART_KEYPOINTS[:, 0], PART_KEYPOINTS[:, 1]
    L = np.linalg.norm(gt[:, b] - gt[:, a], axis=-1)
    da = np.linalg.norm(pred[:, a, :2] - gt[:, a], axis=-1)
    db = np.linalg.norm(pred[:, b, :2] - gt[:, b], axis=-1)
    return (da <= 0.5 * L) & (db <= 0.5 * L)


def pck(pred: np.ndarray, ref: np.ndarray, alpha: float = 0.2) -> np.ndarray:
    """(N, 15) bool: keypoint within ``alpha`` x the reference torso length of the reference."""
    torso = np.linalg.norm(ref[:, KEYPOINT_INDEX["neck"]] - ref[:, KEYPOINT_INDEX["pelvis"]], axis=-1)
    return np.linalg.norm(pred[..., :2] - ref[..., :2], axis=-1) <= alpha * torso[:, None]


def confusion(true: list[str], pred: list[str], labels=VIEW_NAMES) -> dict:
    M = np.zeros((len(labels), len(labels)))
    for t, p in zip(true, pred):
        if t in labels and p in labels:
            M[labels.index(t), labels.index(p)] += 1
    n = M.sum(axis=1, keepdims=True)
    R = np.divide(M, n, out=np.zeros_like(M), where=n > 0)
    return {"labels": list(labels), "counts": M.astype(int).tolist(), "rates": R.round(4).tolist(),
            "per_view_accuracy": {v: float(R[i, i]) for i, v in enumerate(labels)},
            "accuracy": float(np.trace(M) / max(1, M.sum()))}


def wilson_interval(hits: int, n: int, z: float = 1.959964) -> tuple[float, float] | None:
    """Wilson score interval (95 % by default) of a proportion ``hits / n``; None for ``n = 0``. With
    a few dozen frames per view a per-view accuracy is uncertain by several points, and this says how
    many (Wilson rather than the normal approximation: it stays inside [0, 1] at 0 or n hits)."""
    if n <= 0:
        return None
    p = hits / n
    d = 1.0 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return float(max(0.0, c - h)), float(min(1.0, c + h))


def viewpoint_scores(true: list[str], azimuths: list[float], pred: list[str], tol: float = BOUNDARY_TOL) -> dict:
    """Viewpoint confusion (rows: the nearest view of the camera azimuth, as :func:`confusion`) plus
    the scores that do not depend on how a tie is broken: ``unambiguous``, the confusion over the frames
    whose azimuth has one view (farther than ``tol`` degrees from a view boundary); ``boundary``, the
    frames that sit on a boundary and the share of them called either neighbouring view; and
    ``tolerant_per_view_accuracy`` / ``tolerant_accuracy``, every frame counted correct when the
    estimate is one of its :func:`~vidstyle.pose.data.acceptable_views`."""
    ok = [acceptable_views(a, tol) for a in azimuths]
    single = [len(o) == 1 for o in ok]
    out = confusion(true, pred)
    out["unambiguous"] = confusion([t for t, s in zip(true, single) if s], [p for p, s in zip(pred, single) if s])
    hit = np.array([p in o for p, o in zip(pred, ok)], dtype=bool)
    sb = ~np.array(single, dtype=bool)
    out["boundary"] = {"tolerance_deg": float(tol), "n": int(sb.sum()),
                       "accuracy_either_neighbour": float(hit[sb].mean()) if sb.any() else None}
    tv = np.array(true)
    out["tolerant_per_view_accuracy"] = {v: float(hit[tv == v].mean()) for v in VIEW_NAMES if (tv == v).any()}
    out["tolerant_accuracy"] = float(hit.mean()) if len(hit) else None
    return out


def pcp_table(hits: np.ndarray, views: list[str]) -> dict:
    rows = {}
    views = np.array(views)
    for v in VIEW_NAMES:
        sel = views == v
        if sel.any():
            rows[v] = {short: float(hits[sel, PART_NAMES.index(p)].mean()) for short, p in TABLE5}
            rows[v]["n"] = int(sel.sum())
    rows["all"] = {short: float(hits[:, PART_NAMES.index(p)].mean()) for short, p in TABLE5}
    rows["all"]["n"] = len(hits)
    rows["all"]["mean"] = float(hits.mean())
    return rows


def frame_of(s):
    """The frame a model reads of a rendered sample: its colour frame when kept, else the gray one."""
    return s.bgr if s.bgr is not None else s.image


def clip_backgrounds(samples) -> dict:
    """Clip id -> median background of that clip's frames (clips of at least 3 frames): the person
    prior of a static-camera video, as ``vidstyle pose`` computes it over a whole video."""
    from ..pose.foreground import background_model

    groups: dict = {}
    for s in samples:
        groups.setdefault(s.clip, []).append(frame_of(s))
    return {c: background_model(fr) for c, fr in groups.items() if len(fr) >= 3 and c != -1}


def source_group(source: str, others: set[str] = frozenset()) -> str:
    """The group a rendered sample's source belongs to: ``demo`` (a demo performer), ``other`` (a clip
    of ``others``, e.g. another skeleton) or ``cmu``."""
    return "demo" if source.startswith("demo:") else "other" if source in others else "cmu"


def evaluate_renders(model, samples, blazepose: bool = True, others: set[str] = frozenset()) -> dict:
    """Run every method on the same held-out frames; return the metrics dict (``by_source``: the pictorial
    structures' and BlazePose's scores per :func:`source_group`)."""
    from ..pose.blazepose import BlazePoseEstimator

    gt = np.stack([s.keypoints for s in samples])
    views = [s.view for s in samples]
    methods = {"ps": [], "ps_generic": [], "ps_oracle_view": []}
    prior = model.uses_background
    if prior:
        methods["ps_single_image"] = []
    backgrounds = clip_backgrounds(samples) if prior else {}
    methods_v = model.VIEWPOINTS
    vpred = {w: [] for w in methods_v}
    for s in samples:
        f, scale = model.prepare(frame_of(s))
        feats, maps = model.view_features(f, full=True)
        for w in methods_v:
            vpred[w].append(model.classify_view(feats, w)[0])
        chosen = vpred[model.viewpoint][-1]
        fg = model.foreground_map(frame_of(s), backgrounds.get(s.clip), f)
        for name, mname in (("ps", chosen), ("ps_oracle_view", s.view), ("ps_generic", "generic")):
            methods[name].append(model.solve(mname, maps[mname], scale, fg, f))
        if prior:
            methods["ps_single_image"].append(model.solve(chosen, maps[chosen], scale))
    times = []
    for s in samples[:: max(1, len(samples) // 20)]:  # the pose command's path (only the chosen classifier)
        t0 = time.process_time()
        model.estimate(frame_of(s), background=backgrounds.get(s.clip))
        times.append(time.process_time() - t0)
    if blazepose:
        est = BlazePoseEstimator()
        bp, bview = [], []
        for s in samples:
            pf = est.estimate(s.bgr if s.bgr is not None else np.repeat(s.image[..., None], 3, 2))
            bp.append(pf.points)
            bview.append(pf.viewpoint)
        est.close()
        methods["blazepose"] = bp
        vpred["blazepose"] = bview
    out = {"n_frames": len(samples), "pcp": {}, "pck@0.2": {}, "viewpoint": {}, "by_source": {}}
    group = np.array([source_group(s.source, others) for s in samples])
    azimuths = [s.azimuth for s in samples]
    for g in sorted(set(group)):
        sel = np.flatnonzero(group == g)
        row = {"n_frames": int(len(sel)), "clips": len({samples[i].clip for i in sel})}
        for name in ("ps", "blazepose"):
            if name not in methods:
                continue
            hits = strict_pcp(np.stack([methods[name][i] for i in sel]), gt[sel])
            row[name] = {"pcp_mean": float(hits.mean()),
                         "pcp_per_part": {p: float(v) for p, v in zip(PART_NAMES, hits.mean(axis=0))}}
            vname = model.viewpoint if name == "ps" else "blazepose"
            vs = viewpoint_scores([views[i] for i in sel], [azimuths[i] for i in sel], [vpred[vname][i] for i in sel])
            row[name]["viewpoint_accuracy"] = vs["accuracy"]
            row[name]["viewpoint_accuracy_off_boundary"] = vs["unambiguous"]["accuracy"]
        out["by_source"][g] = row
    for name, preds in methods.items():
        P = np.stack(preds)
        hits = strict_pcp(P, gt)
        out["pcp"][name] = pcp_table(hits, views)
        k = pck(P, gt)
        if name == "blazepose":
            found = P[:, :, 2].max(axis=1) > 0
            out["blazepose_detected"] = float(found.mean())
        out["pck@0.2"][name] = {"all": float(k.mean()), **{kp: float(k[:, i].mean()) for i, kp in enumerate(KEYPOINTS)}}
    for name, pred in vpred.items():
        out["viewpoint"][name] = viewpoint_scores(views, azimuths, pred)
    out["ps_cpu_ms_per_frame_median"] = float(np.median(times) * 1000) if times else None
    out["ps_viewpoint_method"] = model.viewpoint
    out["ps_person_prior"] = {"fg_weight": float(getattr(model, "fg_weight", 0.0)),
                              "clips_with_background": len(backgrounds)}
    return out


def format_tables(m: dict) -> str:
    lines = []
    cols = [s for s, _ in TABLE5]
    for name, rows in m["pcp"].items():
        lines.append(f"strict PCP, {name} (rows: true viewpoint; thesis Table 5 layout)")
        lines.append(f"{'':10s}" + "".join(f"{c:>7s}" for c in cols) + f"{'mean':>7s}{'n':>6s}")
        for v, r in rows.items():
            mean = np.mean([r[c] for c in cols])
            lines.append(f"{v:10s}" + "".join(f"{r[c]:7.2f}" for c in cols) + f"{mean:7.3f}{r['n']:6d}")
        lines.append(f"PCK@0.2 torso: {m['pck@0.2'][name]['all']:.3f}")
        lines.append("")
    for name, c in m["viewpoint"].items():
        lines.append(f"viewpoint confusion, {name} (rows true, columns estimated; thesis Table 6 layout)")
        lines.append(f"{'':8s}" + "".join(f"{v:>8s}" for v in c["labels"]))
        for v, row in zip(c["labels"], c["rates"]):
            lines.append(f"{v:8s}" + "".join(f"{x:8.2f}" for x in row))
        lines.append(f"accuracy {c['accuracy']:.3f}")
        if "unambiguous" in c:
            u, b = c["unambiguous"], c["boundary"]
            lines.append("  away from view boundaries (one true view): " + ", ".join(
                f"{v} {a:.3f}" for v, a in u["per_view_accuracy"].items() if v in c["tolerant_per_view_accuracy"])
                + f"; accuracy {u['accuracy']:.3f}")
            if b["n"]:
                lines.append(f"  on a boundary (+-{b['tolerance_deg']:g} deg; either neighbour counts): "
                             f"{b['accuracy_either_neighbour']:.3f} of {b['n']} frames")
            lines.append("  either neighbour counts at a boundary, by nearest view: " + ", ".join(
                f"{v} {a:.3f}" for v, a in c["tolerant_per_view_accuracy"].items())
                + f"; accuracy {c['tolerant_accuracy']:.3f}")
        lines.append("")
    if "real" in m:
        lines.append("real footage: agreement of ps with blazepose (PCK@0.2 of blazepose's torso)")
        for v, r in m["real"].items():
            lines.append(f"  {v}: {r['pck']:.3f} over {r['frames']} frames (blazepose found a person in "
                         f"{r['blazepose_found']} of them); overlay {r['overlay']}")
    return "\n".join(lines)


SKELETON_LINES = [tuple(p) for p in PART_KEYPOINTS.tolist()]


def draw_overlay(frame: np.ndarray, poses: dict[str, np.ndarray]) -> np.ndarray:
    """Both backends' skeletons drawn on a frame: ps in red, blazepose in green."""
    import cv2

    img = frame.copy()
    s = max(1, round(img.shape[0] / 300))
    colours = {"ps": (40, 40, 230), "blazepose": (40, 200, 40)}
    for name, pts in poses.items():
        col = colours.get(name, (200, 200, 0))
        for a, b in SKELETON_LINES:
            if pts[a, 2] > 0 and pts[b, 2] > 0:
                cv2.line(img, tuple(round(v) for v in pts[a, :2]), tuple(round(v) for v in pts[b, :2]),
                         col, 2 * s, cv2.LINE_AA)
        for p in pts:
            if p[2] > 0:
                cv2.circle(img, (round(p[0]), round(p[1])), 2 * s, col, -1, cv2.LINE_AA)
        cv2.putText(img, name, (10 * s, (30 if name == "ps" else 60) * s), cv2.FONT_HERSHEY_SIMPLEX, 0.8 * s, col, 2 * s)
    return img


def evaluate_real(model_path: str, videos: list[Path], overlay_dir: Path, frames_per_video: int = 6,
                  jobs: int = 1) -> dict:
    from ..fileio import output_dir

    # overlay_dir is made if missing and removed again, when empty, if this fails; temporaries a killed run
    # left for these overlays are swept
    with output_dir(overlay_dir, [f"{Path(v).stem}.pose_overlay.png" for v in videos]):
        return {Path(v).stem: _real_video(model_path, v, overlay_dir, frames_per_video, jobs) for v in videos}


def _real_video(model_path: str, v: Path, overlay_dir: Path, frames_per_video: int, jobs: int) -> dict:
    """One video of :func:`evaluate_real`: the backends' agreement and its overlay PNG (written atomically)."""
    import cv2

    from ..fileio import atomic_path
    from ..pose.run import estimate_video
    from ..video import VideoReader

    with VideoReader(v) as r:
        n = len(r)
    idx = sorted(set(np.linspace(0, n - 1, frames_per_video).round().astype(int).tolist()))
    ps = estimate_video(v, "ps", model_path, idx, jobs=jobs)
    bp = estimate_video(v, "blazepose", None, idx, jobs=jobs)
    P = np.stack([f.points for f in ps.frames])
    B = np.stack([f.points for f in bp.frames])
    found = B[:, :, 2].max(axis=1) > 0
    agree = pck(P[found], B[found]).mean() if found.any() else float("nan")
    mid = int(np.flatnonzero(found)[len(np.flatnonzero(found)) // 2]) if found.any() else 0
    with VideoReader(v) as r:
        frame = np.array(r.frame(idx[mid]))
    png = overlay_dir / f"{Path(v).stem}.pose_overlay.png"
    with atomic_path(png) as tmp:
        if not cv2.imwrite(str(tmp), draw_overlay(frame, {"ps": P[mid], "blazepose": B[mid]})):
            raise OSError(f"{png}: cannot write the overlay")
    return {"pck": float(agree), "frames": len(idx), "blazepose_found": int(found.sum()), "overlay": str(png),
            "ps_viewpoints": [f.viewpoint for f in ps.frames],
            "blazepose_viewpoints": [f.viewpoint for f in bp.frames]}


VIDEO_SUFFIXES = (".mp4", ".mkv", ".avi", ".mov")


def _other_clips(other_dir: str | Path | None, n: int, seed: int) -> list[str]:
    """``n`` BVH files of ``other_dir`` chosen by ``seed`` (all when fewer), sorted; none without a directory."""
    from ..errors import InputError

    if other_dir is None or str(other_dir) in ("", "none") or n <= 0:
        return []
    d = Path(other_dir)
    if not d.is_dir():
        raise InputError(f"{d}: directory of other clips not found")
    files = sorted(str(p) for p in d.glob("*.bvh"))
    if not files:
        raise InputError(f"{d}: no .bvh files")
    rng = np.random.default_rng(np.random.SeedSequence([seed, 7]))
    return sorted(files[i] for i in rng.permutation(len(files))[:n])


def evaluate(model_path: str | Path, cmu_dir: str | Path | None = None, demo_performers: int = 3, cmu_clips: int = 6,
             views_per_clip: int = 4, seconds: float = 2.0, fps: float = 4.0, real_dir: str | Path | None = None,
             overlay_dir: str | Path = "pose_overlays", real_frames: int = 6, seed: int = 0, jobs: int = -1, *,
             other_dir: str | Path | None = None, other_clips: int = 6, elevation: tuple[float, float] | None = None,
             scale: tuple[float, float] | None = None, proportions: float = 0.0) -> dict:
    """``vidstyle evaluate pose``: the metrics of a pose model file on held-out renders (test split: demo
    performers, and CMU clips of ``cmu_dir`` when given) for every method (:func:`evaluate_renders`), and,
    with ``real_dir`` (a directory of videos), the backends' agreement and overlays on that real footage
    (:func:`evaluate_real`). ``other_dir``: BVH clips of another skeleton (e.g. Bandai's), ``other_clips``
    of them (chosen by ``seed``) rendered as well and scored as their own group (``by_source``);
    ``elevation``, ``scale``, ``proportions``: the cameras and bodies of the renders
    (:func:`vidstyle.pose.data.make_specs`). Returns the metrics document (without ``seed``, which the
    caller adds)."""
    from ..errors import InputError
    from ..pose.data import make_specs, render_samples
    from ..pose.estimator import load_model
    from ..pose.training import resolve_cmu_dir

    pm, header = load_model(model_path)
    cmu = resolve_cmu_dir(cmu_dir, cmu_clips)
    from ..pose.data import ELEVATION_RANGE, SCALE_RANGE

    others = _other_clips(other_dir, other_clips, seed)
    elevation = ELEVATION_RANGE if elevation is None else elevation
    scale = SCALE_RANGE if scale is None else scale
    try:
        specs = make_specs("test", demo_performers, cmu_clips, views_per_clip, seed, cmu, fps=fps, seconds=seconds,
                           elevation=elevation, scale=scale, proportions=proportions, other_clips=others)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    samples = render_samples(specs, jobs=jobs, keep_bgr=True)
    metrics = evaluate_renders(pm, samples, others=set(others))
    metrics["params"] = {"model": str(model_path), "model_params": header.get("params"), "seed": seed,
                         "demo_performers": demo_performers, "cmu_clips": cmu_clips, "views_per_clip": views_per_clip,
                         "seconds": seconds, "fps": fps, "cmu_dir": None if cmu is None else str(cmu),
                         "other_dir": None if other_dir is None else str(other_dir), "other_clips": len(others),
                         "elevation": list(map(float, elevation)), "scale": list(map(float, scale)),
                         "proportions": proportions}
    if real_dir is None or str(real_dir) in ("", "none"):
        log.info("no real footage directory given (--real-dir): backend agreement on real footage skipped")
    else:
        rd = Path(real_dir)
        if not rd.is_dir():
            raise InputError(f"{rd}: real footage directory not found")
        videos = sorted(p for p in rd.iterdir() if p.suffix.lower() in VIDEO_SUFFIXES)
        metrics["real"] = evaluate_real(str(model_path), videos, Path(overlay_dir), real_frames, jobs=1)
    return metrics
