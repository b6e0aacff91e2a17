"""The atomic writer keeps a symlink and the file's mode and leaves nothing behind on failure; a stage's run
sweeps the temporaries a killed run left and leaves no empty output directory when it fails (issue 33
item 4)."""

from __future__ import annotations

import os
import time

import pytest

from vidstyle import fileio
from vidstyle.cli import main
from vidstyle.errors import InputError
from vidstyle.fileio import atomic_path, write_json, write_npz, write_text


def test_a_symlink_stays_a_link_and_its_target_is_written(tmp_path):
    (tmp_path / "data").mkdir()
    real = tmp_path / "data" / "ann.json"
    real.write_text("old")
    link = tmp_path / "ann.json"
    link.symlink_to(os.path.relpath(real, tmp_path))  # relative, as a user would make it
    write_text(link, "new")
    assert link.is_symlink() and os.readlink(link) == os.path.join("data", "ann.json")
    assert real.read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ann.json", "data"]
    assert sorted(p.name for p in real.parent.iterdir()) == ["ann.json"]
    dangling = tmp_path / "later.json"  # a link to a file not yet there: the file is made where it points
    dangling.symlink_to(tmp_path / "data" / "later.json")
    write_json(dangling, {"x": 1})
    assert dangling.is_symlink() and (tmp_path / "data" / "later.json").read_text().startswith("{")


@pytest.mark.parametrize("mode", [0o600, 0o640, 0o604])
def test_the_file_keeps_its_mode(tmp_path, mode):
    p = tmp_path / "secret.json"
    p.write_text("{}")
    os.chmod(p, mode)
    write_json(p, {"x": 1})
    assert os.stat(p).st_mode & 0o777 == mode
    link = tmp_path / "link.json"
    link.symlink_to(p)
    write_json(link, {"x": 2})
    assert os.stat(p).st_mode & 0o777 == mode and link.is_symlink()


def test_a_failed_write_leaves_no_temporary_and_the_old_file(tmp_path):
    p = tmp_path / "a.npz"
    write_npz(p, x=[1, 2])
    before = p.read_bytes()
    with pytest.raises(RuntimeError), atomic_path(p) as tmp:
        tmp.write_bytes(b"half")
        raise RuntimeError("killed")
    with pytest.raises(ValueError):
        write_npz(p, x=[[1], [1, 2]])  # a ragged array: numpy refuses it while writing
    assert p.read_bytes() == before and [q.name for q in tmp_path.iterdir()] == ["a.npz"]


def _old(p, age=3600):
    p.write_bytes(b"partial")
    t = time.time() - age
    os.utime(p, (t, t))
    return p


def test_sweep_removes_only_stale_temporaries_of_the_named_outputs(tmp_path):
    stale = _old(tmp_path / ".p00_lowkick_front.k3j_x9a2.tmp.npz")
    stale_pid = _old(tmp_path / ".p00_lowkick_front.4321-k3j_x9a3.tmp.npz")  # the writer's current names
    fresh = tmp_path / ".p00_lowkick_front.zzzzzzzz.tmp.npz"
    fresh.write_bytes(b"being written now")
    keep = [_old(tmp_path / ".other.abcdefgh.tmp.npz"),          # another output's
            _old(tmp_path / ".p00_lowkick_front.abc.tmp.npz"),   # not the writer's pattern
            _old(tmp_path / "p00_lowkick_front.abcdefgh.tmp.npz"),  # not hidden
            _old(tmp_path / ".p00_lowkick_front.abcdefgh.tmp.json"),  # another suffix
            _old(tmp_path / "p00_lowkick_front.npz")]
    (tmp_path / ".p00_lowkick_front.dddddddd.tmp.npz").mkdir()  # a directory is never removed
    removed = fileio.sweep_temporaries(tmp_path, [tmp_path / "p00_lowkick_front.npz"], before=time.time() - 60)
    assert sorted(removed) == sorted([stale, stale_pid]) and not stale.exists() and fresh.exists()
    assert all(p.exists() for p in keep) and (tmp_path / ".p00_lowkick_front.dddddddd.tmp.npz").is_dir()
    assert fileio.sweep_temporaries(tmp_path / "missing", ["a.npz"]) == []


