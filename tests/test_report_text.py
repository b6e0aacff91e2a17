"""`vidstyle report RUN --text`: the headline numbers as a few grouped lines a 120-column terminal shows
(issue 32, item 5: `dvc metrics show` prints them as one ~900-character row)."""

from __future__ import annotations

from vidstyle.report.text import GROUPS, WIDTH, headline_text


def _full_headline() -> dict:
    """Every headline number present, with wide values (large counts, many performers, negative numbers)."""
    head = {"kind": "vidstyle.metrics.headline", "schema_version": 1, "seed": 123456}
    for key, _name, spec in GROUPS:
        head[key] = {k: -12345.678 if "loglik" in k else 987654321 if k in ("test_frames", "graph_frames",
                                                                               "transitions_in_scc") else 0.123456
                     for k, _label, _unit in spec}
    head["style"]["recognised_performers"] = [f"performer{i:02d}" for i in range(12)]
    return head


def test_every_line_fits_120_columns_and_every_number_is_shown():
    head = _full_headline()
    text = headline_text(head)
    lines = text.splitlines()
    assert max(len(line) for line in lines) <= WIDTH == 120, [line for line in lines if len(line) > WIDTH]
    assert len(lines) <= 20  # a 24-line terminal's screenful, grouped
    starts = [line.split()[0] for line in lines if not line.startswith(" ")]
    assert starts == ["recognition", "style", "motion", "augmg", "reconstruct", "action", "keyframes", "run"]
    assert "kind" not in text and "schema_version" not in text and "vidstyle.metrics" not in text
    n_numbers = sum(len(spec) for _key, _name, spec in GROUPS) - 1 + 1  # performers are a list; + the seed
    assert text.count("0.123") + text.count("987654321") + text.count("-12346") + text.count("123456") >= n_numbers
    assert "performer11" in text
    # a narrower terminal: the same, wrapped between items
    assert max(len(line) for line in headline_text(head, width=80).splitlines()) <= 80


def test_missing_numbers_and_groups_are_left_out():
    text = headline_text({"seed": 0, "recognition": {"frame_accuracy_smoothed": 0.8123, "video_accuracy": None},
                          "style": {"transition_mae_truth": None}, "motion": None})
    assert text.splitlines() == ["recognition  frame accuracy 0.812", "run          seed 0"]


def test_cli_prints_the_summary_and_writes_no_page(tmp_path, capsys):
    from vidstyle.cli import main

    run = tmp_path / "out"
    (run / "metrics").mkdir(parents=True)
    assert main(["report", str(run), "--text"]) == 0
    out = capsys.readouterr().out
    assert "no metrics yet" in out and not (run / "report.html").exists()
    assert main(["report", str(tmp_path / "absent"), "--text"]) == 2
