"""The motion-graph stages as library calls (issue 26): with their defaults they write what
``vidstyle build-graph``, ``synthesize`` and ``evaluate motion`` write with theirs, and they check their
parameters themselves (the CLI only names its flags)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_motiongraph_graph import _gait

from vidstyle.cli import main
from vidstyle.errors import ParameterError
from vidstyle.evaluation.motion import evaluate
from vidstyle.fileio import json_default
from vidstyle.mocap import write_bvh
from vidstyle.motiongraph import MotionGraph, build_graph, defaults, save_synthesis, synthesize

# (frames, stride frequency, swing amplitude, speed, phase): a jog close enough to the walk that the
# defaults' 5 % threshold keeps both actions in the graph's component
CLIPS = {"walk_a": (90, 1.0, 30, 4.0, 0.0), "walk_b": (75, 1.0, 30, 4.0, 1.0), "run_a": (80, 1.2, 34, 5.0, 0.0),
         "run_b": (70, 1.2, 34, 5.0, 2.0)}


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("mglib")
    files = []
    for name, (n, freq, amp, speed, phase) in CLIPS.items():
        write_bvh(_gait(n, freq, amp, speed, phase=phase), tmp / f"{name}.bvh")
        files.append(tmp / f"{name}.bvh")
    labels = tmp / "labels.csv"
    labels.write_text("file,label\n" + "".join(f"{n}.bvh,{n.split('_')[0]}\n" for n in CLIPS))
    seq = tmp / "seq.json"
    seq.write_text(json.dumps(["walk", "run", "walk"]))
    return tmp, files, labels, seq


@pytest.fixture(scope="module")
def both(inputs):
    """The same stages run by the CLI (defaults of its flags) and by the library (its defaults)."""
    tmp, files, labels, seq = inputs
    cli, lib = tmp / "cli", tmp / "lib"
    cli.mkdir()
    lib.mkdir()
    assert main(["build-graph", *map(str, files), "--labels", str(labels), "--out", str(cli / "graph.npz")]) == 0
    build_graph(files, [labels]).save(lib / "graph.npz")
    assert main(["synthesize", "--graph", str(cli / "graph.npz"), "--sequence", str(seq),
                 "--out", str(cli / "motion.bvh")]) == 0
    save_synthesis(synthesize(MotionGraph.load(lib / "graph.npz"), seq), lib / "motion.bvh")
    return cli, lib


def _arrays(path) -> dict:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _params(arrays: dict) -> dict:
    p = json.loads(str(arrays["params_json"]))
    p["stats"] = {k: v for k, v in p["stats"].items() if not k.endswith("_seconds")}  # wall-clock times
    return p


def test_build_graph_library_defaults_write_the_cli_graph(both):
    cli, lib = both
    a, b = _arrays(cli / "graph.npz"), _arrays(lib / "graph.npz")
    assert a.keys() == b.keys()
    for key in a:
        if key != "params_json":
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    assert _params(a) == _params(b)
    assert _params(a)["window"] == defaults.WINDOW and _params(a)["threshold_quantile"] == defaults.THRESHOLD_QUANTILE
    g = MotionGraph.load(lib / "graph.npz")
    assert {"walk", "run"} <= {g.label_names_[i] for i in np.unique(g.labels_[g.scc_])}  # a graph worth walking


def test_synthesize_library_defaults_write_the_cli_motion_and_labels(both):
    cli, lib = both
    assert (cli / "motion.bvh").read_bytes() == (lib / "motion.bvh").read_bytes()
    assert (cli / "motion.labels.json").read_bytes() == (lib / "motion.labels.json").read_bytes()
    doc = json.loads((lib / "motion.labels.json").read_text())
    assert doc["bvh"] == "motion.bvh" and {"walk", "run"} <= set(doc["labels"])
    assert doc["planner"]["mismatch_penalty"] == defaults.MISMATCH_PENALTY


def test_evaluate_motion_library_gives_the_cli_metrics(both, tmp_path):
    cli, _ = both
    out = tmp_path / "m.json"
    assert main(["evaluate", "motion", "--graph", str(cli / "graph.npz"), str(cli / "motion.bvh"), "--out", str(out)]) == 0
    written = json.loads(out.read_text())
    ours = evaluate(MotionGraph.load(cli / "graph.npz"), [cli / "motion.bvh"])
    ours = json.loads(json.dumps(ours, default=json_default))
    assert written.pop("graph") == str(cli / "graph.npz")
    assert {k: v for k, v in written.items() if k not in ("kind", "schema_version")} == ours


@pytest.mark.parametrize("kw,flag", [({"dtype": "float16"}, "--dtype"), ({"threshold_quantile": 1.5}, "--quantile"),
                                     ({"threshold": -1.0}, "--threshold"), ({"tile": 4}, "--tile")])
def test_build_graph_checks_parameters_before_reading_clips(inputs, tmp_path, capsys, kw, flag):
    _, files, _, _ = inputs
    with pytest.raises(ParameterError) as e:
        build_graph([tmp_path / "absent.bvh"], **kw)  # the parameter, not the missing clip, is reported
    assert e.value.param == next(iter(kw))
    cli_value = {"dtype": "float16", "threshold_quantile": "1.5", "threshold": "-1", "tile": "4"}[next(iter(kw))]
    out = tmp_path / "g.npz"
    assert main(["build-graph", str(files[0]), flag, cli_value, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"vidstyle: error: {flag}: ") and len(err.splitlines()) == 1
    assert not out.exists()
