"""Every command's --help shows its help texts as written (bracketed defaults survive Rich markup) and
shows on/off flags without a value type."""

from __future__ import annotations

import re

import pytest
import typer

from vidstyle.cli import app, main


def _commands(cmd, path=()):
    subs = getattr(cmd, "commands", None)
    if subs:
        for name, sub in sorted(subs.items()):
            yield from _commands(sub, (*path, name))
    else:
        yield path, cmd


COMMANDS = list(_commands(typer.main.get_command(app)))


def _help(capsys, monkeypatch, args) -> str:
    monkeypatch.setenv("COLUMNS", "1000")  # no wrapping: every help text stays on one line
    assert main([*args, "--help"]) == 0
    return capsys.readouterr().out


def test_every_command_is_walked():
    names = {" ".join(p) for p, _ in COMMANDS}
    assert {"demo make-dataset", "learn-style", "generate", "report", "evaluate style"} <= names


@pytest.mark.parametrize("path", [p for p, _ in COMMANDS], ids=[" ".join(p) for p, _ in COMMANDS])
def test_help_shows_brackets_and_flags_take_no_value(path, capsys, monkeypatch):
    cmd = dict(COMMANDS)[path]
    text = _help(capsys, monkeypatch, list(path))
    assert "<bool>" not in text
    for p in cmd.params:
        help_text = getattr(p, "help", None) or ""
        for bracket in re.findall(r"\[[^\]]*\]", help_text):
            assert bracket in text, (p.name, bracket)
        if getattr(p, "is_flag", False):
            line = next(ln for ln in text.splitlines() if ln.strip("│ *").split()[:1] == [p.opts[0]])
            before_help = line.split(help_text[:12])[0] if help_text else line
            assert not re.search(r"<\w+>", before_help), line


def test_demo_make_dataset_help_shows_its_defaults(capsys, monkeypatch):
    text = _help(capsys, monkeypatch, ["demo", "make-dataset"])
    for shown in ("[front,left,right; --small: front,left]", "[same as --views]", "plain [texture: brick, grass or gravel]",
                  "[10; --small: 4]"):
        assert shown in text, shown
    small = next(ln for ln in text.splitlines() if "--small" in ln and "A small dataset" in ln)
    assert "<" not in small.split("A small dataset")[0]


def test_option_declarations_shared_by_two_commands_are_escaped_once(capsys, monkeypatch):
    from vidstyle.commands import style as style_cmd

    shared = style_cmd._MIN_CONF
    original = shared.help
    try:
        shared.help = "Frames below this confidence are dropped [0.5]."
        shared._vidstyle_literal = False
        from vidstyle import cli

        cli._literal_help(cli.app)
        cli._literal_help(cli.app)  # idempotent
        for args in (["learn-style"], ["evaluate", "style"]):
            text = _help(capsys, monkeypatch, args)
            assert "dropped [0.5]." in text and "\\[" not in text, args
        for args in (["demo", "make-dataset"],):
            assert "[10; --small: 4]" in _help(capsys, monkeypatch, args)  # others not escaped twice
    finally:
        shared.help = original
