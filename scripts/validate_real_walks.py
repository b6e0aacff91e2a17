#!/usr/bin/env python
"""Validate training the 3D SIFT recognizer also on rendered real walks (issue 28: real motion).

The demo has no walking, and both 3D SIFT recognizers the pipeline has trained (S: three cameras; S++: more
views and more performers) read almost every frame of a real walk as a strike. The pose recognizer learned
real walking from CMU subject 03's walks labelled ``Step`` (``pipelines/kickboxing/cmu_walks_labels.csv``).
3D SIFT learns from video, so the same walks are rendered into a dataset of the demo's layout, every window
labelled ``Step`` (subject 03 is in neither real-motion list)::

    vidstyle demo make-cmu-dataset --cmu ../shared/data/mocap/cmu --out /tmp/walks --actions Step=walk \\
        --subjects 03 --max-per-subject 0
    vidstyle features /tmp/walks/videos/*.mp4 --out /tmp/walks_f --variant scovanner2007 --points 10

and join the classifier's set B as one more performer (``vidstyle train-recognizer ... --more-performers
/tmp/walks --more-performers-features /tmp/walks_f``, beside the pipeline's own ``--more-performers``;
the one new performer is not in the vocabulary's share, so the pipeline's vocabulary serves both).

This script scores recognizers given as ``--model NAME=FILE`` on the split seed's validation sets only:
the validation performers' own videos (V), their videos from the validation camera (60 and 120 degrees
at 30 degrees elevation before a held-out texture: ``--camera-dataset``, e.g. ``vidstyle demo make-dataset
--out /tmp/valcam --views 60,120 --elevation 30 --background texture:coins --performances 1
--performance-views 60,120 --single-seconds 8 --performance-seconds 60 --split-seed 0 --split-sets V``),
and the real-motion validation clips (``pipelines/kickboxing/realmotion_val.csv``: CMU subject 07's walks
at the validation camera of ``vidstyle evaluate real-motion``, scored by action family). ``score`` is the
mean of the three (the rule the pose recognizer's validation used: the demo's validation and real motion
weigh alike); ``score_demo`` the mean of the first two, the rule of ``validate_training_views.py``. Each
model's training (its split header: sets, more views, more performers) is recorded. Nothing here reads a
test video or clip::

    python scripts/validate_real_walks.py --dataset pipelines/kickboxing/out/dataset \\
        --features pipelines/kickboxing/out/features --camera-dataset /tmp/valcam --camera-features /tmp/valcam10 \\
        --model S++=pipelines/kickboxing/out/models/recognizer.joblib --model S++walks=/tmp/w_rec.joblib --seed 0

Writes ``validation/real_walks_seed<seed>.json`` (kind ``vidstyle.validation.real_walks``).
"""

from __future__ import annotations

import argparse
import logging
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vidstyle.evaluation.realmotion import VAL_CAMERAS, Recognizers, evaluate_real_motion, read_clip_list  # noqa: E402
from vidstyle.evaluation.recognition import score_set  # noqa: E402
from vidstyle.formats.dataset import read_dataset  # noqa: E402
from vidstyle.formats.validation import REAL_WALKS as KIND  # noqa: E402
from vidstyle.formats.validation import validation_header, write_validation  # noqa: E402
from vidstyle.recognition.recognizer import load_model  # noqa: E402
from vidstyle.recognition.splits import make_split  # noqa: E402

log = logging.getLogger("validate_real_walks")
PIPELINE = ROOT / "pipelines" / "kickboxing"


def table(doc: dict) -> str:
    lines = ["| model | V smoothed | camera smoothed | real walks, right family | score_demo | score | chosen |",
             "|---|---:|---:|---:|---:|---:|---|"]
    for r in doc["rows"]:
        lines.append(f"| {r['name']} | {100 * r['validation']['smoothed']:.1f} | "
                     f"{100 * r['validation_camera']['smoothed']:.1f} | {100 * r['real_motion']:.1f} | "
                     f"{r['score_demo']:.4f} | {r['score']:.4f} | {'yes' if r['name'] == doc['chosen'] else ''} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dataset", type=Path, required=True)
    ap.add_argument("--features", type=Path, required=True)
    ap.add_argument("--camera-dataset", type=Path, required=True)
    ap.add_argument("--camera-features", type=Path, required=True)
    ap.add_argument("--clips", type=Path, default=PIPELINE / "realmotion_val.csv")
    ap.add_argument("--model", action="append", required=True, metavar="NAME=FILE")
    ap.add_argument("--seed", type=int, default=0, help="the split seed the models were trained on")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stderr)
    ds, cam = read_dataset(args.dataset), read_dataset(args.camera_dataset)
    sp = make_split(ds, "unseen-performer", seed=args.seed)
    cam_ids = sorted(v.id for v in cam.videos if v.performer in set(sp.val_performers))
    if not cam_ids:
        raise SystemExit(f"{args.camera_dataset}: no video of the validation performers {list(sp.val_performers)}")
    clips = read_clip_list(args.clips)
    rows = []
    with tempfile.TemporaryDirectory(prefix="vidstyle-realwalks-") as work:
        for item in args.model:
            name, _, path = item.partition("=")
            rec, header = load_model(path)
            split = header.get("split") or {}
            if split.get("seed", args.seed) != args.seed:
                raise SystemExit(f"{path}: trained on split seed {split.get('seed')}, not {args.seed}")
            v = score_set(rec, ds, args.features, list(sp.val), args.jobs)
            c = score_set(rec, cam, args.camera_features, cam_ids, args.jobs)
            rm = evaluate_real_motion(clips, Recognizers(sift=rec), VAL_CAMERAS, seed=args.seed,
                                      work_dir=Path(work) / name)
            real = rm["overall"]["sift"]["family_accuracy"]
            row = {"name": name, "model": path, "more_performers": split.get("more_performers"),
                   "more_views": split.get("more_views"), "validation": v, "validation_camera": c,
                   "real_motion": real, "real_motion_frames": rm["overall"]["sift"].get("frames"),
                   "score_demo": 0.5 * (v["smoothed"] + c["smoothed"]),
                   "score": (v["smoothed"] + c["smoothed"] + real) / 3.0}
            log.info("%s: score %.4f (V %.4f, camera %.4f, real walks %.4f)", name, row["score"], v["smoothed"],
                     c["smoothed"], real)
            rows.append(row)
    best = max(rows, key=lambda r: r["score"])  # the first of equals: the first model given wins ties
    doc = {**validation_header(KIND), "command": "python " + " ".join(sys.argv), "seed": args.seed,
           "validation_performers": list(sp.val_performers), "camera_videos": len(cam_ids),
           "clips": [str(c.bvh.name) for c in clips], "cameras": [c.to_dict() for c in VAL_CAMERAS],
           "rule": "the highest score: mean of the smoothed frame accuracy on the validation performers' own videos, "
                   "on their validation-camera videos, and the right-family share of the real-motion validation "
                   "clips' frames; ties: the first model given",
           "rows": rows, "chosen": best["name"]}
    write_validation(args.out or PIPELINE / "validation" / f"real_walks_seed{args.seed}.json", doc)
    print(table(doc))


if __name__ == "__main__":
    main()
