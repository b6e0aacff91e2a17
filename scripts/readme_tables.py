#!/usr/bin/env python
"""Regenerate the README's results tables from metrics files, so no published number is typed by hand.

Reads every JSON document under ``--metrics DIR`` (recursively) and recognises them by ``kind``:

- ``vidstyle.metrics.recognition`` (``vidstyle evaluate recognition --out``): one row per split
  kind, the mean, spread and minimum over the seeds found, the ablation ``none`` only; the mirror-training
  flag is part of the row name when a file trained without it;
- ``vidstyle.metrics.style`` (``vidstyle evaluate style --out``): transition error and identification per
  label source (ground truth, ground truth of the test performers, recognised labels of the test performers);
- ``vidstyle.metrics.style_viterbi_prior`` (``scripts/style_viterbi_prior.py``): one row per decoder;
- ``vidstyle.validation.recognition`` (``scripts/validate_recognition.py``): the chosen values with the
  validation score each won with;
- ``vidstyle.metrics.pose`` (``vidstyle evaluate pose --out``): mean strict PCP, PCK@0.2 and viewpoint
  accuracy per backend / pictorial-structures variant;
- ``vidstyle.metrics.augmg`` (``vidstyle evaluate augmg --out``): retrieval and transition error per 2D
  source;
- ``vidstyle.metrics.multiview_pose`` (``vidstyle evaluate pose --calibration --out``): PCK on calibrated
  real views, plain and robust references;
- ``vidstyle.metrics.people`` (``vidstyle evaluate people --out``): identity switches and PCK with and
  without following the performer;
- ``vidstyle.metrics.strikes`` (``vidstyle evaluate strikes --out``): the share of a real mocap clip's
  action frames recognised as punches, per camera;
- ``vidstyle.strikes_diagnostics`` (``scripts/strikes_diagnostics.py``): the same share for each variant
  of the clip (mirrored, arms only, upper body, slower, faster) and for demo punches;
- ``vidstyle.metrics.reconstruct`` (``vidstyle evaluate reconstruct --out``), ``vidstyle.validation.
  reconstruct_heldout`` (``scripts/reconstruct_heldout.py``) and ``vidstyle.validation.reconstruct_defaults``
  (``scripts/validate_reconstruct.py``): 3D reconstruction errors per 2D source, method and skeleton, and
  the validated defaults.

Every row names the file it came from (several ``--metrics`` directories: the README uses the committed
results and the validation files, ``--metrics pipelines/kickboxing/results pipelines/kickboxing/validation``).

Three generated blocks, each between its own markers, replaced atomically wherever they appear:

- the full tables, between ``<!-- results:begin -->`` and ``<!-- results:end -->`` (in ``docs/results.md``);
- a short headline table (a few rows in plain words, each linking to ``docs/results.md``),
  between ``<!-- headline:begin -->`` and ``<!-- headline:end -->`` (in the README);
- issue 28's recognition goals with a row per split seed (:func:`recognition_goals`), between
  ``<!-- recognition-goals:begin -->`` and ``<!-- recognition-goals:end -->`` (in the README).

With ``--readme README.md`` the blocks are written into the README and into ``--results`` (default: the
README's ``docs/results.md``, when it exists). Without any markers (or without ``--readme``) the full tables
go to stdout. ``--check`` exits 1 when a file is not up to date.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"
HEAD_BEGIN, HEAD_END = "<!-- headline:begin -->", "<!-- headline:end -->"
GOALS_BEGIN, GOALS_END = "<!-- recognition-goals:begin -->", "<!-- recognition-goals:end -->"


def _pct(x) -> str:
    return "n/a" if x is None else f"{100 * x:.1f} %"


def _pct_number(x) -> str:
    """A fraction as a bare percentage with one decimal (a dash for None), for tables whose header says %."""
    return "—" if x is None else f"{100 * x:.1f}"


def _spread(xs) -> str:
    xs = [x for x in xs if x is not None]
    if not xs:
        return "n/a"
    m = sum(xs) / len(xs)
    if len(xs) == 1:
        return _pct(m)
    sd = (sum((x - m) ** 2 for x in xs) / (len(xs) - 1)) ** 0.5
    return f"{100 * m:.1f} ± {100 * sd:.1f} % (min {100 * min(xs):.1f})"


def load_documents(root: Path) -> dict[str, list[tuple[Path, dict]]]:
    docs: dict[str, list[tuple[Path, dict]]] = defaultdict(list)
    for p in sorted(root.rglob("*.json")):
        try:
            d = json.loads(p.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if isinstance(d, dict) and isinstance(d.get("kind"), str):
            docs[d["kind"]].append((p, d))
    return docs


def _rel(p: Path, root: Path) -> str:
    """``p`` relative to ``root`` (the first metrics directory), or to the parent of the other directory
    it came from (``validation/recognition.json``)."""
    try:
        return str(p.relative_to(root))
    except ValueError:
        pass
    for extra in EXTRA_ROOTS:
        try:
            return str(p.relative_to(extra.parent))
        except ValueError:
            continue
    return str(p)


#: metrics directories after the first (set by :func:`tables`)
EXTRA_ROOTS: list[Path] = []


def _noise_text(noise: dict) -> str:
    """How a pose recognizer's training noise (its metrics' ``training.noise``) was made."""
    if noise.get("kind") == "residuals":
        return ("the pose estimator's own errors on set A's videos"
                + (" (Gaussian beyond their poses' reach)" if noise.get("max_distance") is not None else ""))
    return "noise calibrated on validation" if noise.get("calibrated_on_videos") else ""


def _config(d: dict) -> str:
    """The recognizer values a metrics file records (the decoding of scored labels when it differs)."""
    if d.get("recognizer") in ("pose", "pose+sift"):  # the pose-sequence recognizer keeps its values in params
        q = d.get("params") or {}
        tr = d.get("training") or {}
        views = tr.get("n_views")
        noise = tr.get("noise") or {}
        fusion = d.get("fusion") or {}
        return ", ".join(x for x in ("pose sequences" + (f" from {d['input']}" if d.get("input") else ""),
                                     f"{views} virtual views per take" if views else "",
                                     _noise_text(noise),
                                     (f"fused with the seed's 3D SIFT recognizer, pose weight {fusion['weight_pose']:g}"
                                      + (f", fused scores ^{fusion['emission_weight']:g} in the smoother"
                                         if fusion.get("emission_weight") not in (None, 1, 1.0) else "")
                                      if fusion.get("weight_pose") is not None else ""),
                                     f"C {q['C']:g}" if q.get("C") is not None else "",
                                     f"cap {q['max_frames_per_class']}" if "max_frames_per_class" in q else "",
                                     f"{q['smoothing']}" if q.get("smoothing") else "") if x)
    rp = (d.get("params") or {}).get("recognizer") or {}
    dec = (d.get("decoding") or [{}])[0] if len(d.get("decoding") or []) == 1 else {}
    sm = dec.get("smoothing") or rp.get("smoothing")
    ew = dec.get("emission_weight") if dec.get("emission_weight") is not None else rp.get("emission_weight")
    parts = []
    n_points = (((d.get("params") or {}).get("features") or {}).get("salient") or {}).get("n_points")
    if n_points is not None:
        parts.append(f"{n_points} points")
    n_words = ((d.get("model_header") or {}).get("vocabulary") or {}).get("n_words")
    if n_words is not None:
        parts.append(f"{n_words} words")
    if rp.get("grouping_threshold") is not None and rp.get("grouping", True):
        parts.append(f"grouping {rp['grouping_threshold']:g}")
    if rp.get("C") is not None:
        parts.append(f"C {rp['C']:g}")
    if "max_frames_per_class" in rp:
        parts.append(f"cap {rp['max_frames_per_class']}")
    if rp.get("coarse_context"):
        parts.append(f"context {rp.get('context', 2)}+{rp['coarse_context']}")
    if sm:
        parts.append(f"{sm}" + (f" ^{ew:g}" if sm in ("viterbi", "duration") and ew is not None else ""))
    return ", ".join(parts) or "?"


def _configs(g) -> str:
    """The recognizer values of files sorted by seed: one when they agree, else one per seed."""
    cfgs = [(d.get("seed"), _config(d)) for _, d in g]
    if len({c for _, c in cfgs}) == 1:
        return cfgs[0][1]
    return "; ".join(f"seed {s}: {c}" for s, c in cfgs)


def recognition_table(items, root: Path) -> list[str]:
    groups = _recognition_groups(items)
    lines = ["| split | seeds | recognizer | frame acc. raw | frame acc. smoothed | video acc. | test frames | files |",
             "|---|---|---|---:|---:|---:|---:|---|"]
    for kind in sorted(groups):
        g = groups[kind]
        seeds = ", ".join(str(d.get("seed")) for _, d in g)
        lines.append(
            f"| {kind} | {seeds} | {_configs(g)} | "
            f"{_spread([d['frame_accuracy']['raw'] for _, d in g])} | "
            f"{_spread([d['frame_accuracy']['smoothed'] for _, d in g])} | "
            f"{_spread([d.get('video_accuracy') for _, d in g])} | "
            f"{sum(int(d.get('n_test_frames') or 0) for _, d in g)} | "
            f"{', '.join('`' + _rel(p, root) + '`' for p, _ in g)} |")
    return lines


def confusion_tables(items, root: Path) -> list[str]:
    """Per recognizer and split (the groups of :func:`recognition_table`), the smoothed confusion: the test
    frames' counts summed over the group's seeds, each true class's row in % of its frames."""
    lines = ["Rows: the true action; columns: the recognised one; % of the true action's test frames (smoothed "
             "labels), frames pooled over the seeds of the group; the diagonal is each action's recall.", ""]
    for kind, g in sorted(_recognition_groups(items).items()):
        confs = [d.get("confusion") for _, d in g]
        if not confs or any(not c or not c.get("counts_smoothed") for c in confs):
            continue
        classes = confs[0]["classes"]
        if any(c["classes"] != classes for c in confs):
            continue  # the seeds' classes differ: no pooled table
        total = [[sum(c["counts_smoothed"][i][j] for c in confs) for j in range(len(classes))]
                 for i in range(len(classes))]
        seeds = ", ".join(str(d.get("seed")) for _, d in g)
        lines += [f"*{kind}* (seeds {seeds})", "",
                  "| true \\ recognised | " + " | ".join(classes) + " | frames |",
                  "|---|" + "---:|" * (len(classes) + 1)]
        for name, row in zip(classes, total):
            n = sum(row)
            cells = [("**" + f"{100 * v / n:.1f}" + "**" if i == classes.index(name) else f"{100 * v / n:.1f}")
                     if n else "—" for i, v in enumerate(row)]
            lines.append(f"| {name} | " + " | ".join(cells) + f" | {n} |")
        lines.append("")
    return lines[:-1] if lines and lines[-1] == "" else lines


