"""The pipeline's stage-time table: every ``vidstyle`` process times itself, ``vidstyle timing`` adds up.

**Records.** When the environment variable ``VIDSTYLE_TIMINGS`` names a directory, every ``vidstyle``
command writes one small JSON record there as it exits (:func:`record_run`, called by
:func:`vidstyle.cli.main`; owner :mod:`vidstyle.formats.runrecord`): its subcommand and arguments, its
wall time from the process's own start (interpreter start-up and imports included), its CPU time and
its children's (joblib's worker processes are shut down first, so theirs count), its peak resident set
and its children's, its exit status, and DVC's ``DVC_STAGE``. A failing command records too; a
directory that cannot be written only logs a warning, never changes the command's exit status.

**Stages.** ``dvc repro`` sets ``DVC_STAGE`` (the stage's name) in the environment of every stage command,
and the variable reaches every process the command starts, through shell loops, pipelines, ``xargs -P``
and ``sh -c`` alike. So a record names its stage itself: nothing is guessed from the command text
(matching ``cmd`` words would be ambiguous here: ``vidstyle features`` runs in ``features`` and in
``camera_features``, ``vidstyle recognize`` in ``recognize`` and ``evaluate_camera``, ``vidstyle
synthesize`` in ``synthesize`` and ``synthesize_augmg``). :func:`stage_times` groups the records of one
run by stage, in ``dvc.yaml``'s order (a ``foreach`` / ``matrix`` stage ``name`` owns ``name@...``):
a stage's wall time is the span from its first record's start to its last record's end (its processes
run inside it, so the span covers parallel invocations once), its CPU time the sum over its processes
(CPU above wall means parallel work), its peak RSS the largest single process's. A stage of
``dvc.yaml`` without records was not run (DVC found it up to date: *skipped*), or, when no records were
kept at all, is *not recorded*. Records without a stage (a ``vidstyle`` command run outside DVC) form a
row of their own. Time spent outside ``vidstyle`` processes (DVC's hashing and checks, the shell) is
the difference between the run's wall time (``--since``, the start of ``dvc repro``) and the stages'.

**One run.** ``make demo`` empties ``out/timings``, runs ``dvc repro`` with
``VIDSTYLE_TIMINGS=out/timings``, then ``vidstyle timing out/timings --dvc dvc.yaml --since T0 --out
out/metrics/timing.json``, which prints the table. The report stage runs the same command first (so the
report shows this run's table; the report stage itself is then *running*): rewriting ``report.html``
after ``dvc repro`` instead would change an output DVC tracks and leave the report stage out of date on
every run. Neither the records nor the timing file are DVC outputs, and no stage depends on them.

Limits: a process killed by a signal (``SIGKILL``, the OOM killer) writes no record; children's peak RSS
is the largest single child's, not the sum of those that ran at once.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from .errors import FormatError, InputError
from .formats.metrics import TIMING, Metrics, parse_metrics
from .formats.runrecord import RunRecord, read_run_record, write_run_record

log = logging.getLogger(__name__)

#: the environment variable naming the records directory
ENV = "VIDSTYLE_TIMINGS"
#: the environment variable DVC sets to the running stage's address (``name`` or ``path/dvc.yaml:name``)
DVC_STAGE_ENV = "DVC_STAGE"
#: the row of records made outside any DVC stage
OUTSIDE = "(outside DVC)"


# ------------------------------------------------------------------------------------------ recording


def process_start_time() -> float | None:
    """Unix time at which this process started (Linux ``/proc``; None elsewhere)."""
    try:
        with open("/proc/self/stat", encoding="ascii") as f:
            fields = f.read().rsplit(")", 1)[1].split()  # after the command name, which may hold spaces
        with open("/proc/uptime", encoding="ascii") as f:
            uptime = float(f.read().split()[0])
        ticks = int(fields[19])  # field 22, starttime: clock ticks after boot
        age = uptime - ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None
    return time.time() - max(age, 0.0)


def _shut_down_workers() -> None:
    """Stop joblib's reusable loky workers now (they would be stopped at interpreter exit anyway) so that
    their CPU time and memory count among this process's children."""
    mod = sys.modules.get("joblib.externals.loky.reusable_executor")
    executor = getattr(mod, "_executor", None)
    if executor is not None:
        executor.shutdown(wait=True)


def _mib(maxrss: int) -> float:
    return maxrss / (1024.0 * 1024.0) if sys.platform == "darwin" else maxrss / 1024.0  # bytes vs KiB


def inherited_usage() -> float:
    """CPU seconds of children already waited for by this process id: nonzero when a shell ran other
    commands and then exec'd this one (``sh -c 'a && vidstyle ...'`` does), whose children's CPU would
    otherwise count again in this record (:func:`measure`'s ``children_before``)."""
    import resource

    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return kids.ru_utime + kids.ru_stime


