"""Evaluation of a performer's action-level style fitted from 2D (``scripts/eval_action_style.py``,
``scripts/validate_action_style.py``; :mod:`vidstyle.actionmodel.stylefit`).

* :func:`orthodox_model`: one :class:`~vidstyle.actionmodel.ActionModel` on every take of the given
  (training) performers, southpaws' clips mirrored to orthodox (their lead is the dataset's truth: the
  training performers' mocap is labelled data).
* :func:`performer_videos`: a performer's videos as ``(xy, labels, view, confidence)`` for an input ``kind``:
  ``true`` (true 2D keypoints projected from the truth sidecar), ``noisy`` (true 2D plus Gaussian noise of
  5 % of the torso and 5 % outliers, seeded), ``estimated`` (``<poses_dir>/<id>.poses.json``), with the
  true labels or the recognised ones (``labels_dir``).
* :func:`generated_mpjpe`: per label, the MPJPE (mm) of a generated instance against each of the
  performer's true instances of that label (retargeted onto the model's skeleton, canonical frame) after
  slope-limited DTW alignment of the joint positions (the generated instance decoded at the true
  instance's length, then aligned frame to frame); mean over instances.
* :func:`evaluate_split` (``vidstyle evaluate action-style``, the pipeline's ``action_style`` stage): one
  split's test performers fitted from true 2D and from pose files, the fits spread over workers per
  (performer, input, label); :func:`figure_png` draws one action of each.
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

    clips = orthodox_clips(load_labelled(_takes(dataset, performers)), southpaws(manifest))
    return ActionModel(**{**(params or {}), "random_state": seed}).fit(cut_instances(clips))


def performer_videos(ds, manifest: dict, performer: str, kind: str = "true", poses_dir: Path | None = None,
                     labels_dir: Path | None = None, rng: np.random.Generator | None = None,
                     cache: dict | None = None) -> list:
    """``[(xy, labels, view, confidence)]`` of ``performer``'s videos (module text; ``confidence`` the recognised
    labels' per-frame confidence, None for true labels); a video without a pose file is left out for ``estimated``."""
    from ..actionmodel.stylefit import noisy_track
    from ..formats.poses import read_poses
    from ..recognition.posefeatures import track_from_poses
    from .poserecognition import true_keypoints

    root = Path(ds.root)
    out = []
    for v in manifest["videos"]:
        if v["performer"] != performer:
            continue
        confidence = None
        if labels_dir is not None:
            f = Path(labels_dir) / f"{v['id']}.json"
            if not f.is_file():
                continue
            doc = json.loads(f.read_text())
            labels, confidence = doc["labels"], doc.get("confidence")
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
        out.append((xy, labels, v["view"], confidence))
    return out


def pose_files(dataset: str | Path, videos: list[str], backend: str, out_dir: str | Path, frames: int) -> Path:
    """``out_dir`` holding ``<video>.poses.json`` of the first ``frames`` frames of each of ``videos`` (ids under
    ``dataset/videos``) by ``backend``: made with the pipeline's ``reconstruct_poses`` command (``vidstyle pose
    ... --frames 0,...,frames-1 --jobs 1``) unless every file is there already (the validation scripts)."""
    import subprocess
    import sys

    out = Path(out_dir)
    if not all((out / f"{v}.poses.json").is_file() for v in videos):
        cmd = [sys.executable, "-m", "vidstyle", "pose", *(str(Path(dataset) / "videos" / f"{v}.mp4") for v in videos),
               "--backend", backend, "--out-dir", str(out), "--frames", ",".join(map(str, range(int(frames)))),
               "--jobs", "1"]
        log.info("vidstyle pose --backend %s: %d videos", backend, len(videos))
        subprocess.run(cmd, check=True)
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

    C = np.linalg.norm((gen_pos[:, None] - true_pos[None]), axis=-1).mean(-1)
    _, path = dtw(C, slope_limit)
    path = np.asarray(path)
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
    return score_performer(model, style, len(videos), truth_style, truth, actions, unit_mm,
                           time.perf_counter() - t0, seed)


