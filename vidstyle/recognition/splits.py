"""Vocabulary set A, classifier set B, validation set V and test set T (thesis 4.2;
``docs/results.md``, "Splits").

Every split is made of *performers*: a seeded permutation of the dataset's performers is cut into four
disjoint groups, test (``test_fraction``), validation (``val_fraction`` of all performers), vocabulary
A (``vocab_fraction`` of the rest) and classifier B (the rest). A performer's videos all go to the set of
its group, so the four sets share no performer and, because a take (one recorded motion, rendered from
any number of cameras) belongs to one performer, no take either. :meth:`Split.check` verifies both.

- ``unseen-performer``: T is every video of the test performers.
- ``unseen-view``: one view (``test_view``, or a seeded draw) is held out: T is the test performers'
  videos of that view, and A, B and V hold only the other views of their performers.
- ``unseen-camera``: A, B and V as for ``unseen-performer``; T is the test performers' videos of a
  second dataset, ``test_dataset``, rendered from cameras (azimuth and elevation) that no video of A, B
  or V uses (``vidstyle demo make-dataset --unseen-camera``). The check refuses a camera that occurs in
  training.

Only ``vidstyle evaluate recognition`` scores T. Everything tuned is chosen on V
(``scripts/validate_recognition.py``); A and B then train the final model.

The same dataset, kind and seed always give the same split.
"""

from __future__ import annotations

import logging
from dataclasses import asdict, dataclass, field

import numpy as np

from ..errors import InputError, ParameterError
from ..formats.dataset import Dataset
from ..formats.dataset import VideoEntry as DatasetVideo

log = logging.getLogger(__name__)

KINDS = ("unseen-performer", "unseen-view", "unseen-camera")
MIN_PERFORMERS = 4  # one per set


def take_of(v: DatasetVideo) -> str:
    """The recorded motion a video shows (its BVH in the demo datasets; the video itself otherwise)."""
    return str(v.raw.get("bvh") or v.raw.get("take") or v.id)


def camera_of(v: DatasetVideo) -> tuple[float | None, float | None]:
    """(azimuth, elevation) in degrees, None where the manifest does not say."""
    az, el = v.azimuth_deg, v.raw.get("elevation_deg")
    return (None if az is None else round(float(az) % 360.0, 3), None if el is None else round(float(el), 3))


@dataclass
class Split:
    kind: str
    seed: int
    vocab: list[str]  # set A (video ids)
    train: list[str]  # set B
    val: list[str]  # set V
    test: list[str]  # set T (ids of ``test_dataset`` for unseen-camera)
    vocab_performers: list[str] = field(default_factory=list)
    train_performers: list[str] = field(default_factory=list)
    val_performers: list[str] = field(default_factory=list)
    test_performers: list[str] = field(default_factory=list)
    test_views: list[str] = field(default_factory=list)
    test_cameras: list[list] = field(default_factory=list)
    params: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return asdict(self)

    def sets(self) -> dict[str, list[str]]:
        return {"A": self.vocab, "B": self.train, "V": self.val, "T": self.test}

    def check(self, dataset: Dataset, test_dataset: Dataset | None = None) -> None:
        """Raise AssertionError unless A, B, V and T are pairwise disjoint by video, performer and take
        (and, for unseen-camera, T's cameras are not used by A, B or V)."""
        by_id = dataset.by_id()
        t_by_id = (test_dataset or dataset).by_id()
        sets = {k: [(t_by_id if k == "T" else by_id)[i] for i in ids] for k, ids in self.sets().items()}
        names = list(sets)
        for key, what in ((lambda v: v.id, "video"), (lambda v: v.performer, "performer"), (take_of, "take")):
            vals = {k: {key(v) for v in vs} for k, vs in sets.items()}
            for i, a in enumerate(names):
                for b in names[i + 1:]:
                    common = vals[a] & vals[b]
                    if common:
                        raise AssertionError(f"split sets {a} and {b} share {what}s {sorted(common)[:3]}")
        if self.kind == "unseen-camera":
            train_cams = {camera_of(v) for k in "ABV" for v in sets[k]}
            shared = train_cams & {camera_of(v) for v in sets["T"]}
            if shared:
                raise AssertionError(f"unseen-camera: test cameras {sorted(shared, key=str)} are used in training")
        if self.kind == "unseen-view":
            if any(v.view in self.test_views for k in "ABV" for v in sets[k]):
                raise AssertionError("unseen-view: the test view occurs in training")


def _cut(order: list[str], n: int) -> tuple[list[str], list[str]]:
    return sorted(order[:n]), list(order[n:])