def measure(command: str, argv: list[str], exit_status: int, started: float,
            children_before: float = 0.0) -> RunRecord:
    """This process's record, now: ``started`` is its start (Unix seconds); ``children_before``
    (:func:`inherited_usage` at the start) is taken off the children's CPU."""
    import resource

    _shut_down_workers()
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    end = time.time()
    stage = os.environ.get(DVC_STAGE_ENV) or None
    return RunRecord(command=command, argv=[str(a) for a in argv], stage=stage, pid=os.getpid(),
                     start_time=min(started, end), end_time=end, cpu_seconds=me.ru_utime + me.ru_stime,
                     children_cpu_seconds=max(kids.ru_utime + kids.ru_stime - children_before, 0.0),
                     peak_rss_mb=_mib(me.ru_maxrss),
                     children_peak_rss_mb=_mib(kids.ru_maxrss), exit_status=int(exit_status))


def record_run(directory: str | os.PathLike, command: str, argv: list[str], exit_status: int,
               started: float, children_before: float = 0.0) -> Path | None:
    """Write this process's record into ``directory`` (made if missing) as
    ``<end in microseconds>-<pid>.json``; returns its path, or None (with a warning) when it cannot be
    written. Never raises: timing must not change a command's outcome."""
    try:
        rec = measure(command, argv, exit_status, started, children_before)
        path = Path(directory) / f"{int(rec.end_time * 1e6)}-{rec.pid}.json"
        write_run_record(path, rec)
        return path
    except Exception as e:  # noqa: BLE001 - an unwritable directory, a full disk ...: the command's result stands
        log.warning("%s=%s: run record not written (%s)", ENV, directory, e)
        return None


# ------------------------------------------------------------------------------------------- grouping


def read_records(directory: str | os.PathLike) -> tuple[list[RunRecord], int]:
    """The records in ``directory`` (oldest first) and the number of files that are not valid records
    (each logged and left out: a stray file must not stop the table). A missing directory has none."""
    directory = Path(directory)
    if not directory.is_dir():
        return [], 0
    records, bad = [], 0
    for path in sorted(directory.glob("*.json")):
        if path.name.startswith("."):  # a record being written (fileio.atomic_path's temporary name)
            continue
        try:
            records.append(read_run_record(path))
        except FormatError as e:
            log.warning("skipping %s", e)
            bad += 1
    records.sort(key=lambda r: (r.start_time, r.end_time, r.pid))
    return records, bad


def dvc_stages(dvc_file: str | os.PathLike) -> list[str]:
    """The stage names of a ``dvc.yaml``, in file order (``InputError`` naming the file when it cannot be
    read as one)."""
    from ruamel.yaml import YAML, YAMLError

    path = Path(dvc_file)
    try:
        doc = YAML(typ="safe", pure=True).load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"{path}: cannot be read ({getattr(e, 'strerror', None) or e})") from None
    except YAMLError as e:
        raise InputError(f"{path}: not valid YAML ({' '.join(str(e).split())[:200]})") from None
    stages = doc.get("stages") if isinstance(doc, dict) else None
    if not isinstance(stages, dict) or not stages:
        raise InputError(f"{path}: no 'stages' mapping (not a dvc.yaml?)")
    return [str(name) for name in stages]


def stage_name(address: str | None, stages: list[str]) -> str:
    """The ``dvc.yaml`` stage of a DVC_STAGE value: without its ``path/dvc.yaml:`` prefix, and a
    ``foreach`` / ``matrix`` instance ``name@key`` under ``name`` when ``name`` is a stage; :data:`OUTSIDE`
    for none."""
    if not address:
        return OUTSIDE
    name = address.rsplit(":", 1)[-1]
    base = name.split("@", 1)[0]
    return base if name not in stages and base in stages else name


@dataclass
class _Row:
    stage: str
    records: list[RunRecord]

    def doc(self, status: str) -> dict:
        rs = self.records
        if not rs:
            return {"stage": self.stage, "status": status, "invocations": 0, "failed": 0, "wall_seconds": None,
                    "cpu_seconds": None, "peak_rss_mb": None, "commands": []}
        commands = list(dict.fromkeys(r.command for r in rs))
        return {"stage": self.stage, "status": status, "invocations": len(rs),
                "failed": sum(r.exit_status != 0 for r in rs),
                "wall_seconds": max(r.end_time for r in rs) - min(r.start_time for r in rs),
                "cpu_seconds": sum(r.total_cpu_seconds for r in rs),
                "peak_rss_mb": max(r.max_rss_mb for r in rs), "commands": commands}