def score_performer(model, style, n_videos: int, truth_style: dict, truth: dict, actions: list[str], unit_mm: float,
                    fit_s: float = 0.0, seed: int = 0) -> dict:
    """The scores of :func:`evaluate_performer` for an already fitted ``style`` (its row, ``style`` kept)."""
    gs = style.global_style
    ts = truth_style
    row = {"lead_true": ts["lead"], "lead": gs.lead, "lead_score": gs.lead_score,
           "guard_height_true": ts["guard_height"], "guard_height": gs.guard_height,
           "stance_width_true": ts["stance_width"], "stance_width": gs.stance_width,
           "crouch_true": ts["crouch"], "crouch": gs.crouch,
           "tempo_true": {a: ts["tempo"][k] for k, a in enumerate(actions)},
           "duration_factor_true": {a: ts["tempo"][k] / ts["speed"] for k, a in enumerate(actions)},
           "tempo": gs.tempo, "relative_tempo": gs.relative_tempo,
           "speed_true": ts["speed"], "speed": gs.speed if np.isfinite(gs.speed) else None,
           "action_tempo": gs.action_tempo,
           "videos": n_videos, "fit_seconds": fit_s, "segments": dict(style.counts), "labels": {}}
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
    tt, te, dt, rt, rte, at, ae, ap, ape = [], [], [], [], [], [], [], [], []
    for r in rows:
        mt = np.mean(list(r["tempo_true"].values()))
        for a in actions:
            if a in r["tempo"]:
                tt.append(r["tempo_true"][a])
                dt.append(r["duration_factor_true"][a])
                te.append(r["tempo"][a])
                rt.append(r["tempo_true"][a] / mt)
                rte.append(r["relative_tempo"][a])
            if a in (r.get("action_tempo") or {}):
                at.append(r["tempo_true"][a])
                ae.append(r["action_tempo"][a])
                if a in (r.get("population_tempo_true") or {}):
                    ap.append(r["tempo_true"][a] / r["population_tempo_true"][a])
                    ape.append(r["action_tempo"][a])
    out["duration_factor_r"] = pearson(dt, te)  # tempo / speed: what durations show
    out["tempo_r"] = pearson(tt, te)  # the raw per-action tempo parameter against the duration factor
    out["relative_tempo_r"] = pearson(rt, rte)  # tempo / the performer's mean tempo
    # the per-action tempo itself: the performer's action-to-step length ratio over the population's
    out["action_tempo_r"] = pearson(at, ae)
    out["action_tempo_pairs"] = len(at)
    # the same against the truth over the population's mean tempo of the action: the reference the estimate is
    # relative to (the population's clips are what synthesize re-times), which no video of the performer shows
    out["action_tempo_population_r"] = pearson(ap, ape)
    sp = [(r["speed_true"], r["speed"]) for r in rows if r.get("speed") is not None]
    out["speed_r"] = pearson([a for a, _ in sp], [b for _, b in sp])
    keys = ("fitted_mean_mm", "fitted_sample_mm", "unfitted_mean_mm", "unfitted_sample_mm", "unfitted_mean_true_lead_mm")
    vals = {k: [lr[k] for r in rows for lr in r["labels"].values() if np.isfinite(lr[k])] for k in keys}
    for k in keys:
        out[k] = float(np.mean(vals[k])) if vals[k] else None
    if out.get("unfitted_mean_mm"):
        out["mpjpe_reduction"] = 1 - out["fitted_mean_mm"] / out["unfitted_mean_mm"]
        out["mpjpe_reduction_sample"] = 1 - out["fitted_sample_mm"] / out["unfitted_sample_mm"]
        out["mpjpe_reduction_vs_true_lead"] = 1 - out["fitted_mean_mm"] / out["unfitted_mean_true_lead_mm"]
    return out


