"""``vidstyle annotate``: mark transition frames and action segments in the browser, frame-exact.

    vidstyle annotate v1.mp4 v2.mp4 --annotations annotations.json [--labels v1.json] [--poses p.json]
        [--matches m.json] [--port 8765] [--no-browser]
"""

from __future__ import annotations

import logging
from pathlib import Path

import typer

from ..errors import InputError

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:
    app.command("annotate")(annotate)


def annotate(
    videos: list[Path] = typer.Argument(..., help="Videos to annotate (served by id 0, 1, ... in this order)."),
    annotations: Path = typer.Option(
        Path("annotations.json"), "--annotations", "-a",
        help="Annotations file to edit (created if absent; videos it holds that are not given are kept)."),
    labels: list[Path] = typer.Option([], "--labels", help="Recognised labels JSON from `recognize` (repeatable)."),
    poses: list[Path] = typer.Option([], "--poses", help="poses.json from `pose` (repeatable)."),
    matches: list[Path] = typer.Option([], "--matches", help="matches.json from `match-pose` (repeatable)."),
    classes: str | None = typer.Option(
        None, "--classes",
        help="Comma-separated action classes (keys 1-9 pick the first nine). Default: the file's, else the "
             "recognised labels', else the demo's kickboxing classes."),
    host: str = typer.Option("127.0.0.1", "--host", help="Address to listen on (anything but loopback is "
                                                          "reachable by others: a warning is logged)."),
    port: int = typer.Option(8765, "--port", help="Port (0: any free port)."),
    no_browser: bool = typer.Option(False, "--no-browser", help="Do not open a browser."),
    max_body_mb: float = typer.Option(16.0, "--max-body-mb", help="Largest request body accepted (MB)."),
) -> None:
    """Open a local web page to mark transition frames (T) and action segments ([ ]) frame by frame.

    Frames are decoded on the server by index and the annotations file is saved atomically, tied to each
    video's sha256 and decoded frame count. Press ? in the page for the keys."""
    from ..annotate.overlays import load_overlays
    from ..annotate.server import new_session, serve
    from ..annotate.session import Store, open_videos

    if not 0 <= port < 65536:
        raise InputError(f"--port: must be in 0..65535, got {port}")
    if max_body_mb <= 0:
        raise InputError(f"--max-body-mb: must be positive, got {max_body_mb}")
    if host not in ("127.0.0.1", "localhost", "::1"):
        log.warning("annotate: listening on %s: anyone who can reach this address can read the videos; "
                    "saving still needs the page's session token", host)
    vids = open_videos(videos)
    overlays = load_overlays(vids, labels, poses, matches)
    if classes:
        names = [c.strip() for c in classes.split(",") if c.strip()]
    elif annotations.exists():
        names = []
    else:
        names = []
        for ov in overlays.values():
            for c in ov.get("recognized", {}).get("classes", []):
                if c not in names:
                    names.append(c)
        if not names:
            from ..demo import CLASSES

            names = list(CLASSES)
    store = Store(annotations, vids, names)
    serve(new_session(vids, store, overlays, max_body=int(max_body_mb * (1 << 20))), host, port,
          open_browser=not no_browser)