def stage_times(records: list[RunRecord], stages: list[str] | None = None, *, recorded: bool = True,
                records_dir: str = "", dvc_file: str | None = None, since: float | None = None,
                now: float | None = None, current_stage: str | None = None, unreadable: int = 0) -> Metrics:
    """The ``vidstyle.metrics.timing`` document of one run's ``records`` (see the module docstring).

    ``stages``: ``dvc.yaml``'s stage names (its rows, in order; without them, the stages seen in the
    records, in order of first start); ``recorded``: records were kept (otherwise every stage is *not
    recorded*); ``since``: the run's start (Unix seconds) for ``run_wall_seconds`` up to ``now`` (default:
    the current time); ``current_stage``: the stage this table is made in (DVC_STAGE of the caller), shown
    as *running*."""
    current = stage_name(current_stage, stages or []) if current_stage else None
    by_stage: dict[str, list[RunRecord]] = {}
    for r in records:
        by_stage.setdefault(stage_name(r.stage, stages or []), []).append(r)
    names = list(stages or [])
    extra = [s for s in by_stage if s not in names]  # stages dvc.yaml does not have; then the outside row
    names += sorted((s for s in extra if s != OUTSIDE), key=lambda s: by_stage[s][0].start_time)
    if OUTSIDE in by_stage:
        names.append(OUTSIDE)
    rows = []
    for name in names:
        row = _Row(name, by_stage.get(name, []))
        if row.records and any(r.exit_status != 0 for r in row.records):
            status = "failed"
        elif name == current:
            status = "running"
        elif row.records:
            status = "ran"
        else:
            status = "skipped" if recorded else "not recorded"
        rows.append(row.doc(status))
    now = time.time() if now is None else now
    doc = {"kind": TIMING, "schema_version": 1, "records_dir": str(records_dir), "recorded": bool(recorded),
           "dvc_file": None if dvc_file is None else str(dvc_file),
           "started": min((r.start_time for r in records), default=None),
           "finished": max((r.end_time for r in records), default=None),
           "run_wall_seconds": None if since is None else max(now - since, 0.0),
           "stages_wall_seconds": sum(r["wall_seconds"] or 0.0 for r in rows if r["stage"] != OUTSIDE),
           "cpu_seconds": sum(r["cpu_seconds"] or 0.0 for r in rows),
           "unreadable_records": int(unreadable), "cores": os.cpu_count(), "stages": rows}
    return parse_metrics(doc, None, TIMING)


def collect(records_dir: str | os.PathLike, dvc_file: str | os.PathLike | None = None,
            since: float | None = None) -> Metrics:
    """:func:`stage_times` of the records in ``records_dir`` (``dvc_file``: the pipeline's ``dvc.yaml``),
    made in the current process (its DVC_STAGE, if any, is the *running* stage)."""
    stages = None if dvc_file is None else dvc_stages(dvc_file)
    records, bad = read_records(records_dir)
    return stage_times(records, stages, recorded=Path(records_dir).is_dir(), records_dir=str(records_dir),
                       dvc_file=None if dvc_file is None else str(dvc_file), since=since,
                       current_stage=os.environ.get(DVC_STAGE_ENV), unreadable=bad)


# ------------------------------------------------------------------------------------------------ table


def _num(v: float | None, fmt: str = "{:.1f}") -> str:
    return "-" if v is None else fmt.format(v)


def format_table(m: Metrics) -> str:
    """The stage-time table as plain text (what ``vidstyle timing`` prints)."""
    rows = [["stage", "status", "wall s", "CPU s", "peak RSS MB", "runs"]]
    for s in m.doc["stages"]:
        rows.append([s["stage"], s["status"], _num(s["wall_seconds"]), _num(s["cpu_seconds"]),
                     _num(s["peak_rss_mb"], "{:.0f}"), str(s["invocations"])])
    ran = [s for s in m.doc["stages"] if s["invocations"]]
    rows.append(["total", f"{len(ran)} with runs", _num(m.doc["stages_wall_seconds"]), _num(m.doc["cpu_seconds"]),
                 _num(max((s["peak_rss_mb"] for s in ran), default=None), "{:.0f}"),
                 str(sum(s["invocations"] for s in m.doc["stages"]))])
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = []
    for k, r in enumerate(rows):
        if k == len(rows) - 1:
            lines.append("  ".join("-" * w for w in widths))
        lines.append("  ".join(c.ljust(w) if i < 2 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths))))
    notes = []
    run_wall = m.doc.get("run_wall_seconds")
    if run_wall is not None:
        notes.append(f"run wall time {run_wall:.1f} s, of which {max(run_wall - m.doc['stages_wall_seconds'], 0):.1f} s "
                     "outside vidstyle processes (DVC, the shell)")
    if not m.doc["recorded"]:
        notes.append(f"no records in {m.doc['records_dir']}: run the pipeline with {ENV}={m.doc['records_dir']} "
                     "(make demo does)")
    if m.doc["unreadable_records"]:
        notes.append(f"{m.doc['unreadable_records']} file(s) in {m.doc['records_dir']} are not run records (left out)")
    return "\n".join(lines + notes) + "\n"


__all__ = ["ENV", "OUTSIDE", "collect", "dvc_stages", "format_table", "inherited_usage", "measure", "process_start_time", "read_records",
           "record_run", "stage_name", "stage_times"]
