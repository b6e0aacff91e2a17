"""The recognition stage as library calls (vidstyle.recognition.train_vocabulary / train / recognize_file):
with defaults they give the CLI's numbers; the recognizer's public frame_scores / smooth are what
predict_video computes; parameter checks live in the estimator and reach the CLI as flags."""

from __future__ import annotations

import inspect
import json

import numpy as np
import pytest

from tests.conftest import SEED
from vidstyle.cli import main
from vidstyle.errors import ParameterError
from vidstyle.recognition import (ActionRecognizer, Vocabulary, defaults, load_features, load_model, recognize_file,
                                  smooth_labels, train, train_vocabulary)
from vidstyle.recognition.synthetic import make_dataset

WORDS, COMPONENTS = "60", "24"  # the tiny dataset cannot make 1000 words; both sides get the same values


@pytest.fixture(scope="module")
def ds(tmp_path_factory):
    root = tmp_path_factory.mktemp("lib")
    make_dataset(root, n_performers=4, views=("front", "left"), seed=SEED, dim=24, reps=(2, 3), n_actions=5)
    return root


@pytest.fixture(scope="module")
def cli_run(ds, tmp_path_factory):
    out = tmp_path_factory.mktemp("cli_out")
    common = ["--dataset", str(ds), "--features-dir", str(ds / "features")]
    assert main(["vocabulary", *common, "--words", WORDS, "--out", str(out / "v.npz")]) == 0
    assert main(["train-recognizer", *common, "--vocab", str(out / "v.npz"), "--components", COMPONENTS,
                 "--out", str(out / "m.joblib")]) == 0
    vid = json.loads((ds / "dataset.json").read_text())["videos"][0]["id"]
    feats = ds / "features" / f"{vid}.npz"
    assert main(["recognize", str(feats), "--model", str(out / "m.joblib"), "--out", str(out / "lab.json")]) == 0
    return {"dir": out, "features": feats, "labels": json.loads((out / "lab.json").read_text())}


def test_library_with_defaults_gives_the_cli_numbers(ds, cli_run, tmp_path):
    vrun = train_vocabulary(dataset=ds, features_dir=ds / "features", words=int(WORDS))
    cli_voc = Vocabulary.load(cli_run["dir"] / "v.npz")
    np.testing.assert_array_equal(vrun.vocabulary.cluster_centers_, cli_voc.cluster_centers_)
    vrun.vocabulary.save(tmp_path / "v.npz", training_files=vrun.training_files, extra=vrun.extra)
    run = train(tmp_path / "v.npz", dataset=ds, features_dir=ds / "features", n_components=int(COMPONENTS))
    cli_rec, cli_header = load_model(cli_run["dir"] / "m.joblib")
    assert run.model.get_params(deep=False).keys() == cli_rec.get_params(deep=False).keys()
    assert run.model.public_params() == cli_header["params"]
    assert run.training_files == cli_header["training_files"] and run.extra["split"] == cli_header["split"]
    track = recognize_file(run.model, {}, cli_run["features"])
    lab = cli_run["labels"]
    assert track.labels == lab["labels"] and track.raw == lab["raw"]
    np.testing.assert_array_equal(track.confidence, lab["confidence"])
    np.testing.assert_array_equal(track.raw_confidence, lab["raw_confidence"])
    assert (track.smoothing, track.smoothing_window) == (lab["smoothing"], lab["smoothing_window"])


def test_defaults_module_is_the_library_and_cli_default():
    import typer.main

    from vidstyle.cli import app

    rec = ActionRecognizer().get_params()
    sig = inspect.signature(train).parameters
    cmd = {p.name: p.default for p in typer.main.get_command(app).commands["train-recognizer"].params}
    for name, value in defaults.RECOGNIZER_PARAMS.items():
        assert rec[name] == value, name
        assert sig[name].default == value, name
    cli_names = {"n_components": "components", "C": "c", "smoothing_window": "window"}
    for name, value in defaults.RECOGNIZER_PARAMS.items():
        assert cmd[cli_names.get(name, name)] == value, name
    vsig = inspect.signature(train_vocabulary).parameters
    vcmd = {p.name: p.default for p in typer.main.get_command(app).commands["vocabulary"].params}
    assert vsig["words"].default == vcmd["words"] == defaults.N_WORDS == Vocabulary().n_words
    assert vsig["method"].default == vcmd["method"] == defaults.VOCAB_METHOD == Vocabulary().method


