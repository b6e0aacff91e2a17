"""n-gram distributions of action sequences and the Jensen-Shannon divergence between them."""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Mapping

import numpy as np


def ngram_counts(sequences: Iterable, n: int) -> Counter:
    """Counts of the length-``n`` windows inside each sequence (windows never span two sequences)."""
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    c: Counter = Counter()
    for s in sequences:
        s = [int(x) for x in getattr(s, "actions", s)]
        for i in range(len(s) - n + 1):
            c[tuple(s[i : i + n])] += 1
    return c


def jensen_shannon(p: Mapping, q: Mapping) -> float:
    """JSD(P || Q) in bits (0 for equal distributions, 1 for disjoint supports; symmetric).

    ``p`` and ``q`` map outcomes to non-negative weights (normalised here), e.g. n-gram counts.
    JSD = H(M) - (H(P) + H(Q)) / 2 with M = (P + Q) / 2.
    """
    keys = sorted(set(p) | set(q))
    pv = np.array([float(p.get(k, 0.0)) for k in keys])
    qv = np.array([float(q.get(k, 0.0)) for k in keys])
    if pv.sum() <= 0 or qv.sum() <= 0:
        raise ValueError("both distributions need positive mass")
    pv /= pv.sum()
    qv /= qv.sum()
    m = 0.5 * (pv + qv)

    def h(x: np.ndarray) -> float:
        x = x[x > 0]
        return float(-(x * np.log2(x)).sum())

    return max(0.0, h(m) - 0.5 * (h(pv) + h(qv)))


def ngram_jsd(a: Iterable, b: Iterable, n: int) -> float:
    """JSD (bits) between the ``n``-gram distributions of two sets of sequences; NaN when either holds no
    ``n``-gram (sequences shorter than ``n``: nothing to compare)."""
    ca, cb = ngram_counts(a, n), ngram_counts(b, n)
    if not sum(ca.values()) or not sum(cb.values()):
        return float("nan")
    return jensen_shannon(ca, cb)
