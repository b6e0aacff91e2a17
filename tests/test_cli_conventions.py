"""One convention per option name across commands (issue 32, item 5): --jobs defaults to all cores (-1)
unless the command's help says why not, and annotate's recognised labels are --recognized (the old
--labels still works, hidden) so --labels always names the true action labels of a command's inputs."""

from __future__ import annotations

import typer

from vidstyle.cli import app


def _walk(cmd, path=()):
    yield path, cmd
    for name, sub in sorted((getattr(cmd, "commands", None) or {}).items()):
        yield from _walk(sub, (*path, name))


NODES = list(_walk(typer.main.get_command(app)))


def _option(cmd, flag):
    return next((p for p in cmd.params if flag in getattr(p, "opts", ())), None)


def test_jobs_defaults_to_all_cores_or_says_why():
    seen = {}
    for path, cmd in NODES:
        jobs = _option(cmd, "--jobs")
        if jobs is None:
            continue
        seen[" ".join(path)] = jobs.default
        assert "-1 = all cores" in jobs.help, (path, jobs.help)
        assert "Range: 1..1024, or -1" in jobs.help, (path, jobs.help)  # the same checked range everywhere
        if jobs.default != -1:
            assert "the default" in jobs.help and "unlike other commands" in jobs.help, (path, jobs.help)
    assert {"features", "vocabulary", "train-recognizer", "recognize", "augment", "match-pose", "build-graph",
            "demo make-dataset", "evaluate augmg"} <= set(seen)
    assert [c for c, d in seen.items() if d != -1] == ["build-graph"], seen


def test_annotate_takes_recognized_and_the_old_labels_name(monkeypatch, tmp_path):
    from vidstyle.annotate import launch
    from vidstyle.cli import main

    cmd = dict(NODES)[("annotate",)]
    assert not _option(cmd, "--recognized").hidden and _option(cmd, "--labels").hidden
    got = []
    monkeypatch.setattr(launch, "annotate", lambda videos, annotations, **kw: got.append(kw["labels"]))
    video = tmp_path / "v.mp4"
    video.write_bytes(b"")
    assert main(["annotate", str(video), "--recognized", "a.json", "--labels", "b.json", "--no-browser"]) == 0
    assert [str(p) for p in got[0]] == ["a.json", "b.json"]


def test_labels_names_true_labels_everywhere_else():
    """--labels of every other command takes the true action labels of its inputs (truth, not a model's)."""
    for path, cmd in NODES:
        labels = _option(cmd, "--labels")
        if labels is None or labels.hidden:
            continue
        assert "recogni" not in (labels.help or "").lower(), (path, labels.help)


def test_vocabulary_and_recognizer_help_speak_plainly():
    """No "set A / set B" jargon: the videos the vocabulary is learned on, the videos the classifier is
    trained on."""
    import re

    for path in (("vocabulary",), ("train-recognizer",), ("evaluate", "recognition")):
        cmd = dict(NODES)[path]
        texts = [cmd.help or "", *(getattr(p, "help", "") or "" for p in cmd.params)]
        for text in texts:
            assert not re.search(r"\bsets? [ABVT]\b|\([AB]\)", text), (path, text)
    assert "the videos the vocabulary is learned on" in _option(dict(NODES)[("vocabulary",)], "--split").help.lower()
