"""Shared fixtures. Every random generator is seeded from VIDSTYLE_TEST_SEED (default 0), printed in
the header so a failure can be replayed.

Hypothesis runs under one registered profile, "ci" (derandomized: the examples are a function of the
test alone, so a CI failure replays locally; `print_blob` prints the reproduction blob); it is loaded
unless HYPOTHESIS_PROFILE names another registered profile ("dev": random examples, for exploring).

Under pytest-xdist the suite runs with `--dist loadgroup`: every test of a module that uses a module- or
class-scoped fixture of its own (a DVC run, a trained pose model, ...) gets the module's `xdist_group`, so
that fixture is built once, on one worker, instead of once per worker.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import settings

SEED = int(os.environ.get("VIDSTYLE_TEST_SEED", "0"))
SHARED = Path(__file__).resolve().parents[1].parent / "shared"
CMU_DIR = SHARED / "data" / "mocap" / "cmu"

settings.register_profile("ci", derandomize=True, print_blob=True, database=None)
settings.register_profile("dev", derandomize=False, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


def pytest_report_header(config):
    return (f"vidstyle test seed: VIDSTYLE_TEST_SEED={SEED}; hypothesis profile: {settings._current_profile}; "
            f"shared data: {'present' if SHARED.is_dir() else 'absent'}")


def _module_scoped_fixtures(item) -> bool:
    """True when the test uses a module/class-scoped fixture defined in its own test module."""
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return False
    module = getattr(item, "module", None)
    for defs in info.name2fixturedefs.values():
        for fd in defs:
            if fd.scope in ("module", "class") and module is not None \
                    and getattr(fd.func, "__module__", None) == module.__name__:
                return True
    return False


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    # before xdist's own hook reads the marks (it appends the group to the node id under loadgroup)
    for item in items:
        if item.get_closest_marker("xdist_group") is None and _module_scoped_fixtures(item):
            item.add_marker(pytest.mark.xdist_group(item.module.__name__))


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(SEED)


@pytest.fixture(scope="session")
def cmu_dir() -> Path:
    if not CMU_DIR.is_dir():
        pytest.skip("../shared/data/mocap/cmu is absent")
    return CMU_DIR
