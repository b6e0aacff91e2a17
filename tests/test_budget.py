"""The memory budget (issue 33, "a resource budget"): work whose estimated memory does not fit what the
machine can give is refused before it allocates, with one line naming the option, exit status 2, quickly
and without output. ``VIDSTYLE_MEMORY_LIMIT`` stands in for a small machine."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from vidstyle import budget
from vidstyle.errors import InputError, ParameterError

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("text,expected", [("1024", 1024), ("4G", 4 << 30), ("512m", 512 << 20), ("1.5K", 1536),
                                           ("2GiB", 2 << 30), ("3 MB", 3 << 20)])
def test_parse_size(text, expected):
    assert budget.parse_size(text) == expected


@pytest.mark.parametrize("text", ["", "G", "-1G", "nanG", "inf", "4X", "1e400"])
def test_parse_size_refuses_what_is_not_a_size(text):
    with pytest.raises(ValueError):
        budget.parse_size(text)


def test_the_limit_lowers_what_is_available_and_a_bad_one_is_an_input_error(monkeypatch):
    monkeypatch.delenv("VIDSTYLE_MEMORY_LIMIT", raising=False)
    free = budget.available_bytes()
    assert free is not None and free > 0  # Linux: /proc/meminfo
    monkeypatch.setenv("VIDSTYLE_MEMORY_LIMIT", "1M")
    assert budget.available_bytes() == 1 << 20
    monkeypatch.setenv("VIDSTYLE_MEMORY_LIMIT", "lots")
    with pytest.raises(InputError, match="VIDSTYLE_MEMORY_LIMIT"):
        budget.available_bytes()


def test_require_passes_what_fits_and_names_the_parameter_of_what_does_not(monkeypatch):
    monkeypatch.setenv("VIDSTYLE_MEMORY_LIMIT", "100M")
    budget.require(0.85 * (100 << 20), "work")  # exactly the headroom: allowed
    with pytest.raises(ParameterError) as e:
        budget.require(90 << 20, "the index", "n_views", "fewer views")
    assert e.value.param == "n_views" and "90 MB" in str(e.value) and "85 MB" in str(e.value)
    assert "fewer views" in str(e.value)
    with pytest.raises(InputError) as e:
        budget.require(1 << 40, "the clips")
    assert not isinstance(e.value, ParameterError) and "1 TB" in str(e.value)


def test_library_index_checks_its_memory_before_projecting(monkeypatch):
    from vidstyle.augmg.index import BYTES_PER_INDEXED_POINT, LibraryClip, PoseIndex

    rng = np.random.default_rng(0)
    clips = [LibraryClip("c", rng.normal(size=(300, 15, 3)), 30.0)]
    need = 300 * 360 * BYTES_PER_INDEXED_POINT
    monkeypatch.setenv("VIDSTYLE_MEMORY_LIMIT", str(int(need / budget.HEADROOM) - 1000))
    with pytest.raises(ParameterError) as e:
        PoseIndex(n_views=360, stride=1).fit(clips)
    assert e.value.param == "n_views"
    assert PoseIndex(n_views=12, stride=1).fit(clips).n_frames == 300  # 30x less: fits


def test_pose_training_set_is_checked_against_its_views(monkeypatch):
    from vidstyle.recognition.poserecognizer import PoseRecognizer
    from vidstyle.recognition.posetraining import check_training_memory

    monkeypatch.setenv("VIDSTYLE_MEMORY_LIMIT", "64M")
    rec = PoseRecognizer()
    check_training_memory(rec, 1000)
    with pytest.raises(ParameterError) as e:
        check_training_memory(rec, 10_000_000)
    assert e.value.param == "views"


def test_motion_graph_estimate_grows_with_frames_and_tile():
    from vidstyle.motiongraph.graph import MotionGraph

    g = MotionGraph(n_jobs=2, tile=2048)
    base = g.memory_estimate(0, 31, 10)
    assert g.memory_estimate(100_000, 31, 10) - base == 100_000 * (31 * 640 + 1024)
    assert MotionGraph(n_jobs=2, tile=4096).memory_estimate(0, 31, 10) > 2.5 * base
    # the calibration the docstring states: 15070 and 29494 CMU frames measured at 329 and 676 MB
    assert MotionGraph(n_jobs=1).memory_estimate(15070, 31) > 329 << 20
    assert MotionGraph(n_jobs=1).memory_estimate(29494, 31) > 676 << 20


def _limit() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))


def _cli(args: list[str], limit: str, cwd: Path) -> tuple[subprocess.CompletedProcess, float]:
    env = dict(os.environ, PYTHONPATH=str(ROOT), VIDSTYLE_MEMORY_LIMIT=limit, COLUMNS="200")
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "vidstyle", *args], capture_output=True, text=True, env=env, cwd=cwd,
                       timeout=120, preexec_fn=_limit, check=False)
    return p, time.perf_counter() - t0


def test_features_at_full_size_is_refused_naming_height_and_the_working_size_runs(tmp_path):
    from vidstyle.video import write_video
    from vidstyle.video.numbered import numbered_frame

    v = write_video((numbered_frame(i, 640, 480) for i in range(12)), tmp_path / "v.mp4", 20.0)
    # full size: 640x480 x (128 x 46 + 64) bytes = 1.8 GB; the working 160x120: 114 MB
    p, seconds = _cli(["features", str(v), "--out", str(tmp_path / "f"), "--height", "0", "--jobs", "1"], "400M", tmp_path)
    assert p.returncode == 2, p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert line.startswith("vidstyle: error: --height:") and "640x480" in line and "GB" in line
    assert seconds < 30 and not (tmp_path / "f").exists()  # refused before the output directory is made
    p, _ = _cli(["features", str(v), "--out", str(tmp_path / "f"), "--jobs", "1"], "400M", tmp_path)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "f" / "v.npz").is_file()


def test_build_graph_beyond_the_budget_is_refused_before_the_distances(tmp_path, cmu_dir):
    clips = [str(cmu_dir / n) for n in ("02_01.bvh", "02_02.bvh")]
    out = tmp_path / "g.npz"
    p, seconds = _cli(["build-graph", *clips, "--out", str(out), "--tile", "8192", "--jobs", "1"], "1G", tmp_path)
    assert p.returncode == 2, p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert line.startswith("vidstyle: error: --tile:") and "motion graph" in line
    assert seconds < 30 and not out.exists()
