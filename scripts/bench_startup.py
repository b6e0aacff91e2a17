#!/usr/bin/env python
"""Benchmark: process start-up of the ``vidstyle`` CLI (issue 31: every pipeline stage starts one or more
``vidstyle`` processes, and each paid for imports its command did not need).

Each row starts a fresh interpreter and reads its wall time and CPU time (user + system, ``os.wait4``); the
figure is the median of ``--runs`` runs after one warm-up run (which also writes the bytecode caches, as an
installed package has them), the rows interleaved run by run so that load on the machine falls on all of
them alike. Rows:

- ``python -c pass``: the interpreter alone, the floor of any command (the baseline in the same run);
- ``vidstyle --help`` and ``vidstyle <command> --help`` for light commands: the CLI's own start-up (every
  command builds the whole CLI before it runs);
- ``BlazePose pose imports``: what ``vidstyle pose --backend blazepose`` imports of vidstyle before
  MediaPipe (the pipeline's ``pose_marks`` stage runs it once per video).

With ``--baseline-ref REF`` (e.g. ``main`` or ``HEAD~1``) every vidstyle row also runs on that commit's
``vidstyle/`` (``git archive`` into a temporary directory, first on ``PYTHONPATH``), and the table shows
the ratio now / baseline; ``--baseline DIR`` takes a checkout instead. Also printed, per tree: which heavy
packages ``import vidstyle.cli`` loads, and the slowest imports of ``vidstyle --help`` by cumulative time
(``python -X importtime``, one run).

Prints a table and writes ``bench_results/bench_startup.json``.

    python scripts/bench_startup.py [--runs 7] [--baseline-ref main] [--commands generate,synthesize,pose,report]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("numpy", "scipy", "sklearn", "torch", "mediapipe", "cv2", "numba", "dvc", "hmmlearn", "joblib",
         "onnxruntime", "skl2onnx", "skimage", "matplotlib", "av", "dask", "PIL")
BLAZEPOSE_IMPORTS = ("from vidstyle.pose.run import check_estimate_params\nimport vidstyle.pose.blazepose\n"
                     "check_estimate_params('blazepose', None, None)")


def child_env(tree: Path) -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONDONTWRITEBYTECODE", "VIDSTYLE_TIMINGS", "DVC_STAGE")}
    env["PYTHONPATH"] = str(tree) + os.pathsep + env.get("PYTHONPATH", "")
    env["COLUMNS"] = "100"
    return env


def run_once(argv: list[str], env: dict) -> tuple[float, float]:
    """Wall and CPU seconds (the child's user + system) of one run; a failing run is an error."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    err = proc.stderr.read().decode(errors="replace")
    proc.stderr.close()
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed ({proc.returncode}): {err[-500:]}")
    return wall, usage.ru_utime + usage.ru_stime


def baseline_tree(ref: str, into: Path) -> Path:
    """``vidstyle/`` of commit ``ref`` extracted under ``into``."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", ref, "vidstyle"], capture_output=True, check=False)
    if archive.returncode != 0:
        raise SystemExit(f"git archive {ref}: {archive.stderr.decode(errors='replace').strip()}")
    tar = into / "baseline.tar"
    tar.write_bytes(archive.stdout)
    with tarfile.open(tar) as t:
        t.extractall(into / "baseline", filter="data")
    return into / "baseline"


def heavy_loaded(tree: Path) -> list[str]:
    code = ("import sys, json, vidstyle.cli\n"
            f"assert vidstyle.cli.__file__.startswith({str(tree)!r}), vidstyle.cli.__file__\n"
            "print(json.dumps(sorted({m.split('.')[0] for m in sys.modules})))")
    out = subprocess.run([sys.executable, "-c", code], env=child_env(tree), capture_output=True,
                         text=True, check=True).stdout
    return sorted(set(json.loads(out.splitlines()[-1])) & set(HEAVY))


def slowest_imports(tree: Path, top: int) -> list[dict]:
    """The ``top`` modules of ``vidstyle --help`` by cumulative import time (one ``-X importtime`` run)."""
    res = subprocess.run([sys.executable, "-X", "importtime", "-m", "vidstyle", "--help"], env=child_env(tree),
                         capture_output=True, text=True, check=True)
    rows = []
    for line in res.stderr.splitlines():
        m = re.match(r"import time:\s*(\d+) \|\s*(\d+) \|( +)(\S.*)$", line)
        if m:  # "import time: <self us> | <cumulative us> | <indent><module>", 2 more spaces per level
            rows.append({"module": m.group(4), "depth": (len(m.group(3)) - 1) // 2,
                         "self_ms": int(m.group(1)) / 1000, "cumulative_ms": int(m.group(2)) / 1000})
    return sorted(rows, key=lambda r: -r["cumulative_ms"])[:top]


def main() -> None:
    sys.path.insert(0, os.path.dirname(__file__))
    from _benchutil import machine, write_results

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=7, help="timed runs per row (median; at least 5)")
    ap.add_argument("--commands", default="generate,synthesize,pose,report",
                    help="light commands whose --help is timed (comma-separated)")
    ap.add_argument("--baseline-ref", default=None, help="git commit whose vidstyle/ is the baseline (git archive)")
    ap.add_argument("--baseline", type=Path, default=None, help="a checkout of the baseline code instead")
    ap.add_argument("--top", type=int, default=12, help="slowest imports shown per tree")
    args = ap.parse_args()
    if args.runs < 5:
        ap.error("--runs: at least 5")

    with tempfile.TemporaryDirectory() as tmp:
        # the children start in an empty directory: ``python -m`` / ``-c`` put the working directory first on
        # sys.path, where a checkout would shadow the tree on PYTHONPATH
        os.chdir(tmp)
        trees = {"now": ROOT}
        if args.baseline_ref:
            trees["baseline"] = baseline_tree(args.baseline_ref, Path(tmp))
        elif args.baseline:
            trees["baseline"] = args.baseline.resolve()
        py = sys.executable
        rows: list[tuple[str, str, list[str]]] = [("python -c pass", "-", [py, "-c", "pass"])]
        for tree in trees:
            rows.append(("vidstyle --help", tree, [py, "-m", "vidstyle", "--help"]))
            for cmd in [c for c in args.commands.split(",") if c]:
                rows.append((f"vidstyle {cmd} --help", tree, [py, "-m", "vidstyle", cmd, "--help"]))
            rows.append(("BlazePose pose imports", tree, [py, "-c", BLAZEPOSE_IMPORTS]))
        rows.sort(key=lambda r: (r[0] != "python -c pass", r[0], r[1] != "now"))
        env = {tree: child_env(path) for tree, path in trees.items()}
        env["-"] = child_env(ROOT)
        times: dict[tuple[str, str], list[tuple[float, float]]] = {(n, t): [] for n, t, _ in rows}
        for n, t, argv in rows:  # warm-up: bytecode caches written, files in the page cache
            run_once(argv, env[t])
        for _ in range(args.runs):
            for n, t, argv in rows:
                times[(n, t)].append(run_once(argv, env[t]))
        heavy = {tree: heavy_loaded(path) for tree, path in trees.items()}
        slowest = {tree: slowest_imports(path, args.top) for tree, path in trees.items()}
        os.chdir(ROOT)

    def med(key, i):
        return statistics.median(x[i] for x in times[key])

    results = []
    floor = med(("python -c pass", "-"), 0)
    print(f"start-up, median of {args.runs} runs (wall and CPU seconds; the machine's other load counts in the "
          "wall time, less in the CPU time)")
    head = f"{'command':32s} {'tree':8s} {'wall s':>7s} {'CPU s':>7s} {'over python':>11s}"
    if "baseline" in trees:
        head += f" {'wall now/base':>13s} {'CPU now/base':>12s}"
    print(head)
    for n, t, _ in rows:
        wall, cpu = med((n, t), 0), med((n, t), 1)
        row = {"command": n, "tree": t, "wall_median_s": wall, "cpu_median_s": cpu,
               "wall_min_s": min(x[0] for x in times[(n, t)]), "wall_max_s": max(x[0] for x in times[(n, t)]),
               "runs": args.runs}
        line = f"{n:32s} {t:8s} {wall:7.3f} {cpu:7.3f} {wall - floor:11.3f}"
        if t == "now" and (n, "baseline") in times:
            bw, bc = med((n, "baseline"), 0), med((n, "baseline"), 1)
            row["wall_ratio_to_baseline"], row["cpu_ratio_to_baseline"] = wall / bw, cpu / bc
            line += f" {wall / bw:13.2f} {cpu / bc:12.2f}"
        results.append(row)
        print(line)
    for tree in trees:
        print(f"\n{tree}: heavy packages after `import vidstyle.cli`: {', '.join(heavy[tree]) or 'none'}")
        print(f"{tree}: slowest imports of `vidstyle --help` (cumulative ms, self ms):")
        for r in slowest[tree]:
            print(f"  {'  ' * r['depth']}{r['module']:{max(1, 44 - 2 * r['depth'])}s} {r['cumulative_ms']:9.1f} "
                  f"{r['self_ms']:8.1f}")
    path = write_results("bench_startup", {
        "machine": machine(), "runs": args.runs, "baseline_ref": args.baseline_ref,
        "baseline_dir": None if args.baseline is None else str(args.baseline), "rows": results,
        "heavy_after_import_cli": heavy, "slowest_imports_help": slowest,
    })
    print(f"\nwrote {path}")


if __name__ == "__main__":
    main()