def population_tempo(truth_style: dict, performers, actions: list[str]) -> dict[str, float]:
    """The mean true per-action tempo of ``performers`` (dataset ``style``): the reference that
    :class:`~vidstyle.actionmodel.stylefit.GlobalStyleEstimator` fitted on them measures ``action_tempo``
    against (the mean over its performers of their own action-to-step ratios, each ``tempo[a]`` times a
    constant of the action)."""
    return {a: float(np.mean([truth_style[p]["tempo"][k] for p in performers])) for k, a in enumerate(actions)}


def style_params() -> dict:
    """The fitting and run-timing defaults an action-style metrics file records, with their validations."""
    from ..actionmodel import defaults as D

    return {"n_fit": D.STYLE_N_FIT, "prior_weight": D.STYLE_PRIOR_WEIGHT, "loss_scale": D.STYLE_LOSS_SCALE,
            "elevation_deg": D.STYLE_ELEVATION_DEG, "max_segments": D.STYLE_MAX_SEGMENTS, "rounds": D.STYLE_ROUNDS,
            "validation": "pipelines/kickboxing/validation/action_style.json",
            "min_run_confidence": D.STYLE_MIN_RUN_CONFIDENCE, "step_min_run_confidence": D.STYLE_STEP_MIN_RUN_CONFIDENCE,
            "max_run_factor": D.STYLE_MAX_RUN_FACTOR, "min_run_factor": D.STYLE_MIN_RUN_FACTOR,
            "run_timing": D.STYLE_RUN_TIMING, "motion_level": D.STYLE_MOTION_LEVEL, "motion_filter": D.STYLE_MOTION_FILTER,
            "min_run_confidence_validation": "pipelines/kickboxing/validation/tempo_runs.json"}


def row_json(r: dict) -> dict:
    return {k: v for k, v in r.items() if k != "style"}


# ---------------------------------------------------------------------------------------------- the pipeline's run
#: input kinds of :func:`evaluate_split`: true 2D with the true labels (every video of the performer), and the
#: pose stage's 2D (``poses_dir``: the videos that have a pose file) with the recognised labels (``labels_dir``)
SPLIT_INPUTS = ("true", "estimated")


def fit_training(dataset: str | Path, seed: int = 0, jobs: int = 1, demo: dict | None = None):
    """``(demo, groups, model, estimator)``: the dataset's truth (:func:`demo_truth`, or ``demo`` when already
    read), split ``seed``'s performer groups, and the orthodox model (:func:`orthodox_model`) and the
    population's global-style estimator fitted on the training performers (A+B) only.

    The work is spread over ``jobs`` workers: the population figures and each training
    performer's instances (their takes read, southpaws mirrored, cut and retargeted onto the first take's
    skeleton, as :func:`orthodox_model` does for all at once) at the same time, then the labels' models
    (``ActionModel(n_jobs=jobs)``); the same model as :func:`orthodox_model`'s."""
    from ..actionmodel import ActionModel, InstanceSet
    from ..errors import InputError
    from ..parallel import limit_threads, parallel_map
    from .actionmodel import split_groups

    demo = demo_truth(dataset) if demo is None else demo
    groups = split_groups(demo["manifest"], seed)
    train = sorted(groups["A"] + groups["B"])
    from ..actionmodel import load_labelled
    from ..actionmodel.stylefit import orthodox_clips

    south = southpaws(demo["manifest"])
    # the skeleton orthodox_model retargets onto: the first take of all, mirrored if a southpaw's
    reference = orthodox_clips(load_labelled(_takes(dataset, train)[:1]), south)[0].motion.skeleton
    items = [("population", dataset, train)] + [("instances", dataset, p, south, reference) for p in train]
    est, *parts = parallel_map(_prepare_worker, items, jobs=jobs, description="training performers")
    first = parts[0]
    other = next((part for part in parts if abs(part.fps - first.fps) > 1e-6), None)
    if other is not None:  # what cut_instances says of clips at two frame rates, across performers too
        raise InputError(f"{other.sources[0]}: frame rate {other.fps:g} differs from the first clip's {first.fps:g}; "
                         "resample the clips to one rate")
    iset = InstanceSet([i for part in parts for i in part.instances], first.skeleton, first.fps,
                       [s for part in parts for s in part.sources])
    with limit_threads(1):  # as in a worker: the models do not depend on where they were fitted
        model = ActionModel(random_state=seed, n_jobs=jobs).fit(iset)
    model.n_jobs = None  # the run setting stays with this call
    return demo, groups, model, est


