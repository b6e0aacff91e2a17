"""Every command's and group's --help fits an 80-column terminal (issue 32, item 5): no option name cut,
no line wider than the terminal, no text cut short with an ellipsis."""

from __future__ import annotations

import re

import pytest
import typer

from vidstyle.cli import app, main

WIDTH = 80


def _walk(cmd, path=()):
    yield path, cmd
    for name, sub in sorted((getattr(cmd, "commands", None) or {}).items()):
        yield from _walk(sub, (*path, name))


NODES = list(_walk(typer.main.get_command(app)))


def _names(cmd) -> list[str]:
    """What --help must show in full: every visible option's names (on and off forms) and arguments."""
    names: list[str] = []
    for p in cmd.params:
        if getattr(p, "hidden", False):
            continue
        if getattr(p, "param_type_name", "") == "argument":
            names.append(p.metavar or p.name)
        else:
            names += [*p.opts, *p.secondary_opts]
    return names


def _help(capsys, monkeypatch, path) -> str:
    monkeypatch.setenv("COLUMNS", str(WIDTH))
    monkeypatch.delenv("TERMINAL_WIDTH", raising=False)
    from typer import rich_utils

    monkeypatch.setattr(rich_utils, "MAX_WIDTH", None)
    assert main([*path, "--help"]) == 0
    return capsys.readouterr().out


def test_every_command_and_group_is_walked():
    names = {" ".join(p) for p, _ in NODES}
    assert {"", "demo", "evaluate", "mocap", "train-recognizer", "build-graph", "demo make-dataset"} <= names


@pytest.mark.parametrize("path", [p for p, _ in NODES], ids=[" ".join(p) or "vidstyle" for p, _ in NODES])
def test_help_fits_80_columns(path, capsys, monkeypatch):
    cmd = dict(NODES)[path]
    text = _help(capsys, monkeypatch, list(path))
    wide = [ln for ln in text.splitlines() if len(ln.rstrip()) > WIDTH]
    assert not wide, wide
    assert "…" not in text, [ln for ln in text.splitlines() if "…" in ln]
    for name in _names(cmd):
        shown = re.escape(name) if name.startswith("-") else re.escape(name) + r"(?:\.\.\.)?"
        assert re.search(rf"(?<![\w-]){shown}(?![\w-])", text, re.IGNORECASE if not name.startswith("-") else 0), name
    for sub in getattr(cmd, "commands", {}).values():  # a group lists its commands by their full names
        if not sub.hidden:
            assert re.search(rf"(?<![\w-]){re.escape(sub.name)}(?![\w-])", text), sub.name
