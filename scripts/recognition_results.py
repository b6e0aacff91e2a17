#!/usr/bin/env python
"""Write the committed recognition results (``pipelines/kickboxing/results/``) for some split seeds.

For every seed S this runs the pipeline's own commands with the recognizer values of
``pipelines/kickboxing/params.yaml`` (the values ``scripts/validate_recognition.py`` chose on the
validation performers of seed 0), or, with ``--validation DIR``, with the values that script chose on
seed S's own validation performers (``DIR`` holds one file per seed). The second is the clean protocol
for seeds other than 0: seed 0's validation performers are test performers of other seeds, so
params.yaml's values were tuned on part of their test set.

1. ``vidstyle vocabulary`` on set A and ``vidstyle train-recognizer`` on set B of the unseen-performer
   split of seed S;
2. ``vidstyle recognize`` of the split's test videos and ``vidstyle evaluate recognition --labels-dir``
   -> ``recognition_unseen_performer_seedS.json`` (+ PNGs);
3. with ``--camera-dataset``: the same model on the test performers re-filmed from the unseen cameras
   (``vidstyle demo make-dataset --unseen-camera``, a superset of the test performers) ->
   ``recognition_unseen_camera_seedS.json``;
4. with ``--left-right``: the unseen-view split (test view right) trained with and without mirror images
   -> ``recognition_unseen_view_right_{mirror,nomirror}_seedS.json``;
5. with ``--training-views validation/training_views.json`` (``scripts/validate_training_views.py``): steps 1-3
   with set B as each seed's validation chose it (the training performers also filmed from the cameras of
   ``--more-views``, ``train-recognizer --more-views``, and the chosen cap on training frames per class) ->
   ``recognition_moreviews_unseen_{performer,camera}_seedS.json`` (``--prefix``); where the validation also
   chose more performers (``--more-performers``, ``vocabulary / train-recognizer --more-performers``), they
   join the vocabulary and set B as it chose; with ``--real-walks D``, D's rendered real walks join set B too
   (``scripts/validate_real_walks.py``).

The test split is scored once per file, by ``evaluate recognition``; nothing here tunes anything. Work
files go to ``--work`` (models, labels). The dataset and features are the demo pipeline's (one dataset,
the seed only changes the performer split)::

    python scripts/recognition_results.py --dataset pipelines/kickboxing/out/dataset \\
        --features pipelines/kickboxing/out/features F40 --camera-dataset CAM --camera-features CAMF20 CAMF40 \\
        --validation pipelines/kickboxing/validation --seeds 0 1 2 3 4 --left-right 0 --work /tmp/results_work

``CAM``: ``vidstyle demo make-dataset --unseen-camera --single-seconds 8 --performance-seconds 60``, the
pipeline's camera stage without ``--split-seed``: every performer, so that each seed's test performers are
all there, in the same videos as the pipeline's. The features directories: ``vidstyle features --points N``
of the dataset's and of CAM's videos for every N a seed's validation chose (they are told apart by the
points recorded in their files).
"""

from __future__ import annotations

import argparse
import logging
import shutil
import subprocess
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vidstyle.formats.features import directory_params  # noqa: E402

log = logging.getLogger("recognition_results")


def _run(cmd: list[str]) -> None:
    log.info("$ %s", " ".join(cmd))
    subprocess.run(cmd, check=True)


def _train_args(rp: dict) -> list[str]:
    return ["--C", str(rp["C"]), "--max-frames-per-class", str(rp["max_frames_per_class"]),
            "--grouping-threshold", str(rp["grouping_threshold"]), "--window", str(rp["window"]),
            "--smoothing", rp["smoothing"], "--emission-weight", str(rp["emission_weight"]),
            "--coarse-context", str(rp.get("coarse_context", 0))]


def _test_ids(dataset: Path, split: str, seed: int, test_dataset: Path | None = None, test_view: str | None = None):
    from vidstyle.formats.dataset import read_dataset
    from vidstyle.recognition.splits import make_split

    tds = read_dataset(test_dataset) if test_dataset is not None else None
    return make_split(read_dataset(dataset), split, seed=seed, test_dataset=tds, test_view=test_view).test


