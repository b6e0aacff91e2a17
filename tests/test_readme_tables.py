"""scripts/readme_tables.py: the README results tables come from metrics files, never typed by hand."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "readme_tables.py"
spec = importlib.util.spec_from_file_location("readme_tables", SCRIPT)
rt = importlib.util.module_from_spec(spec)
spec.loader.exec_module(rt)


def _recognition(seed, raw, smoothed, video, kind="unseen-performer", mirror=True, frames=100, **split):
    return {"kind": "vidstyle.metrics.recognition", "schema_version": 1, "seed": seed, "ablation": "none",
            "split": {"kind": kind, "seed": seed, **split}, "scored_set": "T",
            "params": {"recognizer": {"mirror": mirror}},
            "frame_accuracy": {"raw": raw, "smoothed": smoothed}, "video_accuracy": video, "n_test_frames": frames}


@pytest.fixture
def metrics(tmp_path):
    d = tmp_path / "metrics"
    (d / "seeds").mkdir(parents=True)
    for seed, sm in ((0, 0.9), (1, 0.8), (2, 0.85)):
        (d / "seeds" / f"rec{seed}.json").write_text(json.dumps(_recognition(seed, sm - 0.05, sm, 1.0)))
    (d / "cam.json").write_text(json.dumps(_recognition(0, 0.5, 0.55, 0.75, kind="unseen-camera")))
    (d / "lr.json").write_text(json.dumps(_recognition(0, 0.6, 0.62, None, kind="unseen-view", mirror=False,
                                                       test_views=["right"])))
    (d / "abl.json").write_text(json.dumps({**_recognition(0, 0.1, 0.1, 0.1), "ablation": "no-context"}))
    (d / "notes.json").write_text(json.dumps([1, 2]))  # not a metrics document: ignored
    (d / "style.json").write_text(json.dumps({"kind": "vidstyle.metrics.style", "seed": 0, "sources": {
        "recognised": {"summary": {"transition_mae": {"a": 0.0612}, "identification": {"a": {"accuracy_by_heldout_data": 2 / 3}}},
                       "performers": [{"performer": "p02"}, {"performer": "p04"}, {"performer": "p06"}]}}}))
    return d


def test_tables_carry_the_files_numbers(metrics):
    text = rt.tables(metrics)
    rows = {line.split(" | ")[0].strip("| "): line for line in text.splitlines() if line.startswith("| ")}
    up = rows["unseen-performer"]
    # mean 85.0, sample sd 5.0, minimum 80.0 over seeds 0, 1, 2
    assert "| 0, 1, 2 |" in up and "85.0 ± 5.0 % (min 80.0)" in up and "80.0 ± 5.0 % (min 75.0)" in up
    assert "| 300 |" in up and "`seeds/rec0.json`" in up
    assert "55.0 %" in rows["unseen-camera"] and "75.0 %" in rows["unseen-camera"]
    assert "62.0 %" in rows["unseen-view (test view right), no mirror training"]
    assert not any("10.0 %" in r for r in rows.values())  # ablation rows are not headline results
    rec = rows["recognised, test performers (seed 0)"]
    assert "p02, p04, p06" in rec and "0.061" in rec and "66.7 %" in rec


def test_readme_rewritten_between_markers_only(metrics, tmp_path, capsys):
    readme = tmp_path / "README.md"
    readme.write_text("# Title\n\nintro\n\n<!-- results:begin -->\nold 99 %\n<!-- results:end -->\n\nrest\n")
    assert rt.main(["--metrics", str(metrics), "--readme", str(readme), "--check"]) == 1
    assert rt.main(["--metrics", str(metrics), "--readme", str(readme)]) == 0
    text = readme.read_text()
    assert text.startswith("# Title\n\nintro\n\n<!-- results:begin -->\n") and text.endswith("<!-- results:end -->\n\nrest\n")
    assert "old 99 %" not in text and "85.0 ± 5.0 %" in text
    assert rt.main(["--metrics", str(metrics), "--readme", str(readme), "--check"]) == 0
    assert capsys.readouterr().out == ""


def test_without_markers_the_tables_go_to_stdout(metrics, tmp_path, capsys):
    readme = tmp_path / "README.md"
    readme.write_text("# no markers\n")
    assert rt.main(["--metrics", str(metrics), "--readme", str(readme)]) == 0
    assert readme.read_text() == "# no markers\n"
    assert "85.0 ± 5.0 %" in capsys.readouterr().out
    assert rt.main(["--metrics", str(tmp_path / "missing")]) == 2


def test_the_readme_shows_the_committed_results():
    """The README's results tables are exactly what the script makes of the committed metrics files."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    res = subprocess.run([sys.executable, str(root / "scripts" / "readme_tables.py"), "--metrics",
                          str(root / "pipelines" / "kickboxing" / "results"),
                          str(root / "pipelines" / "kickboxing" / "validation"),
                          str(root / "pipelines" / "kickboxing" / "strikes"), "--readme", str(root / "README.md"),
                          "--check"], capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr


