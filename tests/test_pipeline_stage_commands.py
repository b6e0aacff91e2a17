"""The demo pipeline's stage commands as the shell runs them, with a stand-in ``vidstyle`` on ``PATH``.

Several stages of ``pipelines/kickboxing/dvc.yaml`` start one command in the background and run another
beside it (``cmd & pid=$!; cmd2; status=$?; wait "$pid" && exit "$status"``) or fan out over ``xargs -P``.
DVC trusts a stage's exit status: one that reports success while a command in it failed would record
outputs that were never written. Each such stage is run here once with every command succeeding and once
with each of its ``vidstyle`` commands failing in turn; the stand-in logs its arguments, so the test also
sees that every command ran (including the one beside a failure).
"""

from __future__ import annotations

import os
import re
import stat
import subprocess
from pathlib import Path

import pytest
import yaml

PIPELINE = Path(__file__).resolve().parents[1] / "pipelines" / "kickboxing"

STUB = """#!/bin/sh
# stand-in vidstyle: log the arguments, fail when they start with $FAIL
echo "$*" >> "$LOG"
sleep 0.2
case "$*" in
  "$FAIL"*) exit 3 ;;
esac
exit 0
"""


def _params() -> dict:
    return yaml.safe_load((PIPELINE / "params.yaml").read_text())


def _lookup(params: dict, dotted: str):
    value = params
    for key in dotted.split("."):
        value = value[key]
    return value


def _commands() -> dict[str, str]:
    """Every stage's command with DVC's ``${...}`` filled in from params.yaml (what ``dvc repro`` runs)."""
    params = _params()
    stages = yaml.safe_load((PIPELINE / "dvc.yaml").read_text())["stages"]

    def fill(text: str) -> str:
        return re.sub(r"\$\{([A-Za-z_][\w.]*)\}", lambda m: str(_lookup(params, m.group(1))), text)

    return {name: fill(stage["cmd"]) for name, stage in stages.items() if isinstance(stage.get("cmd"), str)}


def _concurrent_stages() -> dict[str, str]:
    return {n: c for n, c in _commands().items() if re.search(r"&\s+\w+=\$!", c) or "xargs -P" in c}


def _vidstyle_subcommands(cmd: str) -> list[str]:
    """The first words after each ``vidstyle`` in a command (its subcommand, e.g. ``evaluate style``)."""
    out = []
    for m in re.finditer(r"\bvidstyle ((?:evaluate |demo )?[a-z][\w-]*)", cmd):
        if m.group(1) not in out:
            out.append(m.group(1))
    return out


def _run(cmd: str, tmp_path: Path, fail: str | None) -> tuple[int, list[str]]:
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir(exist_ok=True)
    stub = bin_dir / "vidstyle"
    stub.write_text(STUB)
    stub.chmod(stub.stat().st_mode | stat.S_IEXEC)
    log = tmp_path / f"log-{fail or 'none'}.txt".replace(" ", "_")
    log.write_text("")
    work = tmp_path / "work"
    work.mkdir(exist_ok=True)
    env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ['PATH']}", "LOG": str(log),
           "FAIL": fail or "no such command"}
    res = subprocess.run(["sh", "-c", cmd], check=False, cwd=work, env=env, capture_output=True, text=True, timeout=60)
    return res.returncode, log.read_text().splitlines()


def test_the_pipeline_has_stages_that_run_commands_side_by_side():
    stages = _concurrent_stages()
    # the stages the pipeline merged for its wall time (docs/pipeline.md); more may come, none may go silently
    assert {"learn_style", "augment", "synthesize", "reconstruct", "action_style", "pose_marks"} <= set(stages)
    for name in ("learn_style", "augment", "reconstruct", "action_style"):
        assert len(_vidstyle_subcommands(stages[name])) == 2, name


@pytest.mark.parametrize("stage", sorted(_concurrent_stages()))
def test_a_stage_succeeds_only_when_every_command_in_it_does(stage, tmp_path):
    cmd = _concurrent_stages()[stage]
    subcommands = _vidstyle_subcommands(cmd)
    status, calls = _run(cmd, tmp_path, None)
    assert status == 0, (stage, calls)
    ran = {s for s in subcommands if any(c.startswith(s) for c in calls)}
    assert ran == set(subcommands), (stage, calls)
    for failing in subcommands:
        status, calls = _run(cmd, tmp_path, failing)
        assert status != 0, f"{stage}: exit 0 although `vidstyle {failing}` failed"
        # the command beside the failing one still ran to its end (nothing is left running in the background)
        assert {s for s in subcommands if any(c.startswith(s) for c in calls)} == set(subcommands), (stage, calls)
