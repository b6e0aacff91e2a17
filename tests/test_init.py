"""`vidstyle init DIR`: the template pipeline (pipelines/template, shipped in the package) written for
the user's files, its params.yaml naming them and the classes / marked videos of the annotations."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from vidstyle.cli import main
from vidstyle.templates import FILES, VALIDATED, set_param, template_text

REPO = Path(__file__).resolve().parents[1]
TEMPLATE = REPO / "pipelines" / "template"
EXAMPLE = TEMPLATE / "example"


def test_the_package_ships_the_repositorys_template():
    for name in FILES:
        assert template_text(name) == (TEMPLATE / name).read_text(), name


def _user_files(tmp_path: Path) -> dict[str, Path]:
    videos = tmp_path / "my videos"
    videos.mkdir()
    clips = tmp_path / "clips"
    clips.mkdir()
    (clips / "a.bvh").write_text("")
    return {"videos": videos, "clips": clips, "annotations": EXAMPLE / "annotations.json",
            "labels": EXAMPLE / "library.csv"}


def test_init_writes_the_template_naming_the_users_files(tmp_path, capsys):
    f = _user_files(tmp_path)
    out = tmp_path / "run"
    assert main(["init", str(out), "--videos", str(f["videos"]), "--annotations", str(f["annotations"]),
                 "--library", str(f["clips"]), "--library", str(f["clips"] / "a.bvh"),
                 "--library-labels", str(f["labels"]), "--pattern", "*.mov"]) == 0
    assert capsys.readouterr().out.split() == [str(out / "dvc.yaml"), str(out / "params.yaml")]
    assert (out / "dvc.yaml").read_text() == (TEMPLATE / "dvc.yaml").read_text()
    got = yaml.safe_load((out / "params.yaml").read_text())
    example = yaml.safe_load((TEMPLATE / "params.yaml").read_text())
    assert got["data"] == {"videos": str(f["videos"].resolve()), "pattern": "*.mov",
                           "annotations": str(f["annotations"].resolve())}
    assert got["library"] == {"clips": f"{f['clips'].resolve()} {(f['clips'] / 'a.bvh').resolve()}",
                              "labels": str(f["labels"].resolve()), "classes": "stand,lunge,turn"}
    # every video of the example is marked; the example's loosened thresholds are back to the validated ones
    assert got["augmg"]["videos"].split() == [f"pose2sim_single_cam0{i}.mp4" for i in range(1, 5)]
    assert got["graph"]["quantile"] == 0.05 and got["augmg"]["max_match_cost"] == "blazepose=0.637"
    for section in ("features", "recognition", "style"):  # the method's parameters as in the template
        assert got[section] == example[section]
    assert "# Written by `vidstyle init`" in (out / "params.yaml").read_text()
    assert "#" in (out / "params.yaml").read_text().split("videos:")[1].splitlines()[0]  # comments kept


def test_init_refuses_to_overwrite_and_names_bad_paths(tmp_path, capsys):
    f = _user_files(tmp_path)
    args = ["--videos", str(f["videos"]), "--annotations", str(f["annotations"]), "--library", str(f["clips"]),
            "--library-labels", str(f["labels"])]
    out = tmp_path / "run"
    assert main(["init", str(out), *args]) == 0
    assert main(["init", str(out), *args]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["init", str(out), *args, "--force"]) == 0
    bad = ["--videos", str(tmp_path / "none"), *args[2:]]
    assert main(["init", str(tmp_path / "other"), *bad]) == 2
    assert "--videos:" in capsys.readouterr().err and not (tmp_path / "other").exists()


def test_set_param_keeps_comments_and_other_sections():
    text = "a:\n  x: 1   # one\n  y: 2\nb:\n  x: 3\n"
    assert set_param(text, "b", "x", "9") == "a:\n  x: 1   # one\n  y: 2\nb:\n  x: 9\n"
    assert set_param(text, "a", "x", '"q r"') == "a:\n  x: \"q r\"   # one\n  y: 2\nb:\n  x: 3\n"
    with pytest.raises(KeyError):
        set_param(text, "a", "z", "1")
    assert set(VALIDATED) == {("graph", "quantile"), ("augmg", "max_match_cost")}
