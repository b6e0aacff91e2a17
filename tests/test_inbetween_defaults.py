"""The in-betweening defaults come from the committed validation table (chosen on the validation subject,
never the test subjects), the committed results file is a valid metrics document of the same split, and
``vidstyle evaluate inbetween`` refuses bad arguments with exit 2."""

from __future__ import annotations

from pathlib import Path

import pytest

from vidstyle.cli import main
from vidstyle.formats.metrics import INBETWEEN, read_metrics
from vidstyle.formats.validation import INBETWEEN as VALIDATION
from vidstyle.formats.validation import read_validation
from vidstyle.inbetween import defaults as D

ROOT = Path(__file__).resolve().parents[1]
VALIDATION_FILE = ROOT / "pipelines" / "kickboxing" / "validation" / "inbetween.json"
RESULTS_FILE = ROOT / "pipelines" / "kickboxing" / "results" / "inbetween.json"


def test_split_gives_each_subject_one_role():
    roles = [set(v) for v in D.EVAL_SPLIT.values()]
    assert all(not (a & b) for i, a in enumerate(roles) for b in roles[i + 1:])


def test_defaults_are_the_validation_choice():
    doc = read_validation(VALIDATION_FILE, VALIDATION)
    assert doc["split"]["validation"] == list(D.EVAL_SPLIT["validation"])
    assert not set(doc["split"]["validation"]) & set(D.EVAL_SPLIT["test"])
    chosen = doc["chosen"]
    assert chosen == {"n_clusters": D.N_CLUSTERS, "n_components": D.N_COMPONENTS, "warp_cost": D.WARP_COST,
                      "root_path": D.ROOT_PATH, "coverage_scale": D.COVERAGE_SCALE}
    # the rule, reapplied to the recorded table: the score is L2P and L2Q as fractions of SLERP's on the same
    # windows, mean over both metrics and the gaps (the goal is against SLERP on both)
    gaps, slerp = doc["gaps"], doc["baselines"]["slerp"]

    def ratio(r, ref):
        return sum(r[f"{m}_{g}"] / ref(m, g) for m in ("l2p", "l2q") for g in gaps) / (2 * len(gaps))

    for r in doc["rows"]:
        assert r["score"] == pytest.approx(ratio(r, lambda m, g: slerp[str(g)][m]))
    best = min(doc["rows"], key=lambda r: r["score"])
    assert best["params"] == {**chosen, "coverage_scale": None}  # the grid and root path: without the gate
    folds = doc["coverage"]["baselines"]["slerp"]["folds"]
    for r in doc["coverage"]["rows"]:
        per = [ratio(f, lambda m, g, h=h: folds[h][f"{m}_{g}"]) for h, f in r["folds"].items()]
        assert r["score"] == pytest.approx(sum(per) / len(per))
    gate = min(doc["coverage"]["rows"], key=lambda r: r["score"])
    assert gate["coverage_scale"] == chosen["coverage_scale"]
    # the gate's folds: the validation subject and library subjects, never a test subject
    held = {f["held_out"][0] for f in doc["coverage"]["folds"]}
    assert held == set(D.EVAL_SPLIT["validation"]) | set(D.EVAL_SPLIT["library"])
    assert not held & set(D.EVAL_SPLIT["test"])
    assert all(set(f["library"]) <= set(D.EVAL_SPLIT["library"]) for f in doc["coverage"]["folds"])


def test_results_file_is_a_metrics_document_of_the_test_split():
    m = read_metrics(RESULTS_FILE, INBETWEEN)
    assert m.seed == 0 and m.get("split", "eval_subjects") == list(D.EVAL_SPLIT["test"])
    assert set(m.get("methods")) == set(D.EVAL_METHODS)
    assert m.get("params", "markov_params", "n_clusters") == D.N_CLUSTERS
    assert m.get("params", "markov_params", "root_path") == D.ROOT_PATH
    assert m.get("params", "markov_params", "coverage_scale") == D.COVERAGE_SCALE


@pytest.mark.parametrize("args", [["--library", "01,02", "--test", "02"], ["--gaps", "15,x"], ["--gaps", "0"],
                                  ["--methods", "markov,spline"]])
def test_evaluate_inbetween_bad_arguments_exit_2(args, tmp_path, capsys):
    out = tmp_path / "m.json"
    assert main(["evaluate", "inbetween", "--cmu", str(tmp_path), *args, "--out", str(out)]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert not out.exists()


def test_evaluate_inbetween_on_a_small_cmu_split(tmp_path):
    from conftest import CMU_DIR

    if not CMU_DIR.is_dir():
        pytest.skip("../shared/data/mocap/cmu is absent")
    out = tmp_path / "m.json"
    assert main(["evaluate", "inbetween", "--cmu", str(CMU_DIR), "--library", "08", "--test", "07", "--gaps", "15",
                 "--methods", "markov,slerp", "--out", str(out), "--graph-cache", str(tmp_path / "g.npz")]) == 0
    m = read_metrics(out, INBETWEEN)
    assert m.get("split", "eval_subjects") == ["07"] and m.get("gaps") == [15]
    for name in ("markov", "slerp"):
        block = m.get("methods", name, "15")
        assert block["windows"] == m.get("by_subject", "07", "windows") > 5
        assert 0 < block["l2p"] < 50 and 0 < block["l2q"] < 10
    assert (tmp_path / "g.npz").is_file()
