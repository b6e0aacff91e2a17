#!/usr/bin/env python
"""Which cue decides a performer's lead (``STYLE_LEAD_CUE`` in ``vidstyle/actionmodel/defaults.py``), chosen on
the *non-test* performers of split seed 0 (sets A, B and V; never the test performers), from what the
pipeline's ``action_style`` stage fits from: the pose stage's 2D of the first ``--frames`` frames of one
front take, with the pipeline's recognised labels.

Candidates (:class:`vidstyle.actionmodel.stylefit.GlobalStyleEstimator` ``lead_cue``):

- ``jab``: the jab rules alone (the jabbing wrist's side of the neck in front views when there are five
  or more jabs, else the pose stage's left/right wrist labels);
- ``stance``: the front foot's image side in every frame (the lower ankle, for a camera that looks down,
  against the hips' midpoint; label-free), when there are ``STYLE_MIN_STANCE_FRAMES`` or more such frames,
  else the jab rules.

Each performer's estimator is fitted (on true 2D, as the pipeline fits it) on the training performers
(A+B) other than that performer, so the sides it learns never saw them. Rule: the highest lead accuracy;
ties go to the larger mean signed margin (the lead score times the true lead's sign, in [-1, 1]).

    python scripts/validate_lead_cue.py --run pipelines/kickboxing/out [--poses DIR]

The poses are made with the pipeline's command (``vidstyle pose ... --backend ps --frames 0,...``) unless
``--poses`` already holds them. Writes ``--out`` (default ``pipelines/kickboxing/validation/lead_cue.json``);
logs on stderr.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import tempfile
import time
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")
sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]
ROOT = Path(__file__).resolve().parents[1]
from _actionstyle_args import pose_run_arguments

log = logging.getLogger("validate_lead_cue")
CUES = ("jab", "stance")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    pose_run_arguments(ap, "lead_cue.json")
    ap.add_argument("--backend", default="ps", help="Pose backend (params.yaml action_style.poses).")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    log.setLevel(logging.INFO)
    import numpy as np

    from vidstyle.actionmodel.stylefit import GlobalStyleEstimator
    from vidstyle.evaluation.actionmodel import split_groups
    from vidstyle.evaluation.actionstyle import demo_truth, performer_videos, pose_files
    from vidstyle.formats.validation import LEAD_CUE, validation_header, write_validation

    t_start = time.perf_counter()
    dataset = args.run / "dataset"
    demo = demo_truth(dataset)
    manifest, ds = demo["manifest"], demo["dataset"]
    g = split_groups(manifest, args.seed)
    train = sorted(g["A"] + g["B"])
    performers = sorted(g["A"] + g["B"] + g["V"])
    videos = [f"{p}_perf0_front" for p in performers]
    poses = pose_files(dataset, videos, args.backend, args.poses or tempfile.mkdtemp(prefix="vidstyle_lead_"),
                       args.frames)
    true2d = {p: performer_videos(ds, manifest, p, "true") for p in train}
    rows = []
    for p in performers:
        pop = [x for q in train if q != p for x in true2d[q]]
        vids = [v for v in performer_videos(ds, manifest, p, "estimated", poses_dir=poses, labels_dir=args.run / "recognized")
                if np.isfinite(v[0]).any()]
        truth = demo["style"][p]["lead"]
        sign = 1.0 if truth == "orthodox" else -1.0
        for cue in CUES:
            est = GlobalStyleEstimator(lead_cue=cue).fit(pop)
            gs = est.estimate(vids)
            rows.append({"performer": p, "group": next(k for k in ("A", "B", "V") if p in g[k]), "cue": cue,
                         "lead_true": truth, "lead": gs.lead, "correct": gs.lead == truth,
                         "lead_score": gs.lead_score, "margin": gs.lead_score * sign, "jabs": gs.n_jabs,
                         "videos": len(vids)})
            log.info("%s %-6s lead %s (true %s), score %+.3f, %d jabs", p, cue, gs.lead, truth, gs.lead_score, gs.n_jabs)
    by_cue = {}
    for cue in CUES:
        rs = [r for r in rows if r["cue"] == cue]
        by_cue[cue] = {"performers": len(rs), "lead_accuracy": float(np.mean([r["correct"] for r in rs])),
                       "mean_margin": float(np.mean([r["margin"] for r in rs])),
                       "southpaws": sum(r["lead_true"] == "southpaw" for r in rs)}
    best = max(CUES, key=lambda c: (by_cue[c]["lead_accuracy"], by_cue[c]["mean_margin"]))
    doc = {**validation_header(LEAD_CUE), "seed": args.seed,
           "command": "python scripts/validate_lead_cue.py " + " ".join(sys.argv[1:]),
           "split": g, "videos": videos, "frames": args.frames, "backend": args.backend,
           "rule": "highest lead accuracy, ties the larger mean signed margin; each performer's estimator "
                   "fitted on the training performers other than it",
           "by_cue": by_cue, "rows": rows, "chosen": best, "wall_seconds": time.perf_counter() - t_start}
    write_validation(args.out, doc)
    print(f"{'performer':>9s} " + " ".join(f"{c + ' lead':>14s} {'score':>6s}" for c in CUES) + "  true")
    for p in performers:
        rs = {r["cue"]: r for r in rows if r["performer"] == p}
        print(f"{p:>9s} " + " ".join(f"{rs[c]['lead']:>14s} {rs[c]['lead_score']:+6.2f}" for c in CUES)
              + f"  {rs[CUES[0]]['lead_true']}")
    for c, s in by_cue.items():
        print(f"{c:>9s}: lead accuracy {s['lead_accuracy']:.3f}, mean margin {s['mean_margin']:+.3f}"
              + ("  <- chosen" if c == best else ""))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
