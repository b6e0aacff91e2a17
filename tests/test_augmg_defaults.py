"""AugMG's validated defaults: the library's (vidstyle.augmg.defaults) are the values
scripts/validate_augmg.py chose on the validation performers (pipelines/kickboxing/validation/augmg.json),
so a rerun of the validation that changes them fails here until the library follows; and every CLI option
and every library entry point defaults to those same values, so a Python user gets the CLI's numbers."""

from __future__ import annotations

import inspect
import json
from pathlib import Path

import pytest
import typer

from vidstyle import augmg
from vidstyle.augmg import defaults as D
from vidstyle.augmg.augment import augment_graph
from vidstyle.cli import app
from vidstyle.commands.augmg import per_source
from vidstyle.evaluation import augmg as evaluation

VALIDATION = Path(__file__).resolve().parents[1] / "pipelines" / "kickboxing" / "validation" / "augmg.json"
PARAMS = Path(__file__).resolve().parents[1] / "pipelines" / "kickboxing" / "params.yaml"


@pytest.fixture(scope="module")
def chosen() -> dict:
    return json.loads(VALIDATION.read_text())


def test_matching_defaults_are_the_validated_ones(chosen):
    assert (D.SEGMENT, D.CONTEXT, D.SCORES, D.K) == (chosen["segment"], chosen["context"], chosen["scores"], chosen["k"])
    assert D.FORESHORTENING == chosen.get("foreshortening", False)
    assert (D.PLACE, D.ANCHOR, D.HOLD) == (chosen["place"], chosen["anchor"], chosen["hold"])
    import yaml

    assert yaml.safe_load(PARAMS.read_text())["augmg"]["context"] == chosen["context"]
    assert D.POSE_SCALES == chosen.get("pose", {}).get("scales")
    # the pipeline's pose_marks stage runs the shipped model with those settings
    scales = yaml.safe_load(PARAMS.read_text())["augmg"]["pose_scales"]
    assert scales == ("" if D.POSE_SCALES is None else "--scales " + ",".join(f"{x:g}" for x in D.POSE_SCALES))
    keys = ("segment", "context", "scores", "k", "foreshortening", "place", "anchor", "hold")
    best = [r for r in chosen["table"] if (r.get("pose", {}), *(r[x] for x in keys))
            == (chosen.get("pose", {}), *(chosen[x] for x in keys))]
    assert len(best) == 1
    assert best[0]["estimated_mean_cross_validated"] == max(r["estimated_mean_cross_validated"] for r in chosen["table"])


@pytest.mark.parametrize("name,key", [("MAX_MATCH_COST", "max_match_cost"), ("MAX_ENH_COST", "max_enh_cost"),
                                      ("MIN_GAIN", "min_gain_mm")])
def test_acceptance_thresholds_are_the_validated_ones(chosen, name, key):
    lib = getattr(D, name)
    want = {s: t[key] for s, t in chosen["thresholds"].items() if t[key] is not None}
    assert set(lib) == set(want)
    for s, v in want.items():
        assert lib[s] == pytest.approx(v, abs=5e-4)
    # the evaluation's per-source table is the same numbers, None where the validation chose none
    assert {s: t[key] for s, t in evaluation.THRESHOLDS.items()} == {s: lib.get(s) for s in chosen["thresholds"]}


def _options(*path: str) -> dict:
    """{parameter name: default} of the command ``vidstyle <path>`` as the CLI parses it."""
    cmd = typer.main.get_command(app)
    for p in path:
        cmd = cmd.commands[p]
    return {p.name: p.default for p in cmd.params if not p.required}


def _library_defaults(fn) -> dict:
    return {n: p.default for n, p in inspect.signature(fn).parameters.items() if p.default is not inspect.Parameter.empty}


# CLI command -> (library function, {CLI name: library name (None: not compared)} where they differ)
PAIRS = [
    (("match-pose",), augmg.match_poses, {}),
    (("augment",), augmg.augment, {}),
    # augment_graph's max_match_cost is one source's threshold (augment picks it by the poses' source)
    (("augment",), augment_graph, {"views": "n_views", "scores": "use_scores", "max_match_cost": None}),
    (("evaluate", "augmg"), evaluation.evaluate, {"transitions": None}),  # a path there, a flag here
    # evaluate_augmg's scalar thresholds apply to every source; its per-source ones are ``thresholds``
    (("evaluate", "augmg"), evaluation.evaluate_augmg, {"views": "n_views", "scores": "use_scores",
                                                        "max_match_cost": None, "max_enh_cost": None}),
]


@pytest.mark.parametrize("command,fn,rename", PAIRS, ids=lambda x: getattr(x, "__name__", None) or str(x))
def test_cli_defaults_are_the_library_defaults(command, fn, rename):
    cli, lib = _options(*command), _library_defaults(fn)
    shared = [n for n in cli if rename.get(n, n) in lib and n not in ("jobs", "scheduler")]
    assert not [n for n in cli if n in lib and n not in shared and n not in ("jobs", "scheduler")
                and rename.get(n, n) is not None]
    assert len(shared) >= 5, shared  # the comparison covers the options that matter
    for name in shared:
        want, got = lib[rename.get(name, name)], cli[name]
        if name in ("max_match_cost", "max_enh_cost", "min_gain"):
            got = per_source(list(got), f"--{name}")
        if isinstance(want, tuple):  # a sequence parameter (poses, poses_dir): empty either way
            want = list(want)
        if name == "pose_scales":
            got = None if got is None else [float(x) for x in got.split(",")]
        assert got == want, f"vidstyle {' '.join(command)} --{name}: CLI default {got!r}, library {want!r}"


def test_library_defaults_are_the_defaults_module():
    want = {"k": D.K, "context": D.CONTEXT, "anchor": D.ANCHOR, "hold": D.HOLD, "foreshortening": D.FORESHORTENING}
    for fn in (augmg.augment, evaluation.evaluate):
        got = _library_defaults(fn)
        assert {k: got[k] for k in want} == want
        assert got["scores"] == D.SCORES
    ev = _library_defaults(evaluation.evaluate)
    assert (ev["segment"], ev["place"], ev["max_match_cost"], ev["max_enh_cost"], ev["min_gain"]) == (
        D.SEGMENT, D.PLACE, D.MAX_MATCH_COST, D.MAX_ENH_COST, D.MIN_GAIN)
    assert _library_defaults(evaluation.evaluate_augmg)["thresholds"] == evaluation.THRESHOLDS
