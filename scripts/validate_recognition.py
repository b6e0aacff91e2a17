#!/usr/bin/env python
"""Choose the recognizer's tuned values on the *validation* performers only (issue 12).

Every candidate trains the vocabulary on set A and the recognizer on set B of the seeded split
(:func:`vidstyle.recognition.splits.make_split`) and is scored on set V; the test performers (set T) are
never loaded. With ``--camera-dataset`` (the *validation camera*: V's performers filmed from cameras, an
elevation and a background that neither the training videos nor the unseen-camera test use) every
candidate is also scored on V's videos there, and the score is the mean of the two smoothed frame
accuracies (the goals ask for unseen performers and an unseen camera both). Factors (``ALL_FACTORS``):

- ``variant``: the descriptor (one features directory per variant: ``--features scovanner2007=DIR
  --features thesis=DIR``; the variant's own features of sets A, B and V are enough),
- ``words``: the vocabulary size,
- ``grouping_threshold``: the word-grouping correlation threshold,
- ``C``: the SVM cost,
- ``max_frames_per_class``: the SVM training frames per class (the cap),
- ``coarse_context``: the multi-scale temporal context (0 = the thesis' single 5-frame context),
- ``points``: salient points per frame (the thesis' 10); every other count needs its own features of the
  starting variant (``--points-features 20=DIR``, ``vidstyle features --points 20``),

and the smoother (``SMOOTHERS``: the thesis' window vote, Viterbi and the explicit-duration Viterbi with
several emission weights), which needs no retraining: every trained candidate is scored with each.

Search: (1) the smoother is chosen on the starting model; (2) the features factor (``points``) one value
at a time from the starting point (``START``), scored with that smoother; (3) the model factors one at a
time from the features winner; for each factor the best value wins (score: smoothed frame accuracy on V;
ties go to the video accuracy, then to the incumbent); (4) when the model factors' winners differ from the
features winner, their combination is trained and scored on V, and it is the final configuration only if
it scores at least as well as the features winner (otherwise its values stay). The default grid tries one
other value per model factor (``FACTORS``; ``--full`` more, ``--quick`` two factors for a smoke run). Candidates train in parallel (``--workers``); with
``--cache-dir`` every trained candidate is kept, so a rerun (another smoother, another factor) trains only
what is new.

Output (``--out``, default ``pipelines/kickboxing/validation/recognition.json``; the library defaults,
the CLI defaults and ``pipelines/kickboxing/params.yaml`` cite it), ``kind``
``vidstyle.validation.recognition``, ``schema_version`` 2: ``command``, ``dataset``, ``dataset_seed``,
``seed``, ``features`` (variant -> directory), ``split`` (performers of A, B, V; the test performers,
not used), ``score``, ``search``, ``start``, ``start_model``, ``factors`` (factor -> values tried besides
the start), ``factors_not_searched``, ``smoothers`` ([method, emission weight]), ``chosen`` (per factor
and ``smoother``: ``value``, ``validation_frame_accuracy_smoothed``, ``validation_video_accuracy``,
``candidates`` value -> V smoothed accuracy, and ``value_if_alone`` when the combination lost),
``final_config``, ``final_validation`` (raw / smoothed / video accuracy, per-class smoothed recall, V
frames) and ``rows`` (every candidate x smoother: ``step``, ``config``, the V scores, ``train_s``).
``points_features`` (points -> directory) names the features of the points candidates; with a validation
camera, ``camera_dataset`` and ``camera_features`` name it, every row adds ``camera_frame_accuracy_raw``,
``camera_frame_accuracy_smoothed``, ``camera_video_accuracy`` and ``n_camera_frames``, and ``score`` (every
row, and ``validation_score`` in ``chosen``) is what the search ranks by. Schema 1
(before the duration smoother and the coarse context) had the same fields without ``smoothers``.

Usage (the demo pipeline's dataset; its features have the starting 10 points per frame, the other counts
and the thesis descriptor are extracted for the search)::

    V=pipelines/kickboxing/out/dataset/videos
    vidstyle features $V/*.mp4 --points 20 --out /tmp/f20     # and --points 30, --points 40
    vidstyle features $V/*.mp4 --points 20 --variant thesis --out /tmp/thesis20
    python scripts/validate_recognition.py --dataset pipelines/kickboxing/out/dataset \\
        --features scovanner2007=pipelines/kickboxing/out/features --features thesis=/tmp/thesis20 \\
        --points-features 20=/tmp/f20 --points-features 30=/tmp/f30 --points-features 40=/tmp/f40 \\
        --camera-dataset /tmp/valcam \\
        --camera-features /tmp/valcam10 /tmp/valcam20 /tmp/valcam30 /tmp/valcam40 /tmp/valcam_thesis20 \\
        --cache-dir /tmp/vcache --seed 0    # and --seed S --out .../recognition_seedS.json for S = 1..4

The validation camera (every performer, so that one dataset serves every seed's V; its features
directories are told apart by the variant and points recorded in them)::

    vidstyle demo make-dataset --out /tmp/valcam --views 60,120 --elevation 30 --background texture:coins \\
        --performances 1 --performance-views 60,120 --single-seconds 8 --performance-seconds 60
"""

