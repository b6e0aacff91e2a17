#!/usr/bin/env python
"""The benchmark table of the README and docs/benchmarks.md, generated from the committed bench files (bench_results/*.json),
so no benchmark figure is typed by hand.

Each ``scripts/bench_*.py`` writes its JSON under ``bench_results/``; this script reads the ones it knows
(one adapter per benchmark below), and writes one row per headline figure: what was measured, the figure,
the goal and whether it is met, the machine's core count and the date of the run (a README.md gets the
compact table: one row per benchmark, its largest scale). With ``--doc
docs/benchmarks.md`` the text between ``<!-- bench:begin -->`` and ``<!-- bench:end -->`` is replaced;
``--check`` exits 1 when the page is not up to date (tests/test_bench_table.py runs it). A file that is
absent is left out of the table; a file it cannot read is an error.

    python scripts/bench_table.py --doc README.md docs/benchmarks.md [--results bench_results] [--check]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "scripts"), str(ROOT)]
BEGIN, END = "<!-- bench:begin -->", "<!-- bench:end -->"


def _cores(d: dict) -> str:
    m = d.get("machine") or {}
    return str(m.get("cores", d.get("cores", "?")))


def _date(d: dict) -> str:
    for key in ("when", "date"):
        if d.get(key):
            return str(d[key])[:10]
    return "?"


def _met(ok) -> str:
    return "n/a" if ok is None else ("yes" if ok else "**no**")


def render(d: dict) -> list[tuple]:
    rows = []
    for r in d["results"]:
        if r["size"] == "160x120" and r["stage"] in ("render_motion", "render_to_file"):
            rows.append((f"render {r['stage']} ({r['motion']}, 160x120, one core)",
                         f"{r['frames_per_s']:.0f} frames/s", f">= {d['goal_frames_per_s']:g} frames/s",
                         _met(r["frames_per_s"] >= d["goal_frames_per_s"])))
    return rows


def augmg(d: dict) -> list[tuple]:
    rows = []
    top = max(r["n"] for r in d["rows"])
    for r in d["rows"]:
        if r["n"] == top and r["index"].endswith(" bal"):  # the index vidstyle ships (augmg.index.build_tree)
            rows.append((f"AugMG query, {r['n']:,} library frames, one core ({r['index']})",
                         f"{r['query_ms']:.2f} ms ({r['speedup']:.0f}x brute force)",
                         f"<= {d['goal_ms_at_1M']:g} ms at 1M", _met(r["query_ms"] <= d["goal_ms_at_1M"])))
    return rows


def video(d: dict) -> list[tuple]:
    c = d["clip"]
    feat = next(r for r in d["rows"] if r["case"] == "vidstyle features")
    g = d["goal"]
    return [(f"features on {c['width']}x{c['height']} {c['fps']:.0f} fps video ({c['duration_s']:.0f} s)",
             f"{feat['realtime_factor']:.2f}x real time, peak {feat['peak_rss_mb_max']:.0f} MB",
             f"> {g['realtime_factor']:g}x, <= {g['peak_rss_mb']:.0f} MB", _met(d["goal_met"]))]


def bvh(d: dict) -> list[tuple]:
    ratio = d.get("ratio_vs_pybvh")
    if ratio is None:
        return []
    goal = d.get("goal_ratio_vs_pybvh", 0.7)
    return [("BVH parse + FK of the 86 CMU clips, one core, time against pybvh 0.9 (same run)",
             f"{ratio:.2f}x pybvh's time", f"<= {goal:g}x", _met(ratio <= goal))]


def motiongraph(d: dict) -> list[tuple]:
    rows = []
    for r in d.get("rows", []):
        frac = r.get("fraction_of_gemm_peak")
        if frac is None or r["frames"] < 10_000:  # 1k frames: too small a problem for the GEMM-rate goal
            continue
        fig = (f"{r['median_s']:.1f} s, {r['gflops']:.0f} GFLOP/s = {100 * frac:.0f} % of the same run's GEMM rate"
               + (f" ({100 * r['fraction_of_gemm_cpu']:.0f} % by CPU time)" if r.get("fraction_of_gemm_cpu") else ""))
        goal = ">= 60 % of the GEMM rate" + (", <= 180 s" if r["frames"] >= 100_000 else "")
        ok = frac >= 0.6 and (r["median_s"] <= 180 if r["frames"] >= 100_000 else True)
        rows.append((f"exact motion graph, all pairs, {r['frames']:,} frames", fig, goal, _met(ok)))
    return rows


def demo_timing(d: dict) -> list[tuple]:
    """``vidstyle timing``'s table of fresh ``make demo`` runs (scripts/bench_demo.py: the median run's
    document, with every run in ``runs``; older files hold one run)."""
    import datetime

    slow = sorted(d["stages"], key=lambda r: -r["wall_seconds"])[:3]
    top = ", ".join(f"{r['stage']} {r['wall_seconds']:.0f} s" for r in slow)
    when = datetime.datetime.fromtimestamp(d["started"], datetime.UTC).strftime("%Y-%m-%d")
    d.setdefault("when", when)
    runs = d.get("runs") or []
    if len(runs) > 1:
        walls = sorted(r["run_wall_seconds"] for r in runs)
        wall = d["median_run_wall_seconds"]
        fig = (f"median {wall:.0f} s wall of {len(runs)} fresh runs ({walls[0]:.0f}-{walls[-1]:.0f} s); the median "
               f"run: {d['cpu_seconds']:.0f} s CPU (slowest: {top})")
    else:
        wall = d["run_wall_seconds"]
        fig = f"{wall:.0f} s wall, {d['cpu_seconds']:.0f} s CPU (slowest: {top})"
    rows = [("`make demo`'s pipeline (`dvc repro`) on a fresh clone", fig, "<= 390 s", _met(wall <= 390))]
    totals = sorted(r["make_demo_seconds"] for r in runs if r.get("make_demo_seconds") is not None)
    if totals:
        med = d.get("median_make_demo_seconds")
        rows.append(("`make demo` on a fresh clone, install included (pip's cache warm)",
                     f"median {med:.0f} s of {len(totals)} runs ({totals[0]:.0f}-{totals[-1]:.0f} s)", "<= 600 s",
                     _met(med <= 600)))
    b = d.get("baseline")
    if b:  # bench_demo.py --baseline: each round a fresh run of the baseline commit and of HEAD
        rows.append((f"`make demo`'s pipeline against commit {b['commit'][:7]}, the same rounds (HEAD / baseline)",
                     f"{b['pipeline_ratio']:.3f} wall, {b['cpu_ratio']:.3f} CPU, {b['make_demo_ratio']:.3f} with the install"
                     + (f", {b['wall_per_cpu_ratio']:.3f} wall per CPU second" if "wall_per_cpu_ratio" in b else "")
                     + f" (median of {len(b['rounds'])} rounds' ratios; baseline median {b['median_run_wall_seconds']:.0f} s)",
                     "<= 1.05: not slower than the baseline beyond the run-to-run noise of a shared machine",
                     _met(b["pipeline_ratio"] <= 1.05)))
    return rows


def reconstruct(d: dict) -> list[tuple]:
    rows = []
    top = max(r["library_frames"] for r in d["rows"])
    for r in d["rows"]:
        if r["library_frames"] == top and r["method"] == "olng":
            goal = d["goal_fps_at_1M"]
            rows.append((f"reconstruct after pose estimation, {top:,} library frames x {d['views']} views, one core "
                         f"(olng; per-frame nn baseline in the same run)",
                         f"{r['frames_per_s']:.0f} frames/s ({r['ratio_vs_nn']:.2f}x nn)", f">= {goal:g} frames/s at 1M",
                         _met(r["frames_per_s"] >= goal) if top >= 1_000_000 else "n/a"))
    return rows


def pose_recognition(d: dict) -> list[tuple]:
    r, p = d["recognizer"], d["pose_stage"]
    return [("pose-sequence recognizer after pose estimation, one core (shipped pictorial structures at "
             f"{p['size'][0]}x{p['size'][1]}, same run)",
             f"{r['frames_per_s']:.0f} frames/s = {100 * d['share']:.1f} % of the pose stage's time per frame "
             f"({p['ms_per_frame']:.1f} ms)", f"<= {100 * d['goal_share']:g} % of the pose stage",
             _met(d["share"] <= d["goal_share"]))]


#: bench file stem -> adapter
ADAPTERS = {"demo_timing": demo_timing, "render": render, "bench_augmg": augmg, "bench_video": video, "bvh": bvh, "motiongraph": motiongraph,
            "reconstruct": reconstruct, "pose_recognition": pose_recognition}


# the README's compact table: one row per benchmark where the full table has several (the largest scale)
COMPACT = {"render": lambda rows: [r for r in rows if r[0].startswith("render render_to_file (cmu")] or rows[:1],
           "motiongraph": lambda rows: rows[-1:]}


def table(results: Path, compact: bool = False) -> str:
    lines = ["<!-- generated by scripts/bench_table.py from bench_results/*.json; do not edit by hand -->", "",
             "| benchmark | figure | goal | met | cores | date | file |", "|---|---|---|---|---|---|---|"]
    for stem, adapter in ADAPTERS.items():
        path = results / f"{stem}.json"
        if not path.is_file():
            continue
        try:
            d = json.loads(path.read_text(encoding="utf-8"))
            rows = adapter(d)
            if compact and stem in COMPACT:
                rows = COMPACT[stem](rows)
        except (ValueError, KeyError, TypeError, StopIteration) as e:
            raise SystemExit(f"bench_table: {path}: cannot read its figures ({type(e).__name__}: {e})") from None
        for what, fig, goal, met in rows:
            lines.append(f"| {what} | {fig} | {goal} | {met} | {_cores(d)} | {_date(d)} | `{path.relative_to(results.parent)}` |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", type=Path, default=ROOT / "bench_results")
    ap.add_argument("--doc", type=Path, nargs="+", default=None,
                    help="pages whose bench:begin/end block is replaced (README.md, docs/benchmarks.md)")
    ap.add_argument("--check", action="store_true", help="exit 1 when --doc is not up to date")
    args = ap.parse_args(argv)
    body = table(args.results)
    if args.doc is None:
        sys.stdout.write(body)
        return 0
    from readme_tables import splice  # the results tables' marker splice (same directory)

    from vidstyle.fileio import write_text

    stale = 0
    for doc in args.doc:
        text = doc.read_text(encoding="utf-8")
        new = splice(text, table(args.results, compact=doc.name == "README.md"), BEGIN, END)
        if new is None:
            raise SystemExit(f"bench_table: {doc} has no {BEGIN} ... {END} block")
        if args.check:
            if new != text:
                print(f"{doc} is not up to date: run python scripts/bench_table.py --doc {doc}", file=sys.stderr)
                stale = 1
            continue
        write_text(doc, new)
    return stale

if __name__ == "__main__":
    sys.exit(main())
