#!/usr/bin/env python
"""Validate training the 3D SIFT recognizer on more camera views of its training performers (issue 28).

The demo's training videos film every performer from three cameras (front, left, right at 10 degrees
elevation). A user's camera is anywhere. This script asks, on each split seed's validation performers only,
whether adding the same training takes filmed from other cameras (``vidstyle train-recognizer --more-views``:
set B's performers in a second dataset, ``vidstyle demo make-dataset --views 45,135,180,225,315 --elevation 25
--performances 0 --single-seconds 8``) helps, and with which cap on the SVM's training frames per class
(more videos of the same takes spread a fixed cap over more views). Per seed, the rows are:

- the seed's own validated recognizer (``validation/recognition.json`` for seed 0,
  ``validation/recognition_seedS.json`` otherwise; its ``final_config``), trained on sets A and B;
- the same with the more-views videos in set B, at each cap of ``--caps``.

Each row is scored like ``scripts/validate_recognition.py`` scores a candidate: the smoothed frame accuracy
on the validation performers' own videos (V), on their videos from the validation camera (60 and 120 degrees
at 30 degrees elevation before a held-out texture, cameras that neither training, the more views nor the
unseen-camera test use), and ``score``, the mean of the two. The rule: the highest score per seed; the
pipeline's default is seed 0's choice, each seed's results use its own. Nothing here reads a test video.

    python scripts/validate_training_views.py --dataset pipelines/kickboxing/out/dataset \\
        --features pipelines/kickboxing/out/features /tmp/f20 --camera-dataset /tmp/valcam \\
        --camera-features /tmp/valcam10 /tmp/valcam20 --more-views /tmp/xview \\
        --more-views-features /tmp/xview10 /tmp/xview20 --seeds 0 1 2 3 4

(features directories are told apart by the points per frame recorded in them; ``/tmp/valcam``: the
validation camera of ``scripts/validate_recognition.py``; ``/tmp/xview``: the make-dataset command above,
every performer, so that one dataset serves every seed). Writes ``validation/training_views.json``.
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

from vidstyle.evaluation.recognition import load_set, score_videos  # noqa: E402
from vidstyle.formats.dataset import read_dataset  # noqa: E402
from vidstyle.formats.features import directory_params  # noqa: E402
from vidstyle.formats.validation import TRAINING_VIEWS as KIND  # noqa: E402
from vidstyle.formats.validation import write_validation  # noqa: E402
from vidstyle.recognition.pipeline import more_view_ids  # noqa: E402
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


def _score(rec, ds, fdir: Path, ids: list[str], jobs: int) -> dict:
    feats, labels = load_set(ds, fdir, ids, jobs)
    by = ds.by_id()
    actions = [by[i].action if by[i].kind == "single" else None for i in ids]
    outs = [rec.smooth(*rec.frame_scores(H)) for H in rec.histograms_many(feats)]
    m = score_videos(rec.classes_, [t.labels for t in labels], outs, ids, actions)
    return {"raw": m["frame_accuracy"]["raw"], "smoothed": m["frame_accuracy"]["smoothed"],
            "video": m["video_accuracy"], "frames": m["n_test_frames"]}


def run_seed(args, seed: int, feats: dict, cam_feats: dict, more_feats: dict) -> dict:
    from vidstyle.recognition.recognizer import ActionRecognizer
    from vidstyle.recognition.vocabulary import Vocabulary

    cfg = seed_config(seed)
    pts = int(cfg["points"])
    for what, d in (("--features", feats), ("--camera-features", cam_feats), ("--more-views-features", more_feats)):
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
    rows = []
    for views, cap in [("none", int(cfg["max_frames_per_class"]))] + [("more", int(c)) for c in args.caps]:
        t0 = time.perf_counter()
        fb, lb = list(B[0]), [t.labels for t in B[1]]
        if views == "more":
            fb += list(XB[0])
            lb += [t.labels for t in XB[1]]
        rec = ActionRecognizer(
            vocabulary=voc, grouping_threshold=cfg["grouping_threshold"], C=cfg["C"], max_frames_per_class=cap,
            coarse_context=cfg.get("coarse_context", 0), smoothing=cfg["smoothing"],
            emission_weight=cfg["emission_weight"], smoothing_window=cfg["smoothing_window"], n_jobs=args.jobs,
            random_state=seed).fit(fb, lb, classes=ds.classes or None)
        v = _score(rec, ds, feats[pts], list(sp.val), args.jobs)
        c = _score(rec, cam, cam_feats[pts], cam_ids, args.jobs)
        row = {"more_views": views, "max_frames_per_class": cap, "n_train_videos": len(fb),
               "validation": v, "validation_camera": c, "score": 0.5 * (v["smoothed"] + c["smoothed"]),
               "train_s": round(time.perf_counter() - t0, 1)}
        log.info("seed %d views %-4s cap %5d: score %.4f V %.4f camera %.4f video %.3f", seed, views, cap,
                 row["score"], v["smoothed"], c["smoothed"], v["video"])
        rows.append(row)
    best = max(rows, key=lambda r: r["score"])  # the first of equals: the seed's own recognizer wins ties
    return {"seed": seed, "config": cfg, "validation_performers": list(sp.val_performers),
            "train_performers": list(sp.train_performers), "more_views_videos": len(xb_ids),
            "camera_videos": len(cam_ids), "rows": rows,
            "chosen": {"more_views": best["more_views"], "max_frames_per_class": best["max_frames_per_class"],
                       "score": best["score"]}}


def table(doc: dict) -> str:
    lines = ["| seed | more views | cap | V smoothed | camera smoothed | V video | score | chosen |",
             "|---|---|---:|---:|---:|---:|---:|---|"]
    for s in doc["seeds"]:
        for r in s["rows"]:
            ch = r["more_views"] == s["chosen"]["more_views"] and r["max_frames_per_class"] == s["chosen"]["max_frames_per_class"]
            lines.append(f"| {s['seed']} | {r['more_views']} | {r['max_frames_per_class']} | "
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
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", type=Path, default=VALIDATION / "training_views.json")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stderr)
    feats, cam_feats, more_feats = by_points(args.features), by_points(args.camera_features), by_points(args.more_views_features)
    doc = {"kind": KIND, "schema_version": 1, "command": "python " + " ".join(sys.argv),
           "more_views": {"dataset": str(args.more_views), "params": json.loads((Path(args.more_views) / "dataset.json").read_text())["params"]},
           "rule": "per seed, the highest score (mean of the smoothed frame accuracy on the validation performers' "
                   "own videos and on their validation-camera videos); ties: the seed's own recognizer",
           "seeds": [run_seed(args, s, feats, cam_feats, more_feats) for s in args.seeds]}
    write_validation(args.out, doc)
    print(table(doc))


if __name__ == "__main__":
    main()
