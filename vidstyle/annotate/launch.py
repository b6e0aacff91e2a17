"""``vidstyle annotate`` as a library call: open the videos, load the overlays, pick the class list and
serve the annotation page until interrupted."""

from __future__ import annotations

import logging
import os
from collections.abc import Sequence
from pathlib import Path

from ..errors import ParameterError

log = logging.getLogger(__name__)

HOST = "127.0.0.1"
PORT = 8765
MAX_BODY_MB = 16.0
#: the range ``max_body_mb`` may take (below 1 MB a save of a few videos' marks would be refused)
MIN_BODY_MB = 1.0
MAX_BODY_LIMIT_MB = 1024.0
LOOPBACK = ("127.0.0.1", "localhost", "::1")


def _given_classes(classes: str | Sequence[str] | None) -> list[str] | None:
    """The class names given (None: none given); a string of separators only (``",,,"``) is an error."""
    if not classes:
        return None
    if isinstance(classes, str):
        names = [c.strip() for c in classes.split(",") if c.strip()]
        if not names:
            raise ParameterError("classes", f"no class name in {classes!r} (comma-separated names expected)")
        return names
    return list(classes)


def class_names(classes: str | Sequence[str] | None, annotations: Path, overlays: dict,
                default_classes: Sequence[str] = ()) -> list[str]:
    """The page's class list: ``classes`` (names or one comma-separated string); else none when the
    annotations file exists (it holds its own); else the recognised labels' classes, in order of first
    appearance; else ``default_classes``."""
    given = _given_classes(classes)
    if given is not None:
        return list(dict.fromkeys(given))  # repeated names once, in order (linear time)
    if annotations.exists():
        return []
    names = dict.fromkeys(c for ov in overlays.values() for c in ov.get("recognized", {}).get("classes", []))
    return list(names) or list(default_classes)


def annotate(
    videos: Sequence[str | os.PathLike],
    annotations: str | os.PathLike,
    *,
    labels: Sequence[str | os.PathLike] = (),
    poses: Sequence[str | os.PathLike] = (),
    matches: Sequence[str | os.PathLike] = (),
    classes: str | Sequence[str] | None = None,
    default_classes: Sequence[str] = (),
    host: str = HOST,
    port: int = PORT,
    open_browser: bool = True,
    max_body_mb: float = MAX_BODY_MB,
) -> None:
    """Serve the annotation page for ``videos`` editing ``annotations`` (see :mod:`vidstyle.annotate`);
    parameters are checked before any video is opened."""
    from . import server
    from .overlays import load_overlays
    from .session import Store, open_videos

    if not 0 <= port < 65536:
        raise ParameterError("port", f"must be in 0..65535, got {port}")
    if not MIN_BODY_MB <= max_body_mb <= MAX_BODY_LIMIT_MB:  # also refuses NaN
        raise ParameterError("max_body_mb", f"must be a number in {MIN_BODY_MB:g}..{MAX_BODY_LIMIT_MB:g} (MB), "
                                            f"got {max_body_mb}")
    _given_classes(classes)  # before any video is opened
    secret = None
    if not is_loopback(host):
        import secrets

        secret = secrets.token_urlsafe(24)
        log.warning("annotate: listening on %s: the page and the API need the key printed below (give it only "
                    "to people who may read the videos and change the annotations)", host)
    annotations = Path(annotations)
    vids = open_videos(list(videos))
    overlays = load_overlays(vids, list(labels), list(poses), list(matches))
    store = Store(annotations, vids, class_names(classes, annotations, overlays, default_classes))
    server.serve(server.new_session(vids, store, overlays, max_body=int(max_body_mb * (1 << 20)), secret=secret),
                 host, port, open_browser=open_browser)


def is_loopback(host: str) -> bool:
    """Whether ``host`` is a loopback address (or ``localhost``): only this machine can connect."""
    import ipaddress

    if host in LOOPBACK:
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False
