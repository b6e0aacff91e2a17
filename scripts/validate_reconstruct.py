#!/usr/bin/env python
"""The reconstruction's defaults (``vidstyle/reconstruct/defaults.py``), chosen on the demo's *validation*
performers only (never the test performers ``vidstyle evaluate reconstruct`` scores).

For one performance take of each validation performer of the ``unseen-performer`` split (seed 0), the first
``--frames`` frames, 2D poses from the shipped pictorial-structures model (``vidstyle pose --backend ps``,
what the pipeline uses on renders; cached in ``--cache``; BlazePose's in its ``blazepose/``), reconstructed
against the demo library (``out/augmg/library``) on the library's skeleton. Score: the pooled root-relative
MPJPE (mm; lower is better). Search: per method, coordinate descent over the factors that method uses, from
the starting values, twice over them; the method whose best scores least wins. Of a factor's candidates within
``TIE_MM`` of its best score the first listed (the cheaper) wins, except the neighbours per frame ``k`` (the
reconstruction's cost grows with it: kNN and the lazy neighbourhood graph), of which the least within
``POSE_TOLERANCE`` of the best wins, and the foot-pinning cap
(``pin_max_offset``, leg lengths; None: no cap), chosen by the least foot skate among those within
``POSE_TOLERANCE`` of the best pose error (pinning may trade one for the other). Then, for the chosen method
with a refinement, ``refine_smooth_frames`` (the refined pose smoothed in time): the least acceleration error
among its candidates within ``POSE_TOLERANCE`` of their best pose error. Last, for the chosen method, the foot
contacts (``contact_threshold``, the vote a planted foot needs, and ``contact_gap_s``, the longest lift
bridged) and ``pin_drift`` (planted feet follow the root's relaxed drift), jointly, with the pictorial
structures' 2D and with BlazePose's (what real footage gets; how far a noisy vote can be trusted depends on
the 2D): per source, the least foot skate (the headline's, of the reconstruction's own low ankles) among the
combinations within ``POSE_TOLERANCE`` of that source's best pose error, as for the pinning cap; for any other
2D (``default``: true 2D, an unknown estimator), the least mean skate among those within it of both sources'
best (none such: the least worst ratio to a source's best). Until then they stay at their starting values, the
reconstruction's behaviour before they existed. Every (values, score) tried is written to the table.

    python scripts/validate_reconstruct.py [--run pipelines/kickboxing/out]

About 130 settings with the pictorial structures' 2D and 32 with BlazePose's, a quarter of an hour on one
core. ``table`` holds the former, ``table_blazepose`` the latter; ``chosen`` the values of
``vidstyle/reconstruct/defaults.py``, ``contacts`` its ``CONTACTS``.

Writes ``--out`` (default ``pipelines/kickboxing/validation/reconstruct.json``); logs on stderr.
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vidstyle.errors import VidstyleError
from vidstyle.formats.validation import RECONSTRUCT_DEFAULTS, validation_header, write_validation

log = logging.getLogger("validate_reconstruct")
ROOT = Path(__file__).resolve().parents[1]
RUN = ROOT / "pipelines" / "kickboxing" / "out"
DEFAULT_OUT = ROOT / "pipelines" / "kickboxing" / "validation" / "reconstruct.json"
DEFAULT_CACHE = Path(os.environ.get("TMPDIR", "/tmp")) / "vidstyle_validate_reconstruct"

#: the pinning cap may cost at most this share of pose error (relative to its factor's best) for less skate, and
#: the neighbours per frame (k) as much for less computation
POSE_TOLERANCE = 0.02
#: differences below this are noise: of the candidates within it of the best, the first listed (the cheaper) wins
TIE_MM = 0.1
#: the figures of a pooled row the tables keep
FIGURES = ("mpjpe_root_relative_mm", "pa_mpjpe_mm", "foot_skate_mm_per_frame", "acceleration_error_mm_per_frame2")
START = {"method": "olng", "k": 32, "n_blend": 8, "window_s": 0.5, "smooth_frames": 1.0, "pin_max_offset": 0.25,
         "refine_prior": None, "refine_smooth_frames": 0.0, "contact_threshold": 0.5, "contact_gap_s": 0.0,
         "pin_drift": False}
CANDIDATES = {"method": ["nn", "olng", "subsequence"], "k": [16, 32, 64, 128], "n_blend": [1, 4, 8, 16, 32],
              "window_s": [0.25, 0.5, 1.0, 2.0], "smooth_frames": [0.0, 1.0, 2.0, 3.0],
              "pin_max_offset": [0.1, 0.25, 0.4, None], "refine_prior": [None, 1.0, 0.1, 0.03],
              "refine_smooth_frames": [0.0, 1.0, 2.0, 3.0], "contact_threshold": [0.5, 0.4, 0.3, 0.2],
              "contact_gap_s": [0.0, 0.05, 0.1, 0.2], "pin_drift": [False, True]}


def poses_for(dataset, videos: list[str], frames: int, cache: Path, backend: str = "ps") -> Path:
    """``cache`` holding ``<video>.poses.json`` of the first ``frames`` frames of each video by ``backend``
    (as ``vidstyle pose --backend B`` estimates them), estimated where missing."""
    from vidstyle.formats.poses import read_poses, write_poses
    from vidstyle.pose.run import estimate_video

    cache.mkdir(parents=True, exist_ok=True)
    for v in videos:
        path = cache / f"{v}.poses.json"
        if path.is_file():
            try:
                p = read_poses(path)
                if p.backend == backend and len(p.frames) >= frames:
                    continue
            except VidstyleError:
                pass
        video = dataset.root / dataset.by_id()[v].video
        log.info("%s: estimating %d frames (%s)", v, frames, backend)
        # the pictorial structures at scale 1 only, as the pipeline's reconstruct_poses stage reads the demo
        write_poses(path, estimate_video(video, backend, None, list(range(frames)), jobs=1,
                                         scales=(1.0,) if backend == "ps" else None))
    return cache


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--run", type=Path, default=RUN, help="A finished demo run (its dataset and library).")
    ap.add_argument("--frames", type=int, default=400)
    ap.add_argument("--cache", type=Path, default=DEFAULT_CACHE)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    log.setLevel(logging.INFO)
    from vidstyle.evaluation.reconstruct import evaluate
    from vidstyle.formats.dataset import read_dataset
    from vidstyle.recognition.splits import make_split

    try:
        dataset = read_dataset(args.run / "dataset")
        split = make_split(dataset, "unseen-performer", seed=args.seed)
        val = set(split.val)
        videos = [sorted(v.id for v in dataset.videos if v.performer == p and v.kind == "performance" and v.id in val)[0]
                  for p in sorted(split.val_performers)]
        cache = poses_for(dataset, videos, args.frames, args.cache)
        cache_bp = poses_for(dataset, videos, args.frames, args.cache / "blazepose", backend="blazepose")
        table: list[dict] = []
        rows: dict[tuple, dict] = {}  # pooled rows with the pictorial structures' 2D, by setting
        bp_rows: dict[tuple, dict] = {}  # and with BlazePose's
        table_bp: list[dict] = []

        def key_of(values: dict) -> tuple:
            return tuple(sorted(values.items(), key=lambda kv: kv[0]))

        def pooled_row(values: dict, poses_dir: Path, source: str, store: dict, record: list) -> dict:
            """The pooled row of ``values`` with ``source``'s 2D (from ``poses_dir``), evaluated once: kept in
            ``store`` and its figures added to ``record``."""
            key = key_of(values)
            if key not in store:
                params = {k: v for k, v in values.items() if k != "method"}
                m = evaluate(args.run / "dataset", [args.run / "augmg" / "library" / "clips"], videos=videos,
                             poses_dirs=[poses_dir], methods=[values["method"]], skeletons=["library"],
                             max_frames=args.frames, seed=args.seed, **params)
                # the method's row (BlazePose's own 3D, "blazepose-world", is another)
                row = next(r for r in m["runs"] if r["data"] == "demo test performers" and r["source"] == source
                           and r["method"] == values["method"])
                store[key] = row
                record.append({**values, **{f: row[f] for f in FIGURES}})
                log.info("%s (%s): %.1f mm", values, source, row["mpjpe_root_relative_mm"])
            return store[key]

        def score(values: dict) -> float:
            if values["n_blend"] > values["k"]:  # not a setting: blend at most the k neighbours
                return float("inf")
            return pooled_row(values, cache, "ps", rows, table)["mpjpe_root_relative_mm"]

        #: the factors each method uses (the subsequence graph has its own window and takes no k / blend)
        uses = {"nn": ["k", "n_blend", "smooth_frames", "pin_max_offset", "refine_prior"],
                "olng": ["k", "n_blend", "window_s", "smooth_frames", "pin_max_offset", "refine_prior"],
                "subsequence": ["smooth_frames", "pin_max_offset", "refine_prior"]}
        per_method = {}
        for method in CANDIDATES["method"]:
            best = {**START, "method": method}
            for _ in range(2):
                for factor in uses[method]:
                    cands = CANDIDATES[factor]
                    scores = {c: score({**best, factor: c}) for c in cands}
                    low = min(scores.values())
                    if factor == "k":  # a cost: the fewest neighbours within POSE_TOLERANCE of the best pose error
                        best[factor] = next(c for c in cands if scores[c] <= low * (1 + POSE_TOLERANCE))
                    elif factor == "pin_max_offset":  # least skate among those within POSE_TOLERANCE of the best pose
                        ok = [c for c in cands if scores[c] <= low * (1 + POSE_TOLERANCE)]
                        skate = {c: rows[key_of({**best, factor: c})]
                                 ["foot_skate_mm_per_frame"] for c in ok}
                        best[factor] = min(ok, key=lambda c: (skate[c], cands.index(c)))
                    else:
                        best[factor] = next(c for c in cands if scores[c] <= low + TIE_MM)  # the first within the tie
            per_method[method] = dict(best)
        method_scores = {m: score(b) for m, b in per_method.items()}
        low = min(method_scores.values())
        best = dict(per_method[next(m for m in CANDIDATES["method"] if method_scores[m] <= low + TIE_MM)])
        if best.get("refine_prior") is not None:
            # last, for the chosen method: the refined pose smoothed in time, which trades pose error for
            # smoothness; the least acceleration error among the candidates within POSE_TOLERANCE of the best
            # pose error (as the pinning cap trades pose error for skate)
            cands = CANDIDATES["refine_smooth_frames"]
            scores = {c: score({**best, "refine_smooth_frames": c}) for c in cands}
            low = min(scores.values())
            ok = [c for c in cands if scores[c] <= low * (1 + POSE_TOLERANCE)]
            acc = {c: rows[key_of({**best, "refine_smooth_frames": c})]
                   ["acceleration_error_mm_per_frame2"] for c in ok}
            best["refine_smooth_frames"] = min(ok, key=lambda c: (acc[c], cands.index(c)))
        # last, the foot contacts and the pins' drift of the chosen method, all three at once (a lower vote and
        # a longer bridge both pin more frames, which a pin that follows the drift makes cheaper), per 2D source
        # (how far a noisy vote can be trusted depends on the 2D): for each source, the least foot skate among
        # the combinations within POSE_TOLERANCE of its best pose error (as the pinning cap); for any other 2D
        # (true 2D, an unknown estimator) the least mean skate within POSE_TOLERANCE of each source's best (none
        # such: the least worst ratio to a source's best)
        contact = ("contact_threshold", "contact_gap_s", "pin_drift")
        # in ``contact``'s order; listed drift off first, then by vote and gap (ties: the earlier listed wins)
        combos = [(t, g, d) for d in CANDIDATES["pin_drift"] for t in CANDIDATES["contact_threshold"]
                  for g in CANDIDATES["contact_gap_s"]]
        settings = {c: {**best, **dict(zip(contact, c))} for c in combos}
        found = {"ps": {c: pooled_row(v, cache, "ps", rows, table) for c, v in settings.items()},
                 "blazepose": {c: pooled_row(v, cache_bp, "blazepose", bp_rows, table_bp) for c, v in settings.items()}}

        def skate_of(row: dict) -> float:  # no planted pair: no figure, not preferred
            return math.inf if row["foot_skate_mm_per_frame"] is None else row["foot_skate_mm_per_frame"]

        lows = {src: min(r["mpjpe_root_relative_mm"] for r in found[src].values()) for src in found}
        contacts = {}
        for src in found:
            ok = [c for c in combos if found[src][c]["mpjpe_root_relative_mm"] <= lows[src] * (1 + POSE_TOLERANCE)]
            contacts[src] = dict(zip(contact, min(ok, key=lambda c: (skate_of(found[src][c]), combos.index(c)))))
        ratio = {c: max(found[src][c]["mpjpe_root_relative_mm"] / lows[src] for src in found) for c in combos}
        ok = [c for c in combos if ratio[c] <= 1 + POSE_TOLERANCE] or [min(combos, key=lambda c: ratio[c])]
        contacts["default"] = dict(zip(contact, min(
            ok, key=lambda c: (sum(skate_of(found[src][c]) for src in found) / len(found), combos.index(c)))))
    except VidstyleError as e:
        log.error("%s", e)
        return 2
    doc = {**validation_header(RECONSTRUCT_DEFAULTS), "script": "scripts/validate_reconstruct.py", "seed": args.seed,
           "videos": videos, "frames": args.frames, "source": "ps", "skeleton": "library",
           "score": "pooled root-relative MPJPE (mm), lower is better", "start": START, "candidates": CANDIDATES,
           "factors_not_searched": ["n_views", "spread", "root_smooth_frames", "relax_s", "ssg_window_s",
                                    "ssg_overlap", "ssg_k", "ssg_transition_weight"],
           "tie_mm": TIE_MM, "pose_tolerance": POSE_TOLERANCE,
           "chosen": {k: v for k, v in best.items() if k not in contact}, "contacts": contacts,
           "per_method": per_method, "chosen_score_mm": rows[key_of({**best, **contacts["ps"]})]["mpjpe_root_relative_mm"], "table": table,
           "table_blazepose": table_bp}
    write_validation(args.out, doc)
    log.info("chosen %s, contacts %s (%.1f mm); wrote %s", doc["chosen"], contacts, doc["chosen_score_mm"], args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