def performer_groups(performers, rng, test_fraction: float = 0.3, val_fraction: float = 0.2,
                     vocab_fraction: float = 0.25) -> dict[str, list[str]]:
    """Performers of T, V, A and B (keys ``"T"``, ``"V"``, ``"A"``, ``"B"``): one seeded permutation
    of the sorted performers, cut in that order. ``rng`` is a seed or a Generator (consumed)."""
    rng = np.random.default_rng(rng) if not isinstance(rng, np.random.Generator) else rng
    performers = sorted(str(p) for p in performers)
    P = len(performers)
    if P < MIN_PERFORMERS:
        raise InputError(f"dataset: a split needs >= {MIN_PERFORMERS} performers (A, B, validation, test), got {P}")
    order = [str(p) for p in rng.permutation(performers)]
    n_test = int(np.clip(round(test_fraction * P), 1, P - 3))
    test_perf, order = _cut(order, n_test)
    n_val = int(np.clip(round(val_fraction * P), 1, len(order) - 2))
    val_perf, order = _cut(order, n_val)
    n_a = int(np.clip(round(vocab_fraction * len(order)), 1, len(order) - 1))
    a_perf, order = _cut(order, n_a)
    return {"T": test_perf, "V": val_perf, "A": a_perf, "B": sorted(order)}


def make_split(
    dataset: Dataset,
    kind: str = "unseen-performer",
    seed: int = 0,
    test_fraction: float = 0.3,
    val_fraction: float = 0.2,
    vocab_fraction: float = 0.25,
    test_view: str | None = None,
    test_dataset: Dataset | None = None,
) -> Split:
    """The seeded A/B/V/T split of ``dataset`` (see the module docstring). ``test_dataset``: the
    unseen-camera videos (required for, and only used by, ``kind="unseen-camera"``)."""
    if kind not in KINDS:
        raise ParameterError("kind", f"must be one of {', '.join(KINDS)}, got {kind!r}")
    for name, f in (("test_fraction", test_fraction), ("val_fraction", val_fraction), ("vocab_fraction", vocab_fraction)):
        if not 0 < f < 1:
            raise ParameterError(name, f"must be in (0, 1), got {f}")
    if kind == "unseen-camera" and test_dataset is None:
        raise ParameterError("test_dataset", "the unseen-camera split needs the dataset of unseen-camera videos")
    rng = np.random.default_rng(seed)
    videos = sorted(dataset.videos, key=lambda v: v.id)
    groups = performer_groups({v.performer for v in videos}, rng, test_fraction, val_fraction, vocab_fraction)
    test_perf, val_perf, a_perf, b_perf = (groups[k] for k in ("T", "V", "A", "B"))

    test_views: list[str] = []
    keep = lambda v: True  # noqa: E731  (training videos of the kept views)
    if kind == "unseen-view":
        views = sorted({v.view for v in videos if v.view is not None})
        if len(views) < 2:
            raise InputError(f"dataset: an unseen-view split needs >= 2 views, got {views}")
        if test_view is None:
            test_view = str(rng.choice(views))
        elif test_view not in views:
            raise ParameterError("test_view", f"{test_view!r} is not one of the dataset's views {views}")
        test_views = [test_view]
        keep = lambda v: v.view != test_view  # noqa: E731

    def ids(perf, pool=videos, cond=keep):
        ps = set(perf)
        return sorted(v.id for v in pool if v.performer in ps and cond(v))

    if kind == "unseen-performer":
        test = ids(test_perf)
    elif kind == "unseen-view":
        test = ids(test_perf, cond=lambda v: v.view == test_view)
    else:
        test = ids(test_perf, pool=sorted(test_dataset.videos, key=lambda v: v.id), cond=lambda v: True)
        missing = sorted(set(test_perf) - {v.performer for v in test_dataset.videos})
        if missing:  # a figure over part of the test performers would not be the split's
            raise InputError(f"split: the unseen-camera dataset has no video of the test performers {missing} "
                             f"(test performers of seed {seed}: {test_perf})")
    test_cams = []
    if kind == "unseen-camera":
        t_by = test_dataset.by_id()
        test_cams = sorted({camera_of(t_by[i]) for i in test}, key=str)
    split = Split(
        kind=kind,
        seed=int(seed),
        vocab=ids(a_perf),
        train=ids(b_perf),
        val=ids(val_perf),
        test=test,
        vocab_performers=a_perf,
        train_performers=b_perf,
        val_performers=val_perf,
        test_performers=test_perf,
        test_views=test_views,
        test_cameras=[list(c) for c in test_cams],
        params={"test_fraction": test_fraction, "val_fraction": val_fraction, "vocab_fraction": vocab_fraction,
                "test_view": test_view},
    )
    for name, s in split.sets().items():
        if not s:
            raise InputError(f"split: set {name} of the {kind} split (seed {seed}) has no video")
    try:
        split.check(dataset, test_dataset)
    except AssertionError as e:
        raise InputError(f"split: {e}") from None
    return split
