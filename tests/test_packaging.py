"""Packaging facts a newcomer trips over: SPDX licence string (no setuptools deprecation warning), no
unused extras, and the browser-test system packages installed without recommended packages."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_pyproject_license_is_an_spdx_string_and_extras_are_used():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert meta["project"]["license"] == "MIT"
    build = " ".join(meta["build-system"]["requires"])
    assert int(re.search(r"setuptools>=(\d+)", build).group(1)) >= 77  # PEP 639 license expressions
    assert "viewer" not in meta["project"]["optional-dependencies"]


def test_makefile_apt_installs_skip_recommended_packages():
    for line in (ROOT / "Makefile").read_text().splitlines():
        if "apt-get install" in line and "chromium" in line:
            assert "--no-install-recommends" in line, line


def test_dvc_reads_its_yaml_files_with_ruamels_c_parser():
    # dvc reads dvc.yaml / dvc.lock / params.yaml with ruamel.yaml typ="safe" several times per stage; without
    # ruamel.yaml.clib (a dependency: 0.19 stopped installing it) that is pure Python, seconds per demo run
    from ruamel.yaml import YAML

    y = YAML(typ="safe")
    assert y.Parser.__name__ == "CParser"
    assert y.load("a: [1, 2]\nb: {c: x}\n") == {"a": [1, 2], "b": {"c": "x"}}