def one(args, rp: dict, seed: int, split: str, name: str, mirror: bool = True, test_view: str | None = None,
        camera: bool = False, training_views: bool = False) -> None:
    vs = [str(args.vidstyle)] if args.vidstyle else [sys.executable, "-m", "vidstyle"]
    rp = config_for_seed(args, rp, seed)
    features = _pick(args.feature_dirs, rp, "--features")
    camera_features = _pick(args.camera_dirs, rp, "--camera-features") if camera else None
    more, vocab_more = [], []
    if training_views:  # the unseen-performer runs only: the validation chose for that split's set B
        rp, more, vocab_more = training_views_for_seed(args, rp, seed)
        name = f"{args.prefix}_{name}"
    w = args.work / f"{name}_seed{seed}"
    w.mkdir(parents=True, exist_ok=True)
    ds = str(args.dataset / "dataset.json")
    tv = ["--test-view", test_view] if test_view else []
    model = w / "recognizer.joblib"
    if not model.is_file():
        # one vocabulary per split, seed and size (the mirror and no-mirror runs share theirs)
        vocab = args.work / (f"vocab_{split}{'_' + test_view if test_view else ''}_{rp['words']}w_"
                             f"{rp['variant']}{rp['points']}{'_performers' if vocab_more else ''}_seed{seed}.npz")
        if not vocab.is_file():
            _run(vs + ["vocabulary", "--dataset", ds, "--features-dir", str(features), "--split", split, *tv,
                       "--words", str(rp["words"]), *vocab_more, "--seed", str(seed), "--out", str(vocab)])
        shutil.copyfile(vocab, w / "vocab.npz")
        _run(vs + ["train-recognizer", "--dataset", ds, "--features-dir", str(features), "--split", split, *tv,
                   "--vocab", str(w / "vocab.npz"), *_train_args(rp), *more, "--mirror" if mirror else "--no-mirror",
                   "--seed", str(seed), "--jobs", str(args.jobs), "--out", str(model)])
    outs = [(split, name, features, None)]
    if camera:
        cam_name = f"{args.prefix}_unseen_camera" if training_views else "unseen_camera"
        outs.append(("unseen-camera", cam_name, camera_features, args.camera_dataset / "dataset.json"))
    for sp, nm, fdir, tds in outs:
        ids = _test_ids(args.dataset, sp, seed, tds, test_view)
        labels = w / f"labels_{nm}"
        if labels.exists():
            shutil.rmtree(labels)
        labels.mkdir()
        _run(vs + ["recognize", *[str(Path(fdir) / f"{i}.npz") for i in ids], "--model", str(model),
                   "--out-dir", str(labels), "--jobs", str(args.jobs)])
        extra = ["--split", sp] + (["--test-dataset", str(tds)] if tds else []) + tv
        _run(vs + ["evaluate", "recognition", "--dataset", ds, "--labels-dir", str(labels), "--model", str(model),
                   *extra, "--seed", str(seed), "--out", str(args.results / f"recognition_{nm}_seed{seed}.json")])


def config_for_seed(args, rp: dict, seed: int) -> dict:
    """params.yaml's recognizer values, or with ``--validation`` those chosen on seed ``seed``'s validation set."""
    if args.validation is None:
        return dict(rp)
    import json

    from vidstyle.formats.validation import RECOGNITION, read_validation

    docs = []
    for f in sorted(Path(args.validation).glob("*.json")):
        if json.loads(f.read_text()).get("kind") != RECOGNITION:
            continue
        d = read_validation(f, RECOGNITION)  # header checked by the format's owner
        if d.get("seed") == seed:
            docs.append((f, d))
    if len(docs) != 1:
        raise SystemExit(f"{args.validation}: {len(docs)} recognition validation files of seed {seed} (need one)")
    f, d = docs[0]
    fc = d["final_config"]
    log.info("seed %d: the values chosen on validation performers %s (%s)", seed, d["split"]["val_performers"], f)
    return {**rp, **{k: fc[k] for k in ("variant", "points", "words", "grouping_threshold", "C", "max_frames_per_class",
                                        "coarse_context", "smoothing", "emission_weight")}}


def training_views_for_seed(args, rp: dict, seed: int) -> tuple[dict, list[str], list[str]]:
    """``scripts/validate_training_views.py``'s choice for seed ``seed``: the recognizer values with the chosen
    cap, the train-recognizer arguments of the more-views dataset (none when the validation kept three views)
    and of the more-performers dataset, and the vocabulary's arguments of the latter (none when it kept
    the split's performers alone)."""
    import json

    doc = json.loads(Path(args.training_views).read_text())
    rows = [s for s in doc["seeds"] if s["seed"] == seed]
    if len(rows) != 1:
        raise SystemExit(f"{args.training_views}: no choice for seed {seed}")
    ch = rows[0]["chosen"]
    rp = {**rp, "max_frames_per_class": ch["max_frames_per_class"]}
    train, vocab = [], []
    if ch["more_views"] == "more":
        fdir = _pick(_by_points(args.more_views_features or []), rp, "--more-views-features")
        train += ["--more-views", str(args.more_views), "--more-views-features", str(fdir)]
    if ch.get("more_performers"):
        if args.more_performers is None:
            raise SystemExit(f"{args.training_views}: seed {seed} chose more performers; give --more-performers")
        fdir = _pick(_by_points(args.more_performers_features or []), rp, "--more-performers-features")
        vocab = ["--more-performers", str(args.more_performers), "--more-performers-features", str(fdir),
                 "--more-performers-vocab-share", repr(float(ch["vocab_share"]))]
        train += vocab
    if args.real_walks is not None:  # set B only: the one walking subject is not in the vocabulary's share
        fdir = _pick(_by_points(args.real_walks_features or []), rp, "--real-walks-features")
        train += ["--more-performers", str(args.real_walks), "--more-performers-features", str(fdir)]
    return rp, train, vocab


