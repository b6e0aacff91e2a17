"""Sets A (vocabulary), B (classifier), V (validation) and T (test): disjoint by video, performer and
take for every seed and dataset size (property test), covering, seeded."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vidstyle.errors import InputError
from vidstyle.formats.dataset import Dataset, PerformerEntry, VideoEntry
from vidstyle.recognition.splits import KINDS, make_split, take_of

VIEWS = {"front": 0.0, "left": 90.0, "right": 270.0}


def dataset(n_perf=10, views=("front", "left", "right"), actions=("Jab", "Hook"), azimuths=None, elevation=10.0,
            performers=None):
    videos = []
    for p in performers if performers is not None else range(n_perf):
        for v in views:
            for a in list(actions) + [None]:
                take = f"p{p:02d}_{a or 'perf'}"
                az = (azimuths or VIEWS)[v]
                videos.append(VideoEntry(f"{take}_{v}", f"p{p:02d}", f"labels/{take}_{v}.json",
                                         "single" if a else "performance", a, v, az, bvh=f"mocap/{take}.bvh",
                                         extra={"elevation_deg": elevation}))
    perf = [PerformerEntry(q) for q in sorted({v.performer for v in videos})]
    return Dataset(Path("."), 20.0, list(actions), list(actions), perf, videos, seed=0)


def camera_dataset(n_perf):
    return dataset(n_perf, views=("az30", "az150"), azimuths={"az30": 30.0, "az150": 150.0}, elevation=30.0)


def _attrs(ds, ids, key):
    by = ds.by_id()
    return {key(by[i]) for i in ids}


def assert_disjoint(s, ds, tds=None):
    sets = {"A": (ds, s.vocab), "B": (ds, s.train), "V": (ds, s.val), "T": (tds or ds, s.test)}
    for key in (lambda v: v.id, lambda v: v.performer, take_of):
        vals = {k: _attrs(d, ids, key) for k, (d, ids) in sets.items()}
        names = list(vals)
        for i, a in enumerate(names):
            assert vals[a], a
            for b in names[i + 1:]:
                assert not vals[a] & vals[b], (a, b)


@settings(max_examples=60, deadline=None)
@given(n_perf=st.integers(4, 25), seed=st.integers(0, 2**31 - 1), kind=st.sampled_from(KINDS),
       test_fraction=st.floats(0.05, 0.6), val_fraction=st.floats(0.05, 0.4), vocab_fraction=st.floats(0.05, 0.9))
def test_sets_are_disjoint_by_video_performer_and_take(n_perf, seed, kind, test_fraction, val_fraction, vocab_fraction):
    ds = dataset(n_perf)
    tds = camera_dataset(n_perf) if kind == "unseen-camera" else None
    s = make_split(ds, kind, seed=seed, test_fraction=test_fraction, val_fraction=val_fraction,
                   vocab_fraction=vocab_fraction, test_dataset=tds)
    assert_disjoint(s, ds, tds)
    perf = {v.id: v.performer for v in ds.videos}
    # the performer lists are the performers of the sets, and together they are all performers
    assert _attrs(ds, s.vocab, lambda v: v.performer) == set(s.vocab_performers)
    assert _attrs(ds, s.train, lambda v: v.performer) == set(s.train_performers)
    assert _attrs(ds, s.val, lambda v: v.performer) == set(s.val_performers)
    assert _attrs(tds or ds, s.test, lambda v: v.performer) == set(s.test_performers)
    all_perf = set(s.vocab_performers) | set(s.train_performers) | set(s.val_performers) | set(s.test_performers)
    assert all_perf == set(perf.values())
    if kind == "unseen-performer":  # every video is used exactly once
        assert sorted(s.vocab + s.train + s.val + s.test) == sorted(perf)
    if kind == "unseen-view":
        view = s.test_views[0]
        assert _attrs(ds, s.test, lambda v: v.view) == {view}
        assert view not in _attrs(ds, s.vocab + s.train + s.val, lambda v: v.view)
    if kind == "unseen-camera":
        train_cams = _attrs(ds, s.vocab + s.train + s.val, lambda v: (v.azimuth_deg, v.raw["elevation_deg"]))
        test_cams = _attrs(tds, s.test, lambda v: (v.azimuth_deg, v.raw["elevation_deg"]))
        assert not train_cams & test_cams


def test_same_seed_same_split_and_the_seed_chooses():
    ds = dataset()
    assert make_split(ds, seed=7).to_dict() == make_split(ds, seed=7).to_dict()
    assert len({tuple(make_split(ds, seed=s).test_performers) for s in range(6)}) > 1
    assert len({tuple(make_split(ds, seed=s).val_performers) for s in range(6)}) > 1


def test_sizes_of_the_default_split():
    s = make_split(dataset(10), seed=0)
    assert (len(s.test_performers), len(s.val_performers), len(s.vocab_performers), len(s.train_performers)) == (3, 2, 1, 4)


def test_check_catches_a_shared_take():
    """A take filmed twice with different performer names (a broken manifest) is caught by the check."""
    ds = dataset(6)
    s = make_split(ds, seed=0)
    by = ds.by_id()
    # give a validation video the take of a training video
    victim = by[s.val[0]]
    victim.bvh = by[s.train[0]].bvh
    with pytest.raises(AssertionError, match="take"):
        s.check(ds)


def test_unseen_camera_refuses_a_training_camera():
    ds = dataset(6)
    tds = dataset(6, views=("az90",), azimuths={"az90": 90.0})  # the left view again: not unseen
    with pytest.raises(InputError, match="used in training"):
        make_split(ds, "unseen-camera", test_dataset=tds)
    with pytest.raises(InputError, match="test_dataset"):
        make_split(ds, "unseen-camera")


def test_unseen_camera_needs_every_test_performer_filmed():
    """A camera dataset holding only some of the seed's test performers would score part of T: refused."""
    ds = dataset(10)
    full = make_split(ds, "unseen-camera", seed=1, test_dataset=camera_dataset(10))
    keep = [int(q[1:]) for q in full.test_performers[:1]]
    part = dataset(views=("az30", "az150"), azimuths={"az30": 30.0, "az150": 150.0}, elevation=30.0, performers=keep)
    with pytest.raises(InputError, match="no video of the test performers"):
        make_split(ds, "unseen-camera", seed=1, test_dataset=part)


def test_errors():
    with pytest.raises(InputError, match=">= 4 performers"):
        make_split(dataset(n_perf=3))
    with pytest.raises(InputError, match="must be one of"):
        make_split(dataset(), "random")
    with pytest.raises(InputError, match="back"):
        make_split(dataset(), "unseen-view", test_view="back")
