#!/usr/bin/env python
"""Keyframe in-betweening on held-out CMU subjects: markov (Molina Tanco & Hilton 2000) against the motion
graph's shortest path and LAFAN1's LERP+SLERP, by LAFAN1's L2P and L2Q at gaps of 15 / 30 / 45 frames.

Split (:data:`vidstyle.evaluation.inbetween.SPLIT`, each subject in one role): library 01, 05, 06, 08;
test 02 and 07 (validation subject 03 is only used by ``scripts/validate_inbetween.py``, which chose the
defaults this run uses). Windows of 65 frames every 40 at 30 fps; 10 frames of past context, the gap,
then the target frame (:mod:`vidstyle.evaluation.inbetween`). Speed: milliseconds per keyframe request
(median over the windows), one thread.

    python scripts/eval_inbetween.py [--cmu ../shared/data/mocap/cmu]

Writes ``--out`` (default ``pipelines/kickboxing/results/inbetween.json``, kind ``vidstyle.metrics.inbetween``)
and prints the table; logs on stderr.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vidstyle.evaluation.inbetween import GAPS, SPLIT, evaluate, table
from vidstyle.formats.metrics import INBETWEEN, write_metrics

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_CMU = ROOT.parent / "shared" / "data" / "mocap" / "cmu"
DEFAULT_OUT = ROOT / "pipelines" / "kickboxing" / "results" / "inbetween.json"
DEFAULT_CACHE = Path(os.environ.get("TMPDIR", "/tmp")) / "vidstyle_inbetween"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cmu", type=Path, default=DEFAULT_CMU, help="CMU BVH clips (default: ../shared beside the repository)")
    ap.add_argument("--cache", type=Path, default=DEFAULT_CACHE, help="Where the library's motion graph is kept.")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    lib = SPLIT["library"]
    doc = evaluate(args.cmu, lib, SPLIT["test"], GAPS, seed=args.seed,
                   graph_cache=args.cache / f"graph_{'_'.join(lib)}_seed{args.seed}.npz",
                   command="python scripts/eval_inbetween.py" + (f" --seed {args.seed}" if args.seed else ""))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_metrics(args.out, doc, kind=INBETWEEN)
    print(table(doc))
    logging.getLogger("eval_inbetween").info("wrote %s", args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