def test_headline_in_readme_tables_in_results_page(metrics, tmp_path):
    """--readme updates the README's headline block and the full tables of docs/results.md beside it;
    --check fails while either is stale."""
    readme = tmp_path / "README.md"
    (tmp_path / "docs").mkdir()
    results = tmp_path / "docs" / "results.md"
    readme.write_text("# T\n\n<!-- headline:begin -->\nold\n<!-- headline:end -->\n")
    results.write_text("# Results\n\n<!-- results:begin -->\nold 99 %\n<!-- results:end -->\n")
    assert rt.main(["--metrics", str(metrics), "--readme", str(readme), "--check"]) == 1
    assert rt.main(["--metrics", str(metrics), "--readme", str(readme)]) == 0
    head, full = readme.read_text(), results.read_text()
    # the headline: the unseen-performer mean over seeds 0, 1, 2 (85.0 %) and its lowest seed, linked to the page
    assert "85.0 % of frames on average over 3 random splits" in head and "(lowest 80.0 %)" in head
    assert "](docs/results.md)" in head and "old" not in head
    assert "85.0 ± 5.0 % (min 80.0)" in full and "old 99 %" not in full
    assert rt.main(["--metrics", str(metrics), "--readme", str(readme), "--check"]) == 0


def test_the_repository_keeps_tables_in_docs_and_a_headline_in_the_readme():
    root = Path(__file__).resolve().parents[1]
    readme = (root / "README.md").read_text(encoding="utf-8")
    results = (root / "docs" / "results.md").read_text(encoding="utf-8")
    assert rt.HEAD_BEGIN in readme and rt.HEAD_END in readme and rt.BEGIN not in readme
    assert rt.BEGIN in results and rt.END in results
    head = readme[readme.index(rt.HEAD_BEGIN):readme.index(rt.HEAD_END)]
    assert 3 <= sum(line.startswith("| ") for line in head.splitlines()) - 1 <= 10  # a few rows, not the tables


def test_recognition_goals_have_a_row_per_seed_and_judge_every_seed():
    """Issue 28's block: a row per split seed from the files named by recognizer and split; a column is met
    only when its least seed reaches the goal, and a missing file shows as a dash, never as met."""
    def doc(seed, smoothed, video=None):
        return {"kind": "vidstyle.metrics.recognition", "seed": seed, "frame_accuracy": {"raw": 0.5, "smoothed": smoothed},
                "video_accuracy": video}

    docs = {"vidstyle.metrics.recognition": [
        (Path(f"r/recognition_unseen_performer_seed{s}.json"), doc(s, acc, 1.0)) for s, acc in ((0, 0.95), (1, 0.93))] + [
        (Path(f"r/recognition_unseen_camera_seed{s}.json"), doc(s, acc)) for s, acc in ((0, 0.90), (1, 0.871))] + [
        (Path("r/recognition_fusion_ps_unseen_performer_seed0.json"), doc(0, 0.99, 0.9))]}
    text = rt.recognition_goals(docs)
    rows = {line.split(" | ")[0].strip("| "): [c.strip(" |") for c in line.split(" | ")[1:]]
            for line in text.splitlines() if line.startswith("| ")}
    head = rows["seed"]
    col = {h: i for i, h in enumerate(head)}
    assert rows["0"][col["unseen performer S"]] == "95.0" and rows["1"][col["unseen camera S"]] == "87.1"
    met = rows["met on every seed"]
    assert met[col["unseen performer S"]] == "yes"  # 95.0 and 93.0 against 92
    assert met[col["unseen camera S"]] == "no"  # 87.1 on seed 1 against 88
    assert met[col["video S"]] == "yes"
    assert rows["1"][col["unseen performer F"]] == "—" and met[col["unseen performer F"]] == "—"  # seed 1 missing
    assert rows["goal"][col["unseen camera T"]] == ">= 88.0" and rows["goal"][col["video F"]] == ">= 100.0"


