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
