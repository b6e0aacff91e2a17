"""Synthesis: the blocked DP against a plain per-frame, per-transition reference; sequence files."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.motiongraph import EdgeKind, MotionGraph, Step, parse_sequence, plan_walk
from vidstyle.motiongraph.blend import blend_weight

from test_motiongraph_graph import _clips


@pytest.fixture(scope="module")
def graph():
    return MotionGraph(window=6, fps=30, threshold_quantile=0.1, random_state=0).fit(_clips())


def reference_cost(graph, steps, mismatch=5.0, penalty=0.2) -> float:
    """The objective of plan_walk by the textbook recursion, one frame and one transition at a time."""
    k = graph.window
    names = graph.label_names_
    req = [st.action for st in steps for _ in range(st.frames)]
    scc = np.flatnonzero(graph.scc_)
    index = {int(f): i for i, f in enumerate(scc)}
    lab = [names[graph.labels_[f]] for f in scc]
    from_side = blend_weight(np.arange(k), k) >= 0.5
    trans = []
    for e in graph.edges(EdgeKind.BLEND, in_scc=True):
        a, b = int(graph.edge_src_[e]) + 1, int(graph.edge_dst_[e])
        blend = [names[graph.labels_[a + p] if from_side[p] else graph.labels_[b - k + 1 + p]] for p in range(k)]
        trans.append((index[a - 1], index[b], graph.edge_cost_[e] / graph.threshold_ + penalty, blend))
    V = [[0.0 if lab[i] == req[0] else mismatch for i in range(len(scc))]]
    for t in range(1, len(req)):
        row = []
        for i, f in enumerate(scc):
            ok = i > 0 and scc[i - 1] == f - 1 and graph.frame_clip_[f - 1] == graph.frame_clip_[f]
            row.append(V[t - 1][i - 1] + (0.0 if lab[i] == req[t] else mismatch) if ok else np.inf)
        if t >= k:
            for d, a, c, blend in trans:
                miss = sum(blend[p] != req[t - k + 1 + p] for p in range(k))
                row[a] = min(row[a], V[t - k][d] + c + mismatch * miss)
        V.append(row)
    return float(min(V[-1]))


def walk_cost(graph, walk, mismatch=5.0, penalty=0.2) -> float:
    """Cost of the walk actually returned (transition costs + mismatched output frames)."""
    names = graph.label_names_
    got = [names[x] for x in graph.labels_[walk.frames]]
    miss = sum(a != b for a, b in zip(got, walk.requested))
    return sum(graph.edge_cost_[e] / graph.threshold_ + penalty for e in walk.transitions_used) + mismatch * miss


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_blocked_dp_matches_the_reference(graph, seed):
    rng = np.random.default_rng(seed)
    # short steps (< k) put several step boundaries inside one blend window
    steps = [Step(str(rng.choice(["walk", "run"])), int(rng.integers(2, 30))) for _ in range(6)]
    walk = plan_walk(graph, steps, strict=False)
    assert walk.cost == pytest.approx(reference_cost(graph, steps), abs=1e-9)
    assert walk_cost(graph, walk) == pytest.approx(walk.cost, abs=1e-9)


def test_checkpointed_history_gives_the_same_walk(graph):
    steps = [Step("walk", 40), Step("run", 33), Step("walk", 41), Step("run", 20)]
    full = plan_walk(graph, steps)
    tiny = plan_walk(graph, steps, max_history_bytes=1)  # keep one block in ~n_blocks, recompute the rest
    assert tiny.cost == full.cost
    np.testing.assert_array_equal(tiny.frames, full.frames)
    assert tiny.transitions_used == full.transitions_used


def test_generate_json_is_read_as_is():
    doc = {"kind": "vidstyle.sequence", "schema_version": 1, "fps": 20.0, "seed": 0,
           "events": [{"action": "Jab", "duration_frames": 13, "start_frame": 0},
                      {"action": "LowKick", "duration_frames": 16, "start_frame": 13}]}
    steps = parse_sequence(doc, 30)
    assert [(s.action, s.frames) for s in steps] == [("Jab", 20), ("LowKick", 24)]
    from vidstyle.errors import InputError

    with pytest.raises(InputError, match="'fps' must be positive"):
        parse_sequence({**doc, "fps": 0}, 30)
