"""Start-up stays light (issue 31): the CLI and the command modules import no numerical package, so
`vidstyle --help` and every process of the pipeline pay only for what their command runs; BlazePose's
pose path imports neither PyTorch nor scikit-learn; the lazily loaded packages still export their API.

Each check runs in a fresh interpreter (this process has long imported everything)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: what no command needs before it runs (each costs 0.2 to 2 s of start-up: scipy.stats through
#: scikit-learn alone is most of a small command's time)
HEAVY = ("numpy", "scipy", "sklearn", "torch", "mediapipe", "cv2", "numba", "dvc", "hmmlearn", "joblib",
         "onnxruntime", "skl2onnx", "skimage", "matplotlib", "av", "dask", "PIL")


def _loaded(code: str) -> set[str]:
    """Top-level packages of HEAVY in sys.modules after running ``code`` in a fresh interpreter."""
    probe = f"{code}\nimport json, sys\nprint(json.dumps(sorted({{m.split('.')[0] for m in sys.modules}})))"
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    res = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=False, env=env, timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    return set(json.loads(res.stdout.splitlines()[-1])) & set(HEAVY)


def test_the_cli_imports_no_numerical_package():
    assert _loaded("import vidstyle.cli") == set()


def test_help_imports_no_numerical_package():
    code = ("import contextlib, io\nfrom vidstyle.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n    assert main(['--help']) == 0\n"
            "    assert main(['generate', '--help']) == 0\n    assert main(['pose', '--help']) == 0")
    assert _loaded(code) == set()


def test_blazepose_pose_path_imports_neither_torch_nor_sklearn():
    code = ("from vidstyle.pose.run import check_estimate_params\nimport vidstyle.pose.blazepose\n"
            "assert check_estimate_params('blazepose', None, None) == (1.0,)")
    assert _loaded(code) & {"torch", "sklearn", "numba", "scipy", "mediapipe"} == set()


@pytest.mark.parametrize("pkg, name, module", [
    ("augmg", "augment", "augment"), ("augmg", "match_poses", "match"), ("style", "learn", "learn"),
    ("style", "Style", "artifact"), ("recognition", "Vocabulary", "vocabulary"), ("features", "extract_videos", "extract"),
])
def test_lazy_packages_export_their_api_whatever_loads_first(pkg, name, module):
    """``vidstyle.augmg.augment`` is the function, also after the submodule of the same name was loaded on
    its own (the import system binds submodules to their package), and ``from pkg import name`` gives
    the object the submodule defines."""
    code = (f"import importlib\nsub = importlib.import_module('vidstyle.{pkg}.{module}')\n"
            f"import vidstyle.{pkg} as pkg\nfrom vidstyle.{pkg} import {name}\n"
            f"assert {name} is getattr(sub, '{name}') and pkg.{name} is {name}, (pkg.{name}, {name})\n"
            f"for n in pkg.__all__:\n    getattr(pkg, n)")
    _loaded(code)


def test_lazy_packages_reach_their_submodules_as_attributes():
    code = ("import types, vidstyle.recognition as r, vidstyle.features as f\n"
            "assert isinstance(r.smoothing, types.ModuleType) and isinstance(f.scovanner2007, types.ModuleType)\n"
            "assert not hasattr(r, 'no_such_module') and not hasattr(r, '_private')")
    _loaded(code)
