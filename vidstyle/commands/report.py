"""``vidstyle report``: a self-contained HTML page of a pipeline run."""

from __future__ import annotations

import logging
from pathlib import Path

import typer

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:
    app.command("report")(report)


def report(
    run_dir: Path = typer.Argument(..., help="Run directory of the kickboxing pipeline (e.g. pipelines/kickboxing/out)."),
    out: Path = typer.Option(None, "--out", "-o", help="HTML file to write (default: RUN_DIR/report.html)."),
    metrics: Path = typer.Option(
        None, "--metrics", help="Also write the run's headline numbers here (flat JSON for `dvc metrics show`)."
    ),
) -> None:
    """Write one self-contained HTML page: confusion matrix, recognised vs true timeline, learned vs true
    transition matrices, generated sequences, motion-graph statistics and the synthesized motion."""
    from ..fileio import write_text
    from ..formats.metrics import write_metrics
    from ..report.build import build_report, headline_metrics

    out = out or run_dir / "report.html"
    html = build_report(run_dir)
    if metrics is not None:
        write_metrics(metrics, headline_metrics(run_dir))
    write_text(out, html)
    log.info("report written to %s", out)
    typer.echo(str(out.resolve()))
