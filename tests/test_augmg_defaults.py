"""The AugMG defaults of the CLI are the values scripts/validate_augmg.py chose on the validation
performers (pipelines/kickboxing/validation/augmg.json), so a rerun of the validation that changes them
fails here until the CLI follows."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from vidstyle.commands import augmg as cmd

VALIDATION = Path(__file__).resolve().parents[1] / "pipelines" / "kickboxing" / "validation" / "augmg.json"
PARAMS = Path(__file__).resolve().parents[1] / "pipelines" / "kickboxing" / "params.yaml"


def _per_source(values: list[str]) -> dict[str, float]:
    return {s: float(v) for s, v in (x.split("=") for x in values)}


@pytest.fixture(scope="module")
def chosen() -> dict:
    return json.loads(VALIDATION.read_text())


def test_matching_defaults_are_the_validated_ones(chosen):
    assert (cmd.SEGMENT, cmd.CONTEXT, cmd.SCORES) == (chosen["segment"], chosen["context"], chosen["scores"])
    assert cmd.FORESHORTENING == chosen.get("foreshortening", False)
    assert (cmd.PLACE, cmd.ANCHOR, cmd.HOLD) == (chosen["place"], chosen["anchor"], chosen["hold"])
    import yaml

    assert yaml.safe_load(PARAMS.read_text())["augmg"]["context"] == chosen["context"]
    assert cmd.POSE_SCALES == chosen.get("pose", {}).get("scales")
    keys = ("segment", "context", "scores", "k", "foreshortening", "place", "anchor", "hold")
    best = [r for r in chosen["table"] if (r.get("pose", {}), *(r[x] for x in keys))
            == (chosen.get("pose", {}), *(chosen[x] for x in keys))]
    assert len(best) == 1
    assert best[0]["estimated_mean_cross_validated"] == max(r["estimated_mean_cross_validated"] for r in chosen["table"])


@pytest.mark.parametrize("option,key", [("MAX_MATCH_COST", "max_match_cost"), ("MAX_ENH_COST", "max_enh_cost"),
                                        ("MIN_GAIN", "min_gain_mm")])
def test_acceptance_thresholds_are_the_validated_ones(chosen, option, key):
    cli = _per_source(getattr(cmd, option))
    want = {s: t[key] for s, t in chosen["thresholds"].items() if t[key] is not None}
    assert set(cli) == set(want)
    for s, v in want.items():
        assert cli[s] == pytest.approx(v, abs=5e-4)
