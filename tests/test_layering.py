"""The package layering (issue 26): no import cycles between vidstyle's packages, ``formats`` imports
no domain package, and only the edge (demo, evaluation, commands, cli) imports the demo generator.

The analysis is ``scripts/import_graph.py`` (which prints the graph); these tests also check that the
analysis itself sees what it claims to, on a small package written for the purpose.
"""

from __future__ import annotations

import importlib.util
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _load():
    spec = importlib.util.spec_from_file_location("import_graph", ROOT / "scripts" / "import_graph.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["import_graph"] = mod
    spec.loader.exec_module(mod)
    return mod


graph = _load()


def test_no_cycles_between_packages():
    assert graph.analyse()["cycles"] == []


def test_layering_rules_hold():
    assert graph.analyse()["breaches"] == []


def test_no_private_names_imported_from_other_modules():
    assert graph.analyse()["private_imports"] == []


def test_scripts_use_no_private_attributes():
    assert graph.analyse()["script_private_attributes"] == []


def test_cycle_finder_on_known_graphs():
    assert graph.cycles({"a": ["b"], "b": ["c"], "c": ["a"], "d": ["a"]}) == [["a", "b", "c"]]
    assert graph.cycles({"a": ["b"], "b": ["c"], "d": ["a"]}) == []
    assert graph.cycles({"a": ["b"], "b": ["a"], "c": ["d"], "d": ["c"]}) == [["a", "b"], ["c", "d"]]


def test_analysis_sees_lazy_relative_and_type_checking_imports(tmp_path, monkeypatch):
    pkg = tmp_path / "vidstyle"
    for name, text in {
        "__init__.py": "",
        "errors.py": "",
        "demo/__init__.py": "",
        "formats/__init__.py": "",
        "formats/a.py": """
            from typing import TYPE_CHECKING
            if TYPE_CHECKING:
                from ..style import Style
            def f():
                from ..errors import InputError
                from .b import _hidden
        """,
        "formats/b.py": "_hidden = 1\n",
        "style/__init__.py": "from ..formats import a\n",
        "pose/__init__.py": "def g():\n    import vidstyle.demo\n",
    }.items():
        path = pkg / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text))
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "s.py").write_text("def h(m):\n    return m._secret(1)\n")
    monkeypatch.setattr(graph, "ROOT", tmp_path)
    monkeypatch.setattr(graph, "PACKAGE", pkg)
    result = graph.analyse()
    assert result["cycles"] == [["formats", "style"]]
    assert any(b.startswith("formats imports style") for b in result["breaches"])
    assert any(b.startswith("pose imports demo") for b in result["breaches"])
    assert any(p.endswith("vidstyle.formats.b._hidden") for p in result["private_imports"])
    assert result["script_private_attributes"] == ["scripts/s.py:2 ._secret"]


@pytest.mark.parametrize("rule", ["formats", "base"])
def test_rules_flag_downward_breaches(rule):
    edges = {"formats": {"motiongraph": ["x:1"]}} if rule == "formats" else {"fileio": {"formats": ["x:1"]}}
    assert len(graph.breaches(edges)) == 1