def fit_population(ds, manifest: dict, performers, cache: dict | None = None, **params):
    """The global-style estimator fitted on the true 2D of ``performers``' videos, each video grouped by its
    performer (:meth:`~vidstyle.actionmodel.stylefit.GlobalStyleEstimator.fit`'s ``groups``)."""
    from ..actionmodel.stylefit import GlobalStyleEstimator

    videos = {p: performer_videos(ds, manifest, p, "true", cache=cache) for p in performers}
    return GlobalStyleEstimator(**params).fit([x for p in performers for x in videos[p]],
                                              groups=[p for p in performers for _ in videos[p]])


def _population(dataset, train):
    demo = demo_truth(dataset)
    return fit_population(demo["dataset"], demo["manifest"], train)


def _takes(dataset, performers) -> list:
    from .actionmodel import performer_takes

    paths = []
    for p in performers:
        s, pf = performer_takes(dataset, p)
        paths += s + pf
    return paths


def _prepare_worker(item):
    """The population's global-style estimator (``"population"``) or one training performer's instances
    (``"instances"``) of :func:`fit_training`."""
    from ..actionmodel import cut_instances, load_labelled
    from ..actionmodel.stylefit import orthodox_clips

    if item[0] == "population":
        return _population(*item[1:])
    _, dataset, performer, south, reference = item
    return cut_instances(orthodox_clips(load_labelled(_takes(dataset, [performer])), south), reference=reference)


def _label_worker(item):
    """One (performer, input, label) fit of :func:`evaluate_split`: (result, seconds)."""
    import time

    from ..actionmodel.stylefit import fit_label_segments

    model, label, segments = item
    t0 = time.perf_counter()
    return fit_label_segments(model, label, segments), time.perf_counter() - t0


def _score_worker(item) -> dict:
    """The scores of one (performer, input) of :func:`evaluate_split`."""
    return score_performer(*item)


