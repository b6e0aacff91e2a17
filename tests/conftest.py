"""Shared fixtures. Every random generator is seeded from VIDSTYLE_TEST_SEED (default 0), printed in
the header so a failure can be replayed.

Hypothesis runs under one registered profile, "ci" (derandomized: the examples are a function of the
test alone, so a CI failure replays locally; `print_blob` prints the reproduction blob); it is loaded
unless HYPOTHESIS_PROFILE names another registered profile ("dev": random examples, for exploring).

Under pytest-xdist the suite runs with `--dist loadfile` (`make test`): all of a module's tests run on
one worker, so a module-scoped fixture (a whole DVC run, a trained pose model, ...) is built once instead
of once per worker. (`--dist loadgroup` with `xdist_group` marks does not group them with pytest 9.2 and
xdist 3.8: checked on a two-worker run, where each worker built the module fixture.)
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

settings.register_profile("ci", derandomize=True, print_blob=True, database=None, deadline=None)  # no
# per-example deadline: a loaded 2-core machine makes timings noise (time limits are pytest-timeout's)
settings.register_profile("dev", derandomize=False, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


def pytest_report_header(config):
    return (f"vidstyle test seed: VIDSTYLE_TEST_SEED={SEED}; hypothesis profile: {settings._current_profile}; "
            f"shared data: {'present' if SHARED.is_dir() else 'absent'}")


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(SEED)


@pytest.fixture(scope="session")
def cmu_dir() -> Path:
    if not CMU_DIR.is_dir():
        pytest.skip("../shared/data/mocap/cmu is absent")
    return CMU_DIR
