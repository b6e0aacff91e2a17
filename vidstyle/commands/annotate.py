"""``vidstyle annotate``: mark transition frames and action segments in the browser, frame-exact, and choose
the performer ``vidstyle pose --annotations`` follows.

    vidstyle annotate v1.mp4 v2.mp4 --annotations annotations.json [--recognized v1.json] [--poses p.json]
        [--matches m.json] [--port 8765] [--no-browser]
"""

from __future__ import annotations

import logging
from pathlib import Path

import typer

from ..annotate.launch import MAX_BODY_LIMIT_MB, MAX_BODY_MB, MIN_BODY_MB
from ._numbers import number

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:
    app.command("annotate")(annotate)


def annotate(
    videos: list[Path] = typer.Argument(..., help="Videos to annotate (served by id 0, 1, ... in this order)."),
    annotations: Path = typer.Option(
        Path("annotations.json"), "--annotations", "-a",
        help="Annotations file to edit (created if absent; videos it holds that are not given are kept)."),
    recognized: list[Path] = typer.Option(
        [], "--recognized",
        help="Recognised labels JSON from `recognize` (repeatable): the label and confidence of the current "
             "frame beside it, and a timeline row."),
    labels: list[Path] = typer.Option([], "--labels", hidden=True, help="Old name of --recognized."),
    poses: list[Path] = typer.Option([], "--poses", help="poses.json from `pose` (repeatable)."),
    matches: list[Path] = typer.Option([], "--matches", help="matches.json from `match-pose` (repeatable)."),
    classes: str | None = typer.Option(
        None, "--classes",
        help="Comma-separated action classes (keys 1-9 pick the first nine). Default: the file's, else the "
             "recognised labels', else the demo's kickboxing classes."),
    host: str = typer.Option("127.0.0.1", "--host", help="Address to listen on (anything but loopback is "
                                                          "reachable by others: the page then needs a key, "
                                                          "printed once at start as the URL's #key=...)."),
    port: int = number(8765, "--port", lo=0, hi=65535, help="Port (0: any free port)."),
    no_browser: bool = typer.Option(False, "--no-browser", help="Do not open a browser."),
    max_body_mb: float = number(MAX_BODY_MB, "--max-body-mb", lo=MIN_BODY_MB, hi=MAX_BODY_LIMIT_MB, help="Largest request body accepted (MB)."),
) -> None:
    """Open a local web page to mark transition frames (T) and action segments ([ ]) frame by frame, and
    to choose the performer (P, then click them; `pose --annotations` follows that person).

    Frames are decoded on the server by index and the annotations file is saved atomically, tied to each
    video's sha256 and decoded frame count. Press ? in the page for the keys."""
    from ..annotate.launch import annotate as serve_page
    from ..demo import CLASSES  # the page's classes when nothing else names any

    serve_page(videos, annotations, labels=[*recognized, *labels], poses=poses, matches=matches, classes=classes,
               default_classes=CLASSES, host=host, port=port, open_browser=not no_browser, max_body_mb=max_body_mb)
