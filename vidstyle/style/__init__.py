"""Behaviour style (issue 5): frame labels -> action events -> HMMs of how a performer chains actions
-> new action sequences in that style. See ``docs`` design section "Behaviour (HMM)".

The stage as library calls (what ``learn-style`` / ``generate`` run): :func:`style_params`, :func:`learn`,
:func:`generate_sequence`, defaults in :mod:`vidstyle.style.defaults`; its evaluation protocol lives in
:mod:`vidstyle.evaluation.style`."""

from .artifact import Style, StyleParams, parse_k_range
from .events import EventParams, EventSequence, track_to_events, tracks_to_events
from .learn import generate_sequence, learn, style_params
from .models import ActionHMM, BigramModel, DurationModel, ModeHMM, forward_log_likelihood
from .ngram import jensen_shannon, ngram_counts, ngram_jsd

__all__ = [
    "ActionHMM", "BigramModel", "DurationModel", "EventParams", "EventSequence", "ModeHMM",
    "Style", "StyleParams", "forward_log_likelihood", "generate_sequence", "jensen_shannon", "learn",
    "ngram_counts", "ngram_jsd", "parse_k_range", "style_params", "track_to_events", "tracks_to_events",
]