@pytest.fixture(scope="module")
def model(cli_run):
    return load_model(cli_run["dir"] / "m.joblib")[0]


def test_frame_scores_and_smooth_are_predict_video(model, cli_run):
    f = load_features(cli_run["features"])
    H = model.histograms(f)
    raw, scores, conf = model.frame_scores(H)
    # independent: the classifier on the PCA features, its classes mapped into classes_ by hand
    pred, s, c = model.clf_.predict_with_scores(model.pca_.transform(model._grouped(H)))
    present = model.clf_.classes_.astype(np.int64)
    np.testing.assert_array_equal(raw, present[pred])
    np.testing.assert_array_equal(scores[:, present], s)
    assert np.all(np.delete(scores, present, axis=1) == 0)
    np.testing.assert_array_equal(conf, c)
    out = model.smooth(raw, scores, conf)
    ref = model.predict_video(f)
    for k in ("raw", "scores", "confidence", "smoothed", "smoothed_confidence"):
        np.testing.assert_array_equal(out[k], ref[k])
    # smooth follows the recognizer's smoother settings, as smooth_labels does with the learned chain
    model.smoothing, model.smoothing_window = "vote", 4
    try:
        sm, sc = smooth_labels(raw, len(model.classes_), 4, conf, scores, "vote")
        out = model.smooth(raw, scores, conf)
        np.testing.assert_array_equal(out["smoothed"], sm)
        np.testing.assert_array_equal(out["smoothed_confidence"], sc)
    finally:
        model.smoothing, model.smoothing_window = defaults.SMOOTHING, defaults.SMOOTHING_WINDOW
    Hs = model.histograms_many([f, f])
    assert all((h != H).nnz == 0 for h in Hs)
    np.testing.assert_array_equal(model.embed(H), model.transform(f))


def test_empty_video_scores_and_smooths_to_nothing(model):
    import scipy.sparse as sp

    raw, scores, conf = model.frame_scores(sp.csr_matrix((0, model.vocabulary.n_words_)))
    assert raw.shape == (0,) and scores.shape == (0, len(model.classes_)) and conf.shape == (0,)
    assert model.smooth(raw, scores, conf)["smoothed"].shape == (0,)


@pytest.mark.parametrize("param,value,flag", [("smoothing_window", 0, "window"), ("smoothing", "median", "smoothing"),
                                              ("emission_weight", 0.0, "emission_weight"), ("C", -1.0, "C"),
                                              ("max_frames_per_class", 0, "max_frames_per_class")])
def test_the_estimator_checks_its_parameters_in_fit(model, cli_run, param, value, flag):
    rec = ActionRecognizer(vocabulary=model.vocabulary, **{param: value})
    f = load_features(cli_run["features"])
    with pytest.raises(ParameterError) as e:
        rec.fit([f], [["x"] * f.n_frames])
    assert e.value.param == flag