def _by_points(dirs) -> dict:
    out = {}
    for fdir in dirs:
        fp = directory_params(fdir)
        out[(fp["variant"], int(fp["salient"]["n_points"]))] = Path(fdir)
    return out


def _pick(dirs: dict, rp: dict, option: str) -> Path:
    key = (rp["variant"], int(rp["points"]))
    if key not in dirs:
        raise SystemExit(f"{option}: no features of {key[0]} with {key[1]} points per frame among "
                         f"{sorted(dirs)}")
    return dirs[key]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", type=Path, required=True, help="the demo dataset directory")
    ap.add_argument("--features", type=Path, required=True, nargs="+",
                    help="its features directories (one per descriptor and points per frame a recognizer uses: "
                         "params.yaml's, or each --validation choice)")
    ap.add_argument("--camera-dataset", type=Path, default=None, help="unseen-camera dataset directory")
    ap.add_argument("--camera-features", type=Path, default=None, nargs="+", help="its features directories")
    ap.add_argument("--validation", type=Path, default=None,
                    help="directory of scripts/validate_recognition.py files: the recognizer of seed S uses the "
                         "values chosen on seed S's own validation performers (the file with that seed), so no "
                         "seed's test performers tuned its recognizer (default: params.yaml's values for every "
                         "seed)")
    ap.add_argument("--training-views", type=Path, default=None,
                    help="validation/training_views.json (scripts/validate_training_views.py): each seed's recognizer "
                         "trained as its validation chose (more camera views of the training performers or not, and "
                         "the cap), written as recognition_<--prefix>_<split>_seedS.json")
    ap.add_argument("--more-views", type=Path, default=None, help="with --training-views: the more-views dataset")
    ap.add_argument("--more-views-features", type=Path, default=None, nargs="+", help="its features directories")
    ap.add_argument("--more-performers", type=Path, default=None,
                    help="with --training-views: the more-performers dataset (vidstyle demo make-dataset --first-performer)")
    ap.add_argument("--more-performers-features", type=Path, default=None, nargs="+", help="its features directories")
    ap.add_argument("--real-walks", type=Path, default=None,
                    help="with --training-views: also this dataset of rendered real walks in set B (vidstyle demo "
                         "make-cmu-dataset --actions Step=walk --subjects 03; scripts/validate_real_walks.py)")
    ap.add_argument("--real-walks-features", type=Path, default=None, nargs="+", help="its features directories")
    ap.add_argument("--prefix", default="moreviews", help="with --training-views: the results files' name prefix")
    ap.add_argument("--seeds", type=int, nargs="*", default=[0], help="split seeds (unseen performer [+ camera])")
    ap.add_argument("--left-right", type=int, nargs="*", default=[],
                    help="seeds of the unseen-view split (test view right), with and without mirror training")
    ap.add_argument("--params", type=Path, default=ROOT / "pipelines" / "kickboxing" / "params.yaml")
    ap.add_argument("--results", type=Path, default=ROOT / "pipelines" / "kickboxing" / "results")
    ap.add_argument("--work", type=Path, required=True, help="models and labels go here")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--vidstyle", type=Path, default=None, help="the vidstyle executable (default: python -m vidstyle)")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    params = yaml.safe_load(args.params.read_text())
    rp = {**params["recognition"], "variant": params["features"]["variant"], "points": int(params["features"]["points"])}
    # features directories by the (descriptor, points per frame) recorded in their files
    args.feature_dirs = _by_points(args.features)
    args.camera_dirs = _by_points(args.camera_features or [])
    args.results.mkdir(parents=True, exist_ok=True)
    for seed in args.seeds:
        one(args, rp, seed, "unseen-performer", "unseen_performer", camera=args.camera_dataset is not None,
            training_views=args.training_views is not None)
    for seed in args.left_right:
        for mirror in (True, False):
            one(args, rp, seed, "unseen-view", f"unseen_view_right_{'mirror' if mirror else 'nomirror'}",
                mirror=mirror, test_view="right")


if __name__ == "__main__":
    from vidstyle.errors import VidstyleError

    try:
        main()
    except VidstyleError as e:  # bad input (e.g. an unreadable features directory): one line, not a traceback
        raise SystemExit(str(e)) from None
