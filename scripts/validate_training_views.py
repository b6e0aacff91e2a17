#!/usr/bin/env python
"""Validate training the 3D SIFT recognizer on more camera views of its training performers, and on more performers (issue 28).

The demo's training videos film every performer from three cameras (front, left, right at 10 degrees
elevation). A user's camera is anywhere. This script asks, on each split seed's validation performers only,
whether adding the same training takes filmed from other cameras (``vidstyle train-recognizer --more-views``:
set B's performers in a second dataset, ``vidstyle demo make-dataset --views 45,135,180,225,315 --elevation 25
--performances 0 --single-seconds 8``) helps, and with which cap on the SVM's training frames per class
(more videos of the same takes spread a fixed cap over more views). Per seed, the rows are:

- the seed's own validated recognizer (``validation/recognition.json`` for seed 0,
  ``validation/recognition_seedS.json`` otherwise; its ``final_config``), trained on sets A and B;
- the same with the more-views videos in set B, at each cap of ``--caps``;
- with ``--more-performers D`` (``vidstyle demo make-dataset --performers 40 --first-performer 10 --performances 0
  --single-seconds 8``: 30 procedural performers that no split holds, at the three cameras): the more views and
  these performers too, a share of them (``--vocab-share``, the first by id) in the vocabulary's set A and the
  rest in set B (``vocabulary / train-recognizer --more-performers``), at each cap of ``--performer-caps``.

Each row is scored like ``scripts/validate_recognition.py`` scores a candidate: the smoothed frame accuracy
on the validation performers' own videos (V), on their videos from the validation camera (60 and 120 degrees
at 30 degrees elevation before a held-out texture, cameras that neither training, the more views nor the
unseen-camera test use), and ``score``, the mean of the two. The rule: the highest score per seed; the
pipeline's default is seed 0's choice, each seed's results use its own. Nothing here reads a test video.

    python scripts/validate_training_views.py --dataset pipelines/kickboxing/out/dataset \\
        --features pipelines/kickboxing/out/features /tmp/f20 --camera-dataset /tmp/valcam \\
        --camera-features /tmp/valcam10 /tmp/valcam20 --more-views /tmp/xview \\
        --more-views-features /tmp/xview10 /tmp/xview20 --more-performers /tmp/perf \\
        --more-performers-features /tmp/perf10 /tmp/perf20 --seeds 0 1 2 3 4

(features directories are told apart by the points per frame recorded in them; ``/tmp/valcam``: the
validation camera of ``scripts/validate_recognition.py``; ``/tmp/xview``: the make-dataset command above,
every performer, so that one dataset serves every seed; ``/tmp/perf``: the more-performers command above).
Writes ``validation/training_views.json``.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vidstyle.evaluation.recognition import load_set, score_set  # noqa: E402
from vidstyle.formats.dataset import read_dataset  # noqa: E402
from vidstyle.formats.features import directory_params  # noqa: E402
from vidstyle.formats.validation import TRAINING_VIEWS as KIND  # noqa: E402
from vidstyle.formats.validation import write_validation  # noqa: E402
from vidstyle.recognition import defaults as D  # noqa: E402
from vidstyle.recognition.pipeline import more_performer_sets, more_view_ids  # noqa: E402
from vidstyle.recognition.splits import make_split  # noqa: E402

log = logging.getLogger("validate_training_views")
VALIDATION = ROOT / "pipelines" / "kickboxing" / "validation"


def by_points(dirs) -> dict[int, Path]:
    """Features directories keyed by the points per frame recorded in them."""
    out = {}
    for d in dirs:
        out[int(directory_params(d)["salient"]["n_points"])] = Path(d)
    return out


def seed_config(seed: int) -> dict:
    f = VALIDATION / ("recognition.json" if seed == 0 else f"recognition_seed{seed}.json")
    return dict(json.loads(f.read_text())["final_config"])


def run_seed(args, seed: int, feats: dict, cam_feats: dict, more_feats: dict, perf_feats: dict) -> dict:
    from vidstyle.recognition.recognizer import ActionRecognizer
    from vidstyle.recognition.vocabulary import Vocabulary

    cfg = seed_config(seed)
    pts = int(cfg["points"])
    checks = [("--features", feats), ("--camera-features", cam_feats), ("--more-views-features", more_feats)]
    if args.more_performers:
        checks.append(("--more-performers-features", perf_feats))
    for what, d in checks:
        if pts not in d:
            raise SystemExit(f"{what}: no directory with {pts} points per frame (seed {seed}'s recognizer)")
    ds, cam, more = read_dataset(args.dataset), read_dataset(args.camera_dataset), read_dataset(args.more_views)
    sp = make_split(ds, "unseen-performer", seed=seed)
    A, B = load_set(ds, feats[pts], sp.vocab, args.jobs), load_set(ds, feats[pts], sp.train, args.jobs)
    desc = np.concatenate([f.descriptors for f in A[0] if f.descriptors.shape[0]])
    voc = Vocabulary(n_words=cfg["words"], random_state=seed).fit(desc)
    xb_ids = more_view_ids(more, sp.train_performers, ds.classes, args.more_views)  # what train-recognizer adds
    XB = load_set(more, more_feats[pts], xb_ids, args.jobs)
    cam_ids = sorted(v.id for v in cam.videos if v.performer in set(sp.val_performers))
    candidates = [("none", int(cfg["max_frames_per_class"]), 0)] + [("more", int(c), 0) for c in args.caps]
    if args.more_performers:
        pd = read_dataset(args.more_performers)
        pa_ids, pb_ids = more_performer_sets(pd, {v.performer for v in ds.videos}, args.vocab_share, ds.classes,
                                             args.more_performers)
        PA, PB = load_set(pd, perf_feats[pts], pa_ids, args.jobs), load_set(pd, perf_feats[pts], pb_ids, args.jobs)
        desc_p = np.concatenate([desc] + [f.descriptors for f in PA[0] if f.descriptors.shape[0]])
        voc_p = Vocabulary(n_words=cfg["words"], random_state=seed).fit(desc_p)
        n_new = len({v.performer for v in pd.videos} - {v.performer for v in ds.videos})
        candidates += [("more", int(c), n_new) for c in args.performer_caps]
    rows = []
    for views, cap, performers in candidates:
        t0 = time.perf_counter()
        fb, lb = list(B[0]), [t.labels for t in B[1]]
        if views == "more":
            fb += list(XB[0])
            lb += [t.labels for t in XB[1]]
        if performers:
            fb += list(PB[0])
            lb += [t.labels for t in PB[1]]
        rec = ActionRecognizer(
            vocabulary=voc_p if performers else voc, grouping_threshold=cfg["grouping_threshold"], C=cfg["C"], max_frames_per_class=cap,
            coarse_context=cfg.get("coarse_context", 0), smoothing=cfg["smoothing"],
            emission_weight=cfg["emission_weight"], smoothing_window=cfg["smoothing_window"], n_jobs=args.jobs,
            random_state=seed).fit(fb, lb, classes=ds.classes or None)
        v = score_set(rec, ds, feats[pts], list(sp.val), args.jobs)
        c = score_set(rec, cam, cam_feats[pts], cam_ids, args.jobs)
        row = {"more_views": views, "max_frames_per_class": cap, "more_performers": performers,
               "vocab_share": float(args.vocab_share) if performers else None, "n_train_videos": len(fb),
               "validation": v, "validation_camera": c, "score": 0.5 * (v["smoothed"] + c["smoothed"]),
               "train_s": round(time.perf_counter() - t0, 1)}
        log.info("seed %d views %-4s cap %5d performers %2d: score %.4f V %.4f camera %.4f video %.3f", seed, views,
                 cap, performers, row["score"], v["smoothed"], c["smoothed"], v["video"])
        rows.append(row)
    best = max(rows, key=lambda r: r["score"])  # the first of equals: the seed's own recognizer wins ties
    return {"seed": seed, "config": cfg, "validation_performers": list(sp.val_performers),
            "train_performers": list(sp.train_performers), "more_views_videos": len(xb_ids),
            "camera_videos": len(cam_ids), "rows": rows,
            "chosen": {"more_views": best["more_views"], "max_frames_per_class": best["max_frames_per_class"],
                       "more_performers": best["more_performers"], "vocab_share": best["vocab_share"],
                       "score": best["score"]}}


def table(doc: dict) -> str:
    lines = ["| seed | more views | more performers | cap | V smoothed | camera smoothed | V video | score | chosen |",
             "|---|---|---:|---:|---:|---:|---:|---:|---|"]
    for s in doc["seeds"]:
        for r in s["rows"]:
            ch = all(r[k] == s["chosen"][k] for k in ("more_views", "max_frames_per_class", "more_performers"))
            lines.append(f"| {s['seed']} | {r['more_views']} | {r['more_performers']} | {r['max_frames_per_class']} | "
                         f"{100 * r['validation']['smoothed']:.1f} | {100 * r['validation_camera']['smoothed']:.1f} | "
                         f"{100 * r['validation']['video']:.1f} | {r['score']:.4f} | {'yes' if ch else ''} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dataset", type=Path, required=True)
    ap.add_argument("--features", type=Path, nargs="+", required=True)
    ap.add_argument("--camera-dataset", type=Path, required=True)
    ap.add_argument("--camera-features", type=Path, nargs="+", required=True)
    ap.add_argument("--more-views", type=Path, required=True)
    ap.add_argument("--more-views-features", type=Path, nargs="+", required=True)
    ap.add_argument("--caps", type=int, nargs="+", default=[1500, 3000, 5000])
    ap.add_argument("--more-performers", type=Path, default=None,
                    help="a dataset of other performers than --dataset's (vidstyle demo make-dataset --first-performer K): "
                         "rows with the more views and these performers too, a share in the vocabulary, the rest in set B")
    ap.add_argument("--more-performers-features", type=Path, nargs="+", default=[])
    ap.add_argument("--performer-caps", type=int, nargs="+", default=[3000, 5000])
    ap.add_argument("--vocab-share", type=float, default=D.MORE_PERFORMERS_VOCAB_SHARE)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", type=Path, default=VALIDATION / "training_views.json")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stderr)
    feats, cam_feats, more_feats = by_points(args.features), by_points(args.camera_features), by_points(args.more_views_features)
    perf_feats = by_points(args.more_performers_features)
    params_of = lambda d: json.loads((Path(d) / "dataset.json").read_text())["params"]  # noqa: E731
    doc = {"kind": KIND, "schema_version": 2, "command": "python " + " ".join(sys.argv),
           "more_views": {"dataset": str(args.more_views), "params": params_of(args.more_views)},
           "more_performers": None if args.more_performers is None else
           {"dataset": str(args.more_performers), "params": params_of(args.more_performers),
            "vocab_share": float(args.vocab_share)},
           "rule": "per seed, the highest score (mean of the smoothed frame accuracy on the validation performers' "
                   "own videos and on their validation-camera videos); ties: the seed's own recognizer",
           "seeds": [run_seed(args, s, feats, cam_feats, more_feats, perf_feats) for s in args.seeds]}
    write_validation(args.out, doc)
    print(table(doc))


if __name__ == "__main__":
    main()
