"""Registers the shared ``evaluate`` group (see :mod:`vidstyle.commands._evaluate`)."""

from __future__ import annotations

import typer

from ._evaluate import evaluate_app


def register(app: typer.Typer) -> None:
    app.add_typer(evaluate_app, name="evaluate")
