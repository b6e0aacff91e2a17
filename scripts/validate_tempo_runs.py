#!/usr/bin/env python
"""Choose which recognised-label runs measure a performer's action lengths and step length (the tempo and
speed of :class:`vidstyle.actionmodel.stylefit.GlobalStyleEstimator`) on the *validation* performers:
its ``min_run_confidence``, and whether dropping runs longer than ``max_run_factor`` times the
population's median length of the label (back-to-back repeats the recognizer joined into one run) helps
(a candidate the library keeps only if validation chooses it).

The recognised labels are the pipeline's (``--recognised-dir``; the recognizer of split seed 0, trained
on its sets A and B). The validation performers are set V of split seed 0 (never its test performers; of
the seeds' validation sets only seed 0's is out of that recognizer's training set). The population is
fitted on A and B (true 2D, true labels), as ``vidstyle evaluate action-style`` fits it.

Each candidate estimates, per validation performer and label
(the six actions and ``Step``), the median length of the runs it trusts, on two sets of videos: all of
the performer's videos, and ``perf0_front`` alone (what the pipeline's action-style evaluation has pose
files for). The error of a (performer, label) pair is ``|log(recognised median / true median)|``, the
true median over the true labels' runs of the same videos. Rule: the candidate of least mean error over
both video sets; every pair must be measured. The estimator's tempo figures against the performers' true
style parameters are recorded too (two performers: a guide, not the rule).

    python scripts/validate_tempo_runs.py

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
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--min-run-confidence", type=float, nargs="+", default=[0.0, 0.3, 0.4, 0.5, 0.6, 0.7])
    ap.add_argument("--max-run-factor", type=float, nargs="+", default=[math.inf, 2.2, 1.8, 1.5])
    ap.add_argument("--out", type=Path, default=ROOT / "pipelines" / "kickboxing" / "validation" / "tempo_runs.json")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    log.setLevel(logging.INFO)
    import numpy as np

    from vidstyle.actionmodel.stylefit import GlobalStyleEstimator, label_runs, video_figures
    from vidstyle.evaluation.actionmodel import split_groups
    from vidstyle.evaluation.actionstyle import demo_truth, fit_population, pearson, performer_videos
    from vidstyle.formats.validation import TEMPO_RUNS, validation_header, write_validation

    class Capped(GlobalStyleEstimator):
        """The estimator with the candidate cap: recognised runs longer than ``cap`` times the population's
        median length of their label are dropped before the library's rule."""

        cap = math.inf

        def trusted_lengths(self, runs):
            ref = lambda a: self.step_frames_ if a == "Step" else self.durations_.get(a, math.nan)
            return super().trusted_lengths([(a, n, c) for a, n, c in runs
                                            if not (math.isfinite(c) and n > self.cap * ref(a))])

    t_start = time.perf_counter()
    demo = demo_truth(args.dataset)
    manifest, ds, actions, truth_style = (demo[k] for k in ("manifest", "dataset", "actions", "style"))
    g = split_groups(manifest, args.seed)
    train = sorted(g["A"] + g["B"])
    est = fit_population(ds, manifest, train)
    est.__class__ = Capped  # the same fitted figures, with the candidate cap
    ids = {p: [v["id"] for v in manifest["videos"] if v["performer"] == p] for p in g["V"]}
    data = {}
    for p in g["V"]:
        true_v = performer_videos(ds, manifest, p, "true")
        rec_v = performer_videos(ds, manifest, p, "true", labels_dir=args.recognised_dir)
        if len(rec_v) != len(true_v):
            raise SystemExit(f"{args.recognised_dir}: recognised labels missing for some of {p}'s videos")
        one = ids[p].index(f"{p}_perf0_front")
        for name, sel in (("all", range(len(true_v))), ("perf0", [one])):
            truth: dict[str, list[int]] = {}
            for i in sel:
                for label, s, e in label_runs(true_v[i][1]):
                    truth.setdefault(label, []).append(e - s)
            runs = [r for i in sel for r in video_figures(*rec_v[i][:2], rec_v[i][3])["runs"]]
            data[(p, name)] = (runs, {a: float(np.median(truth[a])) for a in (*actions, "Step") if truth.get(a)},
                               [rec_v[i] for i in sel])
    cands = []
    for tau, cap in itertools.product(args.min_run_confidence, args.max_run_factor):
        est.set_params(min_run_confidence=tau)
        est.cap = cap
        errs = {"all": [], "perf0": []}
        missing = 0
        fig = {"action_tempo": ([], []), "duration_factor": ([], []), "speed": ([], [])}
        for (p, name), (runs, truth, vids) in data.items():
            got = est.trusted_lengths(runs)
            for a, t in truth.items():
                if a in got:
                    errs[name].append(abs(math.log(float(np.median(got[a])) / t)))
                else:
                    missing += 1
            if name == "all":
                gs, st = est.estimate(vids), truth_style[p]
                for k, a in enumerate(actions):
                    if a in gs.action_tempo:
                        fig["action_tempo"][0].append(st["tempo"][k])
                        fig["action_tempo"][1].append(gs.action_tempo[a])
                    if a in gs.tempo:
                        fig["duration_factor"][0].append(st["tempo"][k] / st["speed"])
                        fig["duration_factor"][1].append(gs.tempo[a])
                fig["speed"][0].append(st["speed"])
                fig["speed"][1].append(gs.speed)
        c = {"min_run_confidence": tau, "max_run_factor": None if math.isinf(cap) else cap,
             "error_all": float(np.mean(errs["all"])), "error_perf0": float(np.mean(errs["perf0"])),
             "pairs_missing": missing,
             "action_tempo_r": pearson(*fig["action_tempo"]), "duration_factor_r": pearson(*fig["duration_factor"]),
             "speed_abs_log_error": float(np.mean(np.abs(np.log(np.asarray(fig["speed"][1]) / np.asarray(fig["speed"][0])))))}
        c["score"] = 0.5 * (c["error_all"] + c["error_perf0"])
        cands.append(c)
    ok = [c for c in cands if c["pairs_missing"] == 0]
    best = min(ok, key=lambda c: c["score"])
    doc = {**validation_header(TEMPO_RUNS), "seed": args.seed,
           "command": " ".join(["python scripts/validate_tempo_runs.py", *sys.argv[1:]]),
           "recognised_dir": os.path.relpath(args.recognised_dir.resolve(), ROOT), "split": g, "validation_performers": g["V"],
           "rule": "least mean |log(recognised median run length / true median)| over validation performer x label "
                   "(six actions and Step), averaged over the two video sets (all videos; perf0_front); every pair measured",
           "candidates": cands,
           "chosen": {"min_run_confidence": best["min_run_confidence"], "max_run_factor": best["max_run_factor"]},
           "wall_seconds": time.perf_counter() - t_start}
    write_validation(args.out, json.loads(json.dumps(doc), parse_constant=lambda x: None))
    f = lambda x: "-" if x is None else f"{x:.3f}"
    print(f"{'min conf':>8s} {'max fac':>7s} {'err all':>8s} {'err perf0':>9s} {'score':>6s} {'missing':>7s} "
          f"{'act.t r':>8s} {'dur.f r':>8s} {'speed err':>9s}")
    for c in cands:
        print(f"{c['min_run_confidence']:8.2f} {f(c['max_run_factor']):>7s} {c['error_all']:8.3f} {c['error_perf0']:9.3f} "
              f"{c['score']:6.3f} {c['pairs_missing']:7d} {f(c['action_tempo_r']):>8s} {f(c['duration_factor_r']):>8s} "
              f"{c['speed_abs_log_error']:9.3f}")
    print("chosen:", doc["chosen"], f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