from __future__ import annotations

import argparse
import hashlib
import json
import logging
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vidstyle.evaluation.recognition import load_set, score_videos  # noqa: E402
from vidstyle.formats.dataset import read_dataset as load_dataset  # noqa: E402
from vidstyle.formats.features import directory_params  # noqa: E402
from vidstyle.formats.validation import write_validation  # noqa: E402
from vidstyle.recognition.splits import make_split  # noqa: E402

log = logging.getLogger("validate_recognition")
DEFAULT_OUT = Path(__file__).resolve().parents[1] / "pipelines" / "kickboxing" / "validation" / "recognition.json"

# the starting point (the values an earlier run of this script chose at 10 points per frame: the duration
# smoother, emission weight 1, cap 1500) and the other values tried per factor
START = {"variant": "scovanner2007", "points": 10, "words": 1000, "grouping_threshold": 0.8, "C": 100.0,
         "max_frames_per_class": 1500, "coarse_context": 0, "smoothing": "duration", "emission_weight": 1.0,
         "smoothing_window": 6}
# the default grid: one other value per factor (what two shared cores allow in an hour: every candidate
# is a full SVM training), two for the cap (one on each side of the start); the points come from the
# --points-features directories given; --full searches more values per factor
FACTORS = {"words": [500], "grouping_threshold": [0.7], "C": [30.0], "max_frames_per_class": [3000, 800],
           "coarse_context": [8]}
QUICK = {"words": [500], "C": [30.0]}
FULL = {"words": [500, 1500], "grouping_threshold": [0.7, 0.9], "C": [30.0, 300.0],
        "max_frames_per_class": [800, 3000, 5000], "coarse_context": [5, 8, 12]}
# every factor the search knows (the descriptor variant's values are the --features directories given)
ALL_FACTORS = ("variant", "points", "words", "grouping_threshold", "C", "max_frames_per_class", "coarse_context")
SMOOTHERS = [("viterbi", 1.0), ("vote", None), ("viterbi", 2.0), ("viterbi", 3.0), ("viterbi", 5.0),
             ("duration", 1.0), ("duration", 2.0), ("duration", 3.0)]
# factors that change the features files (searched first: the model factors are searched on their winner)
FEATURE_FACTORS = ("points",)
MODEL_KEYS = ("variant", "points", "words", "grouping_threshold", "C", "max_frames_per_class", "coarse_context",
              "smoothing_window")


