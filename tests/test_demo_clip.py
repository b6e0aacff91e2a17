"""``vidstyle demo performer`` is vidstyle.demo.clip plus argument parsing (issue 26)."""

from __future__ import annotations

import pytest

from vidstyle.cli import main


def test_cli_performer_is_the_library_clip_with_its_defaults(tmp_path):
    """``demo performer`` with its defaults writes what demo.clip.write_performer_clip writes with its own."""
    from vidstyle.demo.clip import write_performer_clip
    from vidstyle.errors import ParameterError

    assert main(["demo", "performer", "--seed", "2", "--out", str(tmp_path / "cli.bvh")]) == 0
    _, take, labels = write_performer_clip(tmp_path / "lib" / "cli.bvh", seed=2)
    assert (tmp_path / "cli.bvh").read_bytes() == (tmp_path / "lib" / "cli.bvh").read_bytes()
    assert (tmp_path / "cli.labels.json").read_bytes() == labels.read_bytes()
    assert take.motion.fps == 60 and take.motion.n_frames == 8 * 60
    with pytest.raises(ParameterError) as e:
        write_performer_clip(tmp_path / "x.bvh", index=-1)
    assert e.value.param == "index" and not (tmp_path / "x.bvh").exists()
