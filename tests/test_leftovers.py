"""No leftovers (issue 33, item 4): staging directories and writer temporaries are removed when a run
fails, swept by the next run of the same stage when a kill left them, and a failed run leaves no empty
output directory.

The stages that write into a directory: ``features`` (see tests/test_fileio.py), ``recognize --out-dir``,
``learn-style --out-dir``, ``pose --overlay`` and the staged ``demo make-dataset``, ``make-library``,
``make-cmu-dataset`` and the crowd scenes (built in a hidden sibling, ``.<name>.<8 chars>.tmp``).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from vidstyle import fileio
from vidstyle.cli import main
from vidstyle.errors import InputError

ROOT = Path(__file__).resolve().parents[1]


def _old(p: Path, seconds: float = 3600, data: bytes = b"partial") -> Path:
    if not p.exists():
        p.write_bytes(data)
    t = time.time() - seconds
    os.utime(p, (t, t))
    return p


def _old_dir(p: Path) -> Path:
    p.mkdir(parents=True)
    _old(p / "half.bvh")
    return _old(p)


def _hidden(d: Path) -> list[str]:
    return sorted(p.name for p in d.iterdir() if p.name.startswith("."))


def test_killed_make_library_leaves_a_staging_dir_the_next_run_sweeps(tmp_path):
    """kill -9 of ``demo make-library`` while it builds: its ``.lib.*.tmp/`` is removed by the next run
    (before: left for good beside the library)."""
    lib = tmp_path / "lib"
    args = ["demo", "make-library", "-o", str(lib), "--performers", "2", "--action-seconds", "2"]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "vidstyle", *args, "--jobs", "1"], cwd=tmp_path, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    t0 = time.monotonic()
    while not any(n.startswith(".lib.") for n in os.listdir(tmp_path)):
        if proc.poll() is not None or time.monotonic() - t0 > 300:
            proc.kill()
            pytest.fail("make-library ended (or never started) before its staging directory was seen")
        time.sleep(0.01)
    proc.kill()
    proc.wait()
    left = [n for n in os.listdir(tmp_path) if n.startswith(".lib.")]
    if lib.exists():  # the kill came after the rename: nothing to sweep, the case is not reproduced
        pytest.skip("make-library finished before the kill")
    assert left and left[0].endswith(".tmp")
    assert main([*args, "--jobs", "1"]) == 0
    assert (lib / "library.json").is_file()
    assert [n for n in os.listdir(tmp_path) if n.startswith(".")] == []


def test_sweep_staging_removes_only_stale_staging_dirs_of_that_output(tmp_path):
    out = tmp_path / "library"
    stale = _old_dir(tmp_path / ".library.k3j_x9a2.tmp")
    fresh = tmp_path / ".library.zzzzzzzz.tmp"
    fresh.mkdir()
    keep = [_old_dir(tmp_path / ".other.abcdefgh.tmp"),     # another output's
            _old_dir(tmp_path / ".library.abc.tmp"),        # not the writer's pattern
            _old_dir(tmp_path / "library.abcdefgh.tmp"),    # not hidden
            _old(tmp_path / ".library.ffffffff.tmp")]       # a file
    target = _old_dir(tmp_path / "elsewhere")
    (tmp_path / ".library.llllllll.tmp").symlink_to(target)  # a link: never followed
    os.utime(tmp_path / ".library.llllllll.tmp", (0, 0), follow_symlinks=False)
    assert fileio.sweep_staging(out, before=time.time() - 60) == [stale]
    assert not stale.exists() and fresh.is_dir() and all(p.exists() for p in keep)
    assert (target / "half.bvh").exists()
    assert fileio.sweep_staging(tmp_path / "missing" / "x") == []


def test_an_interrupted_replacement_is_undone_or_finished(tmp_path):
    """replace_dir killed between its renames left ``.<name>.old-<pid>`` (of a dead process): put back
    when the output is missing, removed when the new output is in place; a live process's is left."""
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True, check=True)
    pid = int(dead.stdout)
    out = tmp_path / "ds"
    (tmp_path / f".ds.old-{pid}").mkdir()
    (tmp_path / f".ds.old-{pid}" / "dataset.json").write_text("{}")
    fileio.sweep_staging(out)
    assert (out / "dataset.json").read_text() == "{}" and _hidden(tmp_path) == []
    (tmp_path / f".ds.old-{pid}").mkdir()
    assert fileio.sweep_staging(out) == [tmp_path / f".ds.old-{pid}"] and _hidden(tmp_path) == []
    (tmp_path / f".ds.old-{os.getpid()}").mkdir()
    assert fileio.sweep_staging(out) == [] and _hidden(tmp_path) == [f".ds.old-{os.getpid()}"]