def evaluate_split(dataset: str | Path, seed: int = 0, poses_dir: str | Path | None = None,
                   labels_dir: str | Path | None = None, inputs=SPLIT_INPUTS, jobs: int = 1,
                   figure_label: str = "Jab") -> dict:
    """The action-level style of split ``seed``'s test performers (``unseen-performer`` groups), as the
    pipeline runs it: the orthodox model and the population figures on the training performers (sets A
    and B) only, then every test performer fitted from each input of ``inputs`` (:data:`SPLIT_INPUTS`)
    and scored (:func:`evaluate_performer`). A performer without a pose file for ``estimated`` has no
    row for it. Returns ``doc`` (the metrics body), ``model``, ``styles`` (input -> performer ->
    :class:`~vidstyle.actionmodel.stylefit.ActionStyle`) and ``figure`` (per performer of the first
    input with rows: its true, fitted and unfitted ``figure_label`` as keypoint positions)."""
    import time

    from ..actionmodel import defaults as D
    from ..actionmodel.stylefit import assemble_action_style, plan_action_style
    from ..errors import InputError
    from ..mocap.keypoints import keypoint_positions
    from ..parallel import parallel_map

    t_start = time.perf_counter()
    unknown = [k for k in inputs if k not in SPLIT_INPUTS]
    if unknown or not inputs:
        raise InputError(f"inputs: {', '.join(unknown) or 'none given'}: expected some of {', '.join(SPLIT_INPUTS)}")
    if "estimated" in inputs and (poses_dir is None or labels_dir is None):
        raise InputError("the estimated input needs a poses directory and a recognised labels directory")
    for d in (poses_dir, labels_dir):
        if d is not None and not Path(d).is_dir():
            raise InputError(f"{d}: directory not found")
    demo = demo_truth(dataset)
    if figure_label not in demo["actions"]:  # before the fits, not after
        raise InputError(f"label: {figure_label!r} is not an action of {dataset} ({', '.join(demo['actions'])})")
    t0 = time.perf_counter()
    demo, groups, model, est = fit_training(dataset, seed, jobs, demo)
    manifest, ds, unit_mm, actions = demo["manifest"], demo["dataset"], demo["unit_mm"], demo["actions"]
    train = sorted(groups["A"] + groups["B"])
    fit_model_s = time.perf_counter() - t0
    log.info("action style: orthodox model and population on %s (%.1f s)", ", ".join(train), fit_model_s)
    items, keys, truths = [], [], {}
    for p in groups["T"]:
        truths[p] = true_instances(dataset, p, model, seed=seed)
        for kind in inputs:
            if kind == "true":
                vids = performer_videos(ds, manifest, p, "true")
            else:
                vids = [v for v in performer_videos(ds, manifest, p, "estimated", poses_dir=Path(poses_dir),
                                                    labels_dir=Path(labels_dir)) if np.isfinite(v[0]).any()]
            if not vids:
                log.warning("action style: %s has no %s input (no pose file or labels)", p, kind)
                continue
            # what fit_action_style does, its labels spread over the workers (the same fits: the segments are
            # chosen in the same order from the same seed, and each label's fit is independent)
            gs, segs = plan_action_style(model, est, vids, D.STYLE_MAX_SEGMENTS, seed)
            items.append((gs, segs, len(vids)))
            keys.append((p, kind))
    tasks = [(i, label, segs) for i, (_gs, plan, _n) in enumerate(items) for label, segs in plan.items()]
    order = sorted(range(len(tasks)), key=lambda t: -sum(len(x) for x in tasks[t][2]))  # longest first
    done = parallel_map(_label_worker, [(model, tasks[t][1], tasks[t][2]) for t in order], jobs=jobs,
                        description="action-style fits")
    fits: list[dict] = [{} for _ in items]
    seconds = [0.0] * len(items)
    for t, (fit, secs) in zip(order, done):
        i, label, _ = tasks[t]
        fits[i][label] = fit
        seconds[i] += secs
    scored = [(model, assemble_action_style(gs, fits[i]), n, demo["style"][p], truths[p], actions, unit_mm,
               seconds[i], seed) for i, ((p, _kind), (gs, _segs, n)) in enumerate(zip(keys, items))]
    rows = parallel_map(_score_worker, scored, jobs=jobs, description="action-style scores")
    by_kind: dict[str, list] = {k: [] for k in inputs}
    styles: dict[str, dict] = {k: {} for k in inputs}
    pop_tempo = population_tempo(demo["style"], train, actions)
    for (p, kind), r in zip(keys, rows):
        r.update(seed=seed, performer=p, input=kind, population_tempo_true=pop_tempo)
        by_kind[kind].append(r)
        styles[kind][p] = r["style"]
    by_input = {k: summarise(v, actions) for k, v in by_kind.items() if v}
    if not by_input:
        raise InputError("no test performer has any input to fit")
    figure = {}
    first = next(k for k in inputs if by_kind[k])
    lm = model.models_.get(figure_label)
    if lm is not None:
        mu = lm.gmm_means[int(np.argmax(lm.gmm_weights))]
        for p, st in styles[first].items():
            true_m = truths[p].get(figure_label)  # the first of the instances the scores used
            if not true_m or figure_label not in st.coefficients:
                continue
            n = true_m[0].n_frames
            figure[p] = {"lead": demo["style"][p]["lead"], "fitted_lead": st.global_style.lead,
                         "true": keypoint_positions(true_m[0]),
                         "fitted": keypoint_positions(st.realise(model, figure_label, n)),
                         "unfitted": keypoint_positions(model.decode(mu, figure_label, n_frames=n))}
    # the headline: true 2D first (the fit itself, as scripts/eval_action_style.py reports it), then the
    # pose stage's 2D (what the run's own video gives) as estimated_*
    head_kind = "true" if "true" in by_input else first
    head = by_input[head_kind]
    headline = {"lead_accuracy": head.get("lead_accuracy", 0.0), "mpjpe_reduction": head.get("mpjpe_reduction", 0.0),
                "mpjpe_reduction_vs_true_lead": head.get("mpjpe_reduction_vs_true_lead"),
                "performers": head.get("performers"), "input": head_kind}
    if "estimated" in by_input and head_kind != "estimated":
        e = by_input["estimated"]
        headline.update(estimated_lead_accuracy=e.get("lead_accuracy"), estimated_mpjpe_reduction=e.get("mpjpe_reduction"))
    doc = {
        "seed": seed, "seeds": [seed], "dataset": str(dataset), "mm_per_unit": unit_mm,
        "splits": {str(seed): groups},
        "params": style_params(),
        "inputs_note": {"true": "true 2D keypoints of every video of the performer, true labels",
                        "estimated": f"pose files of {poses_dir} (the frames they cover), labels of {labels_dir}"},
        "by_input": by_input,
        "rows": {k: [row_json(r) for r in v] for k, v in by_kind.items() if v},
        "action_style": headline,
        "model_seconds": fit_model_s, "wall_seconds": time.perf_counter() - t_start,
    }
    return {"doc": doc, "model": model, "styles": styles, "figure": figure, "figure_label": figure_label,
            "figure_input": first}


