"""Per-video stages on a Dask cluster give exactly the files of the local joblib run (issue 7, item 4).

A real ``dask.distributed.LocalCluster`` with 2 worker processes is started; ``vidstyle features`` and
``vidstyle recognize`` get its ``tcp://`` address through ``--scheduler``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from dask import distributed

from tests.conftest import SEED
from tests.test_features_cli import write_video
from vidstyle.cli import main
from vidstyle.recognition.synthetic import make_dataset


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as c:
        yield c.scheduler_address


def _npz(path):
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def test_features_on_dask_equal_local(cluster, tmp_path):
    videos = []
    for i, speed in enumerate((1, 2, 3)):
        p = tmp_path / f"v{i}.avi"
        write_video(p, T=14, speed=speed)
        videos.append(str(p))
    assert main(["features", *videos, "--out", str(tmp_path / "local"), "--jobs", "2"]) == 0
    assert main(["features", *videos, "--out", str(tmp_path / "dask"), "--scheduler", cluster]) == 0
    for i in range(3):
        a, b = _npz(tmp_path / "local" / f"v{i}.npz"), _npz(tmp_path / "dask" / f"v{i}.npz")
        assert a.keys() == b.keys() and len(a["points"]) > 0
        for k in a:
            np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def test_recognize_on_dask_equals_local(cluster, tmp_path):
    ds = tmp_path / "ds"
    make_dataset(ds, n_performers=4, views=("front",), seed=SEED, dim=16, reps=(2, 3), n_actions=4)
    common = ["--dataset", str(ds), "--features-dir", str(ds / "features"), "--seed", str(SEED)]
    assert main(["vocabulary", *common, "--words", "30", "--out", str(tmp_path / "v.npz")]) == 0
    assert main(["train-recognizer", *common, "--vocab", str(tmp_path / "v.npz"), "--components", "12",
                 "--out", str(tmp_path / "m.joblib")]) == 0
    feats = sorted(str(p) for p in (ds / "features").glob("*.npz"))
    model = ["--model", str(tmp_path / "m.joblib")]
    assert main(["recognize", *feats, *model, "--out-dir", str(tmp_path / "serial")]) == 0
    assert main(["recognize", *feats, *model, "--out-dir", str(tmp_path / "jobs"), "--jobs", "2"]) == 0
    assert main(["recognize", *feats, *model, "--out-dir", str(tmp_path / "dask"), "--scheduler", cluster]) == 0
    names = sorted(p.name for p in (tmp_path / "serial").iterdir())
    assert len(names) == len(feats)
    for other in ("jobs", "dask"):
        assert sorted(p.name for p in (tmp_path / other).iterdir()) == names
        for n in names:
            assert json.loads((tmp_path / other / n).read_text()) == json.loads((tmp_path / "serial" / n).read_text())


def test_unreachable_scheduler_fails_with_one_line(tmp_path, capsys):
    p = tmp_path / "v.avi"
    write_video(p)
    assert main(["features", str(p), "--out", str(tmp_path / "f"), "--scheduler", "tcp://127.0.0.1:9"]) != 0
    err = capsys.readouterr().err
    assert "cannot connect" in err and not (tmp_path / "f" / "v.npz").exists()
