"""poses.json: round trip, and one clear error per malformed field."""

from __future__ import annotations

import json

import numpy as np
import pytest

from vidstyle.formats import FormatError
from vidstyle.formats.poses import PoseFrame, Poses, read_poses, write_poses
from vidstyle.mocap.keypoints import KEYPOINTS


def _poses(rng) -> Poses:
    frames = [PoseFrame(i, v, np.column_stack([rng.uniform(0, 160, 15), rng.uniform(0, 120, 15), rng.uniform(0, 1, 15)]),
                        {"front": 0.7, "left": 0.1, "right": 0.1, "back": 0.1})
              for i, v in ((3, "front"), (12, "left"), (40, "unknown"))]
    return Poses("clip.mp4", "ps", frames)


def test_round_trip(tmp_path, rng):
    p = _poses(rng)
    path = tmp_path / "poses.json"
    write_poses(path, p)
    doc = json.loads(path.read_text())
    assert doc["kind"] == "vidstyle.poses" and doc["schema_version"] == 1
    assert doc["keypoints"] == list(KEYPOINTS) and doc["backend"] == "ps" and doc["video"] == "clip.mp4"
    assert set(doc["frames"][0]) == {"frame", "viewpoint", "viewpoint_scores", "points"}
    q = read_poses(path)
    assert [f.frame for f in q.frames] == [3, 12, 40]
    for a, b in zip(p.frames, q.frames):
        np.testing.assert_allclose(a.points, b.points, atol=1e-3)
        assert a.viewpoint == b.viewpoint and a.viewpoint_scores == b.viewpoint_scores
    assert q.frame(12).viewpoint == "left"


@pytest.mark.parametrize("edit, field", [
    (lambda d: d.pop("backend"), "backend"),
    (lambda d: d.update(backend="openpose"), "backend"),
    (lambda d: d.update(keypoints=list(reversed(KEYPOINTS))), "keypoints"),
    (lambda d: d["frames"][1].update(frame=3), "frames[1].frame"),
    (lambda d: d["frames"][0].update(points=d["frames"][0]["points"][:14]), "frames[0].points"),
    (lambda d: d["frames"][0]["points"][2].__setitem__(2, 1.5), "frames[0].points"),
    (lambda d: d["frames"][0].update(viewpoint="above"), "frames[0].viewpoint"),
    (lambda d: d["frames"][0]["viewpoint_scores"].update(up=0.1), "frames[0].viewpoint_scores.up"),
    (lambda d: d.update(kind="vidstyle.labels"), "kind"),
])
def test_malformed_fields_are_named(tmp_path, rng, edit, field):
    path = tmp_path / "poses.json"
    write_poses(path, _poses(rng))
    doc = json.loads(path.read_text())
    edit(doc)
    path.write_text(json.dumps(doc))
    with pytest.raises(FormatError) as e:
        read_poses(path)
    assert e.value.field == field and str(path) in str(e.value)


def test_nan_is_refused_before_writing(tmp_path, rng):
    p = _poses(rng)
    p.frames[0].points[0, 0] = np.nan
    path = tmp_path / "poses.json"
    with pytest.raises(FormatError, match="non-finite"):
        write_poses(path, p)
    assert not path.exists()
    path.write_text(json.dumps({"kind": "vidstyle.poses", "schema_version": 1}).replace("}", ', "video": NaN}'))
    with pytest.raises(FormatError):
        read_poses(path)
