#!/usr/bin/env python
"""Choose how recognised labels measure a performer's action lengths and step length (the tempo and speed
of :class:`vidstyle.actionmodel.stylefit.GlobalStyleEstimator`) on the *validation* performers: the run
timing (``run_timing``: the recognised run's length, or the motion's width at ``motion_level`` of the
run's peak displacement from guard after a ``motion_filter``-frame median filter, turned into frames by the
population's ratio), the ``min_run_confidence`` of a run that measures (and the ``step_min_run_confidence``
of a ``Step`` run, whose lengths time the speed; ``same``: the actions' threshold), and the ``max_run_factor``: runs
longer than it times the population's median length of the label (back-to-back repeats the recognizer
joined into one run) do not measure (none: every run does); and the ``min_run_factor``: runs shorter than
it times that length (false and broken runs are short) do not measure. In two stages: first the timing
(every timing with every single threshold and cap, no floor), then, for the first stage's timing, the
actions' and the steps' thresholds, the cap and the floor together.

The recognised labels are the pipeline's (``--recognised-dir``; the recognizer of split seed 0, trained
on its sets A and B). The validation performers are set V of split seed 0 (never its test performers; of
the seeds' validation sets only seed 0's is out of that recognizer's training set). The population is
fitted on A and B (true 2D, true labels), as ``vidstyle evaluate action-style`` fits it.

Inputs: the validation performers' true 2D and, with ``--poses-dir``, the pictorial structures' 2D of
their videos (``vidstyle pose <their videos> --backend ps --scales 1 --out-dir DIR``, the pose files
``scripts/eval_action_style.py --poses-dir`` reads for the test performers). Each candidate estimates, per
input, validation performer and label (the six actions and ``Step``), the median length of the runs it
trusts, on two sets of videos: all of the performer's videos, and ``perf0_front`` alone (what the
pipeline's action-style evaluation has pose files for). The error of a (performer, label) pair is
``|log(recognised median / true median)|``, the true median over the true labels' runs of the same
videos. Rule: the candidate of least mean error over the inputs and both video sets; every pair must be
measured. The estimator's tempo figures against the performers' true style parameters are recorded too
(two performers: a guide, not the rule), as is ``model_reference_error``: the mean error of the six
actions' lengths over the same inputs and video sets when the reference is the training performers'
orthodox action model (:meth:`~vidstyle.actionmodel.stylefit.GlobalStyleEstimator.from_model`, what
``learn-style --poses-dir`` uses without a population).

    python scripts/validate_tempo_runs.py --poses-dir /tmp/ps_validation

Writes ``pipelines/kickboxing/validation/tempo_runs.json`` and prints the table.
"""

from __future__ import annotations