def test_confusion_tables_pool_the_seeds_counts_per_recognizer_and_split():
    def doc(seed, counts, classes=("A", "B")):
        return {**_recognition(seed, 0.5, 0.5, 1.0), "confusion": {"classes": list(classes), "counts_smoothed": counts}}

    items = [(Path("r/s0.json"), doc(0, [[3, 1], [0, 4]])), (Path("r/s1.json"), doc(1, [[1, 3], [2, 2]])),
             (Path("r/cam.json"), {**doc(0, [[5, 0], [0, 0]]), "split": {"kind": "unseen-camera", "seed": 0}})]
    text = "\n".join(rt.confusion_tables(items, Path("r")))
    perf = text[text.index("*unseen-performer*"):]
    # pooled: A -> (4, 4) of 8 frames, B -> (2, 6) of 8; the diagonal in bold
    assert "| A | **50.0** | 50.0 | 8 |" in perf and "| B | 25.0 | **75.0** | 8 |" in perf
    assert "(seeds 0, 1)" in perf
    cam = text[text.index("*unseen-camera*"):text.index("*unseen-performer*")]
    assert "| A | **100.0** | 0.0 | 5 |" in cam and "| B | — | — | 0 |" in cam  # no B frame: no percentages


def test_segments_table_lists_the_files_that_record_boundary_scores():
    with_segments = {**_recognition(0, 0.8, 0.85, 1.0), "segments": {"smoothed": {
        "boundary_tolerant_accuracy": {"1": 0.9, "2": 0.95, "3": 0.97}, "segmental_f1": {"10": 0.8, "25": 0.75, "50": 0.7}}}}
    lines = rt.segments_table([(Path("r/a.json"), with_segments), (Path("r/b.json"), _recognition(1, 0.7, 0.7, 1.0))],
                              Path("r"))
    assert len(lines) == 3  # header, rule, the one file with segments
    assert lines[2] == ("| unseen-performer | 0 | 85.0 % | 90.0 % | 95.0 % | 97.0 % | 80.0 % | 75.0 % | 70.0 % "
                        "| `a.json` |")
    assert rt.segments_table([(Path("r/b.json"), _recognition(1, 0.7, 0.7, 1.0))], Path("r")) == []


def test_headline_shows_in_betweening_against_slerp_from_its_metrics_file():
    def block(l2p, l2q):
        return {"l2p": l2p, "l2q": l2q, "ms_per_request": 1.0, "windows": 9}

    doc = {"kind": "vidstyle.metrics.inbetween", "seed": 0, "split": {"eval_subjects": ["02", "07"]},
           "methods": {"markov": {"30": block(2.1, 0.98), "45": block(3.2, 1.449)},
                       "slerp": {"30": block(2.4, 1.05), "45": block(3.45, 1.5)}}}
    text = rt.headline({"vidstyle.metrics.inbetween": [(Path("r/inbetween.json"), doc)]})
    assert ("30 frames: L2P 2.10 / L2Q 0.98 against SLERP's 2.40 / 1.05; 45 frames: L2P 3.20 / L2Q 1.45 against "
            "SLERP's 3.45 / 1.50") in text and "subjects 02, 07" in text
    assert "keyframes" not in rt.headline({"vidstyle.metrics.inbetween": [(Path("r/other.json"), doc)]})


