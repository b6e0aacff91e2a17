"""Behaviour style (issue 5): frame labels -> action events -> HMMs of how a performer chains actions
-> new action sequences in that style. See ``docs/design.md``, section "Behaviour".

The stage as library calls (what ``learn-style`` / ``generate`` run): :func:`style_params`, :func:`learn`,
:func:`generate_sequence`, defaults in :mod:`vidstyle.style.defaults`; its evaluation protocol lives in
:mod:`vidstyle.evaluation.style`."""

from typing import TYPE_CHECKING

from ..lazy import lazy_package

if TYPE_CHECKING:  # pragma: no cover
    from .artifact import Style, StyleParams, parse_k_range
    from .events import EventParams, EventSequence, track_to_events, tracks_to_events
    from .learn import generate_sequence, learn, style_params
    from .models import ActionHMM, BigramModel, DurationModel, ModeHMM, forward_log_likelihood
    from .ngram import jensen_shannon, ngram_counts, ngram_jsd

# The names below load their submodule on first use (PEP 562, :mod:`vidstyle.lazy`): the CLI reads
# ``vidstyle.style.defaults`` when it builds its options, and that must not import scikit-learn, SciPy
# or OpenCV into every command's start-up. Submodules load on first use too.
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
__getattr__ = lazy_package(__name__, _WHERE)


__all__ = [
    "ActionHMM", "BigramModel", "DurationModel", "EventParams", "EventSequence", "ModeHMM",
    "Style", "StyleParams", "forward_log_likelihood", "generate_sequence", "jensen_shannon", "learn",
    "ngram_counts", "ngram_jsd", "parse_k_range", "style_params", "track_to_events", "tracks_to_events",
]