import argparse
import itertools
import json
import logging
import math
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
ROOT = Path(__file__).resolve().parents[1]
log = logging.getLogger("validate_tempo_runs")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", type=Path, default=ROOT / "pipelines" / "kickboxing" / "out" / "dataset")
    ap.add_argument("--recognised-dir", type=Path, default=ROOT / "pipelines" / "kickboxing" / "out" / "recognized")
    ap.add_argument("--poses-dir", type=Path, default=None,
                    help="the validation performers' pose files (estimated 2D); without it, true 2D alone")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--min-run-confidence", type=float, nargs="+", default=[0.0, 0.3, 0.4, 0.5, 0.6, 0.7])
    ap.add_argument("--step-min-run-confidence", nargs="+", default=[None, 0.4, 0.5, 0.6, 0.7],
                    type=lambda x: None if x == "same" else float(x),
                    help="stage 2: candidates for Step runs (same: the actions' threshold)")
    ap.add_argument("--max-run-factor", type=float, nargs="+", default=[math.inf, 2.2, 1.8, 1.5])
    ap.add_argument("--min-run-factor", type=float, nargs="+", default=[math.inf, 0.6, 0.7, 0.8],
                    help="stage 2: runs shorter than this times the population's length do not measure (inf: no floor)")
    ap.add_argument("--motion-level", type=float, nargs="+", default=[0.2, 0.3, 0.4, 0.5])
    ap.add_argument("--motion-filter", type=int, nargs="+", default=[1, 3, 5])
    ap.add_argument("--out", type=Path, default=ROOT / "pipelines" / "kickboxing" / "validation" / "tempo_runs.json")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    log.setLevel(logging.INFO)
    import numpy as np

    from vidstyle.actionmodel.stylefit import GlobalStyleEstimator, label_runs
    from vidstyle.evaluation.actionmodel import split_groups
    from vidstyle.evaluation.actionstyle import (
        demo_truth,
        fit_population,
        orthodox_model,
        pearson,
        performer_videos,
    )
    from vidstyle.formats.validation import TEMPO_RUNS, validation_header, write_validation

    t_start = time.perf_counter()
    demo = demo_truth(args.dataset)
    manifest, ds, actions, truth_style = (demo[k] for k in ("manifest", "dataset", "actions", "style"))
    g = split_groups(manifest, args.seed)
    train = sorted(g["A"] + g["B"])
    cache: dict = {}
    inputs = ["true"] + (["estimated"] if args.poses_dir is not None else [])
    ids = {p: [v["id"] for v in manifest["videos"] if v["performer"] == p] for p in g["V"]}
    data = {}
    for p in g["V"]:
        true_v = performer_videos(ds, manifest, p, "true", cache=cache)
        for kind in inputs:
            rec_v = performer_videos(ds, manifest, p, kind, poses_dir=args.poses_dir, labels_dir=args.recognised_dir,
                                     cache=cache)
            if len(rec_v) != len(true_v):
                raise SystemExit(f"{args.recognised_dir} / {args.poses_dir}: recognised labels or poses missing for "
                                 f"some of {p}'s videos")
            one = ids[p].index(f"{p}_perf0_front")
            for name, sel in (("all", range(len(true_v))), ("perf0", [one])):
                truth: dict[str, list[int]] = {}
                for i in sel:
                    for label, s, e in label_runs(true_v[i][1]):
                        truth.setdefault(label, []).append(e - s)
                data[(kind, p, name)] = ({a: float(np.median(truth[a])) for a in (*actions, "Step") if truth.get(a)},
                                         [rec_v[i] for i in sel])
    # the reference learn-style uses without a population: the training performers' orthodox action model
    model = orthodox_model(args.dataset, manifest, train, args.seed)
    timings = [("labels", None, None)] + [("motion", lv, fl) for lv in args.motion_level for fl in args.motion_filter]
    inf = lambda x: None if math.isinf(x) else x  # noqa: E731
    cands = []
    timed: dict = {}  # timing -> (population estimator, its timed runs, model estimator, its timed runs)

    def timed_for(timing, level, filt):
        """The two estimators of a timing and every video set's timed runs, computed once per timing (the
        thresholds, cap and floor only choose among the runs)."""
        if (timing, level, filt) not in timed:
            extra = {"run_timing": timing} | ({"motion_level": level, "motion_filter": filt} if timing == "motion" else {})
            est = fit_population(ds, manifest, train, cache=cache, **extra)
            mest = GlobalStyleEstimator.from_model(model, float(manifest["fps"]), **extra)
            timed[(timing, level, filt)] = (
                est, {key: [r for v in vids for r in est.timed_runs(v)] for key, (_t, vids) in data.items()},
                mest, {key: [r for v in vids for r in mest.timed_runs(v)] for key, (_t, vids) in data.items()})
        return timed[(timing, level, filt)]

    def stage(n: int, timing_grid, threshold_grid) -> None:
        for timing, level, filt in timing_grid:
            est, runs, mest, model_runs = timed_for(timing, level, filt)
            for thresholds in threshold_grid:
                est.set_params(**thresholds)
                mest.set_params(**thresholds)
                c = {"stage": n, "run_timing": timing, "motion_level": level, "motion_filter": filt, **thresholds}
                cands.append(c | score(est, mest, runs, model_runs))
            log.info("stage %d, %s level %s filter %s: best score %.4f", n, timing, level, filt,
                     min(c["score"] for c in cands if c["stage"] == n and c["run_timing"] == timing
                         and c["motion_level"] == level and c["motion_filter"] == filt))

    def score(est, mest, runs, model_runs) -> dict:
        model_errs = []
        for (_kind, _p, _name), (truth, _vids) in data.items():
            got = mest.trusted_lengths(model_runs[(_kind, _p, _name)])
            model_errs += [abs(math.log(float(np.median(got[a])) / t)) for a, t in truth.items()
                           if a != "Step" and a in got]
        errs = {(kind, name): [] for kind in inputs for name in ("all", "perf0")}
        missing = 0
        fig = {kind: {"action_tempo": ([], []), "duration_factor": ([], []), "speed": ([], [])} for kind in inputs}
        for (kind, p, name), (truth, vids) in data.items():
            got = est.trusted_lengths(runs[(kind, p, name)])
            for a, t in truth.items():
                if a in got:
                    errs[(kind, name)].append(abs(math.log(float(np.median(got[a])) / t)))
                else:
                    missing += 1
            if name == "all":
                gs, st, fk = est.estimate(vids), truth_style[p], fig[kind]
                for k, a in enumerate(actions):
                    if a in gs.action_tempo:
                        fk["action_tempo"][0].append(st["tempo"][k])
                        fk["action_tempo"][1].append(gs.action_tempo[a])
                    if a in gs.tempo:
                        fk["duration_factor"][0].append(st["tempo"][k] / st["speed"])
                        fk["duration_factor"][1].append(gs.tempo[a])
                fk["speed"][0].append(st["speed"])
                fk["speed"][1].append(gs.speed)
        c = {"pairs_missing": missing}
        for kind in inputs:
            c[f"error_{kind}_all"] = float(np.mean(errs[(kind, "all")]))
            c[f"error_{kind}_perf0"] = float(np.mean(errs[(kind, "perf0")]))
            fk = fig[kind]
            c[f"action_tempo_r_{kind}"] = pearson(*fk["action_tempo"])
            c[f"duration_factor_r_{kind}"] = pearson(*fk["duration_factor"])
            c[f"speed_abs_log_error_{kind}"] = float(np.mean(np.abs(np.log(np.asarray(fk["speed"][1])
                                                                            / np.asarray(fk["speed"][0])))))
        c["score"] = float(np.mean([c[f"error_{kind}_{name}"] for kind in inputs for name in ("all", "perf0")]))
        # a guide, not the rule: the same error of the six actions (no steps: the model has no step
        # length) with the action model as the reference, as learn-style estimates without a population
        c["model_reference_error"] = float(np.mean(model_errs))
        return c

    # stage 1: the timing, with one confidence threshold for every label and no floor
    stage(1, timings, [{"min_run_confidence": tau, "step_min_run_confidence": None, "max_run_factor": inf(cap),
                        "min_run_factor": None}
                       for tau, cap in itertools.product(args.min_run_confidence, args.max_run_factor)])
    first = min((c for c in cands if c["pairs_missing"] == 0), key=lambda c: c["score"])
    # stage 2: for that timing, the steps' own threshold and the floor with the threshold and cap again
    grid2 = [{"min_run_confidence": tau, "step_min_run_confidence": st, "max_run_factor": inf(cap),
              "min_run_factor": inf(fl)}
             for tau, st, cap, fl in itertools.product(args.min_run_confidence, args.step_min_run_confidence,
                                                       args.max_run_factor, args.min_run_factor)
             if st is None or st != tau]  # a step threshold equal to the actions' is the same as None
    stage(2, [(first["run_timing"], first["motion_level"], first["motion_filter"])], grid2)
    ok = [c for c in cands if c["pairs_missing"] == 0 and c["stage"] == 2]
    best = min(ok, key=lambda c: c["score"])
    chosen = {k: best[k] for k in ("run_timing", "motion_level", "motion_filter", "min_run_confidence",
                                   "step_min_run_confidence", "max_run_factor", "min_run_factor")}
    doc = {**validation_header(TEMPO_RUNS), "seed": args.seed,
           "command": " ".join(["python scripts/validate_tempo_runs.py", *sys.argv[1:]]),
           "recognised_dir": os.path.relpath(args.recognised_dir.resolve(), ROOT),
           "poses_dir": None if args.poses_dir is None else str(args.poses_dir), "inputs": inputs,
           "split": g, "validation_performers": g["V"],
           "rule": "least mean |log(recognised median run length / true median)| over validation performer x label "
                   "(six actions and Step), averaged over the inputs (true 2D; estimated 2D) and the two video sets "
                   "(all videos; perf0_front); every pair measured. Stage 1: the timing (with one confidence "
                   "threshold and no floor); stage 2, for stage 1's timing: the thresholds, the cap and the floor",
           "candidates": cands, "chosen": chosen, "wall_seconds": time.perf_counter() - t_start}
    write_validation(args.out, json.loads(json.dumps(doc), parse_constant=lambda x: None))
    f = lambda x, d=3: "-" if x is None else f"{x:.{d}f}"
    head = f"{'st':>2s} {'timing':>6s} {'level':>5s} {'filt':>4s} {'min conf':>8s} {'step':>5s} {'max fac':>7s} {'min fac':>7s}"
    for kind in inputs:
        head += f" {'err ' + kind[:4] + ' all':>13s} {'perf0':>6s} {'act.t r':>7s} {'dur.f r':>7s}"
    print(head + f" {'score':>6s} {'missing':>7s} {'model ref':>9s}")
    for c in cands:
        row = (f"{c['stage']:>2d} {c['run_timing']:>6s} {f(c['motion_level'], 1):>5s} "
               f"{'-' if c['motion_filter'] is None else c['motion_filter']:>4} {c['min_run_confidence']:8.2f} "
               f"{f(c['step_min_run_confidence'], 2):>5s} {f(c['max_run_factor'], 1):>7s} {f(c['min_run_factor'], 1):>7s}")
        for kind in inputs:
            row += (f" {c[f'error_{kind}_all']:13.3f} {c[f'error_{kind}_perf0']:6.3f} "
                    f"{f(c[f'action_tempo_r_{kind}']):>7s} {f(c[f'duration_factor_r_{kind}']):>7s}")
        print(row + f" {c['score']:6.3f} {c['pairs_missing']:7d} {c['model_reference_error']:9.3f}")
    print("chosen:", chosen, f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
