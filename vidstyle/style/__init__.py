"""Behaviour style (issue 5): frame labels -> action events -> HMMs of how a performer chains actions
-> new action sequences in that style. See ``docs`` design section "Behaviour (HMM)"."""

from .artifact import Style, StyleParams, parse_k_range
from .events import EventParams, EventSequence, track_to_events, tracks_to_events
from .models import ActionHMM, BigramModel, DurationModel, ModeHMM, forward_log_likelihood
from .ngram import jensen_shannon, ngram_counts, ngram_jsd

__all__ = [
    "ActionHMM", "BigramModel", "DurationModel", "EventParams", "EventSequence", "ModeHMM",
    "Style", "StyleParams", "forward_log_likelihood", "jensen_shannon", "ngram_counts",
    "ngram_jsd", "parse_k_range", "track_to_events", "tracks_to_events",
]
