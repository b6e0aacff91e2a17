"""Behaviour style (issue 5): frame labels -> action events -> HMMs of how a performer chains actions
-> new action sequences in that style. See ``docs`` design section "Behaviour (HMM)".

The stage as library calls (what ``learn-style`` / ``generate`` run): :func:`style_params`, :func:`learn`,
:func:`generate_sequence`, defaults in :mod:`vidstyle.style.defaults`; its evaluation protocol lives in
:mod:`vidstyle.evaluation.style`."""

import sys
from importlib import import_module
from importlib.util import find_spec
from types import ModuleType
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from .artifact import Style, StyleParams, parse_k_range
    from .events import EventParams, EventSequence, track_to_events, tracks_to_events
    from .learn import generate_sequence, learn, style_params
    from .models import ActionHMM, BigramModel, DurationModel, ModeHMM, forward_log_likelihood
    from .ngram import jensen_shannon, ngram_counts, ngram_jsd

# The names below load their submodule on first use (PEP 562), as in :mod:`vidstyle.motiongraph`: the
# CLI reads ``vidstyle.style.defaults`` when it builds its options, and that must not import
# scikit-learn, SciPy or OpenCV into every command's start-up. Submodules load on first use too.
_WHERE = {
    "Style": "artifact",
    "StyleParams": "artifact",
    "parse_k_range": "artifact",
    "EventParams": "events",
    "EventSequence": "events",
    "track_to_events": "events",
    "tracks_to_events": "events",
    "generate_sequence": "learn",
    "learn": "learn",
    "style_params": "learn",
    "ActionHMM": "models",
    "BigramModel": "models",
    "DurationModel": "models",
    "ModeHMM": "models",
    "forward_log_likelihood": "models",
    "jensen_shannon": "ngram",
    "ngram_counts": "ngram",
    "ngram_jsd": "ngram",
}


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(import_module(f".{_WHERE[name]}", __name__), name)
    elif not name.startswith("_") and find_spec(f"{__name__}.{name}") is not None:  # a submodule
        value = import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


class _Package(ModuleType):
    """The package module. The import system binds a submodule to its package's attribute when it first
    loads it; ``style.learn`` stays the function of the API (as when this file imported everything),
    whoever loads the submodule ``learn`` first."""

    def __setattr__(self, name: str, value) -> None:
        if name in _WHERE and isinstance(value, ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


__all__ = [
    "ActionHMM", "BigramModel", "DurationModel", "EventParams", "EventSequence", "ModeHMM",
    "Style", "StyleParams", "forward_log_likelihood", "generate_sequence", "jensen_shannon", "learn",
    "ngram_counts", "ngram_jsd", "parse_k_range", "style_params", "track_to_events", "tracks_to_events",
]
