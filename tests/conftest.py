"""Shared fixtures. Every random generator is seeded from VIDSTYLE_TEST_SEED (default 0), printed in
the header so a failure can be replayed."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

SEED = int(os.environ.get("VIDSTYLE_TEST_SEED", "0"))
SHARED = Path(__file__).resolve().parents[1].parent / "shared"
CMU_DIR = SHARED / "data" / "mocap" / "cmu"


def pytest_report_header(config):
    return f"vidstyle test seed: VIDSTYLE_TEST_SEED={SEED}; shared data: {'present' if SHARED.is_dir() else 'absent'}"


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(SEED)


@pytest.fixture(scope="session")
def cmu_dir() -> Path:
    if not CMU_DIR.is_dir():
        pytest.skip("../shared/data/mocap/cmu is absent")
    return CMU_DIR