class Search:
    """Trains candidates on sets A/B of ``split`` and scores them on V. With ``cache_dir``, every trained
    candidate (the model and its raw V outputs) is kept there under a key of its training values, so a
    rerun (e.g. with another smoother) retrains nothing it has already trained."""

    def __init__(self, ds, features: dict[str, str], split, seed: int, jobs: int, cache_dir: Path | None = None,
                 points_features: dict[int, str] | None = None, variant_points: dict[str, int] | None = None,
                 camera_dataset=None, camera_features: dict | None = None):
        self.ds, self.features, self.split, self.seed, self.jobs = ds, features, split, seed, jobs
        # the validation camera: the validation performers filmed from cameras, an elevation and a background
        # that neither training nor the test cameras use; features by (variant, points)
        self.camera_dataset, self.camera_features = camera_dataset, dict(camera_features or {})
        self._camera_sets: dict = {}
        self.points_features = {int(k): v for k, v in (points_features or {}).items()}
        self.variant_points = dict(variant_points or {})  # points per frame of each --features directory
        self.cache_dir = None if cache_dir is None else Path(cache_dir)
        self._sets: dict = {}
        self._vocab: dict = {}
        self._memo: dict = {}
        self.start_model, self.start_cfg, self.start_key = None, None, None
        self.rows: list[dict] = []
        by_id = ds.by_id()
        self.actions = [by_id[i].action if by_id[i].kind == "single" else None for i in split.val]

    def features_dir(self, variant, points=None) -> str:
        """Features of ``variant`` with ``points`` per frame (``--points-features`` for the starting variant's
        other counts; the ``--features`` directory of the variant for its own count)."""
        if variant == START["variant"] and points in self.points_features:
            return self.points_features[points]
        if points is None or points == self.variant_points.get(variant, START["points"]):
            return self.features[variant]
        raise SystemExit(f"no features of {variant} with {points} points per frame were given")

    def sets(self, variant, points=None):
        key = self.features_dir(variant, points)
        if key not in self._sets:
            fdir = Path(self.features_dir(variant, points))
            self._sets[key] = {k: load_set(self.ds, fdir, ids, self.jobs)
                               for k, ids in (("A", self.split.vocab), ("B", self.split.train), ("V", self.split.val))}
        return self._sets[key]

    def vocabulary(self, variant, words, points=None):
        from vidstyle.recognition.vocabulary import Vocabulary

        key = (self.features_dir(variant, points), words)
        if key not in self._vocab and self.start_model is not None and (variant, words) == self.start_key \
                and key[0] == self.features[variant]:
            self._vocab[key] = self.start_model.vocabulary  # the same fit on the same set A
        if key not in self._vocab:
            feats_a = self.sets(variant, points)["A"][0]
            desc = np.concatenate([f.descriptors for f in feats_a if f.descriptors.shape[0]])
            self._vocab[key] = Vocabulary(n_words=words, random_state=self.seed).fit(desc)
        return self._vocab[key]

    def _cache_file(self, cfg: dict) -> Path | None:
        if self.cache_dir is None:
            return None
        ident = json.dumps({"dataset": str(self.ds.root) if hasattr(self.ds, "root") else None,
                            "features": str(Path(self.features_dir(cfg["variant"], cfg.get("points"))).resolve()),
                            "seed": self.seed, "val": sorted(self.split.val), "train": sorted(self.split.train),
                            **{k: cfg.get(k, START[k]) for k in MODEL_KEYS}}, sort_keys=True)
        return self.cache_dir / (hashlib.sha256(ident.encode()).hexdigest()[:20] + ".joblib")

    def trained(self, cfg: dict):
        """(model, raw V outputs, training seconds) of the candidate ``cfg`` (memo, cache, start model or a fit)."""
        import joblib

        from vidstyle.recognition.recognizer import ActionRecognizer

        key = tuple((k, cfg.get(k, START[k])) for k in MODEL_KEYS)
        if key in self._memo:
            return self._memo[key]
        cache = self._cache_file(cfg)
        if cache is not None and cache.is_file():
            d = joblib.load(cache)
            self._memo[key] = (d["model"], d["raw"], d["train_s"])
            return self._memo[key]
        t0 = time.perf_counter()
        pts = cfg.get("points")
        feats_v, _ = self.sets(cfg["variant"], pts)["V"]
        same_as_start = self.start_model is not None and all(cfg.get(k, START[k]) == self.start_cfg.get(k, START[k])
                                                              for k in MODEL_KEYS)
        if same_as_start:
            rec = self.start_model  # trained by `vidstyle train-recognizer` on the same A/B with these values
        else:
            voc = self.vocabulary(cfg["variant"], cfg["words"], pts)
            feats_b, labels_b = self.sets(cfg["variant"], pts)["B"]
            rec = ActionRecognizer(
                vocabulary=voc, grouping_threshold=cfg["grouping_threshold"], C=cfg["C"],
                max_frames_per_class=cfg["max_frames_per_class"], coarse_context=cfg.get("coarse_context", 0),
                smoothing=cfg["smoothing"], emission_weight=cfg["emission_weight"],
                smoothing_window=cfg["smoothing_window"], n_jobs=self.jobs, random_state=self.seed,
            ).fit(feats_b, [t.labels for t in labels_b], classes=self.ds.classes or None)
        raw = [rec.frame_scores(H) for H in rec.histograms_many(feats_v)]
        train_s = time.perf_counter() - t0
        self._memo[key] = (rec, raw, train_s)
        if cache is not None:
            cache.parent.mkdir(parents=True, exist_ok=True)
            tmp = cache.with_suffix(".tmp")
            joblib.dump({"model": rec, "raw": raw, "train_s": train_s, "config": dict(key)}, tmp)
            tmp.replace(cache)
        return self._memo[key]

    def camera_set(self, variant, points):
        """(features, labels, ids, actions) of the validation performers' validation-camera videos."""
        key = (variant, int(points if points is not None else START["points"]))
        if key not in self._camera_sets:
            if key not in self.camera_features:
                raise SystemExit(f"--camera-features: no features of {key[0]} with {key[1]} points per frame")
            val = set(self.split.val_performers)
            videos = [v for v in sorted(self.camera_dataset.videos, key=lambda v: v.id) if v.performer in val]
            missing = val - {v.performer for v in videos}
            if missing:
                raise SystemExit(f"--camera-dataset: no video of the validation performers {sorted(missing)}")
            ids = [v.id for v in videos]
            feats, labels = load_set(self.camera_dataset, Path(self.camera_features[key]), ids, self.jobs)
            self._camera_sets[key] = (feats, labels, ids, [v.action if v.kind == "single" else None for v in videos])
        return self._camera_sets[key]

    def run(self, step: str, cfg: dict, smoothers=None) -> list[dict]:
        """Train on A/B with ``cfg`` and score V (and V's validation-camera videos) once per smoother;
        one row per smoother."""
        rec, raw, train_s = self.trained(cfg)
        cam = None
        if self.camera_dataset is not None:
            feats_c, labels_c, ids_c, actions_c = self.camera_set(cfg["variant"], cfg.get("points"))
            cam = ([rec.frame_scores(H) for H in rec.histograms_many(feats_c)],
                   labels_c, ids_c, actions_c)
        labels_v = self.sets(cfg["variant"], cfg.get("points"))["V"][1]
        if not hasattr(rec, "durations_") and hasattr(rec, "fit_durations"):  # trained before the duration smoother
            rec.fit_durations([t.labels for t in self.sets(cfg["variant"], cfg.get("points"))["B"][1]])
        rows = []
        for smoothing, weight in smoothers or [(cfg["smoothing"], cfg["emission_weight"])]:
            rec.smoothing = smoothing
            if weight is not None:
                rec.emission_weight = weight
            outs = [rec.smooth(*r) for r in raw]
            m = score_videos(rec.classes_, [t.labels for t in labels_v], outs, self.split.val, self.actions)
            c = {**cfg, "smoothing": smoothing, "emission_weight": weight if weight is not None else cfg["emission_weight"]}
            row = {"step": step, "config": c, "frame_accuracy_raw": m["frame_accuracy"]["raw"],
                   "frame_accuracy_smoothed": m["frame_accuracy"]["smoothed"], "video_accuracy": m["video_accuracy"],
                   "per_class_recall_smoothed": {k: v["recall_smoothed"] for k, v in m["per_class"].items()},
                   "n_val_frames": m["n_test_frames"], "train_s": train_s}
            if cam is not None:
                mc = score_videos(rec.classes_, [t.labels for t in cam[1]], [rec.smooth(*r) for r in cam[0]],
                                  cam[2], cam[3])
                row.update({"camera_frame_accuracy_raw": mc["frame_accuracy"]["raw"],
                            "camera_frame_accuracy_smoothed": mc["frame_accuracy"]["smoothed"],
                            "camera_video_accuracy": mc["video_accuracy"], "n_camera_frames": mc["n_test_frames"]})
            row["score"] = _score(row)
            rows.append(row)
            self.rows.append(row)
            log.info("%-20s %s: score %.4f smoothed %.4f raw %.4f video %s camera %s (%.0f s)", step, _short(c),
                     row["score"], row["frame_accuracy_smoothed"], row["frame_accuracy_raw"], row["video_accuracy"],
                     row.get("camera_frame_accuracy_smoothed"), train_s)
        return rows


