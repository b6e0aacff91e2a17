"""Library errors name parameters (``jobs: ...``); the CLI shows its own flags (``--jobs: ...``)."""

from __future__ import annotations

import contextlib
import re
from collections.abc import Iterator

from ..errors import VidstyleError


@contextlib.contextmanager
def as_flags(**flags: str) -> Iterator[None]:
    """Re-raise a :class:`VidstyleError` whose message starts with a parameter name in ``flags``
    (``jobs="--jobs"``) with the flag instead; other errors pass unchanged."""
    try:
        yield
    except VidstyleError as e:
        msg = str(e)
        for param, flag in flags.items():
            m = re.match(rf"{re.escape(param)}(?=[: ])", msg)
            if m:
                new = type(e).__new__(type(e))
                new.__dict__.update(e.__dict__)
                new.args = (flag + msg[m.end():],)
                raise new from None
        raise
