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
    text: bool = typer.Option(
        False, "--text", help="Print the headline numbers as a few grouped lines (at most 120 columns) "
                              "instead of writing the page."
    ),
) -> None:
    """Write one self-contained HTML page: confusion matrix, recognised vs true timeline, learned vs true
    transition matrices, generated sequences, motion-graph statistics and the synthesized motion."""
    from ..fileio import write_text
    from ..formats.metrics import write_metrics
    from ..report.build import build_report, headline_metrics

    if text:
        from ..errors import InputError
        from ..report.text import headline_text

        if not run_dir.is_dir():
            raise InputError(f"{run_dir}: run directory not found")
        head = headline_metrics(run_dir)
        if metrics is not None:
            write_metrics(metrics, head)
        typer.echo(headline_text(head) or f"{run_dir}: no metrics yet (out/metrics/*.json)")
        return
    out = out or run_dir / "report.html"
    html = build_report(run_dir)
    if metrics is not None:
        write_metrics(metrics, headline_metrics(run_dir))
    write_text(out, html)
    log.info("report written to %s", out)
    typer.echo(str(out.resolve()))