def test_output_dir_removes_what_a_failed_run_created_empty(tmp_path):
    out = tmp_path / "a" / "b" / "feat"
    with pytest.raises(RuntimeError), fileio.output_dir(out, ["x.npz"]):
        assert out.is_dir()
        raise RuntimeError("the run failed")
    assert not (tmp_path / "a").exists()
    (tmp_path / "kept").mkdir()
    with pytest.raises(RuntimeError), fileio.output_dir(tmp_path / "kept", ["x.npz"]):
        raise RuntimeError("the run failed")
    assert (tmp_path / "kept").is_dir()  # it was there before the run
    with pytest.raises(RuntimeError), fileio.output_dir(tmp_path / "new", ["x.npz"]) as d:
        (d / "x.npz").write_bytes(b"done")
        raise RuntimeError("the second video failed")
    assert (tmp_path / "new" / "x.npz").exists()  # not empty: kept
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="not a directory"), fileio.output_dir(tmp_path / "file"):
        pass


def test_features_sweeps_a_killed_runs_partial_files_and_a_failed_run_leaves_no_directory(tmp_path, capsys):
    bad = tmp_path / "clip.mp4"
    bad.write_bytes(b"not a video at all" * 100)
    out = tmp_path / "feat"
    assert main(["features", str(bad), "--out", str(out), "--jobs", "1"]) != 0
    assert not out.exists()  # created by the failed run, empty: removed
    out.mkdir()
    stale = _old(out / ".clip.q1w2e3r4.tmp.npz")
    other = _old(out / ".notes.q1w2e3r4.tmp.txt")
    assert main(["features", str(bad), "--out", str(out), "--jobs", "1"]) != 0
    assert not stale.exists() and other.exists() and out.is_dir()


def _dead_pid() -> int:
    import subprocess
    import sys

    return int(subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                              text=True, check=True).stdout)


def test_the_next_write_of_a_file_removes_a_dead_writers_temporary_and_only_that(tmp_path):
    """A single-file output: what a killed writer left beside it (its pid no longer runs) goes at the next
    write of the same file, however fresh; a live writer's temporary, another file's, and a name not of the
    writer's pattern stay."""
    dead = _dead_pid()
    left = tmp_path / f".model.{dead}-ab_cd123.tmp.json"
    left.write_text("{half")
    live = tmp_path / f".model.{os.getpid()}-zzzzzzzz.tmp.json"
    live.write_text("{being written")
    keep = [tmp_path / f".other.{dead}-abcdefgh.tmp.json", tmp_path / f".model.{dead}-abcdefgh.tmp.npz",
            tmp_path / f".model.{dead}-abc.tmp.json"]
    for p in keep:
        p.write_text("x")
    write_json(tmp_path / "model.json", {"a": 1})
    assert not left.exists() and live.exists() and all(p.exists() for p in keep)
    assert (tmp_path / "model.json").read_text() == '{\n  "a": 1\n}\n'


def test_kill_9_during_a_write_then_a_rerun_leaves_nothing_beside_the_file(tmp_path):
    """The case of issue 33 item 4 for single-file outputs: a writer killed with SIGKILL inside
    ``atomic_path`` leaves its temporary (nothing can remove it then); the next run that writes the same
    file removes it."""
    import signal
    import subprocess
    import sys

    out = tmp_path / "metrics.json"
    code = ("import sys, time; from vidstyle.fileio import atomic_path\n"
            "with atomic_path(sys.argv[1]) as t:\n"
            "    t.write_text('{half'); print('ready', flush=True); time.sleep(60)\n")
    proc = subprocess.Popen([sys.executable, "-c", code, str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "ready"
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)
    finally:
        proc.kill()
    hidden = [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]
    assert len(hidden) == 1 and hidden[0].startswith(f".metrics.{proc.pid}-") and not out.exists()
    write_json(out, [1])
    assert [p.name for p in tmp_path.iterdir()] == ["metrics.json"]


def test_errors_with_fields_survive_pickling():
    # parallel_map's workers send their exceptions to the parent by pickle: an error class whose __init__
    # takes more than the message failed to unpickle there, and the user got joblib's traceback instead of
    # the one-line error naming the file
    import pickle

    from vidstyle.errors import FormatError, ParameterError
    from vidstyle.mocap.bvh import BVHError

    for err in (FormatError("a.json", "frames", "must be a list"), FormatError(None, None, "empty"),
                ParameterError("window", "must be >= 1"), BVHError("x.bvh", 7, "bad channel count"),
                BVHError(None, None, "empty")):
        back = pickle.loads(pickle.dumps(err))
        assert type(back) is type(err)
        assert str(back) == str(err)
        assert back.__dict__ == err.__dict__
