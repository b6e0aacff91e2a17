"""parallel_map: joblib locally and a Dask cluster give the same ordered results as a plain loop."""

from __future__ import annotations

import numpy as np
import pytest
from dask import distributed

from vidstyle.errors import InputError
from vidstyle.parallel import parallel_map


def _work(seed: int) -> float:
    return float(np.random.default_rng(seed).normal(size=1000).sum())


def test_local_matches_serial():
    items = list(range(7))
    expected = [_work(i) for i in items]
    assert parallel_map(_work, items, jobs=1) == expected
    assert parallel_map(_work, items, jobs=2) == expected
    assert parallel_map(_work, [], jobs=2) == []


def test_dask_cluster_matches_local():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        got = parallel_map(_work, list(range(6)), scheduler=cluster.scheduler_address)
    assert got == [_work(i) for i in range(6)]


def test_unreachable_scheduler_is_a_clear_error():
    with pytest.raises(InputError, match="cannot connect"):
        parallel_map(_work, [1], scheduler="tcp://127.0.0.1:9")


def test_atomic_files_get_the_normal_mode(tmp_path):
    import os

    from vidstyle.fileio import write_json

    write_json(tmp_path / "a.json", {"x": 1})
    plain = tmp_path / "plain.txt"
    plain.write_text("x")
    assert os.stat(tmp_path / "a.json").st_mode & 0o777 == os.stat(plain).st_mode & 0o777


def test_library_errors_name_parameters_and_the_cli_its_flags(capsys):
    from vidstyle.cli import main
    from vidstyle.commands._flags import as_flags

    with pytest.raises(InputError, match=r"^jobs: must be a positive"):
        parallel_map(_work, [1], jobs=0)
    with pytest.raises(InputError, match=r"^--jobs: must be a positive"):
        with as_flags(jobs="--jobs"):
            parallel_map(_work, [1], jobs=0)
    with pytest.raises(InputError, match=r"^jobsite"):  # only a whole parameter name is mapped
        with as_flags(jobs="--jobs"):
            raise InputError("jobsite")
    assert main(["recognize", "x.npz", "--model", "m.joblib", "--out", "o.json", "-j", "0"]) == 2


def test_limit_threads_restores_opencv():
    import cv2

    from vidstyle.parallel import limit_threads

    before = cv2.getNumThreads()
    with limit_threads(1):
        assert cv2.getNumThreads() == 1
    assert cv2.getNumThreads() == before