def _short(c: dict) -> str:
    ctx = f" ctx2+{c['coarse_context']}" if c.get("coarse_context") else ""
    return (f"{c['variant']} {c.get('points', 10)}pt {c['words']}w g{c['grouping_threshold']:g} C{c['C']:g} "
            f"cap{c['max_frames_per_class']}{ctx} {_smoother(c)}")


def _score(row) -> float:
    """The validation score: V's smoothed frame accuracy, or with a validation camera the mean of it and
    the smoothed frame accuracy on V's validation-camera videos (the goals ask for both)."""
    if row.get("camera_frame_accuracy_smoothed") is None:
        return row["frame_accuracy_smoothed"]
    return 0.5 * (row["frame_accuracy_smoothed"] + row["camera_frame_accuracy_smoothed"])


def _key(row):
    return (row.get("score", row["frame_accuracy_smoothed"]), row["video_accuracy"] or 0.0)


def best(rows):
    """Highest score; ties keep the earliest row (the incumbent comes first)."""
    top = rows[0]
    for r in rows[1:]:
        if _key(r) > _key(top):
            top = r
    return top


def _smoothers():
    from vidstyle.recognition.smoothing import METHODS

    return [(m, w) for m, w in SMOOTHERS if m in METHODS]


def _candidate(args) -> list[dict]:
    """One trained candidate (a worker process): rows for every smoother."""
    (dataset, features, points_features, variant_points, camera, seed, cache_dir, step, cfg, start_model,
     start_cfg) = args
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    ds = load_dataset(dataset)
    split = make_split(ds, "unseen-performer", seed=seed)
    cam_ds, cam_features = (load_dataset(camera[0]), camera[1]) if camera else (None, None)
    search = Search(ds, features, split, seed, 1, cache_dir, points_features, variant_points, cam_ds, cam_features)
    if start_model is not None:
        from vidstyle.recognition.recognizer import load_model

        search.start_model = load_model(start_model)[0]
        search.start_cfg, search.start_key = start_cfg, (start_cfg["variant"], start_cfg["words"])
    return search.run(step, cfg, smoothers=_smoothers())