def test_staged_dir_cleans_up_a_failed_build(tmp_path):
    out = tmp_path / "a" / "b" / "lib"
    with pytest.raises(RuntimeError), fileio.staged_dir(out) as tmp:
        (tmp / "clips").mkdir()
        (tmp / "clips" / "x.bvh").write_text("half")
        raise RuntimeError("a clip failed")
    assert not (tmp_path / "a").exists()  # no staging directory, no empty parents it made
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "old.json").write_text("{}")
    with pytest.raises(RuntimeError), fileio.staged_dir(tmp_path / "lib", overwrite=True):
        raise RuntimeError("failed")
    assert sorted(os.listdir(tmp_path)) == ["lib"] and (tmp_path / "lib" / "old.json").exists()
    with pytest.raises(InputError, match="not empty"), fileio.staged_dir(tmp_path / "lib"):
        pass
    assert sorted(os.listdir(tmp_path)) == ["lib"]
    stale = _old_dir(tmp_path / ".lib.q1w2e3r4.tmp")
    with fileio.staged_dir(tmp_path / "lib", overwrite=True) as tmp:
        (tmp / "new.json").write_text("{}")
        assert not stale.exists()
    assert sorted(os.listdir(tmp_path / "lib")) == ["new.json"] and sorted(os.listdir(tmp_path)) == ["lib"]
    assert (tmp_path / "lib").stat().st_mode & 0o777 == 0o777 & ~_umask()


def _umask() -> int:
    m = os.umask(0)
    os.umask(m)
    return m


def _video(tmp_path: Path) -> Path:
    from tests.test_features_cli import write_video

    p = tmp_path / "clip.avi"
    write_video(p, T=6)
    return p


def test_pose_overlays_sweep_stale_frames_and_a_failure_leaves_no_empty_dir(tmp_path):
    import numpy as np

    from vidstyle.formats.poses import PoseFrame, Poses
    from vidstyle.pose.overlay import write_overlays

    video = _video(tmp_path)
    pts = np.column_stack([np.linspace(5, 50, 15), np.linspace(5, 40, 15), np.ones(15)])
    frames = [PoseFrame(i, "front", pts.copy(), {"front": 1.0}) for i in range(3)]
    out = tmp_path / "ov" / "clip"
    with pytest.raises(Exception):  # noqa: B017 - whichever error the reader gives for a frame past the end
        write_overlays(video, Poses(str(video), "blazepose", [PoseFrame(99, "front", pts, {"front": 1.0})]), out)
    assert not (tmp_path / "ov").exists()  # before: an empty ov/clip/ was left
    out.mkdir(parents=True)
    stale = _old(out / ".000001.q1w2e3r4.tmp.jpg")
    other = _old(out / ".notes.q1w2e3r4.tmp.txt")
    assert write_overlays(video, Poses(str(video), "blazepose", frames), out) == 3
    assert sorted(os.listdir(out)) == [".notes.q1w2e3r4.tmp.txt", "000000.jpg", "000001.jpg", "000002.jpg"]
    assert not stale.exists() and other.exists()


def test_recognize_out_dir_sweeps_what_a_killed_run_left(tmp_path, capsys):
    feats = [_old(tmp_path / f"v{i}.npz", data=b"not an npz") for i in range(2)]
    model = _old(tmp_path / "m.joblib", data=b"not a model")
    out = tmp_path / "rec"
    out.mkdir()
    stale = _old(out / ".v0.q1w2e3r4.tmp.json")
    other = _old(out / ".v9.q1w2e3r4.tmp.json")  # not an output of this run: left
    args = ["recognize", *map(str, feats), "--model", str(model)]
    assert main([*args, "--out-dir", str(out)]) == 2
    assert not stale.exists() and other.exists()
    assert main([*args, "--out-dir", str(tmp_path / "new" / "rec")]) == 2
    assert not (tmp_path / "new").exists()
    capsys.readouterr()


def test_learn_style_out_dir_sweeps_what_a_killed_run_left(tmp_path):
    from vidstyle.style.synthetic import write_fake_dataset

    ds = tmp_path / "ds"
    write_fake_dataset(ds, n_performers=2, n_videos=2, events_per_video=40, seed=3)
    out = tmp_path / "styles"
    out.mkdir()
    stale = _old(out / ".p01.q1w2e3r4.tmp.json")
    assert main(["learn-style", "--dataset", str(ds), "--out-dir", str(out), "--n-init", "1", "--modes", "1-2"]) == 0
    assert sorted(os.listdir(out)) == ["p00.json", "p01.json"] and not stale.exists()
