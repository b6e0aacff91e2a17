"""The project's own modules and its declared dependencies import (a broken install fails here instead of
turning tests into skips). Only truly optional inputs (the ../shared data) may skip a test.

Supersedes the `pytest.importorskip` calls of tests/test_pose_cnn.py:10 ("torch"),
tests/test_motiongraph_cli.py:108 ("vidstyle.render"), tests/test_recognition_cli.py:145
("vidstyle.features.extract") and tests/test_motiongraph_distance.py:126 ("dask.distributed"): those
become plain imports.
"""

from __future__ import annotations

import importlib
import shutil
import sys
from pathlib import Path

import pytest

REQUIRED = [
    # the project's own modules that tests used to import-or-skip
    "vidstyle.render", "vidstyle.features.extract", "vidstyle.pose.cnn",
    # declared dependencies ([project.dependencies] and the dev extra)
    "torch", "dask.distributed", "playwright.sync_api", "hypothesis", "xdist", "pytest_timeout", "yaml", "httpx",
]


@pytest.mark.parametrize("name", REQUIRED)
def test_required_module_imports(name):
    importlib.import_module(name)  # an ImportError here is a failure, never a skip


def test_console_script_and_chromium_are_installed():
    exe = Path(sys.executable).parent / "vidstyle"
    assert exe.is_file() or shutil.which("vidstyle"), "the vidstyle console script is not installed"
    assert any(shutil.which(n) for n in ("chromium", "chromium-browser", "google-chrome")), \
        "chromium is not installed (make test installs Debian's chromium)"
