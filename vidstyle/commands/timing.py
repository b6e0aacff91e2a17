"""``vidstyle timing``: the stage-time table of a pipeline run, from the runs' own timing records."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Annotated

import typer

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:
    app.command("timing")(timing)


def timing(
    records: Annotated[Path, typer.Argument(
        help="Directory of run records: every vidstyle command writes one there when VIDSTYLE_TIMINGS names it.")],
    dvc: Annotated[Path | None, typer.Option(
        "--dvc", help="The pipeline's dvc.yaml: one row per stage, in its order; stages without records show as "
        "skipped (up to date).")] = None,
    since: Annotated[float | None, typer.Option(
        "--since", help="When the run started (Unix seconds, taken before dvc repro): adds the run's wall time and "
        "the part spent outside vidstyle processes (DVC, the shell).")] = None,
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="Write the table as metrics JSON (vidstyle.metrics.timing).")] = None,
    table: Annotated[bool, typer.Option("--table/--no-table", help="Print the table on stdout.")] = True,
) -> None:
    """The stage-time table of a pipeline run, from its processes' own timing records (VIDSTYLE_TIMINGS).

    Groups the records by DVC stage (each names its stage: DVC sets DVC_STAGE for every command of a stage)
    and prints per stage its status (ran, failed, skipped, running), wall time (first start to last end),
    CPU time (the processes and their children), peak RSS of the largest process, and processes. `make
    demo` runs it after `dvc repro` (out/metrics/timing.json; the report shows it)."""
    from ..formats.metrics import write_metrics
    from ..timing import collect, format_table

    m = collect(records, dvc, since=since)
    if out is not None:
        write_metrics(out, m.doc)
        log.info("timing table written to %s", out)
    if table:
        typer.echo(format_table(m), nl=False)