def features_points(fdir: str | Path) -> int:
    """Salient points per frame that the features files of ``fdir`` were extracted with (their params)."""
    return int(directory_params(fdir)["salient"]["n_points"])


def check_start_model(path: Path, start: dict, split, seed: int) -> None:
    """A ``--start-model`` must be the starting configuration trained on this split's set B."""
    from vidstyle.recognition.recognizer import read_header

    h = read_header(path)
    p, sp = h.get("params", {}), h.get("split") or {}
    want = {"C": start["C"], "max_frames_per_class": start["max_frames_per_class"],
            "grouping_threshold": start["grouping_threshold"], "smoothing_window": start["smoothing_window"],
            "coarse_context": start["coarse_context"]}
    got = {k: p.get(k, 0 if k == "coarse_context" else None) for k in want}
    problems = [f"{k} {got[k]} != {v}" for k, v in want.items() if got[k] != v]
    if h.get("vocabulary", {}).get("n_words") != start["words"]:
        problems.append(f"words {h.get('vocabulary', {}).get('n_words')} != {start['words']}")
    if (h.get("features_params") or {}).get("variant", start["variant"]) != start["variant"]:
        problems.append("descriptor variant differs")
    n_points = ((h.get("features_params") or {}).get("salient") or {}).get("n_points", start["points"])
    if n_points != start["points"]:
        problems.append(f"points {n_points} != {start['points']}")
    if sp.get("kind") != "unseen-performer" or sp.get("seed") != seed or sorted(sp.get("val") or []) != sorted(split.val):
        problems.append("trained on another split")
    if h.get("seed") != seed:
        problems.append(f"seed {h.get('seed')} != {seed}")
    if problems:
        raise SystemExit(f"{path}: not the starting configuration on this split: {'; '.join(problems)}")


