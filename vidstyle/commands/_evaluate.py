"""The shared ``vidstyle evaluate`` command group.

Stage modules add their sub-command with ``@evaluate_app.command("<stage>")``; the group itself is
added to the root app once, by :mod:`vidstyle.commands.evaluate`. (A leading underscore keeps this
module out of the automatic ``register(app)`` discovery.)
"""

from __future__ import annotations

import typer

evaluate_app = typer.Typer(
    help="Evaluate a stage (style, recognition, motion, ...): print a table and write metrics JSON.",
    no_args_is_help=True,
)


def merge_headline(path, keys: dict) -> None:
    """Merge an evaluation's headline ``keys`` into the JSON file ``path`` (``--headline``), creating it."""
    from ..fileio import read_json, write_json

    head = read_json(path) if path.is_file() else {}
    head.update(keys)
    write_json(path, head)
