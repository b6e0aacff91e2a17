"""Bad input through the real ``vidstyle`` console script: one line on stderr naming the file and the
problem, exit status 2, and no output file (issue 11's list). Also: stdout carries only a command's data,
logs and internal-error tracebacks go to stderr.

The subprocesses start together (they are independent), so the walk costs about one start-up per core.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

from vidstyle.cli import main
from vidstyle.style.synthetic import write_fake_dataset

ROOT = Path(__file__).resolve().parents[1]


def _console_script() -> list[str]:
    exe = Path(sys.executable).parent / "vidstyle"
    found = str(exe) if exe.is_file() else shutil.which("vidstyle")
    if not found:
        pytest.fail("the vidstyle console script is not installed (pip install -e .)")
    return [found]


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    env["COLUMNS"] = "200"
    return env


@dataclass
class Case:
    name: str
    args: list[str]
    out: Path | None  # must not exist afterwards
    message: str  # must appear in the error line
    names: Path | None = None  # the file the error line must name
    xfail: str | None = None
    result: dict = field(default_factory=dict)


def _write(path: Path, data: bytes | str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(data, str):
        path.write_text(data, encoding="utf-8")
    else:
        path.write_bytes(data)
    return path


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    """A label dataset, a learned style, a sequence; then every bad-input variant of them."""
    root = tmp_path_factory.mktemp("bad")
    ds = root / "ds"
    write_fake_dataset(ds, n_performers=2, n_videos=2, events_per_video=40, seed=1)
    style = root / "style.json"
    labels = [str(ds / "labels" / f"p00_perf{i}.json") for i in range(2)]
    assert main(["learn-style", *labels, "--out", str(style), "--n-init", "1", "--modes", "1-2"]) == 0
    seq = root / "seq.json"
    assert main(["generate", "--style", str(style), "--length", "5", "--format", "json", "--out", str(seq)]) == 0
    good_labels = json.loads(Path(labels[0]).read_text())
    manifest = json.loads((ds / "dataset.json").read_text())
    return {"root": root, "ds": ds, "style": style, "seq": seq, "labels": good_labels, "manifest": manifest}


def _cases(w) -> list[Case]:
    root: Path = w["root"]
    out = root / "out"
    cases: list[Case] = []

    def learn(name, path, message, names=True):
        dest = out / f"{name}.json"
        cases.append(Case(name, ["learn-style", str(path), "--out", str(dest)], dest, message,
                          path if names else None))

    learn("binary", _write(root / "binary.json", bytes(range(256)) * 4), "not UTF-8 text")
    (root / "adir").mkdir(exist_ok=True)
    learn("directory", root / "adir", "is a directory")
    learn("utf16", _write(root / "utf16.json", json.dumps(w["labels"]).encode("utf-16")), "UTF-16")
    learn("labels_list", _write(root / "list.json", "[]"), "expected a JSON object")
    learn("labels_nan", _write(root / "nan.json", json.dumps({**w["labels"], "confidence": [float("nan")] * len(w["labels"]["labels"])})),
          "not valid JSON (NaN is not a JSON number")
    bad = dict(w["labels"])
    bad["labels"] = ["Jab", "Haymaker"] + bad["labels"][2:]
    learn("unknown_class", _write(root / "unknown.json", json.dumps(bad)), "labels[1]: 'Haymaker' is not one of the classes")
    learn("labels_short_confidence", _write(root / "short.json", json.dumps({**w["labels"], "confidence": [0.5]})),
          "confidence: expected shape")

    def manifest(name, doc, message, field_path=True):
        d = root / f"ds_{name}"
        _write(d / "dataset.json", doc if isinstance(doc, str) else json.dumps(doc))
        dest = out / f"styles_{name}"
        cases.append(Case(name, ["learn-style", "--dataset", str(d), "--out-dir", str(dest)], dest, message,
                          d / "dataset.json"))

    m = w["manifest"]
    manifest("manifest_list", "[]", "expected a JSON object")
    manifest("manifest_no_id", {**m, "videos": [{k: v for k, v in m["videos"][0].items() if k != "id"}]},
             "videos[0].id: missing")
    manifest("manifest_no_performers", {k: v for k, v in m.items() if k != "performers"}, "performers: missing")
    manifest("manifest_empty_performers", {**m, "performers": []}, "performers: expected at least 1")
    manifest("manifest_stranger", {**m, "videos": [{**m["videos"][0], "performer": "nobody"}]},
             "videos[0].performer: 'nobody' is not one of performers[].id")

    style_doc = json.loads(w["style"].read_text())
    nan_style = json.dumps(style_doc).replace(str(style_doc["model_a"]["log_likelihood"]), "NaN", 1)
    for name, text, message in (
        ("style_nan", nan_style, "NaN is not a JSON number"),
        ("style_shape", json.dumps({**style_doc, "model_a": {**style_doc["model_a"], "transition": [[1.0]]}}),
         "model_a.transition: expected shape"),
        ("style_list", "[]", "expected a JSON object"),
    ):
        path = _write(root / f"{name}.json", text)
        dest = out / f"{name}.txt"
        cases.append(Case(name, ["generate", "--style", str(path), "--out", str(dest)], dest, message, path))

    run = root / "run"
    _write(run / "metrics" / "recognition.json",
           json.dumps({"kind": "vidstyle.metrics.recognition", "schema_version": 1, "seed": 0, "frame_accuracy": [0.5]}))
    cases.append(Case("report_metrics_shape", ["report", str(run), "--out", str(out / "report.html")],
                      out / "report.html", "frame_accuracy: expected an object", run / "metrics" / "recognition.json"))
    run2 = root / "run2"
    _write(run2 / "metrics" / "style.json", json.dumps({"kind": "vidstyle.metrics.style", "schema_version": 1,
                                                          "sources": {"ground_truth": {"summary": {"transition_mae": 3}}}}))
    cases.append(Case("report_style_metrics_shape", ["report", str(run2), "--out", str(out / "report2.html")],
                      out / "report2.html", "transition_mae: expected an object", run2 / "metrics" / "style.json"))

    good = root / "g.npz"
    np.savez(good, a=np.arange(1000.0))
    raw = good.read_bytes()
    for name, data, xfail in (("graph_truncated", raw[: len(raw) // 2], None), ("graph_wrong_arrays", raw, None)):
        path = _write(root / f"{name}.npz", data)
        dest = out / f"{name}.bvh"
        cases.append(Case(name, ["synthesize", "--graph", str(path), "--sequence", str(w["seq"]), "--out", str(dest)],
                          dest, "", path, xfail=xfail))
    return cases


@pytest.fixture(scope="module")
def results(world):
    cases = _cases(world)
    cmd = _console_script()
    procs = [(c, subprocess.Popen(cmd + c.args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env(),
                                  cwd=world["root"])) for c in cases]
    done = {}
    for c, p in procs:
        so, se = p.communicate(timeout=300)
        done[c.name] = (c, p.returncode, so.decode("utf-8", "replace"), se.decode("utf-8", "replace"))
    return done


NAMES = ["binary", "directory", "utf16", "labels_list", "labels_nan", "unknown_class", "labels_short_confidence",
         "manifest_list", "manifest_no_id", "manifest_no_performers", "manifest_empty_performers",
         "manifest_stranger", "style_nan", "style_shape", "style_list", "report_metrics_shape",
         "report_style_metrics_shape", "graph_truncated", "graph_wrong_arrays"]


@pytest.mark.slow  # ~20 console-script start-ups (about 30 s of CPU, run concurrently)
@pytest.mark.parametrize("name", NAMES)
def test_bad_input_one_line_exit_2_no_output(results, name, request):
    case, code, out, err = results[name]
    if case.xfail:
        request.applymarker(pytest.mark.xfail(reason=case.xfail, strict=False))
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("vidstyle: error: "), err
    assert "Traceback" not in err
    assert code == 2, err
    assert case.message in lines[0], err
    if case.names is not None:
        assert str(case.names) in lines[0], err
    assert out == "", out
    if case.out is not None:  # the case names an output: it must not have been written
        assert not case.out.exists(), case.out


def test_every_case_is_walked(world):
    assert [c.name for c in _cases(world)] == NAMES


@pytest.mark.slow
def test_generate_text_stdout_is_data_and_logs_go_to_stderr(world):
    style = json.loads(world["style"].read_text())
    p = subprocess.run(_console_script() + ["generate", "--style", str(world["style"]), "--length", "12",
                                            "--seed", "4", "--format", "text"],
                       capture_output=True, text=True, env=_env(), timeout=300, check=False)
    assert p.returncode == 0, p.stderr
    words = p.stdout.split()
    assert p.stdout.count("\n") == 1 and len(words) == 12 and set(words) <= set(style["actions"])
    assert "generated 12 events" in p.stderr  # the log line, on stderr only
    p = subprocess.run(_console_script() + ["generate", "--style", str(world["style"]), "--length", "12",
                                            "--seed", "4", "--format", "csv"],
                       capture_output=True, text=True, env=_env(), timeout=300, check=False)
    rows = [r.split(",") for r in p.stdout.splitlines()]
    assert rows[0] == ["index", "action", "duration_frames", "start_frame"] and len(rows) == 13
    assert [r[1] for r in rows[1:]] == words  # same seed, same sequence
    starts = np.cumsum([0] + [int(r[2]) for r in rows[1:-1]])
    assert [int(r[3]) for r in rows[1:]] == starts.tolist()


def test_internal_error_traceback_goes_to_stderr(monkeypatch, capsys, world):
    import vidstyle.formats.style as fs

    def boom(path):
        raise RuntimeError("a bug, not bad input")

    monkeypatch.setattr(fs, "read_style", boom)
    assert main(["generate", "--style", str(world["style"])]) == 1
    cap = capsys.readouterr()
    assert cap.out == ""
    assert "internal error" in cap.err and "Traceback" in cap.err and "a bug, not bad input" in cap.err


def test_library_errors_name_parameters_cli_names_flags(capsys, world):
    from vidstyle.errors import ParameterError
    from vidstyle.style.events import EventParams

    with pytest.raises(ParameterError, match=r"^min_run: must be >= 1"):
        EventParams(min_run=0)
    labels = str(world["ds"] / "labels" / "p00_perf0.json")
    assert main(["learn-style", labels, "--out", str(world["root"] / "x.json"), "--min-run", "0"]) == 2
    assert capsys.readouterr().err.startswith("vidstyle: error: --min-run: must be >= 1")