def _at(rows, smoother):
    return [r for r in rows if (r["config"]["smoothing"], r["config"]["emission_weight"]) == smoother][0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", required=True, help="dataset.json or its directory")
    ap.add_argument("--features", action="append", default=[], metavar="VARIANT=DIR", required=True,
                    help="features directory of each descriptor variant to compare (the first is the starting one "
                         "unless scovanner2007 is given)")
    ap.add_argument("--points-features", action="append", default=[], metavar="N=DIR",
                    help="features of the starting variant with N salient points per frame (`vidstyle features "
                         "--points N`): the candidates of the points factor (the --features directory has "
                         f"{START['points']})")
    ap.add_argument("--camera-dataset", type=Path, default=None,
                    help="the validation camera: a dataset of (at least) the validation performers filmed from "
                         "cameras, an elevation and a background that neither the training videos nor the test "
                         "cameras use; with it the score is the mean of V's smoothed frame accuracy and that on "
                         "these videos")
    ap.add_argument("--camera-features", type=Path, nargs="+", default=[],
                    help="its features directories, one per descriptor and points per frame a candidate uses")
    ap.add_argument("--seed", type=int, default=0, help="split / vocabulary / sampling seed")
    ap.add_argument("--workers", type=int, default=2, help="candidates trained in parallel")
    grid = ap.add_mutually_exclusive_group()
    grid.add_argument("--full", action="store_true", help="more values per factor")
    grid.add_argument("--quick", action="store_true", help="one value per factor (a smoke run)")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--cache-dir", type=Path, default=None,
                    help="keep every trained candidate here; a rerun retrains only what is not there")
    ap.add_argument("--start-model", type=Path, default=None,
                    help="a `vidstyle train-recognizer --dataset` model of the starting values on this split: "
                         "used as the starting candidate (and its vocabulary by the candidates that share it)")
    ap.add_argument("--only", action="append", default=[],
                    help="train only the candidates of these factors (" + ", ".join(ALL_FACTORS) + "); the others "
                         "keep the starting value untested and are listed under factors_not_searched")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    from joblib import Parallel, delayed

    features = dict(f.split("=", 1) for f in args.features)
    points_features = {int(k): v for k, v in (f.split("=", 1) for f in args.points_features)}
    variant_points = {v: features_points(d) for v, d in features.items()}
    if variant_points.get(START["variant"], START["points"]) != START["points"]:
        raise SystemExit(f"--features {START['variant']}=DIR: features with {variant_points[START['variant']]} points "
                         f"per frame; the search starts from {START['points']}")
    for n, fdir in sorted(points_features.items()):
        if features_points(fdir) != n:
            raise SystemExit(f"{fdir}: features with {features_points(fdir)} points per frame, given as {n}")
    ds = load_dataset(args.dataset)
    split = make_split(ds, "unseen-performer", seed=args.seed)
    log.info("validation performers %s (test performers %s are not loaded)", split.val_performers, split.test_performers)
    start = dict(START)
    if start["variant"] not in features:
        start["variant"] = next(iter(features))
    grid_values = FULL if args.full else QUICK if args.quick else FACTORS
    # the descriptor variant last: its candidates need other features files (often computed meanwhile)
    factors = {"points": sorted(points_features), **grid_values, "variant": [v for v in features if v != start["variant"]]}
    factors = {k: v for k, v in factors.items() if v}
    if args.only:
        factors = {k: v for k, v in factors.items() if k in args.only}
    if args.start_model is not None:
        check_start_model(args.start_model, start, split, args.seed)
    camera = None
    if args.camera_dataset is not None:
        cam_dirs = {}
        for d in args.camera_features:
            fp = directory_params(d)
            cam_dirs[(fp["variant"], int(fp["salient"]["n_points"]))] = str(d)
        camera = (str(args.camera_dataset), cam_dirs)
    ctx = (str(args.dataset), features, points_features, variant_points, camera, args.seed, args.cache_dir)
    sm = (None if args.start_model is None else str(args.start_model), start)

    def train(jobs):
        return Parallel(n_jobs=args.workers, backend="loky")(delayed(_candidate)((*ctx, step, c, *sm)) for step, c in jobs)

    # stage 1: the starting model and the features factors (points: other features files)
    feature_factors = {k: v for k, v in factors.items() if k in FEATURE_FACTORS}
    model_factors = {k: v for k, v in factors.items() if k not in FEATURE_FACTORS}
    jobs = [("start", start)] + [(key, {**start, key: v}) for key, vals in feature_factors.items() for v in vals]
    results = train(jobs)
    rows = [r for rs in results for r in rs]
    base = results[0]
    # the smoother, on the starting model (no retraining); then each features factor under that smoother
    win = best([_at(base, (start["smoothing"], start["emission_weight"]))] + base)
    cfg = dict(start)
    cfg["smoothing"], cfg["emission_weight"] = win["config"]["smoothing"], win["config"]["emission_weight"]
    chosen: dict = {"smoother": {"value": {"smoothing": cfg["smoothing"], "emission_weight": cfg["emission_weight"]},
                                 "validation_score": win["score"],
                                 "validation_frame_accuracy_smoothed": win["frame_accuracy_smoothed"],
                                 "validation_video_accuracy": win["video_accuracy"],
                                 "candidates": {_smoother(r["config"]): r["score"] for r in base}}}
    smoother = (cfg["smoothing"], cfg["emission_weight"])

    def choose(factor_set, jobs, results, incumbent):
        winners = {}
        for key in factor_set:
            cands = [incumbent] + [_at(rs, smoother) for (step, _), rs in zip(jobs, results) if step == key]
            w = best(cands)
            winners[key] = w
            cfg[key] = w["config"][key]
            if key == "variant":  # another descriptor comes with the points its features were extracted with
                cfg["points"] = w["config"]["points"]
            chosen[key] = {"value": cfg[key], "validation_score": w["score"],
                           "validation_frame_accuracy_smoothed": w["frame_accuracy_smoothed"],
                           "validation_video_accuracy": w["video_accuracy"],
                           "candidates": {str(r["config"][key]): r["score"] for r in cands}}
        return winners

    start_row = _at(base, smoother)
    winners = choose(feature_factors, jobs, results, start_row)
    # the features the model factors are searched on: the features winner (one features factor at a time;
    # with several, their combination is trained below like the model factors')
    base_cfg = dict(cfg)
    base_row = start_row
    if len(winners) == 1:
        base_row = next(iter(winners.values()))
    elif any(cfg[k] != start[k] for k in feature_factors):
        comb = train([("features winners", base_cfg)])[0]
        rows += comb
        base_row = _at(comb, smoother)
    # stage 2: the model factors, one at a time from the stage-1 configuration
    jobs2 = [(key, {**base_cfg, key: v, **({"points": variant_points[v]} if key == "variant" else {})})
             for key, vals in model_factors.items() for v in vals]
    results2 = train(jobs2) if jobs2 else []
    rows += [r for rs in results2 for r in rs]
    choose(model_factors, jobs2, results2, base_row)
    final = base_row
    if any(cfg[k] != base_cfg[k] for k in model_factors):
        comb = train([("combined winners", dict(cfg))])[0]
        rows += comb
        c = _at(comb, smoother)
        if _key(c) >= _key(final):
            final = c
        else:  # the combination does worse than the stage-1 configuration: keep its values
            log.info("combined winners score below the stage-1 configuration on V; keeping its values")
            for k in model_factors:
                chosen[k]["value_if_alone"] = chosen[k]["value"]
                chosen[k]["value"] = base_cfg[k]
                cfg[k] = base_cfg[k]
    doc = {
        "kind": "vidstyle.validation.recognition", "schema_version": 2,
        "command": "python scripts/validate_recognition.py " + " ".join(sys.argv[1:]),
        "dataset": str(args.dataset), "dataset_seed": ds.seed, "seed": args.seed, "features": features,
        "points_features": {str(k): v for k, v in sorted(points_features.items())},
        "split": {"kind": split.kind, "vocab_performers": split.vocab_performers,
                  "train_performers": split.train_performers, "val_performers": split.val_performers,
                  "test_performers_not_used": split.test_performers},
        "score": ("mean of the smoothed frame accuracy on the validation performers and on their validation-camera "
                  "videos" if camera else "smoothed frame accuracy on the validation performers")
                 + " (ties: video accuracy, then the incumbent)",
        "camera_dataset": None if camera is None else camera[0],
        "camera_features": None if camera is None else {f"{v}@{n}": d for (v, n), d in sorted(camera[1].items())},
        "search": "the smoother on the starting model first; then the features factors (points per frame) one at "
                  "a time from the starting point, scored with that smoother; then the model factors one at a time "
                  "from the features winner; then the combination of their winners (kept only if it scores at least "
                  "as well as the features winner)",
        "start": start, "start_model": None if args.start_model is None else str(args.start_model),
        "factors": factors, "factors_not_searched": sorted(set(ALL_FACTORS) - set(factors)),
        "smoothers": [list(x) for x in _smoothers()], "chosen": chosen, "final_config": cfg,
        "final_validation": {k: final[k] for k in ("score", "frame_accuracy_raw", "frame_accuracy_smoothed",
                                                  "video_accuracy", "per_class_recall_smoothed", "n_val_frames",
                                                  "camera_frame_accuracy_raw", "camera_frame_accuracy_smoothed",
                                                  "camera_video_accuracy", "n_camera_frames") if k in final},
        "rows": rows,
    }
    write_validation(args.out, doc)
    print(table(doc))
    log.info("wrote %s", args.out)


