"""``vidstyle evaluate style`` on a fake dataset of performers with known chains."""

from __future__ import annotations

import json

import pytest

from vidstyle.cli import main
from vidstyle.style.synthetic import write_fake_dataset

FAST = ["--n-init", "2", "--modes", "1-6"]
TEST_PERFORMERS = ["p01", "p03", "p04", "p05"]  # the recognizer's unseen performers in this fake dataset


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    root = tmp_path_factory.mktemp("ds")
    write_fake_dataset(root, n_performers=6, n_videos=3, events_per_video=150, seed=11,
                       recognised_dir=root / "recognised", frame_noise=0.1, event_swap=0.05)
    return root


@pytest.fixture(scope="module")
def metrics(dataset):
    out = dataset / "metrics.json"
    code = main(["evaluate", "style", "--dataset", str(dataset), "--labels-dir", str(dataset / "recognised"),
                 "--performers", ",".join(TEST_PERFORMERS), "--out", str(out), "--seed", "2", *FAST])
    assert code == 0
    return json.loads(out.read_text())


def test_metrics_document(metrics):
    assert metrics["kind"] == "vidstyle.metrics.style" and metrics["seed"] == 2
    assert metrics["params"]["style"]["n_init"] == 2 and metrics["params"]["style"]["seed"] == 2
    assert set(metrics["sources"]) == {"ground_truth", "ground_truth_test_performers", "recognised"}
    assert metrics["recognised_performers"] == TEST_PERFORMERS
    for name, src in metrics["sources"].items():
        want = sorted({f"p{i:02d}" for i in range(6)}) if name == "ground_truth" else TEST_PERFORMERS
        assert sorted(r["performer"] for r in src["performers"]) == want
        assert src["summary"]["n_performers"] == len(want)
        for row in src["performers"]:
            assert row["n_train_sequences"] == 2 and row["n_heldout_sequences"] == 1


def test_targets_on_ground_truth(metrics):
    s = metrics["sources"]["ground_truth"]["summary"]
    assert s["transition_mae"]["a"] <= 0.05
    assert s["identification"]["a"]["accuracy_by_heldout_data"] >= 0.9
    assert s["identification"]["a"]["accuracy_by_true_chain"] >= 0.9
    assert s["identification"]["heldout_sequences_by_model_a"]["accuracy"] >= 0.9
    for m in ("a", "b"):
        f = s["fidelity"][m]
        assert f["jsd_2gram_same"] < 0.5 * f["jsd_2gram_other"]
        assert f["jsd_3gram_same"] < f["jsd_3gram_other"]
        assert f["jsd_2gram_same_lt_other_fraction"] == 1.0
    ll = s["heldout_loglik_per_event"]
    # model (a) ~ bigram on clean labels; (b) must at least be in the same range (see the report)
    assert abs(ll["a"] - ll["bigram"]) < 0.02
    assert ll["b"] > ll["bigram"] - 0.1
    assert s["duration_mean_abs_error_frames"] < 1.0


def test_recognition_errors_are_tolerated(metrics):
    gt = metrics["sources"]["ground_truth_test_performers"]["summary"]
    rec = metrics["sources"]["recognised"]["summary"]
    assert rec["transition_mae"]["a"] <= 0.07
    # the confusion-aware HMM recovers the true chain at least as well as counting noisy labels
    assert rec["transition_mae"]["a"] <= rec["transition_mae"]["bigram"] + 1e-3
    assert rec["identification"]["a"]["accuracy_by_heldout_data"] >= 0.9
    assert rec["heldout_loglik_per_event"]["a"] < gt["heldout_loglik_per_event"]["a"]  # noise costs


def test_single_video_performers_split_by_time(tmp_path):
    write_fake_dataset(tmp_path, n_performers=3, n_videos=1, events_per_video=120, seed=5)
    out = tmp_path / "m.json"
    assert main(["evaluate", "style", "--dataset", str(tmp_path), "--out", str(out), "--n-init", "1",
                 "--modes", "1-2", "--n-generate", "5"]) == 0
    rows = json.loads(out.read_text())["sources"]["ground_truth"]["performers"]
    assert all(r["n_train_sequences"] == 1 and r["n_heldout_sequences"] == 1 for r in rows)
    assert all(35 <= r["n_heldout_events"] <= 45 for r in rows)


def test_bad_evaluate_input(dataset, tmp_path, capsys):
    out = tmp_path / "m.json"
    assert main(["evaluate", "style", "--dataset", str(tmp_path), "--out", str(out)]) != 0
    assert "dataset.json: file not found" in capsys.readouterr().err
    partial = tmp_path / "rec"
    partial.mkdir()
    assert main(["evaluate", "style", "--dataset", str(dataset), "--labels-dir", str(partial),
                 "--performers", "p01,p02", "--out", str(out), *FAST]) != 0
    assert "recognised labels of video p01_perf0 (performer p01) not found" in capsys.readouterr().err
    # recognised labels without naming the unseen performers: refused (they could be training videos)
    assert main(["evaluate", "style", "--dataset", str(dataset), "--labels-dir", str(dataset / "recognised"),
                 "--out", str(out), *FAST]) != 0
    assert "--model" in capsys.readouterr().err
    assert main(["evaluate", "style", "--dataset", str(dataset), "--heldout-fraction", "1.5",
                 "--out", str(out)]) != 0
    assert not out.exists()


def _seq(starts, durations, source):
    import numpy as np

    from vidstyle.style.events import EventSequence

    starts = np.asarray(starts)
    return EventSequence(("A", "B"), np.arange(len(starts)) % 2, np.asarray(durations), starts, source)


def test_split_never_holds_out_another_view_of_a_training_moment():
    from vidstyle.evaluation.style import _split

    # one take seen from two views: recognised events differ a little, the cut is one frame for both
    front = _seq([0, 10, 20, 30, 40, 50], [10] * 6, "front")
    left = _seq([0, 12, 19, 33, 41, 52], [12, 7, 14, 8, 11, 8], "left")
    train, held = _split([front, left], 0.3, ["take0", "take0"])
    assert len(train) == 2 and len(held) == 2
    cut = 42  # (1 - 0.3) * 60
    assert all(s.starts.max() < cut for s in train) and all(s.starts.min() >= cut for s in held)
    assert sum(map(len, train)) + sum(map(len, held)) == 12

    # three takes x two views: whole takes (both views) are held out, never one view of a train take
    seqs = [_seq([0, 10, 20, 30], [10] * 4, f"t{t}_{v}") for t in range(3) for v in ("front", "left")]
    takes = [f"t{t}" for t in range(3) for _ in ("front", "left")]
    train, held = _split(seqs, 0.34, takes)
    assert [s.source for s in held] == ["t2_front", "t2_left"]
    assert {s.source[:2] for s in train} == {"t0", "t1"}
