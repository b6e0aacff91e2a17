"""Validation table for the defaults of ``vidstyle evaluate augmg``: library segment, temporal context,
confidence weighting, candidates, and the acceptance thresholds of the robust AugMG.

Validation performers: the performance videos of the seed-0 demo dataset whose performers the
bundled annotations (``annotations/demo.json``, the test marks) never mark (p00-p02, p07-p09; the test
performers are p03-p06). Queries are every styled transition's key frame of those videos. The 2D
sources are ``gt``, ``noisy`` and the two pose estimators run on the videos at the key frames and
``context`` frames either side (``vidstyle pose --frames``; pass their directories): ``model``
(pictorial structures) and ``blazepose``.

Per configuration (segment, context, scores, k, foreshortening, placement, anchor, hold) every source is evaluated once; then the acceptance
thresholds (match cost, enhanced distance, gain) are searched per source over deciles of the rows' own
values. A configuration's score is its 2-fold cross-validated reduction (thresholds chosen on the
perf0 takes decide the perf1 takes and vice versa), averaged over the two *estimated* sources
(``model``, ``blazepose``); the best configuration's thresholds are then chosen on all validation
rows. Nothing here reads a test performer.

    vidstyle pose out/dataset/videos/p00_perf0_front.mp4 --backend ps [--scales 1,1.2,1.4] \\
        --frames <key-2..key+2 of its styled transitions> --out VAL/ps/p00_perf0_front.poses.json
    (the same with --backend blazepose into VAL/blazepose; scripts/validate_augmg.py --print-frames
     DATASET VIDEO prints the --frames list)
    python scripts/validate_augmg.py out/dataset out/augmg/library VAL/ps VAL/blazepose [VAL/ps_ms ...]

More pictorial-structures directories after the BlazePose one hold the same frames posed with other
``vidstyle pose`` inference settings (e.g. ``--scales 1,1.2,1.4``, read from the files' ``params``):
every configuration is scored with each, and the winner's settings are recorded as ``pose``.

Prints the tables and writes bench_results/validate_augmg.json (every row) and
bench_results/validation_augmg_chosen.json (the chosen defaults with the table they won on; it is
committed as ``pipelines/kickboxing/validation/augmg.json``, and the defaults of ``vidstyle augment`` /
``evaluate augmg``, in :mod:`vidstyle.augmg.defaults`, are its values).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

VALIDATION_VIDEOS = [f"{p}_perf{t}_front" for p in ("p00", "p01", "p02", "p07", "p08", "p09") for t in (0, 1)]
GRID = [  # (segment, context, scores, k, foreshortening, place, anchor, hold)
    ("fixed", 0, False, 10, False, "first", "ends", 0.0),  # the first defaults (single frame, no weights)
    ("adaptive", 0, False, 10, False, "first", "ends", 0.0),
    ("fixed", 2, True, 10, False, "first", "ends", 0.0),
    ("adaptive", 1, True, 10, False, "first", "ends", 0.0),
    ("adaptive", 2, False, 10, False, "first", "ends", 0.0),
    ("adaptive", 2, True, 10, False, "first", "ends", 0.0),
    ("adaptive", 2, True, 30, False, "first", "ends", 0.0),
    ("fixed", 0, False, 10, True, "first", "ends", 0.0),
    ("fixed", 2, False, 10, True, "first", "ends", 0.0),
    ("fixed", 2, True, 10, True, "first", "ends", 0.0),
    ("adaptive", 2, True, 10, True, "first", "ends", 0.0),
    ("fixed", 2, True, 30, True, "first", "ends", 0.0),
    # the segment placed by its enhancement nodes (the library's own look-alikes of the endpoints),
    # with and without a hold of the reference pose
    *[(seg, 2, sc, 10, fs, place, "nodes", hold) for seg in ("fixed", "adaptive")
      for sc, fs in ((False, False), (False, True), (True, True)) for place in ("both", "drift") for hold in (0.0, 0.2)],
]
#: the names of a GRID row's values, in order (the keys of each configuration in the output files)
CONFIG = ("segment", "context", "scores", "k", "foreshortening", "place", "anchor", "hold")
ESTIMATED = ("model", "blazepose")
NOTE = ("seed-0 pipeline output; VAL = vidstyle pose --frames <key-2..key+2> of the validation videos, both "
        "backends")


def print_frames(dataset: str, video: str, context: int = 2) -> None:
    labels = json.loads((Path(dataset) / "labels" / f"{video}.json").read_text())
    print(",".join(str(f) for f in sorted({t["key"] + d for t in labels["styled_transitions"]
                                           for d in range(-context, context + 1)})))


def _reduction(rows: list[dict]) -> float:
    plain = np.mean([r["transition_plain_mm"] for r in rows])
    return float(1 - np.mean([r["transition_augmg_mm"] for r in rows]) / plain)


def search_thresholds(rows: list[dict]) -> tuple[dict, float]:
    """Thresholds ``{"max_match_cost", "max_enh_cost", "min_gain_mm"}`` maximising the transition-error
    reduction of ``rows`` (one source); candidates are deciles of the rows' own values (None = no
    threshold). Returns (thresholds, reduction)."""
    from vidstyle.evaluation.augmg import accept

    def grid(key: str) -> list:
        vals = [r[key] for r in rows if r[key] is not None]
        return [None] + sorted({float(np.quantile(vals, q)) for q in np.linspace(0.1, 0.9, 9)})

    best = ({"max_match_cost": None, "max_enh_cost": None, "min_gain_mm": None}, _reduction(accept(rows)))
    for a in grid("match_cost"):
        for b in grid("enhanced_cost"):
            for g in grid("gain_mm"):
                red = _reduction(accept(rows, a, b, g))
                if red > best[1] + 1e-9:
                    best = ({"max_match_cost": a, "max_enh_cost": b, "min_gain_mm": g}, red)
    return best


def pose_settings(ps_dir: str) -> dict:
    """The ``vidstyle pose`` inference settings recorded in a directory's poses.json files (``params``;
    {} = the defaults: one scale); every file must agree."""
    from vidstyle.formats.poses import read_poses

    got = {json.dumps(read_poses(f).params, sort_keys=True) for f in sorted(Path(ps_dir).glob("*.poses.json"))}
    if len(got) != 1:
        raise SystemExit(f"{ps_dir}: poses made with different settings {sorted(got)} (or none)")
    return json.loads(got.pop())


def main(dataset: str, library: str, ps_dirs: list[str], bp_dir: str, note: str = NOTE) -> None:
    from vidstyle.evaluation.augmg import accept, evaluate_augmg, read_poses_dir, summarise

    bp = read_poses_dir(Path(bp_dir))
    sources = ("model", "blazepose", "gt", "noisy")
    out_rows = []
    hdr = (f"{'pose':18} {'segment':8} {'ctx':>3} {'scores':>6} {'k':>3} {'fore':>5} {'place':>5} {'anchor':>6} "
           f"{'hold':>4} | "
           + " | ".join(f"{s:>13}" for s in sources))
    print("transition-error reduction on the validation performers, without / with the source's thresholds "
          "(2-fold cross-validated over the takes)")
    print(hdr + " | estimated sources' mean (cross-validated)")
    for (pose, ps_dir), (seg, ctx, sc, k, fs, place, anchor, hold) in [(v, g) for v in [(pose_settings(d), d) for d in ps_dirs] for g in GRID]:
        poses = dict([read_poses_dir(Path(ps_dir)), bp])
        # thresholds=None: every row as it comes (the thresholds are searched below)
        m = evaluate_augmg(Path(dataset), Path(library), sources=sources, poses=poses, segment=seg, context=ctx,
                           use_scores=sc, k=k, foreshortening=fs, place=place, anchor=anchor, hold=hold,
                           thresholds=None, videos=VALIDATION_VIDEOS)
        rows = m["rows"]
        thresholds = {s: search_thresholds([r for r in rows if r["source"] == s])[0] for s in sources}
        thr = summarise(accept(rows, thresholds=thresholds), m["params"])["by_source"]
        # the score of a configuration: 2-fold cross-validated over the takes (thresholds chosen on perf0
        # applied to perf1 and vice versa), so in-sample threshold fitting does not pick it
        cv_rows = []
        for fit, held in (("perf0", "perf1"), ("perf1", "perf0")):
            t = {s: search_thresholds([r for r in rows if r["source"] == s and fit in r["video"]])[0] for s in sources}
            cv_rows += accept([r for r in rows if held in r["video"]], thresholds=t)
        cv = summarise(cv_rows, m["params"])["by_source"]
        red = float(np.mean([cv[s]["transition_reduction"] for s in ESTIMATED]))
        entry = {"pose": pose, "ps_dir": ps_dir, **dict(zip(CONFIG, (seg, ctx, sc, k, fs, place, anchor, hold))),
                 "no_threshold": {s: {kk: v for kk, v in m["by_source"][s].items()} for s in m["by_source"]},
                 "thresholds": thresholds, "estimated_reduction": red,
                 "cross_validated": {s: {kk: v for kk, v in cv[s].items()} for s in cv},
                 "with_threshold": {s: {kk: v for kk, v in thr[s].items()} for s in thr},
                 "queries": m["params"]["queries"]}
        out_rows.append(entry)
        cells = " | ".join(f"{100 * m['by_source'][s]['transition_reduction']:5.1f}/{100 * cv[s]['transition_reduction']:5.1f} %"
                           for s in sources)
        label = ",".join(f"{kk}={v}" for kk, v in pose.items()) or "defaults"
        print(f"{label[:18]:18} {seg:8} {ctx:3d} {str(sc):>6} {k:3d} {str(fs):>5} {place:>5} {anchor:>6} {hold:4.2f} | "
              f"{cells} | {100 * red:.1f} %",
              flush=True)
    best = max(out_rows, key=lambda x: x["estimated_reduction"])
    print(f"best: pose={best['pose'] or 'defaults'} " + " ".join(f"{kk}={best[kk]}" for kk in CONFIG) + " "
          f"(estimated sources' mean reduction {100 * best['estimated_reduction']:.1f} % on "
          f"{best['queries']} validation transitions); thresholds:")
    for s, t in best["thresholds"].items():
        print(f"  {s:9} " + "  ".join(f"{kk}={'-' if v is None else f'{v:.3f}'}" for kk, v in t.items()))
    print("best configuration by source and kind (thresholds chosen on all validation rows, in-sample):")
    for s, r in best["with_threshold"].items():
        print(f"  {s:9} plain {r['transition_plain_mm']:6.1f}  AugMG {r['transition_augmg_mm']:6.1f} mm  "
              f"accepted {r['accepted']:.2f}  retrieval {r['retrieval_mpjpe_mm']:6.1f} mm  R@10 {r['recall_at_10']:.2f}")
        for kind, x in r["by_kind"].items():
            print(f"      {kind:10} n={x['queries']:3d}  plain {x['plain_mm']:6.1f}  AugMG {x['augmg_mm']:6.1f}  "
                  f"enhanced {x['enhanced_mm']:6.1f}  oracle {x['oracle_mm']:6.1f}  accepted {x['accepted']:.2f}")
    Path("bench_results").mkdir(exist_ok=True)
    Path("bench_results/validate_augmg.json").write_text(json.dumps(
        {"dataset": dataset, "library": library, "validation_videos": VALIDATION_VIDEOS, "poses": [*ps_dirs, bp_dir],
         "grid": GRID, "rows": out_rows, "best": {kk: best[kk] for kk in ("pose", *CONFIG, "thresholds",
                                                                      "estimated_reduction")}},
        indent=2))
    # the chosen defaults, read by `vidstyle evaluate augmg --validation` (pipelines/kickboxing/validation/)
    Path("bench_results/validation_augmg_chosen.json").write_text(json.dumps(
        {"kind": "vidstyle.validation.augmg", "schema_version": 1, "chosen_on": VALIDATION_VIDEOS,
         **{kk: best[kk] for kk in ("pose", *CONFIG)},
         "thresholds": best["thresholds"], "validation_reduction": {
             s: best["with_threshold"][s]["transition_reduction"] for s in best["with_threshold"]},
         "command": f"python scripts/validate_augmg.py {dataset} {library} {ps_dirs[0]} {bp_dir} "
                    + "".join(f"{d} " for d in ps_dirs[1:]) + f"({note})", "queries": best["queries"],
         "table": [{**{kk: r[kk] for kk in ("pose", *CONFIG)},
                    "reduction_no_threshold": {s: round(r["no_threshold"][s]["transition_reduction"], 4)
                                               for s in r["no_threshold"]},
                    "reduction_cross_validated": {s: round(r["cross_validated"][s]["transition_reduction"], 4)
                                                  for s in r["cross_validated"]},
                    "estimated_mean_cross_validated": round(r["estimated_reduction"], 4)} for r in out_rows]},
        indent=1))


if __name__ == "__main__":
    if sys.argv[1] == "--print-frames":
        print_frames(sys.argv[2], sys.argv[3])
    else:
        argv = sys.argv[1:]
        note = NOTE
        if "--note" in argv:  # --note TEXT: how the pose directories were made (kept with the command)
            i = argv.index("--note")
            note = argv[i + 1]
            del argv[i:i + 2]
        if len(argv) < 4:
            raise SystemExit("usage: validate_augmg.py DATASET LIBRARY PS_DIR BP_DIR [PS_DIR ...] [--note TEXT] | "
                             "--print-frames DATASET VIDEO")
        main(argv[0], argv[1], [argv[2], *argv[4:]], argv[3], note)
