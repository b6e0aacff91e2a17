"""The package import graph of vidstyle, its cycles, and the layering rules the tests enforce.

    python scripts/import_graph.py            # packages and arrows, cycles, rule breaches
    python scripts/import_graph.py --json     # the same as JSON on stdout

Every import counts, at module level or inside a function or a ``TYPE_CHECKING`` block: a lazy
import hides a dependency, it does not remove it. A *package* is a top-level name under
``vidstyle/`` (``formats``, ``mocap``, ``fileio`` ...). The rules (``vidstyle`` layering, issue 26):

1. no cycle between packages;
2. ``formats`` imports no domain package, only the base (``errors``, ``fileio``, ``logutil``), and the
   base imports nothing but the base;
3. only the edge (``demo``, ``evaluation``, ``commands``, ``cli``, ``__main__``) imports ``demo``.

Also counted: private names (``_x``) imported from another module, in ``vidstyle/`` and ``scripts/``,
and private attributes (``obj._x``, not ``self._x``) that ``scripts/`` reaches into.
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "vidstyle"
BASE = frozenset({"budget", "compiled", "errors", "fileio", "lazy", "logutil", "parallel"})
FORMATS_MAY_IMPORT = BASE - {"parallel"}
EDGE = frozenset({"demo", "evaluation", "commands", "cli", "__main__"})


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _absolute(module: str, path: Path, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    base = module.split(".")
    if path.name != "__init__.py":
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imports_of(path: Path, module: str) -> list[tuple[str, list[str], int]]:
    """(imported module, imported names, line) for every import statement in the file."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                found.append((alias.name, [], node.lineno))
        elif isinstance(node, ast.ImportFrom):
            found.append((_absolute(module, path, node), [a.name for a in node.names], node.lineno))
    return found


def package_of(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] != "vidstyle" or len(parts) < 2:
        return None
    return parts[1]


def _is_submodule(module: str, name: str) -> bool:
    parts = module.split(".")[1:] + [name]
    return (PACKAGE.joinpath(*parts).with_suffix(".py")).is_file() or PACKAGE.joinpath(*parts).is_dir()


def analyse() -> dict:
    edges: dict[str, dict[str, list[str]]] = defaultdict(lambda: defaultdict(list))
    private: list[str] = []
    files = sorted(PACKAGE.rglob("*.py"))
    for path in files:
        module = module_name(path)
        src = package_of(module)
        for target, names, line in imports_of(path, module):
            dst = package_of(target)
            if target == "vidstyle":  # from vidstyle import x
                dst_names = [n for n in names if _is_submodule(target, n)]
                for n in dst_names:
                    if n != src:
                        edges[src][n].append(f"{path.relative_to(ROOT)}:{line}")
                continue
            if dst is not None and dst != src:
                edges[src][dst].append(f"{path.relative_to(ROOT)}:{line}")
            if dst is not None and target != module:
                private += [f"{path.relative_to(ROOT)}:{line} {target}.{n}" for n in names
                            if n.startswith("_") and not n.startswith("__")
                            and not _is_submodule(target, n)]
    for path in sorted((ROOT / "scripts").glob("*.py")):
        for target, names, line in imports_of(path, "scripts." + path.stem):
            if package_of(target) is not None:
                private += [f"{path.relative_to(ROOT)}:{line} {target}.{n}" for n in names
                            if n.startswith("_") and not n.startswith("__")
                            and not _is_submodule(target, n)]
    private_attrs = []
    for path in sorted((ROOT / "scripts").glob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and node.attr.startswith("_")
                    and not node.attr.startswith("__")
                    and not (isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"))):
                private_attrs.append(f"{path.relative_to(ROOT)}:{node.lineno} .{node.attr}")
    graph = {s: sorted(d) for s, d in edges.items()}
    return {"graph": graph, "where": {s: {d: w for d, w in dd.items()} for s, dd in edges.items()},
            "cycles": cycles(graph), "breaches": breaches(edges), "private_imports": private,
            "script_private_attributes": private_attrs}


def cycles(graph: dict[str, list[str]]) -> list[list[str]]:
    """Strongly connected components of more than one package (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, []):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(set(graph) | {w for ws in graph.values() for w in ws}):
        if v not in index:
            visit(v)
    return sorted(out)


def breaches(edges) -> list[str]:
    out = []
    for src, dsts in sorted(edges.items()):
        for dst, where in sorted(dsts.items()):
            if src == "formats" and dst not in FORMATS_MAY_IMPORT:
                out.append(f"formats imports {dst} ({where[0]})")
            if src in BASE and dst not in BASE:
                out.append(f"{src} (base) imports {dst} ({where[0]})")
            if dst == "demo" and src not in EDGE:
                out.append(f"{src} imports demo ({where[0]})")
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print the analysis as JSON")
    args = parser.parse_args()
    result = analyse()
    if args.json:
        json.dump({k: v for k, v in result.items() if k != "where"}, sys.stdout, indent=1)
        print()
        return 0
    print("packages and arrows:")
    for src in sorted(result["graph"]):
        print(f"  {src} -> {', '.join(result['graph'][src])}")
    print(f"cycles ({len(result['cycles'])}):")
    for comp in result["cycles"]:
        print("  " + " <-> ".join(comp))
    print(f"layering breaches ({len(result['breaches'])}):")
    for b in result["breaches"]:
        print("  " + b)
    print(f"private names imported across modules: {len(result['private_imports'])}")
    for p in result["private_imports"]:
        print("  " + p)
    print(f"private attributes used by scripts/: {len(result['script_private_attributes'])}")
    for p in result["script_private_attributes"]:
        print("  " + p)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