def _smoother(c: dict) -> str:
    if c["smoothing"] in ("viterbi", "duration"):
        return f"{c['smoothing']}^{c['emission_weight']:g}"
    return f"{c['smoothing']} window {c['smoothing_window']}"


def table(doc: dict) -> str:
    lines = [f"# Recognition validation (seed {doc['seed']}; validation performers {', '.join(doc['split']['val_performers'])}; "
             "test performers not used)", "",
             "| step | candidate | V frame acc. raw | V frame acc. smoothed | V video acc. | V camera smoothed | score |",
             "|---|---|---:|---:|---:|---:|---:|"]
    st = doc["chosen"]["smoother"]["value"]
    for r in doc["rows"]:
        c = r["config"]
        if r["step"] != "start" and (c["smoothing"], c["emission_weight"]) != (st["smoothing"], st["emission_weight"]):
            continue  # the other smoothers are listed for the starting model only (all are in the JSON)
        va = "n/a" if r["video_accuracy"] is None else f"{100 * r['video_accuracy']:.1f} %"
        ca = r.get("camera_frame_accuracy_smoothed")
        lines.append(f"| {r['step']} | {_short(r['config'])} | {100 * r['frame_accuracy_raw']:.1f} % | "
                     f"{100 * r['frame_accuracy_smoothed']:.1f} % | {va} | "
                     f"{'n/a' if ca is None else f'{100 * ca:.1f} %'} | {100 * r.get('score', r['frame_accuracy_smoothed']):.1f} % |")
    lines += ["", "Chosen: " + _short(doc["final_config"]) +
              f" (V smoothed {100 * doc['final_validation']['frame_accuracy_smoothed']:.1f} %, score "
              f"{100 * doc['final_validation'].get('score', doc['final_validation']['frame_accuracy_smoothed']):.1f} %)"]
    return "\n".join(lines)


if __name__ == "__main__":
    from vidstyle.errors import VidstyleError

    try:
        main()
    except VidstyleError as e:  # bad input (e.g. an unreadable features directory): one line, not a traceback
        raise SystemExit(str(e)) from None
