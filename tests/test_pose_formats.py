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
    assert doc["kind"] == "vidstyle.poses" and doc["schema_version"] == 3
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


def test_frames_without_a_pose_are_null_with_a_reason_and_azimuth_round_trips(tmp_path, rng):
    p = _poses(rng)
    p.frames[0].azimuth = -35.25
    p.frames.append(PoseFrame.none(41, "performer not found"))
    path = tmp_path / "poses.json"
    write_poses(path, p)
    doc = json.loads(path.read_text())
    assert doc["frames"][-1] == {"frame": 41, "points": None, "missing": "performer not found"}
    assert doc["frames"][0]["azimuth"] == -35.25 and "azimuth" not in doc["frames"][1]
    q = read_poses(path)
    assert not q.frame(41).found and q.frame(41).missing == "performer not found"
    assert np.isnan(q.frame(41).points).all() and q.frame(41).viewpoint == "unknown"
    assert q.frame(3).azimuth == -35.25 and q.frame(12).azimuth is None and q.frame(3).found
    doc["frames"][-1]["missing"] = ""
    path.write_text(json.dumps(doc))
    with pytest.raises(FormatError) as e:
        read_poses(path)
    assert e.value.field == "frames[3].missing"
    doc["frames"][-1]["missing"] = "x"
    doc["frames"][0]["azimuth"] = "left"
    path.write_text(json.dumps(doc))
    with pytest.raises(FormatError) as e:
        read_poses(path)
    assert e.value.field == "frames[0].azimuth"


def test_version_1_files_still_load_and_their_centre_stand_ins_are_missing(tmp_path):
    centre = [[79.5, 59.5, 0.0]] * 15
    found = [[10.0 + i, 20.0 + i, 0.8] for i in range(15)]
    doc = {"kind": "vidstyle.poses", "schema_version": 1, "video": "v.mp4", "backend": "blazepose",
           "keypoints": list(KEYPOINTS),
           "frames": [{"frame": 0, "viewpoint": "front", "viewpoint_scores": {"front": 1.0}, "points": found},
                      {"frame": 1, "viewpoint": "unknown", "viewpoint_scores": {}, "points": centre}]}
    path = tmp_path / "old.json"
    path.write_text(json.dumps(doc))
    q = read_poses(path)
    assert q.frame(0).found and np.allclose(q.frame(0).points, found)
    assert not q.frame(1).found and q.frame(1).missing == "nobody found"


def test_match_pose_reader_skips_missing_frames_with_a_warning(tmp_path, rng, caplog):
    from vidstyle.augmg.poses_io import read_frame_poses

    p = _poses(rng)
    p.frames[2] = PoseFrame(40, "unknown", p.frames[2].points, {}, azimuth=120.0)
    p.frames.append(PoseFrame.none(50, "nobody found"))
    write_poses(tmp_path / "p.json", p)
    video, frames = read_frame_poses(tmp_path / "p.json")
    assert [f.frame for f in frames] == [3, 12, 40]
    assert frames[2].viewpoint == "120"  # unknown view but a known azimuth: matched at that azimuth
    assert "1 of 4 frames have no pose" in caplog.text and "frame 50: nobody found" in caplog.text


def test_world_keypoints_round_trip_and_are_validated(tmp_path, rng):
    p = _poses(rng)
    p.backend = "blazepose"
    world = rng.uniform(-0.9, 0.9, (15, 3))
    p.frames[0].world = world
    path = tmp_path / "poses.json"
    write_poses(path, p)
    doc = json.loads(path.read_text())
    assert doc["schema_version"] == 3 and len(doc["frames"][0]["world"]) == 15 and "world" not in doc["frames"][1]
    q = read_poses(path)
    np.testing.assert_allclose(q.frame(3).world, world, atol=1e-5)
    assert q.frame(12).world is None
    for edit, problem in ((lambda w: w[:14], "shape"), (lambda w: [r[:2] for r in w], "shape"),
                          (lambda w: [[1e6, 0, 0]] + w[1:], "within"), (lambda w: "x", "numeric")):
        bad = json.loads(json.dumps(doc))
        bad["frames"][0]["world"] = edit(doc["frames"][0]["world"])
        path.write_text(json.dumps(bad))
        with pytest.raises(FormatError, match=problem) as e:
            read_poses(path)
        assert e.value.field == "frames[0].world" and str(path) in str(e.value)
    p.frames[0].world = world.copy()
    p.frames[0].world[2, 1] = np.nan
    with pytest.raises(FormatError, match="non-finite"):
        write_poses(tmp_path / "nan.json", p)
    missing = PoseFrame.none(50, "nobody found")
    missing.world = world
    p.frames[0].world = None
    p.frames.append(missing)
    with pytest.raises(FormatError, match="no world"):
        write_poses(tmp_path / "m.json", p)


def test_version_2_files_still_load_without_world(tmp_path, rng):
    path = tmp_path / "poses.json"
    write_poses(path, _poses(rng))
    doc = json.loads(path.read_text())
    doc["schema_version"] = 2
    doc["frames"][0]["world"] = "ignored in version 2"
    path.write_text(json.dumps(doc))
    assert all(f.world is None for f in read_poses(path).frames)


def test_params_must_be_finite_json(tmp_path, rng):
    p = _poses(rng)
    p.params = {"scales": [1.0, float("nan")]}
    with pytest.raises(FormatError) as e:
        write_poses(tmp_path / "p.json", p)
    assert e.value.field.startswith("params")
