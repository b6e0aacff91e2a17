"""Numeric options are checked where they enter (issue 33, items 1 and 7), through the real command line:
NaN, infinity, zero, negative and huge values of every option family are refused before any work, with
one stderr line naming the flag, exit status 2 and no output written; and the tracebacks of item 7 are
one-line errors.

Each case is its own ``python -m vidstyle`` process (the unchecked code ran out of memory or ran for
minutes on some of them), under an address-space limit and a timeout, a few at a time.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LIMIT_BYTES = 3 << 30  # a case that allocates more fails (exit 3 or killed), it does not take the machine
TIMEOUT = 60


@dataclass
class Case:
    name: str
    args: list[str]
    flag: str  # the error line starts with "vidstyle: error: <flag>"
    out: Path | None
    result: dict = field(default_factory=dict)


def _limit() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT_BYTES, LIMIT_BYTES))


def _run(case: Case) -> Case:
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""), COLUMNS="200")
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, "-m", "vidstyle", *case.args], capture_output=True, text=True, env=env,
                           timeout=TIMEOUT, preexec_fn=_limit, check=False)
        case.result = {"code": p.returncode, "err": p.stderr, "out": p.stdout}
    except subprocess.TimeoutExpired:
        case.result = {"code": "timeout", "err": "", "out": ""}
    case.result["seconds"] = time.perf_counter() - t0
    return case


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    from vidstyle.formats.annotations import (Annotations, ActionSpan, Transition, VideoAnnotations,
                                              file_sha256, write_annotations)
    from vidstyle.video import write_video
    from vidstyle.video.numbered import numbered_frame

    d = tmp_path_factory.mktemp("numbers")
    v = write_video((numbered_frame(i, 160, 120) for i in range(40)), d / "v.mp4", 20.0)
    entry = VideoAnnotations(str(v), file_sha256(v), 40, 20.0, transitions=[Transition(20, "Jab", "Hook", "accepted")],
                             segments=[ActionSpan(0, 15, "Jab"), ActionSpan(25, 40, "Hook")])
    write_annotations(d / "ann.json", Annotations(["Jab", "Hook"], [entry], 0))
    (d / "exists.txt").write_text("a file, not a directory\n")
    (d / "zero.bvh").write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n"
                                "  End Site\n  {\n    OFFSET 0 1 0\n  }\n}\nMOTION\nFrames: 0\nFrame Time: 0.05\n")
    import cv2

    ok, png = cv2.imencode(".png", numbered_frame(3, 160, 120))
    (d / "image.mp4").write_bytes(png.tobytes())
    (d / "out").mkdir()
    return d


NAN_INF = ["nan", "inf", "-inf"]
HUGE_INT = "1000000000"


def _cases(d: Path) -> list[Case]:
    out = d / "out"
    v, ann = str(d / "v.mp4"), str(d / "ann.json")
    cases: list[Case] = []

    def family(cmd: str, args: list[str], flag: str, values: list[str], dest: Path) -> None:
        for value in values:
            cases.append(Case(f"{cmd}{flag}={value}", [*args, flag, value], flag, dest))

    ev_out = out / "augmg.json"
    ev = ["evaluate", "augmg", "--dataset", str(d / "no-dataset"), "--library", str(d / "no-library"), "-a", ann,
          "-o", str(ev_out)]
    family("evaluate-augmg", ev, "--context", [*NAN_INF, "-1", "1.5", "1001", HUGE_INT], ev_out)
    family("evaluate-augmg", ev, "--k", [*NAN_INF, "0", "-1", HUGE_INT], ev_out)
    family("evaluate-augmg", ev, "--views", ["nan", "0", "-1", "361", "100000"], ev_out)
    family("evaluate-augmg", ev, "--noise", [*NAN_INF, "-1", "1e400", "1e9"], ev_out)
    pose_out = out / "p.json"
    pose = ["pose", v, "-a", ann, "-o", str(pose_out)]
    family("pose", pose, "--context", ["nan", "inf", "-1", HUGE_INT], pose_out)
    cases.append(Case("pose--context-beyond-video", [*pose, "--context", "40"], "--context", pose_out))
    aug_out = out / "g.npz"
    aug = ["augment", "-g", str(d / "no-graph.npz"), "-a", ann, "-l", str(d / "no-library"), "-o", str(aug_out)]
    family("augment", aug, "--context", ["nan", "-1", HUGE_INT], aug_out)
    family("augment", aug, "--edges-per-side", ["nan", "0", "-1", "1000000"], aug_out)
    family("augment", aug, "--enhancement-cost", [*NAN_INF, "0", "-1", "1e400"], aug_out)
    match_out = out / "m.json"
    match = ["match-pose", str(d / "no-poses.json"), "-l", str(d / "no-library"), "-o", str(match_out)]
    family("match-pose", match, "--views", ["nan", "0", "-1", "100000"], match_out)
    family("match-pose", match, "--fps", [*NAN_INF, "0", "-1", "1e9"], match_out)
    train_out = out / "r.joblib"
    train = ["train-recognizer", str(d / "no-features.npz"), "--annotations", ann, "--vocab",
             str(d / "no-vocab.npz"), "-o", str(train_out)]
    family("train-recognizer", train, "--context", ["nan", "-1", HUGE_INT], train_out)
    family("train-recognizer", train, "--window", ["nan", "0", "-1", HUGE_INT], train_out)
    family("train-recognizer", train, "--C", [*NAN_INF, "0", "-1", "1e400"], train_out)
    ann_out = out / "a.json"
    serve = ["annotate", v, "-a", str(ann_out), "--no-browser", "--port", "0"]
    family("annotate", serve, "--max-body-mb", [*NAN_INF, "0", "-1", "1e-9", "1e9"], ann_out)
    family("annotate", serve, "--classes", [",,,", " , "], ann_out)
    feat_out = out / "features"
    feat = ["features", v, "-o", str(feat_out), "-j", "1"]
    family("features", feat, "--fps", [*NAN_INF, "-1", "1e9"], feat_out)
    family("features", feat[:-2], "--jobs", ["0", "-2", "1000000", "nan"], feat_out)
    # item 7: tracebacks once
    cases.append(Case("features-o-existing-file", ["features", v, "-o", str(d / "exists.txt"), "-j", "1"],
                      str(d / "exists.txt"), None))
    cases.append(Case("pose-o-proc", ["pose", v, "--frames", "0", "-o", "/proc/nope/p.json"], "/proc/nope/p.json", None))
    cases.append(Case("bvh-zero-frames", ["mocap", "info", str(d / "zero.bvh")], f"{d / 'zero.bvh'}:12: no motion", None))
    cases.append(Case("image-as-video", ["features", str(d / "image.mp4"), "-o", str(out / "fimg"), "-j", "1"],
                      f"{d / 'image.mp4'}: is a still image", out / "fimg" / "image.npz"))
    return cases


@pytest.fixture(scope="module")
def results(world):
    with ThreadPoolExecutor(max_workers=3) as pool:
        return {c.name: c for c in pool.map(_run, _cases(world))}


def _names() -> list[str]:
    return [c.name for c in _cases(Path("/nonexistent"))]


@pytest.mark.slow  # about 80 start-ups of the command line (~25 s of CPU, three at a time)
@pytest.mark.parametrize("name", _names())
def test_bad_number_is_one_line_exit_2_before_any_work(results, name):
    case = results[name]
    r = case.result
    lines = r["err"].splitlines()
    assert r["code"] == 2, (r["code"], r["err"][-2000:])
    assert len(lines) == 1 and lines[0].startswith(f"vidstyle: error: {case.flag}"), r["err"]
    assert "Traceback" not in r["err"] and r["out"] == ""
    assert r["seconds"] < 30, r["seconds"]
    if case.out is not None:
        assert not case.out.exists(), case.out


def test_help_documents_the_ranges():
    from typer.testing import CliRunner

    from vidstyle.cli import app

    runner = CliRunner()
    text = " ".join(runner.invoke(app, ["augment", "--help"], env={"COLUMNS": "400"}).output.split())
    for help_end in ("frame count). Range: 0..1000.", "library is projected at. Range: 1..360.",
                     "edges per mark. Range: 1..1000.", "prefers the enhancement). Range: > 0."):
        assert help_end in text, help_end


def test_library_bounds_too():
    """The library functions check the same ranges (a caller that is not the CLI)."""
    from vidstyle.augmg.augment import check_augment_params
    from vidstyle.errors import ParameterError
    from vidstyle.evaluation.augmg import check_evaluate_params

    for kw in ({"context": 10**9}, {"n_views": 100000}, {"edges_per_side": 10**6}, {"enhancement_cost": float("nan")},
               {"enhancement_cost": -1.0}):
        with pytest.raises(ParameterError):
            check_augment_params(**kw)
    for kw in ({"context": 10**9}, {"k": 0}, {"views": 361}, {"noise": float("nan")}):
        with pytest.raises(ParameterError):
            check_evaluate_params(**kw)


def test_context_sum_is_bounded_by_the_video():
    import numpy as np
    import scipy.sparse as sp

    from vidstyle.recognition.histograms import context_sum

    counts = sp.csr_matrix(np.eye(5, 3))
    t0 = time.perf_counter()
    got = context_sum(counts, 10**9).toarray()
    assert time.perf_counter() - t0 < 1.0
    assert np.array_equal(got, np.tile(np.eye(5, 3).sum(axis=0), (5, 1)))


def test_json_of_this_module_is_valid():  # the case table builds (names unique)
    names = _names()
    assert len(names) == len(set(names)) and json.dumps(names)