def figure_png(figure: dict, label: str, title: str = "") -> bytes:
    """PNG of :func:`evaluate_split`'s ``figure``: one row per performer, their true (black), fitted (blue)
    and unfitted (red) ``label`` as stick figures from above and from the side at the start, middle and
    end of the true instance (the generated ones at the frames DTW aligns with those), side by side."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..actionmodel.dtw import dtw
    from ..mocap.keypoints import KEYPOINT_INDEX, PARTS

    bones = [(KEYPOINT_INDEX[a], KEYPOINT_INDEX[b]) for a, b in PARTS.values()]
    bones += [(KEYPOINT_INDEX["neck"], KEYPOINT_INDEX[s]) for s in ("left_shoulder", "right_shoulder")]
    bones += [(KEYPOINT_INDEX["pelvis"], KEYPOINT_INDEX[s]) for s in ("left_hip", "right_hip")]
    colours = {"true": "k", "fitted": "tab:blue", "unfitted": "tab:red"}
    perfs = sorted(figure)
    fig, axes = plt.subplots(max(len(perfs), 1), 2, figsize=(9, 2.6 * max(len(perfs), 1)), squeeze=False)
    for row, p in enumerate(perfs):
        seqs = {k: np.asarray(figure[p][k]) for k in colours}
        truth = seqs["true"]
        n = len(truth)
        height = float(np.ptp(truth[..., 1])) or 1.0
        step = 1.2 * height
        marks = np.linspace(0, n - 1, 3).astype(int)
        for col, (view, (a, b)) in enumerate((("from above", (0, 2)), ("from the side", (2, 1)))):
            ax = axes[row, col]
            for name, pts in seqs.items():
                if name == "true":
                    idx = marks
                else:
                    C = np.linalg.norm(pts[:, None] - truth[None], axis=-1).mean(-1)
                    path = np.asarray(dtw(C, 5)[1])
                    idx = [int(path[path[:, 1] == t][0, 0]) for t in marks]
                for k, f in enumerate(idx):
                    for bi, (i, j) in enumerate(bones):
                        q = pts[f, [i, j]]
                        ax.plot(q[:, a] + k * step, q[:, b], colours[name], lw=1.2, alpha=0.85,
                                label=name if bi == 0 and k == 0 and row == 0 and col == 0 else None)
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title(f"{p} ({figure[p]['lead']}, fitted {figure[p]['fitted_lead']}): {label} {view}, "
                         "start / middle / end", fontsize=8)
    if perfs:
        handles, names = axes[0, 0].get_legend_handles_labels()
        fig.legend(handles, names, fontsize=7, loc="lower center", ncol=3, frameon=False)
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return buf.getvalue()