def test_real_motion_goals_rows_come_from_the_strikes_and_real_motion_files():
    strikes = {"overall": {"smoothed": {"punch_fraction": 0.634}}}
    real = {"overall": {"sift": {"family_accuracy": 0.026}, "pose": {"family_accuracy": 0.871}}}
    docs = {"vidstyle.metrics.strikes": [(Path("s/strikes_02_05_pose_cmuwalks_ps_seed0.json"), strikes)],
            "vidstyle.metrics.real_motion": [(Path("r/real_motion_cmuwalks_seed0.json"), real)]}
    rows = rt.real_motion_goals(docs)
    assert any("demo mocap + real walks | 63.4 | >= 80.0 |" in r for r in rows)
    assert any("pose sequences, PS 2D, demo mocap + real walks | 87.1 | >= 85.0 |" in r for r in rows)
    assert not any("3D SIFT" in r for r in rows)  # the 3D SIFT row is taken from the demo-only file alone
    assert rt.real_motion_goals({}) == []
    # the pipeline's default 3D SIFT (S++) has its own files and rows beside the three-camera one's (S)
    docs = {"vidstyle.metrics.strikes": [(Path("s/strikes_02_05_seed0.json"), strikes),
                                         (Path("s/strikes_02_05_moreperformers_seed0.json"),
                                          {"overall": {"smoothed": {"punch_fraction": 0.5}}})],
            "vidstyle.metrics.real_motion": [(Path("r/real_motion_seed0.json"), real),
                                             (Path("r/real_motion_moreperformers_seed0.json"),
                                              {"overall": {"sift": {"family_accuracy": 0.3}}})]}
    rows = rt.real_motion_goals(docs)
    assert any("3D SIFT S (three demo cameras) | 63.4 | >= 80.0 | `results/strikes_02_05_seed0.json` |" in r for r in rows)
    assert any("3D SIFT S++ (more views and performers, the pipeline's default) | 50.0 | >= 80.0 | "
               "`results/strikes_02_05_moreperformers_seed0.json` |" in r for r in rows)
    assert any("3D SIFT S (three demo cameras) | 2.6 | >= 85.0 | `results/real_motion_seed0.json` |" in r for r in rows)
    assert any("the pipeline's default) | 30.0 | >= 85.0 | `results/real_motion_moreperformers_seed0.json` |" in r
               for r in rows)
    # S++ trained also on rendered real walks: its own rows, named as such
    docs["vidstyle.metrics.strikes"].append((Path("s/strikes_02_05_realwalks_seed0.json"),
                                             {"overall": {"smoothed": {"punch_fraction": 0.171}}}))
    docs["vidstyle.metrics.real_motion"].append((Path("r/real_motion_realwalks_seed0.json"),
                                                 {"overall": {"sift": {"family_accuracy": 0.759}}}))
    rows = rt.real_motion_goals(docs)
    walks = [r for r in rows if "3D SIFT S++ + real walks" in r]
    assert [r.split(" | ")[-3:] for r in walks] == [["17.1", ">= 80.0", "`results/strikes_02_05_realwalks_seed0.json` |"],
                                                    ["75.9", ">= 85.0", "`results/real_motion_realwalks_seed0.json` |"]]


def test_real_walks_validation_table_marks_the_chosen_model_and_the_class_only_datasets():
    row = lambda name, v, c, rm, more: {"name": name, "validation": {"smoothed": v}, "validation_camera": {"smoothed": c},  # noqa: E731
                                        "real_motion": rm, "score": (v + c + rm) / 3, "score_demo": (v + c) / 2,
                                        "more_views": [{}], "more_performers": more}
    perf = {"dataset": "out/performers_dataset", "performers": ["p20", "p21"]}
    walks = {"dataset": "/tmp/walks", "performers": ["s03"], "classes": ["Step"]}
    doc = {"seed": 0, "clips": ["07_01.bvh"], "rule": "the highest score", "chosen": "with walks",
           "rows": [row("S++", 0.905, 0.856, 0.0, [perf]), row("with walks", 0.901, 0.854, 1.0, [perf, walks])]}
    lines = rt.real_walks_table([(Path("/v/real_walks_seed0.json"), doc)], Path("/v"))
    body = [ln for ln in lines if ln.startswith("| S++") or ln.startswith("| with walks")]
    assert body[0] == ("| S++ | more views; 2 performers of `out/performers_dataset` | 90.5 % | 85.6 % | 0.0 % | "
                       "0.5870 | 0.8805 |  |")
    assert "1 performer of `/tmp/walks` (Step only)" in body[1] and body[1].endswith("| 0.9183 | 0.8775 | yes |")
