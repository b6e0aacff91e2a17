#!/usr/bin/env python
"""The keyframe in-betweening defaults (``vidstyle/inbetween/defaults.py``: ``N_CLUSTERS``, ``N_COMPONENTS``,
``WARP_COST``, ``ROOT_PATH``), chosen on the CMU *validation* subject only, never on the test subjects that
``scripts/eval_inbetween.py`` scores.

Split (each CMU subject in one role; :data:`vidstyle.evaluation.inbetween.SPLIT`): library 01, 05, 06, 08
(the motion graph and the Markov model are fitted on them), validation 03, test 02 and 07. Windows of the
validation subject at 30 fps, gaps of 15 / 30 / 45 frames, LAFAN1's L2P and L2Q
(:mod:`vidstyle.evaluation.inbetween`). Grid: every combination of the candidates below; the winner is the
least mean L2P over the three gaps (ties: the first listed). Then, for the winner, the root path
(``ROOT_PATH``: the library segments' own, or the keys' Hermite curve) by the same criterion. The graph,
SLERP and SLERP-with-the-Hermite-root baselines are scored once on the same windows for reference. Every
row tried is written to the table.

    python scripts/validate_inbetween.py [--cmu ../shared/data/mocap/cmu]

Writes ``--out`` (default ``pipelines/kickboxing/validation/inbetween.json``); logs on stderr.
"""

from __future__ import annotations

import argparse
import itertools
import logging
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vidstyle.evaluation.inbetween import GAPS, SPLIT, benchmark, prepare
from vidstyle.formats.validation import INBETWEEN, validation_header, write_validation

log = logging.getLogger("validate_inbetween")
ROOT = Path(__file__).resolve().parents[1]
DEFAULT_CMU = ROOT.parent / "shared" / "data" / "mocap" / "cmu"
DEFAULT_OUT = ROOT / "pipelines" / "kickboxing" / "validation" / "inbetween.json"
DEFAULT_CACHE = Path(os.environ.get("TMPDIR", "/tmp")) / "vidstyle_inbetween"
GRID = {"n_clusters": [16, 32, 64], "n_components": [8, 16, 32, 64], "warp_cost": [None, 0.2]}
ROOT_PATHS = ["library", "hermite"]  # searched last, for the grid's winner (the grid runs on "library")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cmu", type=Path, default=DEFAULT_CMU, help="CMU BVH clips (default: ../shared beside the repository)")
    ap.add_argument("--cache", type=Path, default=DEFAULT_CACHE, help="Where the library's motion graph is kept.")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    lib = SPLIT["library"]
    data = prepare(args.cmu, lib, SPLIT["validation"], args.seed,
                   args.cache / f"graph_{'_'.join(lib)}_seed{args.seed}.npz")
    base = benchmark(data, ("graph", "slerp", "slerp_hermite"), GAPS, args.seed)["methods"]

    def row(params: dict) -> dict:
        res = benchmark(data, ("markov",), GAPS, args.seed, params)["methods"]["markov"]
        score = sum(res[str(g)]["l2p"] for g in GAPS) / len(GAPS)
        log.info("%s mean L2P %.4f", params, score)
        return {"params": params, "mean_l2p": score,
                **{f"l2p_{g}": res[str(g)]["l2p"] for g in GAPS}, **{f"l2q_{g}": res[str(g)]["l2q"] for g in GAPS}}

    rows = [row({**dict(zip(GRID, values)), "root_path": ROOT_PATHS[0]}) for values in itertools.product(*GRID.values())]
    grid_best = min(rows, key=lambda r: r["mean_l2p"])
    rows += [row({**grid_best["params"], "root_path": rp}) for rp in ROOT_PATHS[1:]]
    best = min(rows, key=lambda r: r["mean_l2p"])
    cols = [f"l2p_{g}" for g in GAPS] + [f"l2q_{g}" for g in GAPS]
    print(f"{'n_clusters':>10} {'n_comp':>6} {'warp':>5} {'root':>8} " + " ".join(f"{c:>7}" for c in cols) + "  mean_l2p")
    for r in rows:
        p = r["params"]
        print(f"{p['n_clusters']:>10} {p['n_components']:>6} {p['warp_cost']!s:>5} {p['root_path']:>8} "
              + " ".join(f"{r[c]:7.3f}" for c in cols) + f"  {r['mean_l2p']:.3f}" + ("  <- chosen" if r is best else ""))
    for name, res in base.items():
        print(f"{name:>33} " + " ".join(f"{res[str(g)]['l2p']:7.3f}" for g in GAPS) + " "
              + " ".join(f"{res[str(g)]['l2q']:7.3f}" for g in GAPS))
    doc = {**validation_header(INBETWEEN), "seed": args.seed,
           "command": "python scripts/validate_inbetween.py",
           "split": {k: list(v) for k, v in SPLIT.items()}, "windows": len(data["wins"]), "gaps": list(GAPS),
           "criterion": "least mean L2P over the gaps, validation subject only; the root path searched last, "
                        "for the grid's winner",
           "grid": {**GRID, "root_path": ROOT_PATHS}, "rows": rows, "chosen": best["params"], "baselines": base}
    write_validation(args.out, doc)
    log.info("wrote %s; chosen %s", args.out, best["params"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