def segments_table(items, root: Path) -> list[str]:
    """Boundary-tolerant accuracy and segmental F1 of every recognition file that records them (smoothed)."""
    groups = _recognition_groups(items)
    lines = ["| split | seed | frame acc. | within 1 frame | within 2 | within 3 | F1@10 | F1@25 | F1@50 | file |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for kind, g in sorted(groups.items()):
        for p, d in g:
            sm = (d.get("segments") or {}).get("smoothed")
            if not sm:
                continue
            tol, f1 = sm.get("boundary_tolerant_accuracy") or {}, sm.get("segmental_f1") or {}
            lines.append(f"| {kind} | {d.get('seed')} | {_pct(d['frame_accuracy']['smoothed'])} | "
                         + " | ".join(_pct(tol.get(k)) for k in ("1", "2", "3")) + " | "
                         + " | ".join(_pct(f1.get(k)) for k in ("10", "25", "50")) + f" | `{_rel(p, root)}` |")
    return lines if len(lines) > 2 else []


def _recognition_groups(items) -> dict[str, list[tuple[Path, dict]]]:
    """The recognition metrics files by split and recognizer (the rows of :func:`recognition_table`), each
    group sorted by seed; ablations left out."""
    groups: dict[str, list[tuple[Path, dict]]] = defaultdict(list)
    for p, d in items:
        if d.get("ablation") not in (None, "none", "from model"):
            continue
        split = d.get("split") or {}
        kind = split.get("kind") or "?"
        if kind == "unseen-view":
            kind += f" (test view {', '.join(split.get('test_views') or []) or split.get('params', {}).get('test_view') or '?'})"
        rp = ((d.get("params") or {}).get("recognizer") or {})
        if rp.get("mirror") is False:
            kind += ", no mirror training"
        if d.get("scored_set") == "V":
            kind += ", validation set"
        msplit = (d.get("model_header") or {}).get("split") or {}
        if msplit.get("more_views") or "_moreviews_" in Path(p).name:
            kind += ", 3D SIFT trained also on more camera views"
        if msplit.get("more_performers"):
            kind += " and more performers"
            for m in msplit["more_performers"]:
                if m.get("classes"):  # a dataset of some classes only: rendered real mocap (make-cmu-dataset)
                    kind += f", and real mocap of {', '.join(m['classes'])} ({', '.join(m['performers'])})"
        if d.get("recognizer") in ("pose", "pose+sift"):
            sp = d.get("split")
            what = "pose sequences" if d["recognizer"] == "pose" else "pose sequences + 3D SIFT"
            extra = (d.get("training") or {}).get("extra_clips") or []
            if extra:
                what += f", trained also on {len(extra)} labelled mocap clips"
            kind = f"{sp if isinstance(sp, str) else kind}, {what} ({d.get('input', '?')})"
        groups[kind].append((p, d))
    return {k: sorted(g, key=lambda x: (x[1].get("seed") is None, x[1].get("seed"))) for k, g in groups.items()}


def style_table(items, root: Path) -> list[str]:
    lines = ["| labels | performers | transition MAE (a) | identification (a) | file |", "|---|---|---:|---:|---|"]
    names = {"ground_truth": "ground truth, every performer",
             "ground_truth_test_performers": "ground truth, test performers",
             "recognised": "recognised, test performers"}
    for p, d in items:
        for src, block in (d.get("sources") or {}).items():
            s = block.get("summary") or {}
            perf = ", ".join(r.get("performer", "?") for r in block.get("performers", []))
            lines.append(f"| {names.get(src, src)} (seed {d.get('seed')}) | {perf} | "
                         f"{s.get('transition_mae', {}).get('a', float('nan')):.3f} | "
                         f"{_pct(s.get('identification', {}).get('a', {}).get('accuracy_by_heldout_data'))} | "
                         f"`{_rel(p, root)}` |")
    return lines


def prior_table(items, root: Path) -> list[str]:
    lines = ["| decoder (test performers) | transition MAE (a) | identification (a) | file |", "|---|---:|---:|---|"]
    for p, d in items:
        for r in d.get("rows", []):
            lines.append(f"| {r['labels']} (seed {d.get('seed')}) | {r['transition_mae_a']:.3f} | "
                         f"{_pct(r['identification_a'])} | `{_rel(p, root)}` |")
    return lines


def validation_table(items, root: Path) -> list[str]:
    """The search of the library's defaults (seed 0's validation file) value by value; with files of other
    seeds, one line per seed with its chosen configuration."""
    items = sorted(items, key=lambda x: (x[1].get("seed") is None, x[1].get("seed")))
    lines = ["| tuned value | chosen | validation score | the other candidates | file |", "|---|---|---:|---|---|"]
    for p, d in items[:1]:
        lines.insert(0, f"Score: {d.get('score', 'smoothed frame accuracy on the validation performers')}.")
        lines.insert(1, "")
        for key, c in (d.get("chosen") or {}).items():
            value = c.get("value")
            shown = value if not isinstance(value, dict) else (_smoother_name(value) or json.dumps(value))
            others = ", ".join(f"{k} {_pct(v)}" for k, v in (c.get("candidates") or {}).items()
                               if k not in (str(value), _smoother_name(value)))
            won = c.get("validation_score", c.get("validation_frame_accuracy_smoothed"))
            lines.append(f"| {key} | {shown} | {_pct(won)} | {others} "
                         f"| `{_rel(p, root)}` |")
    if len(items) > 1:
        lines += ["", "Per split seed (the recognizer of each seed's results uses its own seed's choice):", "",
                  "| seed | validation performers | points | words | grouping | C | cap | context | smoother "
                  "| V smoothed | V video | V camera smoothed | score | file |",
                  "|---|---|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---|"]
        for p, d in items:
            fc, fv = d.get("final_config") or {}, d.get("final_validation") or {}
            lines.append(
                f"| {d.get('seed')} | {', '.join((d.get('split') or {}).get('val_performers') or [])} | "
                f"{fc.get('points', 10)} | {fc.get('words')} | {fc.get('grouping_threshold')} | {fc.get('C', 0):g} | "
                f"{fc.get('max_frames_per_class')} | {fc.get('coarse_context') or 'no'} | "
                f"{_smoother_name(fc) or fc.get('smoothing')} | {_pct(fv.get('frame_accuracy_smoothed'))} | "
                f"{_pct(fv.get('video_accuracy'))} | {_pct(fv.get('camera_frame_accuracy_smoothed'))} | "
                f"{_pct(fv.get('score', fv.get('frame_accuracy_smoothed')))} | `{_rel(p, root)}` |")
    return lines


def _smoother_name(value) -> str | None:
    """The candidate key of a smoother value (as scripts/validate_recognition.py names them)."""
    if not isinstance(value, dict) or "smoothing" not in value:
        return None
    w = value.get("emission_weight")
    return f"{value['smoothing']}^{w:g}" if value["smoothing"] in ("viterbi", "duration") else None


def pose_table(items, root: Path) -> list[str]:
    lines = [("| backend (held-out renders) | frames | mean strict PCP | PCK@0.2 | viewpoint accuracy (nearest view) "
              "| viewpoint accuracy, frames off view boundaries | viewpoint accuracy, either neighbour on a boundary | file |"),
             "|---|---:|---:|---:|---:|---:|---:|---|"]

    def accs(c: dict) -> str:
        c = c or {}
        u = (c.get("unambiguous") or {}).get("accuracy")
        t = c.get("tolerant_accuracy")
        return (f"{'' if c.get('accuracy') is None else _pct(c.get('accuracy'))} | {'' if u is None else _pct(u)} | "
                f"{'' if t is None else _pct(t)}")

    # the default detectors first, then the thesis' HOG baseline; BlazePose once (the same frames)
    items = sorted(items, key=lambda x: ((x[1].get("params") or {}).get("model_params") or {}).get("detector", "hog") != "cnn")
    seen_blazepose: set = set()
    for p, d in items:
        # BlazePose once per set of held-out frames (the cnn and HOG files score the same frames)
        frames_key = tuple((d.get("params") or {}).get(k) for k in ("seed", "demo_performers", "cmu_clips",
                                                                  "views_per_clip", "seconds", "fps"))
        det = ((d.get("params") or {}).get("model_params") or {}).get("detector", "hog")
        ps = "pictorial structures, cnn detectors" if det == "cnn" else "pictorial structures, HOG detectors"
        names = {"ps": f"{ps}{' (default)' if det == 'cnn' else ' (thesis baseline)'}",
                 "ps_single_image": f"{ps}, single image", "ps_generic": f"{ps}, generic {'tree' if det == 'cnn' else 'detectors'}",
                 "ps_oracle_view": f"{ps}, true viewpoint", "blazepose": "BlazePose"}
        vp = d.get("viewpoint") or {}
        for key, block in (d.get("pcp") or {}).items():
            if key == "blazepose":
                if frames_key in seen_blazepose:
                    continue
                seen_blazepose.add(frames_key)
            if key == "ps":
                c = vp.get(d.get("ps_viewpoint_method") or "")
            elif key == "blazepose":
                c = vp.get(key)
            else:
                c = None
            lines.append(f"| {names.get(key, key)} | {d.get('n_frames')} | {(block.get('all') or {}).get('mean', float('nan')):.3f} | "
                         f"{((d.get('pck@0.2') or {}).get(key) or {}).get('all', float('nan')):.3f} | {accs(c) if c else ' |  | '} | "
                         f"`{_rel(p, root)}` |")
        for key in sorted(vp):
            if key not in (d.get("pcp") or {}):
                lines.append(f"| {'cnn' if det == 'cnn' else 'HOG'} model's viewpoint classifier `{key}` | {d.get('n_frames')} | | | "
                             f"{accs(vp[key])} | `{_rel(p, root)}` |")
    sets = []
    for p, d in items:
        q = d.get("params") or {}
        if all(k in q for k in ("demo_performers", "cmu_clips", "views_per_clip")):
            extra, flags = "", ""
            if q.get("other_clips"):
                extra += f", {q['other_clips']} clips of {Path(str(q.get('other_dir'))).name}"
                flags += f" --other-dir {q.get('other_dir')} --other-clips {q['other_clips']}"
            if q.get("elevation") and list(q["elevation"]) != [0.0, 20.0]:
                el = q["elevation"]
                extra += f", elevations {el[0]:g} to {el[1]:g} degrees"
                flags += f" --elevations {el[0]:g},{el[1]:g}"
            if q.get("scale") and list(q["scale"]) != [0.9, 1.1]:
                flags += f" --figure-scales {q['scale'][0]:g},{q['scale'][1]:g}"
            if q.get("proportions"):
                extra += f", bone lengths varied by up to {q['proportions']:.0%}"
                flags += f" --proportions {q['proportions']:g}"
            model = Path(str(q.get("model") or "")).name
            flags = (f" --model {model}" if model and model != "ps_cnn.joblib" else "") + flags
            sets.append(f"- `{_rel(p, root)}`: {d.get('n_frames')} frames of {q['demo_performers']} held-out demo performers "
                        f"and up to {q['cmu_clips']} held-out CMU clips{extra}, {q['views_per_clip']} azimuths each "
                        f"(`vidstyle evaluate pose --demo-performers {q['demo_performers']} --cmu-clips {q['cmu_clips']} "
                        f"--views-per-clip {q['views_per_clip']}{flags} --seed {q.get('seed', 0)}`)")
    by_source = [(p, d) for p, d in items if d.get("by_source")]
    if by_source:
        lines += ["", "Pictorial structures (and BlazePose) per kind of held-out source: demo performers, CMU subjects "
                  "never trained on, and another skeleton (`--other-dir`); strict PCP mean and its weakest part, "
                  "viewpoint accuracy off view boundaries:", "",
                  "| file | source | frames | PCP | weakest part | viewpoint (off boundaries) | BlazePose PCP |",
                  "|---|---|---:|---:|---|---:|---:|"]
        for p, d in by_source:
            for g, row in d["by_source"].items():
                ps, bp = row.get("ps") or {}, row.get("blazepose") or {}
                parts = ps.get("pcp_per_part") or {}
                weakest = min(parts, key=parts.get) if parts else None
                vp = ps.get("viewpoint_accuracy_off_boundary")
                lines.append(f"| `{_rel(p, root)}` | {g} | {row.get('n_frames')} | {ps.get('pcp_mean', float('nan')):.3f} | "
                             f"{'' if weakest is None else f'{weakest} {parts[weakest]:.3f}'} | "
                             f"{'' if vp is None else _pct(vp)} | "
                             f"{'' if bp.get('pcp_mean') is None else format(bp['pcp_mean'], '.3f')} |")
    if sets:
        lines += ["", "Held-out render sets:", "", *sets]
    notes = []
    for p, d in items:
        for key, c in sorted((d.get("viewpoint") or {}).items()):
            u = (c or {}).get("unambiguous")
            if u:
                from vidstyle.evaluation.pose import wilson_interval

                per = ", ".join(f"{v} {_pct(a)} (n {sum(row)}; 95 % interval "
                                + " to ".join(_pct(x) for x in wilson_interval(row[i], sum(row))) + ")"
                                for i, ((v, a), row) in enumerate(zip(u["per_view_accuracy"].items(), u["counts"]))
                                if sum(row))
                notes.append(f"- viewpoint classifier `{key}` (`{_rel(p, root)}`), frames off view boundaries: {per}")
    if notes:
        lines += ["", "Viewpoint accuracy per true view, away from view boundaries:", "", *notes]
    return lines


#: what each committed AugMG metrics file is (the 2D sources' poses and the validation file of its thresholds)
AUGMG_FILES = {
    "augmg_seed0.json": "the pipeline's augment stage (`vidstyle evaluate augmg`): pictorial structures = the model shipped in the package "
                        "(`scripts/train_default_pose.py`; poses at scales 1, 1.2, 1.4); defaults and thresholds from "
                        "`validation/augmg.json`",
    "augmg_trainpose_seed0.json": "the same marks with pictorial structures = `vidstyle train-pose`'s default model "
                                  "(30 demo performers + 71 CMU clips x 16 azimuths, 20 epochs, 2-px heatmaps, test-time flip, unary "
                                  "weight 16; test poses at scales 1, 1.2, 1.4); matching defaults "
                                  "and thresholds chosen on that model's validation poses (`validation/augmg_trainpose.json`)",
}


def augmg_table(items, root: Path) -> list[str]:
    names = {"model": "pictorial structures", "blazepose": "BlazePose", "gt": "true 2D", "noisy": "true 2D + 5 % noise"}
    lines = ["| 2D source | marks | retrieval MPJPE | recall@10 | plain | AugMG | lower by (95 % bootstrap interval) | accepted | file |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---|"]
    for p, d in items:
        for src, b in (d.get("by_source") or {}).items():
            red = b.get("transition_reduction")
            seed = d.get("seed", (d.get("params") or {}).get("seed"))
            lines.append(f"| {names.get(src, src)} (seed {seed}) | {b.get('queries')} | "
                         f"{b['retrieval_mpjpe_mm']:.1f} mm | {_pct(b.get('recall_at_10'))} | "
                         f"{b['transition_plain_mm']:.1f} mm | {b['transition_augmg_mm']:.1f} mm | {_pct(red)}"
                         + (" ({} to {})".format(*(_pct(x) for x in b["transition_reduction_ci95"]))
                            if b.get("transition_reduction_ci95") else "") + " | "
                         f"{_pct(b.get('accepted'))} | `{_rel(p, root)}` |")
    notes = [f"- `{_rel(p, root)}`: {AUGMG_FILES[Path(p).name]}" for p, _d in items if Path(p).name in AUGMG_FILES]
    if notes:
        lines += ["", *notes]
    return lines


def strikes_table(items, root: Path) -> list[str]:
    from vidstyle.evaluation.realmocap import strikes_rows

    lines = ["| clip, camera | recognizer | action frames | punch (smoothed) | kick (smoothed) | punch share smoothed | raw | file |",
             "|---|---|---:|---:|---:|---:|---:|---|"]
    for p, d in items:
        clip = Path(str(d.get("bvh") or "?")).stem
        is_pose = "velocity_steps" in ((d.get("model") or {}).get("params") or {})
        rec = f"pose sequences ({(d.get('params') or {}).get('pose_input')} 2D)" if is_pose else "3D SIFT"
        for r in strikes_rows(d):
            sm, raw = r["smoothed"], r["raw"]
            lines.append(f"| {clip}, {r['name']} | {rec} | {r['action_video_frames']} | {sm.get('punch')} | {sm.get('kick')} | "
                         f"{_pct(sm.get('punch_fraction'))} | {_pct(raw.get('punch_fraction'))} | `{_rel(p, root)}` |")
    return lines


def strikes_diagnostics_table(items, root: Path) -> list[str]:
    """One row per variant of ``scripts/strikes_diagnostics.py``: the punch share of the action frames
    (smoothed, all cameras) and the punch share of the frames read as a punch or a kick."""
    lines = ["| variant | recognizer | action frames | punch share smoothed | punch share of punch + kick | raw | file |",
             "|---|---|---:|---:|---:|---:|---|"]
    for p, d in items:
        for name, v in (d.get("variants") or {}).items():
            o = v.get("overall") or {}
            sm, raw = o.get("smoothed") or {}, o.get("raw") or {}
            mp = (v.get("model") or {}).get("params") or {}
            rec = (f"{(v.get('params') or {}).get('points')} points, cap {mp.get('max_frames_per_class')}, "
                   f"{mp.get('smoothing')}")
            frames = sum(int(sm.get(k) or 0) for k in ("punch", "kick", "other"))
            lines.append(f"| {name} | {rec} | {frames} | {_pct(sm.get('punch_fraction'))} | "
                         f"{_pct(sm.get('punch_share_of_strikes'))} | {_pct(raw.get('punch_fraction'))} | "
                         f"`{_rel(p, root)}` |")
    return lines


def multiview_table(items, root: Path) -> list[str]:
    """One row per poses set scored on calibrated real views (``vidstyle evaluate pose --calibration``):
    PCK@0.2 / PCK@0.1 / median error with the plain DLT reference and the robust one."""
    lines = ["| poses | views x frames | PCK@0.2 (plain DLT) | PCK@0.1 | median error | PCK@0.2 (robust reference) | file |",
             "|---|---|---|---|---|---|---|"]
    for p, d in sorted(items, key=lambda t: str(t[0])):
        refs = d.get("references") or {}
        dlt, rob = (refs.get("dlt") or {}).get("overall") or {}, (refs.get("robust") or {}).get("overall") or {}
        poses = (d.get("params") or {}).get("poses") or []
        where = str(Path(poses[0]).parent) if poses else "?"

        def f(x):
            return "" if x is None else f"{x:.3f}"

        lines.append(f"| `{where}` | {len(d.get('views') or [])} x {d.get('frames')} | {f(dlt.get('pck@0.2'))} | "
                     f"{f(dlt.get('pck@0.1'))} | {f(dlt.get('median_error'))} | {f(rob.get('pck@0.2'))} | `{_rel(p, root)}` |")
    return lines


def people_table(items, root: Path) -> list[str]:
    """Following one performer among several people (``vidstyle evaluate people``)."""
    lines = ["| take | backend | mode | identity switches / 100 frames | PCK@0.2 | file |", "|---|---|---|---|---|---|"]
    for p, d in sorted(items, key=lambda t: str(t[0])):
        q = d.get("params") or {}
        take = f"{d.get('people')} people, {len(d.get('views') or [])} views x {d.get('frames')} frames"
        for mode, m in (d.get("modes") or {}).items():
            lines.append(f"| {take} | {q.get('backend')} | {mode} | {m['identity_switches_per_100_frames']:.2f} | "
                         f"{m['pck@0.2']:.3f} | `{_rel(p, root)}` |")
    return lines


_REC_SOURCES = {"true2d": "true 2D", "ps": "pictorial structures", "blazepose": "BlazePose",
                "noisy": "true 2D + 5 % noise", "truth": "3D truth"}


def _mm(x) -> str:
    return "n/a" if x is None else f"{x:.1f}"


def _reconstruct_rows(rows, data_prefix: str) -> list[str]:
    out = []
    for r in rows:
        if not str(r["data"]).startswith(data_prefix):
            continue
        out.append(f"| {_REC_SOURCES.get(r['source'], r['source'])} | {r['method']} | {r['skeleton']} | {r['frames']} | "
                   f"{_mm(r['mpjpe_root_relative_mm'])} | {_mm(r['pa_mpjpe_mm'])} | {_mm(r['mpjpe_mm'])} | "
                   f"{_mm(r['acceleration_error_mm_per_frame2'])} | {_mm(r['foot_skate_mm_per_frame'])} |")
    return out


_REC_HEAD = ["| 2D source | method | skeleton | frames | root-relative MPJPE (mm) | PA-MPJPE (mm) | MPJPE (mm) | "
             "acceleration error (mm/frame²) | foot skate (mm/frame) |", "|---|---|---|---:|---:|---:|---:|---:|---:|"]


def training_views_table(items, root: Path) -> list[str]:
    """``scripts/validate_training_views.py``: per split seed, the seed's own recognizer against the same trained
    also on the more-views dataset at each cap, and also with the more-performers dataset, scored on the
    validation performers only."""
    lines = []
    for p, d in items:
        mv = (d.get("more_views") or {}).get("params") or {}
        mp = d.get("more_performers") or {}
        who = ""
        if mp:
            share = float(mp.get("vocab_share") or 0.0)
            who = (f" *More performers*: procedural performers no split holds (`{mp.get('dataset')}`, "
                   f"`vidstyle demo make-dataset --first-performer`, {', '.join(str(v) for v in (mp.get('params') or {}).get('views') or [])}, "
                   f"{(mp.get('params') or {}).get('single_seconds', '?')} s single-action videos), "
                   f"{share:.0%} of them (the first by id) added to the vocabulary's set A and the rest to set B.")
        lines += [f"`{_rel(p, root)}`: set B's performers also filmed from azimuths {', '.join(mv.get('views') or [])} "
                  f"at {mv.get('elevation_deg')} degrees elevation.{who} *V*: the validation performers' own videos, "
                  "*camera*: their videos from the validation camera (60 and 120 degrees at 30 degrees, a held-out "
                  "background); score: the mean of the two smoothed accuracies. Rule: " + str(d.get("rule")) + ".", "",
                  "| seed | more views | more performers | frames per class | training videos | V smoothed | V video | "
                  "camera smoothed | score | chosen |", "|---:|---|---:|---:|---:|---:|---:|---:|---:|---|"]
        def key(x: dict) -> tuple:
            return x.get("more_views"), x.get("max_frames_per_class"), x.get("more_performers") or 0

        for sd in d.get("seeds") or []:
            ch = sd.get("chosen") or {}
            for r in sd.get("rows") or []:
                mark = "yes" if key(r) == key(ch) else ""
                lines.append(f"| {sd['seed']} | {r['more_views']} | {r.get('more_performers') or 0} | "
                             f"{r['max_frames_per_class']} | {r['n_train_videos']} | "
                             f"{_pct(r['validation']['smoothed'])} | {_pct(r['validation']['video'])} | "
                             f"{_pct(r['validation_camera']['smoothed'])} | {r['score']:.4f} | {mark} |")
    return lines


def real_walks_table(items, root: Path) -> list[str]:
    """``scripts/validate_real_walks.py``: 3D SIFT recognizers of one split seed, with and without rendered real
    walks in set B, on the validation performers, the validation camera and the real-motion validation clips."""
    lines = []
    for p, d in items:
        lines += [f"`{_rel(p, root)}` (split seed {d.get('seed')}; real-motion validation clips "
                  f"{', '.join(d.get('clips') or [])}). *V*: the validation performers' own videos, *camera*: their "
                  "validation-camera videos, *real walks*: right action family of the real-motion validation frames. "
                  "Rule: " + str(d.get("rule")) + ".", "",
                  "| model | training sets B beyond the split's | V smoothed | camera smoothed | real walks | "
                  "score (mean of the three) | mean of V and camera | chosen |",
                  "|---|---|---:|---:|---:|---:|---:|---|"]
        for r in d.get("rows") or []:
            extra = [f"{len(m.get('performers') or [])} performer{'' if len(m.get('performers') or []) == 1 else 's'} "
                     f"of `{m.get('dataset')}`"
                     + (f" ({', '.join(m['classes'])} only)" if m.get("classes") else "")
                     for m in r.get("more_performers") or []]
            if r.get("more_views"):
                extra.insert(0, "more views")
            lines.append(f"| {r['name']} | {'; '.join(extra) or '—'} | {_pct(r['validation']['smoothed'])} | "
                         f"{_pct(r['validation_camera']['smoothed'])} | {_pct(r['real_motion'])} | {r['score']:.4f} | "
                         f"{r['score_demo']:.4f} | {'yes' if r['name'] == d.get('chosen') else ''} |")
        lines.append("")
    return lines[:-1]


def reconstruct_table(items, root: Path) -> list[str]:
    lines = []
    for p, d in items:
        mf = (d.get("params") or {}).get("max_frames")
        lines += [f"Held-out renders: {', '.join(d.get('videos') or [])}, first "
                  f"{int(mf) if isinstance(mf, float) and mf.is_integer() else mf} frames each (`{_rel(p, root)}`). Skeleton *library*: "
                  "the output is on the library's skeleton (the performer's body unknown); *height*: the same scaled "
                  "to the performer's standing height (`vidstyle reconstruct --height`, when the user knows it); "
                  "*performer*: the take's own skeleton given, so the error is the motion's alone. *blazepose-world*: BlazePose's own 3D.", "",
                  *_REC_HEAD, *_reconstruct_rows(d["runs"], "demo test performers"), ""]
    return lines[:-1]


def reconstruct_heldout_table(items, root: Path) -> list[str]:
    lines = []
    for p, d in items:
        cmu, real = d.get("cmu"), d.get("real")
        if cmu:
            lines += [f"CMU subjects {', '.join(cmu['test_subjects'])} against a library of subjects "
                      f"{', '.join(cmu['library_subjects'])} ({cmu['library_frames']:,} indexed frames), seeded "
                      f"cameras (`{_rel(p, root)}`, `scripts/reconstruct_heldout.py`)"
                      + ("; skeletons: the library's and the library's at the subject's height (*height*)"
                         if any(r.get("skeleton") == "height" for r in cmu["runs"]) else "") + ":", "", *_REC_HEAD,
                      *_reconstruct_rows(cmu["runs"], "cmu held-out"), ""]
        rend = d.get("cmu_rendered")
        if rend:
            how = ""
            if "ps_scales" in rend:
                how = (f" (the pictorial structures zoomed by {', '.join(f'{z:g}' for z in rend['ps_scales'])}, their "
                       f"viewpoints tracked at step cost {rend['view_step_cost']:g}"
                       + (f", {rend['view_dwell_s']:g} s between quarter turns" if "view_dwell_s" in rend else "")
                       + "; a camera framing each whole clip "
                       "draws these walkers at about half the demo's figure size)")
            lines += [f"The same held-out subjects rendered to video ({', '.join(rend['videos'])}; the first "
                      f"frames of each) with 2D estimated on the renders{how}; skeletons: the library's, the library's "
                      f"at the subject's height (*height*) and the subject's own:", "", *_REC_HEAD, *_reconstruct_rows(rend["runs"], "cmu rendered"), ""]
        if real:
            lines += [f"The real pose2sim take ({real['frames']} frames), each of the views {', '.join(real['views'])} "
                      f"alone, against the 3D triangulated from all four (BlazePose 2D; all 86 CMU clips as the "
                      f"library; the reconstructions' pelvis and neck are the midpoints of their hips and shoulders, "
                      f"as the reference's BlazePose keypoints define them):", "", *_REC_HEAD, *_reconstruct_rows(real["runs"], "real pose2sim"), ""]
        if any(r["method"] == "library-bound" for part in (cmu, real) if part for r in part["runs"]):
            lines += ["*library-bound*: per frame, the library frame nearest the 3D truth after a similarity "
                      "alignment (`vidstyle.reconstruct.metrics.library_bound`): the PA-MPJPE floor that the "
                      "library's coverage sets for one library pose per frame. On the real take it includes "
                      "what still differs between BlazePose's keypoints (hips, shoulders, the head top "
                      "extrapolated from the face) and the library's joints.", ""]
    return lines[:-1] if lines else []


def reconstruct_defaults_table(items, root: Path) -> list[str]:
    lines = []
    for p, d in items:
        c = d["chosen"]
        lines.append(f"- `{_rel(p, root)}`: on {', '.join(d['videos'])} ({d['frames']} frames, {d['source']} 2D): "
                     + ", ".join(f"{k} {v}" for k, v in c.items())
                     + "".join(f"; foot contacts with {'other (true, unknown)' if src == 'default' else src} 2D: "
                               f"vote {v['contact_threshold']}, "
                               + (f"lifts up to {v['contact_gap_s']} s bridged" if v["contact_gap_s"] else "no lift bridged")
                               + f", pins {'following' if v['pin_drift'] else 'without'} the drift"
                               for src, v in (d.get("contacts") or {}).items())
                     + f", root-relative MPJPE {d['chosen_score_mm']:.1f} mm ({len(d['table'])} settings tried"
                     + (f", {len(d['table_blazepose'])} with BlazePose's 2D" if d.get("table_blazepose") else "") + ")")
    return lines


def real_motion_table(items, root: Path) -> list[str]:
    """Real mocap clips at unseen cameras, by action family (``vidstyle evaluate real-motion``)."""
    lines = ["| clips | recognizer | pose input | family accuracy | punch | other | videos right (majority) | file |",
             "|---|---|---|---:|---:|---:|---:|---|"]
    for p, d in sorted(items, key=lambda t: str(t[0])):
        clips = ", ".join(c["clip"] for c in d.get("clips", []))
        pin = (d.get("params") or {}).get("pose_input", "?")
        for r, v in (d.get("overall") or {}).items():
            fam = v.get("per_family") or {}
            name = r if r != "fusion" else f"fusion (pose weight {d.get('fusion_weight'):g})"
            lines.append(f"| {clips} | {name} | {pin if r != 'sift' else '—'} | {_pct(v.get('family_accuracy'))} | "
                         f"{_pct(fam.get('punch'))} | {_pct(fam.get('other'))} | {_pct(v.get('video_majority_accuracy'))} | "
                         f"`{_rel(p, root)}` |")
    return lines


def pose_recognition_validation_table(items, root: Path) -> list[str]:
    """Pose recognizer vs 3D SIFT vs fusion on the validation sets (``scripts/pose_recognition_results.py``)."""
    lines = ["| seed | training noise | pose weight (0 = 3D SIFT alone) | fused scores' power in the smoother | "
             "validation performers, smoothed | real-motion validation, family | score | file |",
             "|---|---|---:|---:|---:|---:|---:|---|"]
    for p, d in sorted(items, key=lambda t: (t[1].get("seed") is None, t[1].get("seed"))):
        ch = d.get("chosen") or {}
        for r in d.get("rows", []):
            # files from before the power was validated: their fusions used the pose recognizer's own (1)
            power = r.get("emission_weight", 1.0 if 0 < r["weight_pose"] < 1 else None)
            mine = (r["noise"], r["weight_pose"], power)
            mark = " **(chosen)**" if mine == (ch.get("noise"), ch.get("weight_pose"),
                                               ch.get("emission_weight", power)) else ""
            lines.append(f"| {d.get('seed')} | {r['noise']} | {r['weight_pose']:g}{mark} | "
                         f"{'—' if power is None else f'{power:g}'} | {_pct(r['smoothed'])} | "
                         f"{_pct(r.get('real_motion_val'))} | {_pct(r.get('score'))} | `{_rel(p, root)}` |")
    return lines


def inbetween_table(items, root: Path) -> list[str]:
    """Keyframe in-betweening on held-out CMU windows (``scripts/eval_inbetween.py``)."""
    lines = []
    for p, d in items:
        gaps = [str(g) for g in d["gaps"]]
        sp = d.get("split") or {}
        lines += [f"Library subjects {', '.join(map(str, sp.get('library_subjects', [])))}, test subjects "
                  f"{', '.join(map(str, sp.get('eval_subjects', [])))}, {sp.get('windows')} windows (`{_rel(p, root)}`, seed {d.get('seed')}); lower is better.", "",
                  "| method | " + " | ".join(f"L2P@{g}" for g in gaps) + " | " + " | ".join(f"L2Q@{g}" for g in gaps)
                  + " | ms per request |", "|---|" + "---:|" * (2 * len(gaps) + 1)]
        for name, m in d["methods"].items():
            ms = max(m[g]["ms_per_request"] for g in gaps)
            lines.append(f"| {name} | " + " | ".join(f"{m[g]['l2p']:.2f}" for g in gaps) + " | "
                         + " | ".join(f"{m[g]['l2q']:.2f}" for g in gaps) + f" | {ms:.0f} |")
        lines.append("")
    return lines[:-1]


def actionmodel_table(items, root: Path) -> list[str]:
    """Statistical action models: naturalness of samples against the source clips, reconstruction."""
    lines = ["| file | action | instances | velocity variance, samples / sources | acceleration, samples / sources | "
             "encode-decode MPJPE, held-out take (mm) | unseen performers (mm) | sample ms |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for p, d in sorted(items, key=lambda t: str(t[0])):
        for label, v in d["labels"].items():
            lines.append(f"| `{_rel(p, root)}` | {label} | {v.get('instances')} | "
                         f"{v.get('ratio_velocity_variance_mm2', float('nan')):.2f} | "
                         f"{v.get('ratio_acceleration_mm_per_frame2', float('nan')):.2f} | "
                         f"{_mm(v.get('mpjpe_heldout_mm'))} | {_mm(v.get('mpjpe_unseen_performers_mm'))} | "
                         f"{_mm(v.get('sample_ms_per_instance'))} |")
    return lines


def action_style_table(items, root: Path) -> list[str]:
    """A performer's action-level style fitted from 2D: global figures and generated-action MPJPE."""
    lines = ["| file | input | performers | lead accuracy | guard r | stance r | duration factor r | relative tempo r | "
             "speed r | action tempo r | action tempo r, population-relative truth | MPJPE fitted (mm) | unfitted (mm) | unfitted, true lead (mm) | reduction | "
             "reduction vs true lead |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    f = lambda x, d=2: "-" if x is None else f"{x:.{d}f}"
    for p, d in sorted(items, key=lambda t: str(t[0])):
        for name, v in d["by_input"].items():
            lines.append(f"| `{_rel(p, root)}` | {name} | {v.get('performers')} | {f(v.get('lead_accuracy'))} | "
                         f"{f(v.get('guard_height_r'))} | {f(v.get('stance_width_r'))} | {f(v.get('duration_factor_r'))} | "
                         f"{f(v.get('relative_tempo_r'))} | {f(v.get('speed_r'))} | {f(v.get('action_tempo_r'))} | "
                         f"{f(v.get('action_tempo_population_r'))} | {f(v.get('fitted_mean_mm'), 1)} | {f(v.get('unfitted_mean_mm'), 1)} | "
                         f"{f(v.get('unfitted_mean_true_lead_mm'), 1)} | {f(v.get('mpjpe_reduction'))} | "
                         f"{f(v.get('mpjpe_reduction_vs_true_lead'))} |")
    return lines


def tables(root: Path, extra: list[Path] | tuple = ()) -> str:
    docs = load_documents(root)
    EXTRA_ROOTS[:] = list(extra)
    for e in extra:
        for kind, items in load_documents(e).items():
            docs[kind] += items
    out = []
    sections = [("vidstyle.metrics.recognition", "Recognition (`vidstyle evaluate recognition`)", recognition_table),
                ("vidstyle.metrics.recognition", "Confusion of each recognizer on each split (`vidstyle evaluate "
                 "recognition` and the pose-sequence scripts' metrics files, above)", confusion_tables),
                ("vidstyle.metrics.recognition", "Boundaries or actions? Frame accuracy with the true boundaries "
                 "allowed to move by 1-3 frames, and segmental F1 (`vidstyle evaluate recognition`, smoothed labels; "
                 "vidstyle.evaluation.segments)", segments_table),
                ("vidstyle.metrics.style", "Style (`vidstyle evaluate style`)", style_table),
                ("vidstyle.metrics.style_viterbi_prior", "Viterbi prior and style (`scripts/style_viterbi_prior.py`)",
                 prior_table),
                ("vidstyle.validation.recognition", "Tuned on validation performers (`scripts/validate_recognition.py`)",
                 validation_table),
                ("vidstyle.validation.training_views", "More camera views of the training performers, chosen on "
                 "validation performers (`scripts/validate_training_views.py`)", training_views_table),
                ("vidstyle.validation.real_walks", "Real walks in 3D SIFT's training, chosen on the validation sets "
                 "(`scripts/validate_real_walks.py`)", real_walks_table),
                ("vidstyle.validation.pose_recognition", "Pose sequences, 3D SIFT and their fusion on the validation "
                 "sets (`scripts/pose_recognition_results.py`; estimated 2D: pictorial structures)",
                 pose_recognition_validation_table),
                ("vidstyle.metrics.real_motion", "Real motion at unseen cameras, by action family "
                 "(`vidstyle evaluate real-motion`)", real_motion_table),
                ("vidstyle.metrics.strikes", "Real mocap strikes through the demo-trained recognizer (`vidstyle evaluate strikes`)",
                 strikes_table),
                ("vidstyle.strikes_diagnostics", "Why real strikes are missed: the same evaluation on variants of the "
                 "clip and on demo punches (`scripts/strikes_diagnostics.py`, diagnostics only)",
                 strikes_diagnostics_table),
                ("vidstyle.metrics.pose", "2D pose (`vidstyle evaluate pose`)", pose_table),
                ("vidstyle.metrics.multiview_pose", "2D pose on real calibrated views, without labels "
                 "(`vidstyle evaluate pose --calibration`, leave-one-view-out)", multiview_table),
                ("vidstyle.metrics.people", "Following one performer among several people (`vidstyle evaluate people`)",
                 people_table),
                ("vidstyle.metrics.augmg", "AugMG (`vidstyle evaluate augmg`, held-out performers' marks)", augmg_table),
                ("vidstyle.metrics.inbetween", "Keyframe in-betweening (`vidstyle evaluate inbetween`, LAFAN1's "
                 "L2P / L2Q on held-out CMU windows)", inbetween_table),
                ("vidstyle.metrics.actionmodel", "Statistical action models (`scripts/eval_actionmodel.py`, Du 2014)",
                 actionmodel_table),
                ("vidstyle.metrics.action_style", "A performer's action-level style fitted from 2D "
                 "(`scripts/eval_action_style.py`, test performers of split seeds 0-4)", action_style_table),
                ("vidstyle.metrics.reconstruct", "Whole video to 3D (`vidstyle evaluate reconstruct`)", reconstruct_table),
                ("vidstyle.validation.reconstruct_heldout", "Whole video to 3D beyond the demo", reconstruct_heldout_table),
                ("vidstyle.validation.reconstruct_defaults",
                 "Reconstruction defaults, chosen on validation performers (`scripts/validate_reconstruct.py`)",
                 reconstruct_defaults_table)]
    for kind, title, fn in sections:
        if docs.get(kind) and (rows := fn(docs[kind], root)):
            out += [f"**{title}**", "", *rows, ""]
        if kind == "vidstyle.metrics.strikes" and (rows := real_motion_goals(docs)):
            out += ["**Real motion against issue 28's goals (split seed 0's recognizers)**", "", *rows, ""]
    if not out:
        raise SystemExit(f"{root}: no metrics documents found")
    return "\n".join(["<!-- generated by scripts/readme_tables.py; do not edit by hand -->", "", *out]).rstrip() + "\n"


def splice(text: str, table: str, begin: str = BEGIN, end: str = END) -> str | None:
    """``text`` with the part between the markers replaced, or None when the markers are absent."""
    b, e = text.find(begin), text.find(end)
    if b < 0 or e < 0 or e < b:
        return None
    return text[: b + len(begin)] + "\n" + table + text[e:]


def _first(items):
    """The first document of a kind with seed 0 (or the first at all), as (path, doc), or None."""
    items = sorted(items or [], key=lambda x: (x[1].get("seed") not in (0, None), str(x[0])))
    return items[0] if items else None


def headline(docs: dict, results_link: str = "docs/results.md") -> str:
    """A few rows in plain words, each from one kind of metrics file, with a link to the full table."""
    rows = []

    def rec(kind_name):
        g = [(p, d) for p, d in docs.get("vidstyle.metrics.recognition", [])
             if (d.get("split") or {}).get("kind") == kind_name and d.get("ablation") in (None, "none", "from model")
             and d.get("recognizer") not in ("pose", "pose+sift") and (((d.get("params") or {}).get("recognizer") or {}).get("mirror") is not False)
             and d.get("scored_set") != "V"]
        # the pipeline's default recognizer (more camera views and more performers), when its files are there
        default = [(p, d) for p, d in g if Path(p).name.startswith(DEFAULT_GOAL_RECOGNIZER[2])]
        return default or g

    for kind_name, what in (("unseen-performer", "Demo: actions recognised frame by frame, for performers no training video showed"),
                            ("unseen-camera", "The same, filmed from cameras and a background no training video used")):
        g = rec(kind_name)
        if g:
            xs = [d["frame_accuracy"]["smoothed"] for _, d in g]
            rows.append(f"| {what} | {_pct(sum(xs) / len(xs))} of frames on average over {len(g)} random splits "
                        f"of the performers (lowest {_pct(min(xs))}) | [recognition](" + results_link + ") |")
    strikes = {Path(p).name: d for p, d in docs.get("vidstyle.metrics.strikes", [])}
    walks, demo_only = strikes.get("strikes_02_05_pose_cmuwalks_ps_seed0.json"), strikes.get("strikes_02_05_pose_ps_seed0.json")
    # the pipeline's default 3D SIFT recognizer (S++) where its file is committed, else the three-camera one's
    spp = strikes.get("strikes_02_05_moreperformers_seed0.json")
    sift_doc = spp or strikes.get("strikes_02_05_seed0.json")
    sift_name = "the pipeline's 3D SIFT recognizer" if spp else "the thesis' 3D SIFT recognizer"
    if sift_doc and (walks or demo_only):
        # which training the validation preferred: the higher chosen score of the two runs' validation files
        val = {Path(p).name: d for p, d in docs.get("vidstyle.validation.pose_recognition", [])}
        score = {k: (val.get(f) or {}).get("chosen", {}).get("score", float("-inf"))
                 for k, f in (("walks", "pose_recognition_cmuwalks_seed0.json"), ("demo", "pose_recognition_seed0.json"))}
        walks_first = score["walks"] > score["demo"]
        runs = [(walks, "demo mocap + real walks"), (demo_only, "the demo's mocap alone")]
        if not walks_first:
            runs.reverse()
        parts = [f"{_pct(d['overall']['smoothed']['punch_fraction'])} "
                 + (f"by the validated pose-sequence recognizer (trained on {what}) on estimated 2D" if i == 0
                    else f"by the one trained on {what}")
                 for i, (d, what) in enumerate([r for r in runs if r[0]])]
        rows.append("| Real mocap punches (CMU 02_05) rendered from six cameras: strike frames recognised as punches "
                    f"| {', '.join(parts)}, {_pct(sift_doc['overall']['smoothed']['punch_fraction'])} by {sift_name} "
                    "| [recognition](" + results_link + ") |")
    first = _first([(p, d) for p, d in docs.get("vidstyle.metrics.style", [])
                    if "recognised" in (d.get("sources") or {})])
    if first:
        _, d = first
        s = (d["sources"]["recognised"].get("summary") or {})
        acc = s.get("identification", {}).get("a", {}).get("accuracy_by_heldout_data")
        rows.append(f"| Demo: sequences generated in a performer's style (learned from recognised actions) attributed to that performer | {_pct(acc)} "
                    f"| [style](" + results_link + ") |")
    first = next(((p, d) for p, d in docs.get("vidstyle.metrics.augmg", []) if Path(p).name == "augmg_seed0.json"), None)
    if first and "model" in (first[1].get("by_source") or {}):
        b = first[1]["by_source"]["model"]
        rows.append(f"| Demo, method 2: transitions through the performer's own pose, error against the true transition "
                    f"| {b['transition_augmg_mm']:.0f} mm instead of {b['transition_plain_mm']:.0f} mm with a plain blend "
                    f"(lower by {_pct(b.get('transition_reduction'))}) | [AugMG](" + results_link + ") |")
    first = _first(docs.get("vidstyle.metrics.reconstruct", []))
    if first:
        h = first[1].get("headline") or {}
        if h.get("reconstruct.mpjpe_mm") is not None:
            rows.append(f"| Demo: a video's performer as 3D motion, mean joint error against the true motion (root-relative, "
                        f"{_REC_SOURCES.get(h.get('reconstruct.source'), h.get('reconstruct.source'))} 2D) "
                        f"| {h['reconstruct.mpjpe_mm']:.0f} mm on the library's skeleton, "
                        + (f"{h['reconstruct.mpjpe_height_given_mm']:.0f} mm at the performer's height (given), "
                           if h.get("reconstruct.mpjpe_height_given_mm") is not None else "")
                        + f"{h['reconstruct.mpjpe_performer_skeleton_mm']:.0f} mm on the performer's own "
                        f"| [reconstruct](" + results_link + ") |")
    first = next(((p, d) for p, d in docs.get("vidstyle.metrics.multiview_pose", [])
                  if Path(p).name == "pose_realviews_blazepose.json"), None)
    if first:
        o = (((first[1].get("references") or {}).get("dlt") or {}).get("overall") or {})
        if o.get("pck@0.2") is not None:
            rows.append(f"| 2D pose on real footage (BlazePose): keypoints within a fifth of the torso length of where "
                        f"the other cameras put them | {_pct(o['pck@0.2'])} | [2D pose](" + results_link + ") |")
    first = _first(docs.get("vidstyle.metrics.action_style", []))
    if first:
        a = first[1].get("action_style") or {}
        t = (first[1].get("by_input") or {}).get("true") or {}
        if a.get("lead_accuracy") is not None and t.get("fitted_mean_mm") is not None:
            rows.append(f"| Demo: a performer's way of doing each action, fitted from true 2D (test performers, "
                        f"{t.get('performers')} fits over split seeds): lead found, and generated actions' joint error "
                        f"| lead {_pct(a['lead_accuracy'])}; {t['fitted_mean_mm']:.0f} mm against {t['unfitted_mean_mm']:.0f} mm "
                        f"unfitted ({t['unfitted_mean_true_lead_mm']:.0f} mm unfitted with the true lead) "
                        f"| [action style](" + results_link + ") |")
    first = next(((p, d) for p, d in docs.get("vidstyle.metrics.inbetween", []) if Path(p).name == "inbetween.json"), None)
    if first and {"markov", "slerp"} <= set(first[1].get("methods") or {}):
        m, sl = first[1]["methods"]["markov"], first[1]["methods"]["slerp"]
        gaps = [g for g in ("30", "45") if g in m and g in sl]
        if gaps:
            subjects = ", ".join((first[1].get("split") or {}).get("eval_subjects") or [])
            rows.append(f"| Motion between two keyframes (Molina Tanco & Hilton's Markov chain), held-out CMU subjects "
                        f"{subjects}: LAFAN1's position / rotation errors, lower is better | "
                        + "; ".join(f"{g} frames: L2P {m[g]['l2p']:.2f} / L2Q {m[g]['l2q']:.2f} against SLERP's "
                                    f"{sl[g]['l2p']:.2f} / {sl[g]['l2q']:.2f}" for g in gaps)
                        + " | [in-betweening](" + results_link + ") |")
    lines = ["<!-- generated by scripts/readme_tables.py; do not edit by hand -->", "",
             "| what | result | details |", "|---|---|---|", *rows]
    return "\n".join(lines) + "\n"


#: issue 28's goals: (split kind, figure) -> the least value on every seed
RECOGNITION_GOALS = {("unseen-performer", "smoothed"): 0.92, ("unseen-camera", "smoothed"): 0.88, "video": 1.0,
                     "strikes": 0.80, "real_motion": 0.85}
#: the recognizers of the per-seed table: (column name, metrics file stem before the split kind, command)
GOAL_RECOGNIZERS = (("S", "3D SIFT, trained on the three demo cameras", "recognition_",
                     "python scripts/recognition_results.py --validation pipelines/kickboxing/validation --seeds S"),
                    ("S+", "3D SIFT, trained also on more camera views of its training performers (`train-recognizer "
                     "--more-views`)", "recognition_moreviews_",
                     "python scripts/recognition_results.py --training-views pipelines/kickboxing/validation/"
                     "training_views.json --seeds S (before the more performers)"),
                    ("S++", "3D SIFT, trained also on more camera views and on more performers (`vocabulary / "
                     "train-recognizer --more-performers`, the pipeline's default)", "recognition_moreperformers_",
                     "python scripts/recognition_results.py --training-views pipelines/kickboxing/validation/"
                     "training_views.json --more-performers D --prefix moreperformers --seeds S"),
                    ("S++w", "S++ trained also on rendered real walks (CMU subject 03 as `Step`; validated on seed 0, "
                     "needs `../shared`, so not in `make demo`)", "recognition_realwalks_",
                     "python scripts/recognition_results.py --validation pipelines/kickboxing/validation --training-views "
                     "pipelines/kickboxing/validation/training_views.json --more-performers D --real-walks W --prefix "
                     "realwalks --seeds S"),
                    ("F", "fusion of both, PS 2D", "recognition_fusion_ps_", "python scripts/pose_recognition_results.py --seed S"),
                    ("P", "pose sequences, PS 2D", "recognition_pose_ps_", "python scripts/pose_recognition_results.py --seed S"),
                    ("T", "pose sequences, true 2D", "recognition_pose_true2d_",
                     "python scripts/eval_pose_recognition.py --seed S"))
#: the recognizers whose video accuracy the block shows (the pose-sequence ones alone have no goal there)
VIDEO_GOAL_RECOGNIZERS = ("S", "S+", "S++", "S++w", "F")
#: the pipeline's default recognizer among them (the headline's, and the ±1-frame diagnostic's)
DEFAULT_GOAL_RECOGNIZER = GOAL_RECOGNIZERS[2]


def recognition_goals(docs: dict) -> str:
    """Issue 28's measure table with a row per split seed: smoothed frame accuracy on unseen performers and
    unseen cameras and video accuracy for each recognizer (goal per column), the goal and whether every seed
    meets it; every value from a committed metrics file the block names (the real-motion goals are in the
    full tables: :func:`real_motion_goals`)."""
    files = {Path(p).name: d for p, d in docs.get("vidstyle.metrics.recognition", [])}
    seeds = sorted({d.get("seed") for d in files.values() if isinstance(d.get("seed"), int)})
    cols = []  # (header, getter(seed) -> value or None, goal)
    for kind, label in (("unseen-performer", "unseen performer"), ("unseen-camera", "unseen camera")):
        goal = RECOGNITION_GOALS[(kind, "smoothed")]
        for key, _name, stem, _ in GOAL_RECOGNIZERS:
            def get(seed, stem=stem, kind=kind):
                d = files.get(f"{stem}{kind.replace('-', '_')}_seed{seed}.json")
                return None if d is None else d["frame_accuracy"]["smoothed"]
            cols.append((f"{label} {key}", get, goal))
    for key, _name, stem, _ in (g for g in GOAL_RECOGNIZERS if g[0] in VIDEO_GOAL_RECOGNIZERS):
        def get(seed, stem=stem):
            d = files.get(f"{stem}unseen_performer_seed{seed}.json")
            return None if d is None else d.get("video_accuracy")
        cols.append((f"video {key}", get, RECOGNITION_GOALS["video"]))
    # a diagnostic beside the goals: the default 3D SIFT's smoothed accuracy with the true boundaries allowed to
    # move a frame
    for kind, label in (("unseen-performer", "unseen performer"), ("unseen-camera", "unseen camera")):
        def get(seed, kind=kind):
            d = files.get(f"{DEFAULT_GOAL_RECOGNIZER[2]}{kind.replace('-', '_')}_seed{seed}.json")
            return (((d or {}).get("segments") or {}).get("smoothed") or {}).get("boundary_tolerant_accuracy", {}).get("1")
        cols.append((f"{label} {DEFAULT_GOAL_RECOGNIZER[0]} ±1 frame", get, None))
    lines = ["<!-- generated by scripts/readme_tables.py; do not edit by hand -->", "",
             "Smoothed frame accuracy on unseen performers and unseen cameras, and video accuracy on unseen "
             "performers (%), on each split seed's test set; *goal*: the least value on every seed; *±1 frame*: "
             "the same frames counted right when their label is a true label within one frame of them (a diagnostic "
             "of where the errors are, no goal). Recognizers: "
             + "; ".join(f"**{key}** {name} (`pipelines/kickboxing/results/{stem}<split>_seed<S>.json`, `{cmd}`)"
                         for key, name, stem, cmd in GOAL_RECOGNIZERS) + ".", "",
             "| seed | " + " | ".join(h for h, _, _ in cols) + " |",
             "|---|" + "---:|" * len(cols)]
    for seed in seeds:
        lines.append(f"| {seed} | " + " | ".join(_pct_number(get(seed)) for _, get, _ in cols) + " |")
    lines.append("| goal | " + " | ".join("—" if g is None else f">= {_pct_number(g)}" for _, _, g in cols) + " |")
    met = []
    for _h, get, g in cols:
        vals = [get(sd) for sd in seeds]
        met.append("—" if g is None or any(v is None for v in vals) else ("yes" if min(vals) >= g - 1e-12 else "no"))
    lines.append("| met on every seed | " + " | ".join(met) + " |")
    return "\n".join(lines) + "\n"


def real_motion_goals(docs: dict) -> list[str]:
    """Issue 28's real-motion goals (split seed 0's recognizers): the real strikes' punch share and the
    real-motion split's right action family, each recognizer against its goal, with its file."""
    strikes = {Path(p).name: d for p, d in docs.get("vidstyle.metrics.strikes", [])}
    real = {Path(p).name: d for p, d in docs.get("vidstyle.metrics.real_motion", [])}
    rows = []
    sift_s, sift_spp = "3D SIFT S (three demo cameras)", "3D SIFT S++ (more views and performers, the pipeline's default)"
    sift_walks = "3D SIFT S++ + real walks (rendered CMU 03 walks as `Step`; validated, needs `../shared`)"
    for name, f in ((sift_s, "strikes_02_05_seed0.json"), (sift_spp, "strikes_02_05_moreperformers_seed0.json"),
                    (sift_walks, "strikes_02_05_realwalks_seed0.json"),
                    ("pose sequences, PS 2D, demo mocap", "strikes_02_05_pose_ps_seed0.json"),
                    ("pose sequences, PS 2D, demo mocap + real walks", "strikes_02_05_pose_cmuwalks_ps_seed0.json")):
        if f in strikes:
            rows.append(f"| real CMU punches (02_05), punch share of strike frames, `vidstyle evaluate strikes` | {name} | "
                        f"{_pct_number(strikes[f]['overall']['smoothed']['punch_fraction'])} | >= "
                        f"{_pct_number(RECOGNITION_GOALS['strikes'])} | `results/{f}` |")
    # each file, the name of its 3D SIFT recognizer (None: the same as another file's) and its pose training
    for f, sift, training in (("real_motion_seed0.json", sift_s, "demo mocap"),
                              ("real_motion_moreperformers_seed0.json", sift_spp, None),
                              ("real_motion_realwalks_seed0.json", sift_walks, None),
                              ("real_motion_cmuwalks_seed0.json", None, "demo mocap + real walks")):
        for r, v in ((real.get(f) or {}).get("overall") or {}).items():
            if r == "sift" and sift is None:
                continue  # the cmuwalks run's 3D SIFT is S, as in real_motion_seed0.json
            name = {"sift": sift, "pose": f"pose sequences, PS 2D, {training}",
                    "fusion": f"fusion, PS 2D, {training}"}.get(r, r)
            rows.append(f"| real-motion split, right action family, `vidstyle evaluate real-motion` | {name} | "
                        f"{_pct_number(v.get('family_accuracy'))} | >= {_pct_number(RECOGNITION_GOALS['real_motion'])} | `results/{f}` |")
    return ["| figure | recognizer | % | goal | file |", "|---|---|---:|---:|---|", *rows] if rows else []


def update(text: str, full: str, head: str, goals: str | None = None) -> str | None:
    """``text`` with every generated block it holds replaced; None when it holds none."""
    out, found = text, False
    blocks = [(BEGIN, END, full), (HEAD_BEGIN, HEAD_END, head)] + ([(GOALS_BEGIN, GOALS_END, goals)] if goals else [])
    for begin, end, table in blocks:
        new = splice(out, table, begin, end)
        if new is not None:
            out, found = new, True
    return out if found else None


def _load_all(root: Path, extra) -> dict:
    docs = load_documents(root)
    for e in extra:
        for kind, items in load_documents(e).items():
            docs[kind] += items
    return docs


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--metrics", type=Path, required=True, nargs="+",
                    help="directories of metrics JSON files (files are named relative to the first; the others "
                         "as <directory name>/<file>)")
    ap.add_argument("--readme", type=Path, default=None, help="README to update between the markers")
    ap.add_argument("--results", type=Path, default=None,
                    help="the results page to update as well (default: docs/results.md beside the README, if present)")
    ap.add_argument("--check", action="store_true", help="exit 1 if a file differs from the metrics")
    args = ap.parse_args(argv)
    for d in args.metrics:
        if not d.is_dir():
            print(f"{d}: metrics directory not found", file=sys.stderr)
            return 2
    table = tables(args.metrics[0], args.metrics[1:])
    if args.readme is None:
        sys.stdout.write(table)
        return 0
    everything = _load_all(args.metrics[0], args.metrics[1:])
    head, goals = headline(everything), recognition_goals(everything)
    results = args.results if args.results is not None else args.readme.parent / "docs" / "results.md"
    targets = [args.readme] + ([results] if results.is_file() and results.resolve() != args.readme.resolve() else [])
    status, any_markers = 0, False
    for path in targets:
        text = path.read_text(encoding="utf-8")
        new = update(text, table, head, goals)
        if new is None:
            continue
        any_markers = True
        if args.check:
            if new != text:
                print(f"{path}: results tables are out of date (rerun scripts/readme_tables.py)", file=sys.stderr)
                status = 1
            continue
        if new != text:
            fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".readme.")
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write(new)
            os.replace(tmp, path)
    if not any_markers:
        print(f"{args.readme}: no {BEGIN} ... {END} markers; tables written to stdout", file=sys.stderr)
        sys.stdout.write(table)
        return 0
    return status


if __name__ == "__main__":
    sys.exit(main())