def test_bad_window_is_one_flag_line_and_no_output(cli_run, tmp_path, capsys):
    out = tmp_path / "lab.json"
    assert main(["recognize", str(cli_run["features"]), "--model", str(cli_run["dir"] / "m.joblib"),
                 "--window", "0", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == "vidstyle: error: --window: must be an integer in 1..1000, got 0"
    assert not out.exists()


def test_more_views_join_set_b_with_its_performers_only(ds, tmp_path):
    """train(..., more_views=[(dataset, features)]): the videos of set B's performers in another dataset of
    the same performers (other cameras) are appended to set B; no other performer's video trains, and the
    split (so every test video) stays the first dataset's."""
    from vidstyle.errors import InputError

    xd = tmp_path / "views"
    make_dataset(xd, n_performers=4, views=("right", "back"), seed=SEED + 1, dim=24, reps=(2, 3), n_actions=5)
    voc = train_vocabulary(dataset=ds, features_dir=ds / "features", words=int(WORDS)).vocabulary
    base = train(voc, dataset=ds, features_dir=ds / "features", n_components=int(COMPONENTS))
    run = train(voc, dataset=ds, features_dir=ds / "features", n_components=int(COMPONENTS),
                more_views=[(xd, xd / "features")])
    split = run.extra["split"]
    b = set(split["train_performers"])
    videos = json.loads((xd / "dataset.json").read_text())["videos"]
    want = sorted(v["id"] for v in videos if v["performer"] in b)
    n = len(base.training_files)
    assert run.training_files[:n] == base.training_files
    assert [t["features"].rsplit("/", 1)[-1][:-4] for t in run.training_files[n:]] == want
    assert 0 < len(want) < len(videos) and split["more_views_videos"] == len(want)
    assert split["test"] == base.extra["split"]["test"]
    feats = [t["features"] for t in base.training_files]
    labs = [t["labels"] for t in base.training_files]
    with pytest.raises(InputError, match="--more-views"):
        train(voc, feats, labels=labs, n_components=int(COMPONENTS), more_views=[(xd, xd / "features")])
    # a more-views dataset of other performers only is refused, naming the file
    doc = json.loads((xd / "dataset.json").read_text())
    doc["videos"] = [v for v in videos if v["performer"] not in b]
    (xd / "dataset.json").write_text(json.dumps(doc))
    with pytest.raises(InputError, match="no video of the training performers"):
        train(voc, dataset=ds, features_dir=ds / "features", n_components=int(COMPONENTS),
              more_views=[(xd, xd / "features")])


def _new_performers(tmp_path, keep_from: int = 4):
    """A dataset of 7 synthetic performers with p00..p<keep_from - 1> (the ``ds`` fixture's ids) taken out."""
    xd = tmp_path / "people"
    make_dataset(xd, n_performers=7, views=("front", "left"), seed=SEED + 2, dim=24, reps=(2, 3), n_actions=5)
    doc = json.loads((xd / "dataset.json").read_text())
    doc["videos"] = [v for v in doc["videos"] if int(v["performer"][1:]) >= keep_from]
    (xd / "dataset.json").write_text(json.dumps(doc))
    return xd, doc["videos"]


def test_more_performers_divide_between_vocabulary_and_classifier(ds, tmp_path):
    """more_performers=[(dataset, features)]: of the performers --dataset does not hold, the first
    round(share * n) by id join the vocabulary's set A and the others the classifier's set B, so the
    vocabulary and the classifier never share a performer; the split's test videos stay --dataset's."""
    from vidstyle.errors import InputError
    from vidstyle.formats.dataset import read_dataset
    from vidstyle.recognition.pipeline import more_performer_sets

    xd, videos = _new_performers(tmp_path)
    ids = lambda ps: sorted(v["id"] for v in videos if v["performer"] in ps)  # noqa: E731
    main_performers = {f"p{i:02d}" for i in range(4)}
    for share, a in ((1 / 3, {"p04"}), (0.5, {"p04", "p05"}), (0.0, set()), (1.0, {"p04", "p05", "p06"})):
        got = more_performer_sets(read_dataset(xd), main_performers, share)
        assert got == (ids(a), ids({"p04", "p05", "p06"} - a)), share
    base_v = train_vocabulary(dataset=ds, features_dir=ds / "features", words=int(WORDS))
    vrun = train_vocabulary(dataset=ds, features_dir=ds / "features", words=int(WORDS),
                            more_performers=[(xd, xd / "features")])
    n = len(base_v.training_files)
    assert vrun.training_files[:n] == base_v.training_files
    assert [f.rsplit("/", 1)[-1][:-4] for f in vrun.training_files[n:]] == ids({"p04"})
    assert vrun.extra["split"]["more_performers"][0]["performers"] == ["p04"]
    assert vrun.n_descriptors > base_v.n_descriptors
    vfile = tmp_path / "v.npz"
    vrun.vocabulary.save(vfile, training_files=vrun.training_files, extra=vrun.extra)
    base = train(vfile, dataset=ds, features_dir=ds / "features", n_components=int(COMPONENTS))
    run = train(vfile, dataset=ds, features_dir=ds / "features", n_components=int(COMPONENTS),
                more_performers=[(xd, xd / "features")])
    m = len(base.training_files)
    assert run.training_files[:m] == base.training_files
    assert [t["features"].rsplit("/", 1)[-1][:-4] for t in run.training_files[m:]] == ids({"p05", "p06"})
    assert run.extra["split"]["more_performers"][0]["performers"] == ["p05", "p06"]
    assert run.extra["split"]["test"] == base.extra["split"]["test"]
    # the same share on both sides: the vocabulary's videos never train the classifier (the overlap check)
    with pytest.raises(InputError, match="also built the vocabulary"):
        train(vfile, dataset=ds, features_dir=ds / "features", n_components=int(COMPONENTS),
              more_performers=[(xd, xd / "features")], more_performers_vocab_share=0.0)
    with pytest.raises(InputError, match="--more-performers"):
        train_vocabulary([f"{ds}/features/x.npz"], words=int(WORDS), more_performers=[(xd, xd / "features")])
    # a dataset of --dataset's own performers only adds nobody: refused, naming the file
    with pytest.raises(InputError, match="every performer of the dataset"):
        train(vfile, dataset=ds, features_dir=ds / "features", n_components=int(COMPONENTS),
              more_performers=[(ds, ds / "features")])


def test_more_performers_of_some_of_the_classes(ds, tmp_path):
    """A more-performers dataset of one of the split's classes (real walks labelled ``Step``: ``demo
    make-cmu-dataset --actions Step=walk``) trains the same machines: its frames join set B under that
    class; a dataset with a class the split lacks is refused, naming the file and the class."""
    from vidstyle.errors import InputError
    from vidstyle.recognition.synthetic import CLASSES

    xd, videos = _new_performers(tmp_path)
    only = CLASSES[1]
    doc = json.loads((xd / "dataset.json").read_text())
    doc["classes"] = doc["actions"] = [only]
    doc["videos"] = videos = [{**v, "action": only if v["action"] else None} for v in videos]
    (xd / "dataset.json").write_text(json.dumps(doc))
    n_frames = 0
    for v in videos:
        lab = json.loads((xd / v["labels"]).read_text())
        lab["classes"], lab["labels"] = [only], [only] * len(lab["labels"])
        n_frames += len(lab["labels"])
        (xd / v["labels"]).write_text(json.dumps(lab))
    voc = train_vocabulary(dataset=ds, features_dir=ds / "features", words=int(WORDS)).vocabulary
    base = train(voc, dataset=ds, features_dir=ds / "features", n_components=int(COMPONENTS),
                 max_frames_per_class=0)
    run = train(voc, dataset=ds, features_dir=ds / "features", n_components=int(COMPONENTS),
                more_performers=[(xd, xd / "features")], more_performers_vocab_share=0.0, max_frames_per_class=0)
    assert list(run.model.classes_) == list(base.model.classes_)
    assert run.extra["split"]["more_performers"][0]["classes"] == [only]
    m = len(base.training_files)
    assert [t["features"].rsplit("/", 1)[-1][:-4] for t in run.training_files[m:]] == sorted(v["id"] for v in videos)
    # every one of their frames trains under that class, and no other class gains a frame
    factor = 2 if run.model.n_mirrored_videos_ else 1
    gained = {c: run.model.train_class_counts_[c] - base.model.train_class_counts_[c] for c in CLASSES}
    assert gained == {c: n_frames * factor if c == only else 0 for c in CLASSES}
    doc["classes"] = [only, "Somersault"]
    (xd / "dataset.json").write_text(json.dumps(doc))
    with pytest.raises(InputError, match=r"people.*Somersault"):
        train(voc, dataset=ds, features_dir=ds / "features", n_components=int(COMPONENTS),
              more_performers=[(xd, xd / "features")], more_performers_vocab_share=0.0)


def test_more_performers_flags(ds, cli_run, tmp_path, capsys):
    common = ["--dataset", str(ds), "--features-dir", str(ds / "features")]
    assert main(["vocabulary", *common, "--words", WORDS, "--more-performers", str(ds),
                 "--out", str(tmp_path / "v.npz")]) == 2
    assert "--more-performers: 1 datasets for 0 --more-performers-features" in capsys.readouterr().err
    assert main(["train-recognizer", *common, "--vocab", str(cli_run["dir"] / "v.npz"), "--components", COMPONENTS,
                 "--more-performers", str(ds), "--more-performers-features", str(ds / "features"),
                 "--more-performers-vocab-share", "1.5", "--out", str(tmp_path / "m.joblib")]) == 2
    assert "--more-performers-vocab-share" in capsys.readouterr().err
    assert not (tmp_path / "v.npz").exists() and not (tmp_path / "m.joblib").exists()
    xd, _ = _new_performers(tmp_path)
    more = ["--more-performers", str(xd), "--more-performers-features", str(xd / "features")]
    assert main(["vocabulary", *common, "--words", WORDS, *more, "--out", str(tmp_path / "v.npz")]) == 0
    assert main(["train-recognizer", *common, "--vocab", str(tmp_path / "v.npz"), "--components", COMPONENTS, *more,
                 "--out", str(tmp_path / "m.joblib")]) == 0
    _, header = load_model(tmp_path / "m.joblib")
    assert header["split"]["more_performers"][0]["performers"] == ["p05", "p06"]
    assert header["split"]["more_performers_vocab_share"] == pytest.approx(defaults.MORE_PERFORMERS_VOCAB_SHARE)


def test_more_views_flags_pair_up(ds, cli_run, tmp_path, capsys):
    common = ["--dataset", str(ds), "--features-dir", str(ds / "features"), "--vocab", str(cli_run["dir"] / "v.npz"),
              "--components", COMPONENTS, "--out", str(tmp_path / "m.joblib")]
    assert main(["train-recognizer", *common, "--more-views", str(ds)]) == 2
    assert "--more-views: 1 datasets for 0 --more-views-features" in capsys.readouterr().err
    assert not (tmp_path / "m.joblib").exists()


def test_score_set_counts_frames_as_the_recognizer_labels_them(ds):
    """vidstyle.evaluation.recognition.score_set (the validation scripts' score): its frame accuracies are
    the share of frames whose predicted label is the true one, counted here frame by frame from
    predict_video, and its frame count is the videos' length."""
    from vidstyle.evaluation.recognition import score_set
    from vidstyle.formats.dataset import read_dataset
    from vidstyle.formats.labels import read_labels
    from vidstyle.recognition.splits import make_split

    voc = train_vocabulary(dataset=ds, features_dir=ds / "features", words=int(WORDS)).vocabulary
    run = train(voc, dataset=ds, features_dir=ds / "features", n_components=int(COMPONENTS))
    d = read_dataset(ds)
    ids = list(make_split(d, "unseen-performer", seed=SEED).test)
    got = score_set(run.model, d, ds / "features", ids, 2)
    by = d.by_id()
    right = {"raw": 0, "smoothed": 0}
    n = 0
    for i in ids:
        out = run.model.predict_video(load_features(ds / "features" / f"{i}.npz"))
        truth = read_labels(d.labels_path(by[i])).labels
        for k in right:
            right[k] += sum(run.model.classes_[p] == t for p, t in zip(out[k], truth))
        n += len(truth)
    assert got["frames"] == n
    assert got["raw"] == pytest.approx(right["raw"] / n) and got["smoothed"] == pytest.approx(right["smoothed"] / n)
    assert 0.0 <= got["video"] <= 1.0
