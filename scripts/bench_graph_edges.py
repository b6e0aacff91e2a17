"""Benchmark: the planner over the open edge table against the planner it replaced.

On the CMU walk/run/jump graph (mirrored, ~11k frames, as scripts/bench_motiongraph.py), plan the same
20-step request (1-3 s steps) with

- the planner of a baseline git revision (default ``main``: parallel ``trans_*`` arrays, one kind of
  transition), run from a ``git archive`` of that revision on the same graph saved as a v1 file;
- this checkout's planner on the same graph (v2 edge table), with 0, 1 000 and 10 000 added ENHANCEMENT
  edges (2k frames each, random ends, through 50 stored segments, costs drawn around the blend costs).

Each configuration runs in a fresh subprocess (one warm-up, then ``--runs`` >= 5 plans), and the
configurations take turns for ``--rounds`` rounds, so load from other processes on a shared machine
falls on all of them alike; the table gives the median over all rounds' plans.

    python scripts/bench_graph_edges.py [--runs 5] [--baseline main]

Prints a table and writes bench_results/graph_edges.json.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CMU = ROOT.parent / "shared" / "data" / "mocap" / "cmu"


def _steps(Step, acts):
    rng = np.random.default_rng(0)
    return [Step(acts[i % len(acts)], int(rng.integers(30, 90))) for i in range(20)]


def worker(graph_path: str, n_enh: int, runs: int) -> dict:
    from vidstyle.motiongraph import MotionGraph, Step, plan_walk

    g = MotionGraph.load(graph_path)
    present = {g.label_names_[i] for i in np.unique(g.labels_[g.scc_])}
    acts = [a for a in ("walk", "run", "jump") if a in present]
    if n_enh:
        from vidstyle.motiongraph import EdgeKind

        rng = np.random.default_rng(1)
        k = int(g.window)
        kept = np.flatnonzero(g.scc_)
        fc = g.frame_clip_
        N = g.n_frames
        ok_src = kept[(kept + k < N) & (fc[np.minimum(kept + k, N - 1)] == fc[kept])]
        ok_dst = kept[(kept - k + 1 >= 0) & (fc[np.maximum(kept - k + 1, 0)] == fc[kept])]
        segs = []
        for c in rng.choice(ok_src, 50):
            f = np.arange(c + 1, c + 2 * k + 1)
            segs.append(g.add_segment(g.rotations_[f], g.root_positions_[f], centre=k - 1))
        blend = g.edge_cost_[g.edges(EdgeKind.BLEND)]
        g.add_edges(rng.choice(ok_src, n_enh), rng.choice(ok_dst, n_enh), EdgeKind.ENHANCEMENT,
                    cost=rng.choice(blend, n_enh) * rng.uniform(0.5, 2.0, n_enh), segment=rng.choice(segs, n_enh))
    seq = _steps(Step, acts)
    walk = plan_walk(g, seq, strict=False)  # warm-up
    ts = []
    for _ in range(runs):
        t0 = time.perf_counter()
        walk = plan_walk(g, seq, strict=False)
        ts.append(time.perf_counter() - t0)
    return {"median_s": statistics.median(ts), "times_s": ts, "runs": runs, "cost": walk.cost, "frames": g.n_frames,
            "output_frames": int(sum(s.frames for s in seq)), "used": len(walk.transitions_used)}


def build(tmp: Path) -> tuple[Path, Path]:
    sys.path.insert(0, str(ROOT))
    from vidstyle.motiongraph import EdgeKind, MotionGraph, load_clips
    from vidstyle.motiongraph.labels import cmu_action

    rows = list(csv.DictReader(open(CMU / "clips.csv")))
    files = [CMU / r["file"] for r in rows if cmu_action(r["description"]) in ("walk", "run", "jump")]
    g = MotionGraph(mirror=True).fit(load_clips(files, [CMU / "clips.csv"]))
    v2 = tmp / "g2.npz"
    g.save(v2)
    # the same graph in the layout the baseline revision reads (schema 1)
    with np.load(v2, allow_pickle=False) as z:
        a = {k: z[k] for k in z.files}
    blend = a["edge_kind"] == EdgeKind.BLEND
    v1 = {k: v for k, v in a.items() if not k.startswith(("edge_", "segment_")) and k not in ("kind", "schema_version")}
    v1.update(schema=np.array("vidstyle.motiongraph/1"), trans_from=a["edge_src"][blend] + 1, trans_to=a["edge_dst"][blend],
              trans_cost=a["edge_cost"][blend], trans_in_scc=a["edge_in_scc"][blend])
    v1["trans_theta"], v1["trans_x0"], v1["trans_z0"] = a["edge_align"][blend].T
    path1 = tmp / "g1.npz"
    np.savez(path1, **v1)
    return v2, path1


def run(pythonpath: str, graph: Path, n_enh: int, runs: int) -> dict:
    env = dict(os.environ, PYTHONPATH=pythonpath, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    code = (f"import json, sys; sys.path.insert(0, {str(ROOT / 'scripts')!r}); import bench_graph_edges as b; "
            f"print(json.dumps(b.worker({str(graph)!r}, {n_enh}, {runs})))")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--baseline", default="main", help="git revision whose planner is the baseline")
    args = ap.parse_args()
    if not CMU.is_dir():
        sys.exit(f"{CMU} is absent")
    runs = max(5, args.runs)
    with tempfile.TemporaryDirectory() as td:
        tmp = Path(td)
        old = tmp / "baseline"
        old.mkdir()
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.baseline, "vidstyle"], capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", str(old)], input=archive.stdout, check=True)
        v2, v1 = build(tmp)
        configs = [(f"baseline ({args.baseline})", str(old), v1, 0)] + [("edge table", str(ROOT), v2, n) for n in (0, 1000, 10_000)]
        rows = [{"planner": name, "enhancement_edges": n, "times_s": []} for name, _, _, n in configs]
        for _ in range(max(1, args.rounds)):
            for row, (_, pp, graph, n) in zip(rows, configs):
                r = run(pp, graph, n, runs)
                row["times_s"] += r.pop("times_s")
                row.update(r)
        for row in rows:
            row["median_s"] = statistics.median(row["times_s"])
            row["runs"] = len(row["times_s"])
    base = rows[0]["median_s"]
    print(f"{'planner':<18} {'enh. edges':>10} {'median ms':>10} {'vs baseline':>12} {'x real time':>12} {'walk cost':>10}")
    for r in rows:
        r["ratio_to_baseline"] = r["median_s"] / base
        xrt = r["output_frames"] / 30.0 / r["median_s"]
        print(f"{r['planner']:<18} {r['enhancement_edges']:>10} {r['median_s'] * 1000:>10.1f} {r['ratio_to_baseline']:>11.2f}x "
              f"{xrt:>11.0f}x {r['cost']:>10.3f}")
    res = {"graph_frames": rows[0]["frames"], "runs_per_round": runs, "rounds": args.rounds, "one_thread": True, "rows": rows}
    path = ROOT / "bench_results" / "graph_edges.json"
    path.parent.mkdir(exist_ok=True)
    path.write_text(json.dumps(res, indent=2))


if __name__ == "__main__":
    main()
