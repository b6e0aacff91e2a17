"""One ``vidstyle`` process's own timing (``VIDSTYLE_TIMINGS``): the owner of ``kind`` ``"vidstyle.run_record"``.

Every ``vidstyle`` command, when the environment variable ``VIDSTYLE_TIMINGS`` names a directory, writes
one of these there as it exits (:func:`vidstyle.timing.record_run`); ``vidstyle timing`` groups them into
the pipeline's stage-time table (``vidstyle.metrics.timing``, :mod:`vidstyle.formats.metrics`).

Schema (``schema_version`` 1)::

    {"kind": "vidstyle.run_record", "schema_version": 1,
     "command": "demo make-dataset",      # the subcommand path ("" for the bare ``vidstyle``)
     "argv": ["demo", "make-dataset", "--out", "out/dataset"],
     "stage": "make_dataset" | null,      # DVC's DVC_STAGE of the process (null outside ``dvc repro``)
     "pid": 4242,
     "start_time": 1764770000.12,         # Unix seconds: the process's start (interpreter start-up included)
     "end_time": 1764770170.40,           # >= start_time
     "wall_seconds": 170.28,              # end_time - start_time
     "cpu_seconds": 12.5,                 # user + system of the process itself
     "children_cpu_seconds": 301.7,       # of its waited-for children (joblib workers, ffmpeg ...)
     "peak_rss_mb": 410.2,                # the process's own peak resident set (MiB)
     "children_peak_rss_mb": 380.0,       # the largest single child's
     "exit_status": 0}                    # the command's exit status (0 ok, 2 bad input, ...)

Other fields are carried along.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

from ._base import Fields, FormatError, check_header, header, read_json_document, write_json_document

KIND = "vidstyle.run_record"
SCHEMA_VERSION = 1
_FIELDS = ("kind", "schema_version", "command", "argv", "stage", "pid", "start_time", "end_time", "wall_seconds",
           "cpu_seconds", "children_cpu_seconds", "peak_rss_mb", "children_peak_rss_mb", "exit_status")


@dataclass
class RunRecord:
    command: str
    argv: list[str]
    stage: str | None
    pid: int
    start_time: float
    end_time: float
    cpu_seconds: float
    children_cpu_seconds: float
    peak_rss_mb: float
    children_peak_rss_mb: float
    exit_status: int
    extra: dict[str, Any] = field(default_factory=dict)
    path: str = ""

    @property
    def wall_seconds(self) -> float:
        return self.end_time - self.start_time

    @property
    def total_cpu_seconds(self) -> float:
        """The process's CPU time and its children's."""
        return self.cpu_seconds + self.children_cpu_seconds

    @property
    def max_rss_mb(self) -> float:
        """The peak resident set of the largest single process: this one or one of its children."""
        return max(self.peak_rss_mb, self.children_peak_rss_mb)

    def to_dict(self) -> dict[str, Any]:
        doc = {**header(KIND, SCHEMA_VERSION), "command": self.command, "argv": list(self.argv),
               "stage": self.stage, "pid": self.pid, "start_time": self.start_time, "end_time": self.end_time,
               "wall_seconds": self.wall_seconds, "cpu_seconds": self.cpu_seconds,
               "children_cpu_seconds": self.children_cpu_seconds, "peak_rss_mb": self.peak_rss_mb,
               "children_peak_rss_mb": self.children_peak_rss_mb, "exit_status": self.exit_status}
        return {**doc, **{k: v for k, v in self.extra.items() if k not in doc}}


def parse_run_record(doc: Any, path: str | os.PathLike | None = None) -> RunRecord:
    check_header(doc, path, KIND, (SCHEMA_VERSION,))
    f = Fields(doc, path)
    command = f.str("command")
    argv = f.str_list("argv", nonempty_items=False)
    stage = None if doc.get("stage") is None else f.str("stage", nonempty=True)
    pid = f.int("pid", min=0)
    start = f.number("start_time", min=0)
    end = f.number("end_time", min=0)
    if end < start:
        raise FormatError(path, "end_time", f"{end} is before start_time {start}")
    wall = f.number("wall_seconds", min=0)
    if abs(wall - (end - start)) > 1e-3 * max(1.0, wall):
        raise FormatError(path, "wall_seconds", f"{wall} but end_time - start_time is {end - start}")
    cpu = f.number("cpu_seconds", min=0)
    children_cpu = f.number("children_cpu_seconds", min=0)
    rss = f.number("peak_rss_mb", min=0)
    children_rss = f.number("children_peak_rss_mb", min=0)
    status = f.int("exit_status", min=-255, max=255)
    extra = {k: v for k, v in doc.items() if k not in _FIELDS}
    return RunRecord(command, argv, stage, pid, start, end, cpu, children_cpu, rss, children_rss, status, extra,
                     "" if path is None else str(path))


def read_run_record(path: str | os.PathLike) -> RunRecord:
    return parse_run_record(read_json_document(path, max_bytes=1 << 20), path)


def write_run_record(path: str | os.PathLike, record: RunRecord) -> None:
    doc = record.to_dict()
    parse_run_record(doc, path)
    write_json_document(path, doc)


__all__ = ["KIND", "SCHEMA_VERSION", "RunRecord", "parse_run_record", "read_run_record", "write_run_record"]
