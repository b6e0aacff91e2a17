"""``vidstyle compile`` (vidstyle/warmup.py): every numba kernel cached, and a pipeline run afterwards compiles nothing.

Independent truth: the kernels are found by reading the package's source (every function passed to
``compile_kernel`` or a module's ``_compiled`` helper), not from the warm-up's task list. "Compiles nothing"
is read from numba's cache: its index files list every signature compiled, and a run that compiles
one rewrites its index.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "vidstyle"
VIDSTYLE = [sys.executable, "-m", "vidstyle"]


def kernels_in_source() -> set[tuple[str, str]]:
    """(module file stem, function name) of every function the package hands to numba."""
    found = set()
    for path in PACKAGE.rglob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                    and node.func.id in ("compile_kernel", "_compiled") and node.args
                    and isinstance(node.args[0], ast.Name) and node.args[0].id != "loop"):
                found.add((path.stem, node.args[0].id))
    return found


def index_files(cache: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in cache.rglob("*.nbi")}


@pytest.fixture(scope="module")
def compiled_cache(tmp_path_factory) -> tuple[Path, dict]:
    cache = tmp_path_factory.mktemp("numba_cache")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    res = subprocess.run([*VIDSTYLE, "compile", "--jobs", "2"], env=env, capture_output=True, text=True,
                         timeout=600)
    assert res.returncode == 0, res.stderr
    assert res.stdout == ""  # logs go to stderr
    return cache, env


def test_the_source_scan_finds_the_kernels():
    found = kernels_in_source()
    # a few known ones, from four subpackages, and nothing that is not a function of its module
    assert {("raster", "_draw_loop"), ("kinematics", "_fk_loop"), ("distance", "_tail1_loop"),
            ("dt", "_envelope_rows"), ("markov", "_segment_loop")} <= found
    assert len(found) >= 20


def test_compile_caches_every_kernel_the_package_compiles(compiled_cache):
    cache, _ = compiled_cache
    names = index_files(cache)
    missing = sorted(f"{stem}.{fn}" for stem, fn in kernels_in_source()
                     if not any(n.startswith(f"{stem}.{fn}-") for n in names))
    assert not missing, f"not compiled by vidstyle compile: {missing}"


def test_pipeline_commands_after_compile_compile_nothing(compiled_cache, tmp_path):
    """make-dataset (renderer, BVH writer), features (salient points, 3D SIFT), build-graph (BVH reader, forward
    kinematics, distance kernels) at the pipeline's settings on a small dataset: numba loads every kernel
    from the cache and writes no index."""
    cache, env = compiled_cache
    before = index_files(cache)
    data = tmp_path / "data"
    steps = [
        ["demo", "make-dataset", "--out", str(data), "--performers", "1", "--views", "front", "--single-seconds",
         "2", "--performances", "0", "--jobs", "1"],
    ]
    for step in steps:
        res = subprocess.run([*VIDSTYLE, *step], env=env, capture_output=True, text=True, timeout=600)
        assert res.returncode == 0, res.stderr
    videos = sorted((data / "videos").glob("*.mp4"))[:2]
    for step in (["features", *map(str, videos), "--out", str(tmp_path / "features"), "--jobs", "1",
                  "--variant", "scovanner2007", "--points", "10"],
                 ["build-graph", str(data / "mocap"), "--fps", "30", "--window", "10", "--out",
                  str(tmp_path / "graph.npz")]):
        res = subprocess.run([*VIDSTYLE, *step], env=env, capture_output=True, text=True, timeout=600)
        assert res.returncode == 0, res.stderr
    after = index_files(cache)
    changed = sorted(n for n in after if before.get(n) != after[n])
    assert not changed, f"compiled again after vidstyle compile: {changed}"
