"""The reconstruction's defaults are the values scripts/validate_reconstruct.py chose on the validation
performers (pipelines/kickboxing/validation/reconstruct.json), and the CLI and the library default to them."""

from __future__ import annotations

import inspect
import itertools
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
            D.REFINE_SMOOTH_FRAMES, D.CONTACT_THRESHOLD, D.CONTACT_GAP_S, D.PIN_DRIFT) == (
        chosen["method"], chosen["k"], chosen["n_blend"], chosen["window_s"], chosen["smooth_frames"],
        chosen["pin_max_offset"], chosen["refine_prior"], chosen["refine_smooth_frames"],
        chosen["contact_threshold"], chosen["contact_gap_s"], chosen["pin_drift"])
    scores = [r["mpjpe_root_relative_mm"] for r in doc["table"]]
    best = [r for r in doc["table"] if all(r[k] == v for k, v in chosen.items())]
    # the pose error is the search's score; the smoothing of the refined pose may give up POSE_TOLERANCE of it
    assert len(best) == 1 and best[0]["mpjpe_root_relative_mm"] <= (min(scores) + doc["tie_mm"] * 2) * (1 + doc["pose_tolerance"])
    tol = 1 + doc["pose_tolerance"]
    contact = ("contact_threshold", "contact_gap_s", "pin_drift")
    # the refined pose's smoothing was chosen with the contacts at their starting values
    at_start = {**chosen, **{k: doc["start"][k] for k in contact}}
    same = [r for r in doc["table"] if all(r[k] == v for k, v in at_start.items() if k != "refine_smooth_frames")]
    assert {r["refine_smooth_frames"] for r in same} == set(doc["candidates"]["refine_smooth_frames"])
    smooth = [r for r in same if r["mpjpe_root_relative_mm"] <= min(x["mpjpe_root_relative_mm"] for x in same) * tol]
    assert min(smooth, key=lambda r: r["acceleration_error_mm_per_frame2"])["refine_smooth_frames"] == chosen["refine_smooth_frames"]
    # then the contacts, every combination: the least skate within the pose tolerance of their best
    combos = [r for r in doc["table"] if all(r[k] == v for k, v in chosen.items() if k not in contact)]
    assert ({tuple(r[k] for k in contact) for r in combos}
            == set(itertools.product(*(doc["candidates"][k] for k in contact))))
    ok = [r for r in combos if r["mpjpe_root_relative_mm"] <= min(x["mpjpe_root_relative_mm"] for x in combos) * tol]
    assert best[0]["foot_skate_mm_per_frame"] == min(r["foot_skate_mm_per_frame"] for r in ok)
    assert set(doc["per_method"]) == {"nn", "olng", "subsequence"}
    assert "p02" not in json.dumps(doc["videos"]) and "p04" not in json.dumps(doc["videos"])  # test performers


def test_library_and_cli_default_to_them():
    p = Reconstructor().get_params()
    assert (p["method"], p["k"], p["n_blend"], p["window_s"], p["smooth_frames"], p["pin_max_offset"],
            p["refine_prior"], p["refine_smooth_frames"], p["contact_threshold"], p["contact_gap_s"],
            p["pin_drift"]) == (D.METHOD, D.K, D.N_BLEND, D.WINDOW_S, D.SMOOTH_FRAMES, D.PIN_MAX_OFFSET,
                                D.REFINE_PRIOR, D.REFINE_SMOOTH_FRAMES, D.CONTACT_THRESHOLD, D.CONTACT_GAP_S,
                                D.PIN_DRIFT)
    sig = inspect.signature(reconstruct_cmd).parameters
    assert sig["method"].default.default == D.METHOD
    assert sig["k"].default.default == D.K and sig["blend"].default.default == D.N_BLEND
    assert sig["window"].default.default == D.WINDOW_S and sig["smooth"].default.default == D.SMOOTH_FRAMES
    assert sig["refine"].default.default is (D.REFINE_PRIOR is not None)
    assert sig["contact_threshold"].default.default == D.CONTACT_THRESHOLD
    assert sig["contact_gap"].default.default == D.CONTACT_GAP_S and sig["pin_drift"].default.default is D.PIN_DRIFT
