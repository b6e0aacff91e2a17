"""Headless Chromium for tests: load a local HTML file, dump its DOM after load, take a screenshot.

Uses Debian's chromium (installed by `make test`); the flags keep it off the network (this machine has
none) and out of any profile. Tests using it fail when no chromium binary is found (a required system
dependency, not an optional one).
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
]


def chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    pytest.fail("chromium is not installed (make test installs Debian's chromium: apt-get install chromium)")


def _run(args: list[str], timeout: float = 90) -> subprocess.CompletedProcess:
    with tempfile.TemporaryDirectory() as profile:
        return subprocess.run(
            [chromium(), *FLAGS, f"--user-data-dir={profile}", *args],
            capture_output=True,
            text=True,
            timeout=timeout,
        )


def dump_dom(page: Path) -> str:
    res = _run(["--virtual-time-budget=5000", "--dump-dom", page.resolve().as_uri()])
    assert res.returncode == 0, res.stderr[-2000:]
    return res.stdout


def screenshot(page: Path, png: Path, size: tuple[int, int] = (1200, 2400)) -> Path:
    res = _run([f"--screenshot={png}", f"--window-size={size[0]},{size[1]}", "--virtual-time-budget=5000",
                page.resolve().as_uri()])
    assert res.returncode == 0 and png.exists(), res.stderr[-2000:]
    return png
