"""Sets A (vocabulary), B (classifier) and test: disjoint, seeded, by performer or by view."""

from __future__ import annotations

from pathlib import Path

import pytest

from vidstyle.errors import InputError
from vidstyle.formats.dataset import Dataset, PerformerEntry, VideoEntry
from vidstyle.recognition.splits import make_split


def dataset(n_perf=10, views=("front", "left", "right"), actions=("Jab", "Hook")):
    videos = []
    for p in range(n_perf):
        for v in views:
            for a in list(actions) + [None]:
                vid = f"p{p:02d}_{a or 'perf'}_{v}"
                videos.append(VideoEntry(vid, f"p{p:02d}", f"labels/{vid}.json", "single" if a else "performance",
                                         a, v, 0.0))
    performers = [PerformerEntry(f"p{p:02d}") for p in range(n_perf)]
    return Dataset(Path("."), 20.0, list(actions), list(actions), performers, videos, seed=0)


@pytest.mark.parametrize("ab_by", ["performer", "video"])
def test_unseen_performer_disjoint_and_covering(ab_by):
    ds = dataset()
    s = make_split(ds, "unseen-performer", seed=4, ab_by=ab_by)
    a, b, t = set(s.vocab), set(s.train), set(s.test)
    assert not (a & b) and not (a & t) and not (b & t)
    assert a | b | t == {v.id for v in ds.videos}
    perf = {v.id: v.performer for v in ds.videos}
    test_perf = {perf[i] for i in t}
    assert test_perf == set(s.test_performers) and len(test_perf) == 3
    assert not test_perf & {perf[i] for i in a | b}
    if ab_by == "performer":
        assert not {perf[i] for i in a} & {perf[i] for i in b}


def test_unseen_view():
    ds = dataset()
    s = make_split(ds, "unseen-view", seed=1, test_view="left")
    view = {v.id: v.view for v in ds.videos}
    assert {view[i] for i in s.test} == {"left"}
    assert "left" not in {view[i] for i in s.vocab + s.train}
    assert s.test_views == ["left"]
    with pytest.raises(InputError, match="back"):
        make_split(ds, "unseen-view", test_view="back")


def test_deterministic_from_seed():
    ds = dataset()
    assert make_split(ds, seed=7).to_dict() == make_split(ds, seed=7).to_dict()
    tests = {tuple(make_split(ds, seed=s).test_performers) for s in range(6)}
    assert len(tests) > 1  # the seed does choose


def test_too_few_performers():
    with pytest.raises(InputError, match=">= 3 performers"):
        make_split(dataset(n_perf=2))
    with pytest.raises(InputError, match="^kind: must be one of"):
        make_split(dataset(), "random")
