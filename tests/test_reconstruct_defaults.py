"""The reconstruction's defaults are the values scripts/validate_reconstruct.py chose on the validation
performers (pipelines/kickboxing/validation/reconstruct.json), and the CLI and the library default to them."""

from __future__ import annotations

import inspect
import itertools
import json
import math
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
    assert D.CONTACTS == doc["contacts"]
    tol = 1 + doc["pose_tolerance"]
    contact = ("contact_threshold", "contact_gap_s", "pin_drift")
    # the search ran with the contacts at their starting values until its last step
    at_start = {**chosen, **{k: doc["start"][k] for k in contact}}
    scores = [r["mpjpe_root_relative_mm"] for r in doc["table"] if all(r[k] == doc["start"][k] for k in contact)]
    best = [r for r in doc["table"] if all(r[k] == v for k, v in at_start.items())]
    # the pose error is the search's score; the fewest neighbours per frame (k) may give up POSE_TOLERANCE of it
    # for less computation, and the smoothing of the refined pose as much again
    assert len(best) == 1 and best[0]["mpjpe_root_relative_mm"] <= (min(scores) + doc["tie_mm"] * 2) * tol * tol
    assert chosen["k"] in doc["candidates"]["k"]
    same = [r for r in doc["table"] if all(r[k] == v for k, v in at_start.items() if k != "refine_smooth_frames")]
    assert {r["refine_smooth_frames"] for r in same} == set(doc["candidates"]["refine_smooth_frames"])
    smooth = [r for r in same if r["mpjpe_root_relative_mm"] <= min(x["mpjpe_root_relative_mm"] for x in same) * tol]
    assert min(smooth, key=lambda r: r["acceleration_error_mm_per_frame2"])["refine_smooth_frames"] == chosen["refine_smooth_frames"]
    # last the contacts, every combination with both 2D sources: per source the least skate within the pose
    # tolerance of its best; "default" the least mean skate within it of both (none such: the least worst ratio)
    every = set(itertools.product(*(doc["candidates"][k] for k in contact)))
    by_source = {}
    for src, table in (("ps", doc["table"]), ("blazepose", doc["table_blazepose"])):
        rows = {tuple(r[k] for k in contact): r for r in table if all(r[k] == v for k, v in chosen.items())}
        assert set(rows) == every
        by_source[src] = rows

    def skate(r):
        return math.inf if r["foot_skate_mm_per_frame"] is None else r["foot_skate_mm_per_frame"]

    lows = {src: min(r["mpjpe_root_relative_mm"] for r in rows.values()) for src, rows in by_source.items()}
    for src, rows in by_source.items():
        ok = [c for c in every if rows[c]["mpjpe_root_relative_mm"] <= lows[src] * tol]
        mine = tuple(doc["contacts"][src][k] for k in contact)
        assert mine in ok and skate(rows[mine]) == min(skate(rows[c]) for c in ok)
    ratio = {c: max(by_source[src][c]["mpjpe_root_relative_mm"] / lows[src] for src in by_source) for c in every}
    ok = [c for c in every if ratio[c] <= tol] or [min(every, key=ratio.get)]
    mean = {c: sum(skate(by_source[src][c]) for src in by_source) / 2 for c in ok}
    mine = tuple(doc["contacts"]["default"][k] for k in contact)
    assert mine in ok and mean[mine] == min(mean.values())
    assert set(doc["per_method"]) == {"nn", "olng", "subsequence"}
    assert "p02" not in json.dumps(doc["videos"]) and "p04" not in json.dumps(doc["videos"])  # test performers


