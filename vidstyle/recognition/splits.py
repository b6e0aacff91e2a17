"""Vocabulary set A, classifier set B and the test set, disjoint (thesis 4.2; evaluation.md "Splits").

- ``unseen-performer``: a seeded draw of ``test_fraction`` of the performers is the test set; none of
  their videos is in A or B.
- ``unseen-view``: every video of one view (``test_view``, or a seeded draw) is the test set; A and B
  only hold the other views.

The remaining videos are shared between A and B by performer (``ab_by="performer"``: A and B have no
performer in common either, the stricter choice) or by video (``ab_by="video"``). ``vocab_fraction`` is the
share that goes to A. The same dataset, kind and seed always give the same split.
"""

from __future__ import annotations

import logging
from dataclasses import asdict, dataclass, field

import numpy as np

from ..errors import InputError, ParameterError
from ..formats.dataset import Dataset

log = logging.getLogger(__name__)

KINDS = ("unseen-performer", "unseen-view")


@dataclass
class Split:
    kind: str
    seed: int
    vocab: list[str]  # set A (video ids)
    train: list[str]  # set B
    test: list[str]
    test_performers: list[str] = field(default_factory=list)
    test_views: list[str] = field(default_factory=list)
    params: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return asdict(self)

    def check(self) -> None:
        a, b, t = set(self.vocab), set(self.train), set(self.test)
        if a & b or a & t or b & t:
            raise AssertionError("split sets overlap")


def make_split(
    dataset: Dataset,
    kind: str = "unseen-performer",
    seed: int = 0,
    test_fraction: float = 0.3,
    vocab_fraction: float = 0.3,
    test_view: str | None = None,
    ab_by: str = "performer",
) -> Split:
    if kind not in KINDS:
        raise ParameterError("kind", f"must be one of {', '.join(KINDS)}, got {kind!r}")
    if ab_by not in ("performer", "video"):
        raise InputError(f"ab_by: must be performer or video, got {ab_by!r}")
    if not 0 < test_fraction < 1 or not 0 < vocab_fraction < 1:
        raise InputError("split fractions must be in (0, 1)")
    rng = np.random.default_rng(seed)
    videos = sorted(dataset.videos, key=lambda v: v.id)
    performers = sorted({v.performer for v in videos})
    test_performers: list[str] = []
    test_views: list[str] = []
    if kind == "unseen-performer":
        if len(performers) < 3:
            raise InputError(f"dataset: an unseen-performer split needs >= 3 performers, got {len(performers)}")
        order = list(rng.permutation(performers))
        n_test = int(np.clip(round(test_fraction * len(performers)), 1, len(performers) - 2))
        test_performers = sorted(order[:n_test])
        test = [v for v in videos if v.performer in test_performers]
        rest = [v for v in videos if v.performer not in test_performers]
    else:
        views = sorted({v.view for v in videos if v.view is not None})
        if len(views) < 2:
            raise InputError(f"dataset: an unseen-view split needs >= 2 views, got {views}")
        if test_view is None:
            test_view = str(rng.choice(views))
        elif test_view not in views:
            raise ParameterError("test_view", f"{test_view!r} is not one of the dataset's views {views}")
        test_views = [test_view]
        test = [v for v in videos if v.view == test_view]
        rest = [v for v in videos if v.view != test_view]
    rest_perf = sorted({v.performer for v in rest})
    if ab_by == "performer" and len(rest_perf) < 2:
        log.warning("only %d training performer(s): sets A and B are split by video instead", len(rest_perf))
        ab_by = "video"
    if ab_by == "performer":
        order = list(rng.permutation(rest_perf))
        n_a = int(np.clip(round(vocab_fraction * len(rest_perf)), 1, len(rest_perf) - 1))
        a_perf = set(order[:n_a])
        vocab = [v.id for v in rest if v.performer in a_perf]
        train = [v.id for v in rest if v.performer not in a_perf]
    else:
        ids = [v.id for v in rest]
        order = list(rng.permutation(ids))
        n_a = int(np.clip(round(vocab_fraction * len(ids)), 1, len(ids) - 1))
        vocab = sorted(order[:n_a])
        train = sorted(order[n_a:])
    split = Split(
        kind=kind,
        seed=int(seed),
        vocab=sorted(vocab),
        train=sorted(train),
        test=sorted(v.id for v in test),
        test_performers=test_performers,
        test_views=test_views,
        params={"test_fraction": test_fraction, "vocab_fraction": vocab_fraction, "ab_by": ab_by, "test_view": test_view},
    )
    split.check()
    return split
