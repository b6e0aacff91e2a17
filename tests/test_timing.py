"""The stage-time table (issue 31): every vidstyle command records its own run when VIDSTYLE_TIMINGS names a
directory, `vidstyle timing` groups the records of a run by DVC stage (a real `dvc repro` of a small pipeline
whose stages run vidstyle in loops, pipes and `xargs -P`), the metrics document round-trips through its owner,
and the report shows the table."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from vidstyle.cli import main
from vidstyle.errors import FormatError
from vidstyle.formats.metrics import TIMING, read_metrics, write_metrics
from vidstyle.formats.runrecord import RunRecord, parse_run_record, read_run_record
from vidstyle.timing import OUTSIDE, collect, format_table, stage_name, stage_times

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


def _records(directory: Path) -> list[RunRecord]:
    return sorted((read_run_record(p) for p in directory.glob("*.json")), key=lambda r: r.end_time)


def _rec(stage, start, end, cpu=1.0, kids=0.0, rss=100.0, kids_rss=0.0, status=0, command="generate"):
    return RunRecord(command, [command], stage, 1, start, end, cpu, kids, rss, kids_rss, status)


def _env(**extra) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("VIDSTYLE_TIMINGS", "DVC_STAGE")}
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return {**env, **extra}


# ------------------------------------------------------------------------------------------------ records


def test_a_command_records_itself_only_when_the_variable_names_a_directory(tmp_path, monkeypatch, capsys):
    rec_dir = tmp_path / "records"
    monkeypatch.delenv("VIDSTYLE_TIMINGS", raising=False)
    assert main(["--version"]) == 0
    assert not rec_dir.exists()
    monkeypatch.setenv("VIDSTYLE_TIMINGS", str(rec_dir))
    monkeypatch.setenv("DVC_STAGE", "pipelines/kickboxing/dvc.yaml:report")
    assert main(["timing", str(tmp_path / "none"), "--no-table"]) == 0
    (r,) = _records(rec_dir)
    assert r.command == "timing" and r.argv == ["timing", str(tmp_path / "none"), "--no-table"]
    assert r.exit_status == 0 and r.stage == "pipelines/kickboxing/dvc.yaml:report" and r.pid == os.getpid()
    assert r.end_time >= r.start_time and r.wall_seconds > 0 and r.cpu_seconds > 0 and r.peak_rss_mb > 10
    capsys.readouterr()


def test_a_failing_command_records_its_exit_status(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("VIDSTYLE_TIMINGS", str(tmp_path / "records"))
    monkeypatch.delenv("DVC_STAGE", raising=False)
    bad = tmp_path / "bad.yaml"
    bad.write_text("not: [a, dvc file\n")
    assert main(["-q", "timing", str(tmp_path), "--dvc", str(bad)]) == 2
    assert main(["demo", "make-dataset", "--no-such-flag"]) == 2  # a usage error
    assert "not valid YAML" in capsys.readouterr().err
    first, second = _records(tmp_path / "records")
    assert (first.command, first.exit_status, first.stage) == ("timing", 2, None)
    assert (second.command, second.exit_status) == ("demo make-dataset", 2)


def test_an_unwritable_directory_warns_and_keeps_the_exit_status(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")  # a directory cannot be made under a regular file (even as root)
    res = subprocess.run([sys.executable, "-m", "vidstyle", "--version"], capture_output=True, text=True, check=False,
                         env=_env(VIDSTYLE_TIMINGS=str(blocker / "records")), timeout=300)
    assert res.returncode == 0 and res.stdout.startswith("vidstyle ")
    assert "run record not written" in res.stderr and len(res.stderr.strip().splitlines()) == 1
    res = subprocess.run([sys.executable, "-m", "vidstyle", "generate", "--style", str(tmp_path / "missing.json")],
                         capture_output=True, text=True, check=False, timeout=300,
                         env=_env(VIDSTYLE_TIMINGS=str(blocker / "records"), COLUMNS="1000"))
    assert res.returncode == 2 and "run record not written" in res.stderr


def test_a_record_times_the_whole_process_and_its_workers(tmp_path):
    """From the process's own start (imports included), and joblib's loky workers' CPU counts as children's."""
    code = textwrap.dedent("""
        import sys, time
        from joblib import Parallel, delayed
        from vidstyle.timing import process_start_time, record_run
        def burn(n):
            s = 0
            for i in range(n):
                s += i * i
            return s
        time.sleep(0.5)
        Parallel(n_jobs=2, backend="loky")(delayed(burn)(2_000_000) for _ in range(4))
        record_run(sys.argv[1], "test", [], 0, process_start_time())
    """)
    subprocess.run([sys.executable, "-c", code, str(tmp_path)], check=True, env=_env(), timeout=300)
    (r,) = _records(tmp_path)
    assert r.wall_seconds > 0.5  # the sleep and what ran before it
    assert r.children_cpu_seconds > 0.2 and r.children_peak_rss_mb > 10  # the workers, shut down first


def test_a_command_a_shell_execs_after_another_records_only_itself(tmp_path):
    """``sh -c 'a && exec vidstyle ...'`` (what a DVC stage's ``a && vidstyle ...`` becomes): the process id
    started with the shell and has already waited for ``a``, whose CPU and time are not this command's."""
    burn = f"{sys.executable} -c 'import time\nt = time.process_time()\nwhile time.process_time() - t < 1.5: pass'"
    subprocess.run(["sh", "-c", f'{burn} && exec "{sys.executable}" -m vidstyle --help'], check=True, timeout=300,
                   capture_output=True, env=_env(VIDSTYLE_TIMINGS=str(tmp_path)))
    (r,) = _records(tmp_path)
    assert r.children_cpu_seconds < 0.5  # the 1.5 s burn is not this command's children
    assert r.wall_seconds < 1.2  # nor is its time


def test_record_owner_checks_its_fields():
    doc = _rec("s", 10.0, 12.0).to_dict()
    assert parse_run_record(doc).wall_seconds == 2.0
    for key, value, problem in [("end_time", 9.0, "before start_time"), ("wall_seconds", 5.0, "end_time - start_time"),
                                ("cpu_seconds", -1, "at least 0"), ("argv", "generate", "expected a list"),
                                ("exit_status", 1.5, "expected an integer")]:
        with pytest.raises(FormatError, match=problem):
            parse_run_record({**doc, key: value}, "r.json")


# ----------------------------------------------------------------------------------------------- grouping


STAGES = ["make", "loop", "fan", "sweep", "report"]


def test_records_group_by_stage_with_spans_sums_and_statuses():
    recs = [
        _rec("make", 0.0, 10.0, cpu=2.0, kids=6.0, rss=200.0, kids_rss=300.0, command="demo make-dataset"),
        _rec("loop", 11.0, 12.0, cpu=1.0), _rec("loop", 12.5, 14.0, cpu=1.5),          # one after the other
        _rec("fan", 20.0, 25.0, cpu=4.0), _rec("fan", 20.1, 23.0, cpu=3.0),            # xargs -P 2: at once
        _rec("fan", 23.1, 27.0, cpu=4.0, status=2),
        _rec("dir/dvc.yaml:sweep@0", 30.0, 31.0), _rec("sweep@1", 31.0, 33.0),        # foreach instances
        _rec(None, 40.0, 41.0, command="timing"),                                     # outside DVC
    ]
    m = stage_times(recs, STAGES, since=-5.0, now=45.0, current_stage="pipelines/kickboxing/dvc.yaml:report")
    rows = {s["stage"]: s for s in m.doc["stages"]}
    assert [s["stage"] for s in m.doc["stages"]] == [*STAGES, OUTSIDE]
    make, loop, fan, sweep = rows["make"], rows["loop"], rows["fan"], rows["sweep"]
    assert (make["status"], make["wall_seconds"], make["cpu_seconds"], make["peak_rss_mb"]) == ("ran", 10.0, 8.0, 300.0)
    assert make["commands"] == ["demo make-dataset"]
    assert (loop["invocations"], loop["wall_seconds"], loop["cpu_seconds"]) == (2, 3.0, 2.5)
    assert (fan["status"], fan["invocations"], fan["failed"], fan["wall_seconds"]) == ("failed", 3, 1, 7.0)
    assert fan["cpu_seconds"] == 11.0  # more CPU than wall: the invocations ran in parallel
    assert (sweep["invocations"], sweep["wall_seconds"]) == (2, 3.0)
    assert rows["report"]["status"] == "running" and rows["report"]["wall_seconds"] is None
    assert rows[OUTSIDE]["invocations"] == 1
    assert m.doc["stages_wall_seconds"] == pytest.approx(10 + 3 + 7 + 3)
    assert m.doc["cpu_seconds"] == pytest.approx(8 + 2.5 + 11 + 2 + 1)
    assert (m.doc["started"], m.doc["finished"], m.doc["run_wall_seconds"]) == (0.0, 41.0, 50.0)
    text = format_table(m)
    assert text.splitlines()[0].split() == ["stage", "status", "wall", "s", "CPU", "s", "peak", "RSS", "MB", "runs"]
    assert "fan" in text and "failed" in text and "of which 27.0 s outside vidstyle processes" in text


def test_stages_without_records_are_skipped_or_not_recorded():
    m = stage_times([_rec("loop", 0.0, 1.0)], STAGES)
    assert {s["stage"]: s["status"] for s in m.doc["stages"]} == {
        "make": "skipped", "loop": "ran", "fan": "skipped", "sweep": "skipped", "report": "skipped"}
    m = stage_times([], STAGES, recorded=False)
    assert {s["status"] for s in m.doc["stages"]} == {"not recorded"}
    assert m.doc["started"] is None and m.doc["stages_wall_seconds"] == 0
    assert "no records in" in format_table(m)


def test_stage_names_come_from_dvc_stage():
    assert stage_name("features", STAGES) == "features"
    assert stage_name("pipelines/kickboxing/dvc.yaml:loop", STAGES) == "loop"
    assert stage_name("sweep@3", STAGES) == "sweep" and stage_name("other@3", STAGES) == "other@3"
    assert stage_name(None, STAGES) == OUTSIDE and stage_name("", STAGES) == OUTSIDE


def test_collect_skips_stray_files_and_reads_the_stage_order(tmp_path, monkeypatch):
    monkeypatch.delenv("DVC_STAGE", raising=False)
    recs = tmp_path / "records"
    recs.mkdir()
    (recs / "stray.json").write_text('{"kind": "something else"}')
    (recs / ".partial.tmp.json").write_text("{")  # a record being written: not read
    (tmp_path / "dvc.yaml").write_text("stages:\n  b:\n    cmd: x\n  a:\n    cmd: y\n")
    from vidstyle.formats.runrecord import write_run_record

    write_run_record(recs / "1.json", _rec("a", 1.0, 2.0))
    m = collect(recs, tmp_path / "dvc.yaml")
    assert [(s["stage"], s["status"]) for s in m.doc["stages"]] == [("b", "skipped"), ("a", "ran")]
    assert m.doc["unreadable_records"] == 1 and "not run records" in format_table(m)


# ------------------------------------------------------------------------------------------ metrics owner


def test_timing_metrics_round_trip_through_the_owner(tmp_path):
    m = stage_times([_rec("loop", 0.0, 1.5, kids=0.5), _rec("fan", 2.0, 3.0, status=1)], STAGES, since=-1.0,
                    now=4.0, records_dir="out/timings", dvc_file="dvc.yaml")
    write_metrics(tmp_path / "timing.json", m.doc)
    back = read_metrics(tmp_path / "timing.json")
    assert back.kind == TIMING and back.schema_version == 1 and back.seed is None
    assert back.doc == json.loads(json.dumps(m.doc))


@pytest.mark.parametrize("change, problem", [
    (lambda d: d["stages"][1].update(status="done"), "is not one of"),
    (lambda d: d["stages"][1].update(failed=5), "more than the 1 invocation"),
    (lambda d: d["stages"][0].update(wall_seconds=1.0), "must be null"),
    (lambda d: d["stages"][1].update(wall_seconds=None), "expected a number"),
    (lambda d: d["stages"].append(dict(d["stages"][0])), "appears more than once"),
    (lambda d: d.update(finished=None), "both numbers or both null"),
    (lambda d: d.update(finished=-1.0), "at least 0"),
    (lambda d: d.update(schema_version=2), "schema_version"),
])
def test_timing_metrics_owner_refuses_bad_documents(tmp_path, change, problem):
    doc = json.loads(json.dumps(stage_times([_rec("loop", 1.0, 2.0)], STAGES).doc))
    change(doc)
    (tmp_path / "t.json").write_text(json.dumps(doc))
    with pytest.raises(FormatError, match=problem):
        read_metrics(tmp_path / "t.json", TIMING)


# ------------------------------------------------------------------------------------------------- report


def test_report_shows_the_stage_time_table(tmp_path):
    from vidstyle.report.build import build_report

    run = tmp_path / "out"
    run.mkdir()
    assert "Not available: stage times" in build_report(run)
    m = stage_times([_rec("make", 0.0, 12.25, cpu=3.0, kids=20.0, rss=812.4), _rec("loop", 13.0, 14.0, status=2)],
                    STAGES, since=-1.0, now=20.0, current_stage="report")
    write_metrics(run / "metrics" / "timing.json", m.doc)
    html = build_report(run)
    section = html[html.index("<h2>Stage times</h2>"):]
    rows = [r for r in section.split("<tr>")[2:]]
    assert "<td>make</td><td>ran</td>" in rows[0] and ">12.2<" in rows[0] and ">23.0<" in rows[0]
    assert ">812<" in rows[0]
    assert "<td>loop</td><td>failed</td>" in rows[1]
    assert "<td>fan</td><td>skipped</td>" in rows[2] and "<td>report</td><td>running</td>" in rows[4]
    assert "21.0 s of wall time, 7.8 s of it outside vidstyle processes" in section
    write_metrics(run / "metrics" / "timing.json", stage_times([], STAGES, recorded=False).doc)
    assert "Not recorded: this run kept no timing records" in build_report(run)


# ---------------------------------------------------------------------------------------- a real dvc repro

DVC_YAML = """\
stages:
  one:
    cmd: vidstyle --version > one.txt
    deps: [one.in]
    outs: [one.txt]
  loop:
    cmd: for i in 1 2; do vidstyle --version > "loop$i.txt" || exit 1; done
    deps: [one.txt]
    outs: [loop1.txt, loop2.txt]
  fan:
    cmd: >-
      mkdir -p fan && printf '%s\\n' a b c | xargs -P 2 -I{} sh -c
      'vidstyle --version | cat > "fan/$1.txt"' _ {}
    deps: [one.txt]
    outs: [fan]
  last:
    cmd: vidstyle timing records --dvc dvc.yaml --no-table --out timing.json && cat fan/a.txt > last.txt
    deps: [fan, loop1.txt]
    outs: [last.txt]
"""


@pytest.mark.slow
def test_dvc_repro_records_group_into_their_stages(tmp_path):
    """DVC_STAGE reaches every vidstyle process of a stage, through loops, pipes, xargs -P and sh -c; a second
    run that changes nothing leaves every stage skipped; the stage that makes the table is running."""
    (tmp_path / "dvc.yaml").write_text(DVC_YAML)
    (tmp_path / "one.in").write_text("1")
    env = _env(PATH=f"{BIN}{os.pathsep}{os.environ['PATH']}", DVC_NO_ANALYTICS="1",
               VIDSTYLE_TIMINGS=str(tmp_path / "records"))

    def dvc(*args):
        res = subprocess.run([str(BIN / "dvc"), *args], cwd=tmp_path, env=env, capture_output=True, text=True, check=False,
                             timeout=900)
        assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-2000:]

    dvc("init", "--no-scm", "-q")
    dvc("repro")
    recs = _records(tmp_path / "records")
    assert sorted(r.stage for r in recs) == ["fan", "fan", "fan", "last", "loop", "loop", "one"]
    inside = read_metrics(tmp_path / "timing.json", TIMING)  # made by the last stage, while it ran
    assert [(s["stage"], s["status"], s["invocations"]) for s in inside.doc["stages"]] == [
        ("one", "ran", 1), ("loop", "ran", 2), ("fan", "ran", 3), ("last", "running", 0)]

    m = collect(tmp_path / "records", tmp_path / "dvc.yaml")
    rows = {s["stage"]: s for s in m.doc["stages"]}
    assert [rows[s]["invocations"] for s in ("one", "loop", "fan", "last")] == [1, 2, 3, 1]
    assert {s["status"] for s in m.doc["stages"]} == {"ran"}
    assert rows["last"]["commands"] == ["timing"] and rows["fan"]["commands"] == [""]
    loop = [r for r in recs if r.stage == "loop"]
    assert rows["loop"]["wall_seconds"] == pytest.approx(max(r.end_time for r in loop) - min(r.start_time for r in loop))

    for p in (tmp_path / "records").iterdir():  # the next run, as make demo starts it
        p.unlink()
    (tmp_path / "one.in").write_text("1")
    dvc("repro")
    m = collect(tmp_path / "records", tmp_path / "dvc.yaml")
    assert {s["status"] for s in m.doc["stages"]} == {"skipped"}