def test_library_and_cli_default_to_them():
    p = Reconstructor().get_params()
    assert (p["method"], p["k"], p["n_blend"], p["window_s"], p["smooth_frames"], p["pin_max_offset"],
            p["refine_prior"], p["refine_smooth_frames"]) == (D.METHOD, D.K, D.N_BLEND, D.WINDOW_S, D.SMOOTH_FRAMES,
                                                              D.PIN_MAX_OFFSET, D.REFINE_PRIOR, D.REFINE_SMOOTH_FRAMES)
    # the contacts default to the 2D backend's validated values; a value given overrides its backend's
    assert (p["contact_threshold"], p["contact_gap_s"], p["pin_drift"]) == (None, None, None)
    for backend, want in (("ps", D.CONTACTS["ps"]), ("blazepose", D.CONTACTS["blazepose"]),
                          (None, D.CONTACTS["default"]), ("hog", D.CONTACTS["default"])):
        assert Reconstructor().contact_settings(backend) == want
    assert Reconstructor(contact_gap_s=1.0).contact_settings("ps") == {**D.CONTACTS["ps"], "contact_gap_s": 1.0}
    sig = inspect.signature(reconstruct_cmd).parameters
    assert sig["method"].default.default == D.METHOD
    assert sig["k"].default.default == D.K and sig["blend"].default.default == D.N_BLEND
    assert sig["window"].default.default == D.WINDOW_S and sig["smooth"].default.default == D.SMOOTH_FRAMES
    assert sig["refine"].default.default is (D.REFINE_PRIOR is not None)
    assert (sig["contact_threshold"].default.default, sig["contact_gap"].default.default,
            sig["pin_drift"].default.default) == (None, None, None)


def test_view_step_cost_is_the_view_tracking_validation_choice():
    from vidstyle.formats.validation import VIEW_TRACKING, read_validation

    doc = read_validation(VALIDATION.with_name("view_tracking.json"), VIEW_TRACKING)
    assert {"step_cost": D.VIEW_STEP_COST, "dwell_s": D.VIEW_DWELL_S} == doc["chosen"]
    rows, tol = doc["candidates"], doc["tolerance"]
    near = [r for r in rows if r["flips"] <= min(x["flips"] for x in rows) + tol]  # the rule, reapplied
    best = max(r["view_accuracy"] for r in near)
    pick = min((r for r in near if r["view_accuracy"] >= best - tol), key=lambda r: (r["step_cost"], r["dwell_s"]))
    assert {k: pick[k] for k in ("step_cost", "dwell_s")} == doc["chosen"]
    for r in rows:  # the pooled scores are the clips' frames
        assert r["frames"] == sum(c["frames"] for c in r["per_clip"])
        assert math.isclose(r["flips"] * r["frames"], sum(c["flips"] * c["frames"] for c in r["per_clip"]), abs_tol=1e-6)
    tested = {"05_01", "06_01"} | {f"{s}_" for s in ("03", "07", "08")}  # real-motion, held-out and pose test clips
    assert not any(v["clip"] in tested or v["clip"][:3] in tested for v in doc["videos"])
    assert {v["clip"][:2] for v in doc["videos"]} <= set(doc["subjects"])
    from vidstyle.reconstruct.core import Observation

    params = inspect.signature(Observation.from_poses).parameters
    assert params["view_step_cost"].default is None and params["view_dwell_s"].default is None
    # the library reads the defaults where it builds observations: a confident flicker to the back inside a
    # front video is tracked away (left and right exchanged) by default, as with the validated values given,
    # and kept when the tracking is off
    import numpy as np

    from vidstyle.formats.poses import PoseFrame, Poses
    from vidstyle.pose.viewtrack import RING

    def frame(i, view, scores):
        pts = np.column_stack([np.arange(30.0).reshape(15, 2) + 40 + i, np.full(15, 0.8)])
        return PoseFrame(i, view, pts, dict(zip(RING, scores)))

    frames = [frame(i, "front", (0.9, 0.04, 0.02, 0.04)) for i in range(12)]
    frames[5] = frame(5, "back", (0.3, 0.05, 0.6, 0.05))
    poses = Poses("v.mp4", "ps", frames)
    by_default = Observation.from_poses(poses, 20.0, (160, 120))
    given = Observation.from_poses(poses, 20.0, (160, 120), view_step_cost=D.VIEW_STEP_COST,
                                   view_dwell_s=D.VIEW_DWELL_S)
    off = Observation.from_poses(poses, 20.0, (160, 120), view_step_cost=0.0)
    np.testing.assert_array_equal(by_default.xy, given.xy)
    assert not np.array_equal(by_default.xy[5], off.xy[5])
    cli = inspect.signature(reconstruct_cmd).parameters  # the CLI's defaults are the validated ones
    assert cli["view_step_cost"].default.default == D.VIEW_STEP_COST
    assert cli["view_dwell"].default.default == D.VIEW_DWELL_S
