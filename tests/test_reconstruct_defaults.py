"""The reconstruction's defaults are the values scripts/validate_reconstruct.py chose on the validation
performers (pipelines/kickboxing/validation/reconstruct.json), and the CLI and the library default to them."""

from __future__ import annotations

import inspect
import json
from pathlib import Path

from vidstyle.commands.reconstruct import reconstruct as reconstruct_cmd
from vidstyle.reconstruct import defaults as D
from vidstyle.reconstruct.core import Reconstructor

VALIDATION = Path(__file__).resolve().parents[1] / "pipelines" / "kickboxing" / "validation" / "reconstruct.json"


def test_defaults_are_the_validated_choice():
    doc = json.loads(VALIDATION.read_text())
    chosen = doc["chosen"]
    assert (D.METHOD, D.K, D.N_BLEND, D.WINDOW_S, D.SMOOTH_FRAMES, D.PIN_MAX_OFFSET, D.REFINE_PRIOR,
            D.REFINE_SMOOTH_FRAMES) == (
        chosen["method"], chosen["k"], chosen["n_blend"], chosen["window_s"], chosen["smooth_frames"],
        chosen["pin_max_offset"], chosen["refine_prior"], chosen["refine_smooth_frames"])
    scores = [r["mpjpe_root_relative_mm"] for r in doc["table"]]
    best = [r for r in doc["table"] if all(r[k] == v for k, v in chosen.items())]
    # the pose error is the search's score; the smoothing of the refined pose may give up POSE_TOLERANCE of it
    assert len(best) == 1 and best[0]["mpjpe_root_relative_mm"] <= (min(scores) + doc["tie_mm"] * 2) * (1 + doc["pose_tolerance"])
    same = [r for r in doc["table"] if all(r[k] == v for k, v in chosen.items() if k != "refine_smooth_frames")]
    assert {r["refine_smooth_frames"] for r in same} == set(doc["candidates"]["refine_smooth_frames"])
    assert best[0]["acceleration_error_mm_per_frame2"] == min(
        r["acceleration_error_mm_per_frame2"] for r in same
        if r["mpjpe_root_relative_mm"] <= min(x["mpjpe_root_relative_mm"] for x in same) * (1 + doc["pose_tolerance"]))
    assert set(doc["per_method"]) == {"nn", "olng", "subsequence"}
    assert "p02" not in json.dumps(doc["videos"]) and "p04" not in json.dumps(doc["videos"])  # test performers


def test_library_and_cli_default_to_them():
    p = Reconstructor().get_params()
    assert (p["method"], p["k"], p["n_blend"], p["window_s"], p["smooth_frames"], p["pin_max_offset"],
            p["refine_prior"], p["refine_smooth_frames"]) == (D.METHOD, D.K, D.N_BLEND, D.WINDOW_S, D.SMOOTH_FRAMES,
                                                              D.PIN_MAX_OFFSET, D.REFINE_PRIOR, D.REFINE_SMOOTH_FRAMES)
    sig = inspect.signature(reconstruct_cmd).parameters
    assert sig["method"].default.default == D.METHOD
    assert sig["k"].default.default == D.K and sig["blend"].default.default == D.N_BLEND
    assert sig["window"].default.default == D.WINDOW_S and sig["smooth"].default.default == D.SMOOTH_FRAMES
    assert sig["refine"].default.default is (D.REFINE_PRIOR is not None)
