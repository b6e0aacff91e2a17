"""Real mocap through the recognizer (``vidstyle evaluate strikes``): the action-frame rule on a synthetic
arm motion with known strikes, the committed 02_05 labels, and the command end to end on a short slice."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from vidstyle.cli import main
from vidstyle.demo.skeleton import build_skeleton
from vidstyle.evaluation.realmocap import (
    KICKS,
    PUNCHES,
    StrikeRule,
    action_frames,
    arm_signals,
    clean_mask,
    parse_cameras,
    segments,
)
from vidstyle.mocap import Motion

REPO = Path(__file__).resolve().parents[1]
FPS = 120.0


def _arm_motion(kinds: list[tuple[str, int]], yaw_deg: float = 0.0) -> tuple[Motion, np.ndarray]:
    """A motion on the demo's CMU skeleton (clean T-pose, facing +Z) whose right arm holds, frame by
    frame, one of: ``guard`` (upper arm down, forearm forward: bent), ``strike`` (straight forward),
    ``hang`` (straight down), ``side`` (straight out sideways, the T-pose); the left arm stays in guard.
    The whole body is turned by ``yaw_deg``. Returns the motion and the truth: frames that strike."""
    sk = build_skeleton()
    F = sum(n for _, n in kinds)
    q = np.tile(np.array([0.0, 0.0, 0.0, 1.0]), (F, sk.n_joints, 1))
    ra, rf = sk.names.index("RightArm"), sk.names.index("RightForeArm")
    la, lf = sk.names.index("LeftArm"), sk.names.index("LeftForeArm")
    # the right arm points along -X at rest, the left along +X
    pose = {
        "guard": (Rotation.from_euler("z", 90, degrees=True), Rotation.from_euler("y", 90, degrees=True)),
        "strike": (Rotation.from_euler("y", 90, degrees=True), Rotation.identity()),
        "hang": (Rotation.from_euler("z", 90, degrees=True), Rotation.identity()),
        "side": (Rotation.identity(), Rotation.identity()),
    }
    truth = np.zeros(F, bool)
    f = 0
    for kind, n in kinds:
        arm, fore = pose[kind]
        q[f:f + n, ra] = arm.as_quat()
        q[f:f + n, rf] = fore.as_quat()
        truth[f:f + n] = kind == "strike"
        f += n
    q[:, la] = Rotation.from_euler("z", -90, degrees=True).as_quat()
    q[:, lf] = Rotation.from_euler("y", -90, degrees=True).as_quat()
    q[:, 0] = (Rotation.from_euler("y", yaw_deg, degrees=True) * Rotation.from_quat(q[:, 0])).as_quat()
    root = np.tile([0.0, 17.0, 0.0], (F, 1))
    return Motion(sk, q, None, FPS, root_positions=root), truth


KINDS = [("guard", 60), ("strike", 30), ("guard", 60), ("hang", 30), ("guard", 20), ("side", 30), ("guard", 20),
         ("strike", 3), ("guard", 40), ("strike", 24), ("guard", 5), ("strike", 20), ("guard", 40)]


@pytest.mark.parametrize("yaw", [0.0, 130.0])
def test_rule_finds_the_known_strikes(yaw):
    motion, truth = _arm_motion(KINDS, yaw)
    sig = arm_signals(motion)["Right"]
    # analytic values: straight arm 1, bent at a right angle sqrt(u^2 + f^2) / (u + f) < 0.8
    assert np.allclose(sig["extension"][truth], 1.0, atol=1e-6)
    sk = motion.skeleton
    u = np.linalg.norm(sk.offsets[sk.names.index("RightForeArm")])
    f = np.linalg.norm(sk.offsets[sk.names.index("RightHand")])
    assert np.allclose(sig["extension"][:60], np.hypot(u, f) / (u + f), atol=1e-6)
    assert np.allclose(sig["reach"][:60], f / (u + f), atol=1e-6)
    assert np.allclose(sig["extension"][150:180], 1.0) and np.allclose(sig["reach"][150:180], 0.0, atol=1e-6)
    assert np.allclose(sig["reach"][truth], 1.0, atol=1e-6)
    mask = action_frames(motion)
    # the 3-frame blip (< 0.05 s) is dropped, the 5-frame gap (< 0.1 s) between two strikes is bridged;
    # hanging or sideways straight arms are not strikes
    want = np.zeros_like(truth)
    want[60:90] = True
    want[293:342] = True
    assert [(s["start"], s["end"]) for s in segments(mask)] == [(60, 90), (293, 342)]
    assert np.array_equal(mask, want)


def test_rule_thresholds_are_parameters():
    motion, _ = _arm_motion(KINDS)
    # with no forward-reach condition a straight hanging or sideways arm counts as a strike too
    loose = action_frames(motion, StrikeRule(reach_min=-1.0))
    assert loose[150:180].all() and loose[200:230].all() and not loose[:60].any()
    # the bent guard arm (extension ~0.71) passes an extension threshold of 0.7
    assert action_frames(motion, StrikeRule(extension_min=0.7, reach_min=0.0))[:60].all()


def test_clean_mask_merges_then_drops():
    m = np.zeros(40, bool)
    m[2:4] = m[5:9] = m[20:21] = True
    out = clean_mask(m, fps=10.0, min_seconds=0.5, merge_seconds=0.2)
    assert np.flatnonzero(out).tolist() == [2, 3, 4, 5, 6, 7, 8]


def test_parse_cameras():
    cams = parse_cameras("0:10:texture, -45:20:texture:moon")
    assert [(c.azimuth_deg, c.elevation_deg, c.background) for c in cams] == [(0, 10, "texture"), (-45, 20, "texture:moon")]
    assert cams[1].name == "azm45_el20_texture-moon"
    from vidstyle.errors import ParameterError

    for bad in ("", "0:10", "a:10:plain", "0:95:plain", "0:10:plain,0:10:plain"):
        with pytest.raises(ParameterError):
            parse_cameras(bad)


def test_committed_02_05_labels_are_the_rule_output(cmu_dir):
    from vidstyle.formats.labels import read_labels
    from vidstyle.mocap import read_bvh

    doc = json.loads((REPO / "pipelines/kickboxing/strikes/02_05.actions.json").read_text())
    track = read_labels(REPO / "pipelines/kickboxing/strikes/02_05.actions.json")
    start = doc["frame_offset"]
    motion = read_bvh(cmu_dir / "02_05.bvh")[start:]
    rule = StrikeRule(**{**doc["rule"], "arms": tuple(doc["rule"]["arms"])})
    mask = action_frames(motion, rule)
    assert np.array_equal(np.array(track.labels) == "Strike", mask)
    # what the plot shows and the eye checks: nine right-hand punches, none at the T-pose release at the
    # start nor with the arms hanging at the end
    ev = doc["events"]
    assert len(ev) == 9 and ev[0]["start"] > 100 and ev[-1]["end"] < motion.n_frames - 150


def _toy_model(path: Path, rng, points: int | None = None) -> None:
    """A recognizer of the demo's classes on random scovanner-sized descriptors: its labels are arbitrary,
    what the test checks is the counting. ``points``: the salient points per frame its header says its
    features were extracted with."""
    from vidstyle.demo.actions import CLASSES
    from vidstyle.recognition.io import VideoFeatures
    from vidstyle.recognition.recognizer import ActionRecognizer, save_model
    from vidstyle.recognition.vocabulary import Vocabulary

    vids, labels = [], []
    for v in range(4):
        n = 80
        fi = np.repeat(np.arange(n), 5)
        vids.append(VideoFeatures(rng.integers(0, 255, (len(fi), 640)).astype(np.uint8), fi, n))
        labels.append([CLASSES[(i // 10 + v) % len(CLASSES)] for i in range(n)])
    vocab = Vocabulary(n_words=12, random_state=0).fit(np.concatenate([v.descriptors for v in vids]))
    model = ActionRecognizer(vocab, n_components=8, mirror=False, max_frames_per_class=None, random_state=0)
    model.fit(vids, labels, classes=CLASSES)
    extra = None if points is None else {"features_params": {"variant": "scovanner2007", "salient": {"n_points": points}}}
    save_model(path, model, extra=extra)


def test_command_end_to_end_on_a_slice(cmu_dir, tmp_path, rng):
    from vidstyle.formats.metrics import STRIKES, read_metrics
    from vidstyle.formats.truth import read_truth
    from vidstyle.mocap import read_bvh
    from vidstyle.recognition.io import load_features
    from vidstyle.recognition.recognizer import load_model

    _toy_model(tmp_path / "m.joblib", rng, points=7)
    out, work = tmp_path / "strikes.json", tmp_path / "work"
    args = ["evaluate", "strikes", "--bvh", str(cmu_dir / "02_05.bvh"), "--model", str(tmp_path / "m.joblib"),
            "--cameras", "0:10:texture,150:30:texture:moon", "--start", "100", "--stop", "420", "--seed", "3",
            "--work-dir", str(work), "--out", str(out), "--actions-out", str(tmp_path / "a.json"),
            "--plot", str(tmp_path / "a.png")]
    assert main(args) == 0
    m = read_metrics(out, STRIKES)
    assert m.seed == 3 and m.doc["params"]["start"] == 100 and m.doc["rule"]["extension_min"] == 0.8
    # the clip is described as the model's own features were (its header: 7 points per frame)
    assert m.doc["params"]["points"] == 7 and m.doc["params"]["variant"] == "scovanner2007"
    assert max(np.bincount(np.load(work / f"{m.doc['cameras'][0]['name']}.npz")["points"][:, 0])) == 7
    motion = read_bvh(cmu_dir / "02_05.bvh")[100:420]
    mask = action_frames(motion)
    assert m.doc["action_frames"]["segments"] == segments(mask) and len(segments(mask)) == 2
    model, _ = load_model(tmp_path / "m.joblib")
    total = {"punch": 0, "n": 0}
    for cam in m.doc["cameras"]:
        # recount from the files the command kept: the sidecar maps video frames to motion frames
        t = read_truth(work / f"{cam['name']}.truth.npz").to_arrays()
        act = mask[np.clip(np.rint(t["source_time"] * motion.fps).astype(int), 0, motion.n_frames - 1)]
        names = model.classes_[model.predict_video(load_features(work / f"{cam['name']}.npz"))["smoothed"]]
        assert cam["video_frames"] == len(act) == 54 and cam["action_video_frames"] == act.sum() > 10
        punch = int(np.isin(names[act], PUNCHES).sum())
        kick = int(np.isin(names[act], KICKS).sum())
        s = cam["smoothed"]
        assert (s["punch"], s["kick"], s["other"]) == (punch, kick, act.sum() - punch - kick)
        assert s["punch_fraction"] == pytest.approx(punch / act.sum())
        total["punch"] += punch
        total["n"] += int(act.sum())
    assert m.doc["overall"]["smoothed"]["punch_fraction"] == pytest.approx(total["punch"] / total["n"])
    assert read_truth(work / "az150_el30_texture-moon.truth.npz").to_arrays()["background"] != \
        read_truth(work / "az0_el10_texture.truth.npz").to_arrays()["background"]
    assert json.loads((tmp_path / "a.json").read_text())["events"][0]["label"] == "Strike"
    assert (tmp_path / "a.png").stat().st_size > 5000


def test_command_bad_input(tmp_path, cmu_dir):
    bvh = str(cmu_dir / "02_05.bvh")
    assert main(["evaluate", "strikes", "--bvh", bvh, "--model", str(tmp_path / "none.joblib"),
                 "--out", str(tmp_path / "o.json")]) == 2
    assert main(["evaluate", "strikes", "--bvh", bvh, "--model", str(tmp_path / "none.joblib"),
                 "--cameras", "0:10", "--out", str(tmp_path / "o.json")]) == 2
    assert not (tmp_path / "o.json").exists()


def test_labelled_action_frames(tmp_path):
    from vidstyle.demo.dataset import label_document
    from vidstyle.errors import InputError
    from vidstyle.evaluation.realmocap import labelled_action_frames
    from vidstyle.formats.labels import write_labels

    labels = ["Guard"] * 5 + ["Jab"] * 4 + ["Guard"] * 3 + ["LowKick"] * 2 + ["Uppercut"] * 3
    write_labels(tmp_path / "l.json", label_document(labels, 60.0, ["Jab", "LowKick", "Uppercut"], bvh="t.bvh"))
    mask = labelled_action_frames(tmp_path / "l.json", 12, ("Jab", "Hook", "Uppercut"), start=3)
    assert np.flatnonzero(mask).tolist() == [2, 3, 4, 5, 11]  # Jab at 5..8, Uppercut from 14
    assert labelled_action_frames(tmp_path / "l.json", 17, ("Uppercut",))[14:].all()
    with pytest.raises(InputError):
        labelled_action_frames(tmp_path / "l.json", 16, ("Jab",), start=2)


@pytest.mark.parametrize("kw,param", [({"start": -1}, "start"), ({"start": 5, "stop": 5}, "stop"),
                                      ({"points": 0}, "points")])
def test_strike_parameters_are_checked_by_the_library(kw, param):
    from vidstyle.errors import ParameterError
    from vidstyle.evaluation.realmocap import StrikeEvalParams

    with pytest.raises(ParameterError) as e:
        StrikeEvalParams(**kw)
    assert e.value.param == param
    assert StrikeEvalParams(start=0, stop=None, points=1).stop is None  # the edges are allowed


def test_pose_model_end_to_end_on_true_keypoints(cmu_dir, tmp_path, rng):
    """A pose-sequence recognizer through ``evaluate strikes --pose-input true``: the counts are those of the
    model on the clip's keypoints projected through each rendered camera (recounted here from the sidecars
    the command kept)."""
    from vidstyle.demo.actions import CLASSES
    from vidstyle.formats.metrics import STRIKES, read_metrics
    from vidstyle.formats.truth import read_truth
    from vidstyle.mocap import read_bvh
    from vidstyle.mocap.keypoints import keypoint_positions
    from vidstyle.recognition.posefeatures import PoseTrack
    from vidstyle.recognition.poserecognizer import PoseRecognizer, save_pose_model
    from vidstyle.render.camera import Camera

    tracks = [PoseTrack(np.cumsum(rng.normal(0, 2, (80, 15, 2)), axis=0) + 60, 20.0) for _ in range(4)]
    labels = [[CLASSES[(i // 10 + v) % len(CLASSES)] for i in range(80)] for v in range(4)]
    model = PoseRecognizer(max_frames_per_class=None, mirror=False, smoothing="vote", random_state=0)
    save_pose_model(tmp_path / "p.joblib", model.fit(tracks, labels, classes=CLASSES))
    out, work = tmp_path / "strikes.json", tmp_path / "work"
    assert main(["evaluate", "strikes", "--bvh", str(cmu_dir / "02_05.bvh"), "--model", str(tmp_path / "p.joblib"),
                 "--cameras", "0:10:texture,150:30:texture:moon", "--start", "100", "--stop", "420",
                 "--pose-input", "true", "--work-dir", str(work), "--out", str(out)]) == 0
    m = read_metrics(out, STRIKES)
    assert m.doc["params"]["pose_input"] == "true"
    motion = read_bvh(cmu_dir / "02_05.bvh")[100:420]
    mask = action_frames(motion)
    pts = keypoint_positions(motion)
    for cam in m.doc["cameras"]:
        t = read_truth(work / f"{cam['name']}.truth.npz").to_arrays()
        idx = np.clip(np.rint(t["source_time"] * motion.fps).astype(int), 0, motion.n_frames - 1)
        uv, _ = Camera(t["K"], t["R"], t["t"], size=tuple(int(s) for s in t["size"])).project(pts[idx])
        names = model.classes_[model.predict_video(PoseTrack(np.asarray(uv, float), 20.0))["smoothed"]]
        act = mask[idx]
        assert cam["action_video_frames"] == act.sum() > 10
        assert cam["smoothed"]["punch"] == int(np.isin(names[act], PUNCHES).sum())
        assert cam["smoothed"]["kick"] == int(np.isin(names[act], KICKS).sum())
    assert main(["evaluate", "strikes", "--bvh", str(cmu_dir / "02_05.bvh"), "--model", str(tmp_path / "p.joblib"),
                 "--pose-input", "nope", "--out", str(tmp_path / "x.json")]) == 2
    assert not (tmp_path / "x.json").exists()
