"""The real-motion split (issue 28, item 5): clip lists, family scoring recounted from the renders the
command keeps, and bad input."""

from __future__ import annotations

import numpy as np
import pytest

from vidstyle.cli import main
from vidstyle.errors import InputError
from vidstyle.evaluation.realmotion import family_of, read_clip_list, summarise


def test_family_of_covers_the_demo_classes():
    from vidstyle.demo.actions import CLASSES

    fams = {c: family_of(c) for c in CLASSES}
    assert fams == {"Jab": "punch", "Hook": "punch", "Uppercut": "punch", "LowKick": "kick",
                    "RoundhouseKick": "kick", "Defense": "other", "Guard": "other", "Step": "other"}


def test_read_clip_list(tmp_path):
    (tmp_path / "a.bvh").write_text("x")
    (tmp_path / "l.csv").write_text("# comment\nfile,family,frames\na.bvh,punch,strikes\na.bvh,other,all,5,90\n")
    clips = read_clip_list(tmp_path / "l.csv")
    assert [(c.family, c.frames, c.start, c.end) for c in clips] == [("punch", "strikes", 1, None), ("other", "all", 5, 90)]
    assert clips[0].bvh == tmp_path / "a.bvh"
    for bad in ("a.bvh,dance\n", "a.bvh,punch,some\n", "b.bvh,punch\n", "a.bvh,punch,all,9,3\n", "a.bvh\n",
                "a.bvh,punch,all,x\n", ""):
        (tmp_path / "b.csv").write_text(bad)
        with pytest.raises(InputError, match="b.csv"):
            read_clip_list(tmp_path / "b.csv")


def test_summarise_weights_by_frames():
    rows = [{"recognizer": "pose", "clip": "a", "family": "other", "camera": "c1", "frames": 10,
             "family_counts": {"punch": 0, "kick": 2, "other": 8}},
            {"recognizer": "pose", "clip": "b", "family": "punch", "camera": "c1", "frames": 30,
             "family_counts": {"punch": 9, "kick": 0, "other": 21}}]
    s = summarise(rows, ["pose"])["pose"]
    assert s["family_accuracy"] == pytest.approx(17 / 40)
    assert s["per_family"] == {"punch": pytest.approx(0.3), "other": pytest.approx(0.8)}
    assert s["video_majority_accuracy"] == pytest.approx(0.5)


def test_command_with_both_recognizers_and_fusion(cmu_dir, tmp_path, rng):
    """Toy recognizers (arbitrary labels): what is checked is the scoring. The fused row is recomputed from
    the two recognizers' outputs on the kept renders."""
    from test_recognition_realmocap import _toy_model

    from vidstyle.demo.actions import CLASSES
    from vidstyle.formats.metrics import REAL_MOTION, read_metrics
    from vidstyle.formats.truth import read_truth
    from vidstyle.mocap import read_bvh
    from vidstyle.mocap.keypoints import keypoint_positions
    from vidstyle.recognition.fusion import fuse_scores
    from vidstyle.recognition.io import load_features
    from vidstyle.recognition.posefeatures import PoseTrack
    from vidstyle.recognition.poserecognizer import PoseRecognizer, save_pose_model
    from vidstyle.recognition.recognizer import load_model
    from vidstyle.render.camera import Camera

    _toy_model(tmp_path / "s.joblib", rng, points=5)
    tracks = [PoseTrack(np.cumsum(rng.normal(0, 2, (80, 15, 2)), axis=0) + 60, 20.0) for _ in range(4)]
    labels = [[CLASSES[(i // 10 + v) % len(CLASSES)] for i in range(80)] for v in range(4)]
    save_pose_model(tmp_path / "p.joblib", PoseRecognizer(max_frames_per_class=None, mirror=False, smoothing="vote",
                                                          random_state=0).fit(tracks, labels, classes=CLASSES))
    (tmp_path / "l.csv").write_text(f"{cmu_dir / '02_05.bvh'},punch,strikes,100,420\n{cmu_dir / '07_01.bvh'},other,all,1,200\n")
    out, work = tmp_path / "rm.json", tmp_path / "work"
    assert main(["evaluate", "real-motion", "--clips", str(tmp_path / "l.csv"), "--model", str(tmp_path / "s.joblib"),
                 "--pose-model", str(tmp_path / "p.joblib"), "--fusion-weight", "0.5", "--pose-input", "true",
                 "--cameras", "30:30:texture:moon", "--work-dir", str(work), "--out", str(out)]) == 0
    doc = read_metrics(out, REAL_MOTION).doc
    assert doc["recognizers"] == ["sift", "pose", "fusion"] and len(doc["rows"]) == 6
    sift, _ = load_model(tmp_path / "s.joblib")
    pose, _ = load_model(tmp_path / "p.joblib")
    for clip, rng_, fam in (("02_05", (100, 420), "punch"), ("07_01", (1, 200), "other")):
        motion = read_bvh(cmu_dir / f"{clip}.bvh")[rng_[0]:rng_[1]]
        name = f"{clip}_az30_el30_texture-moon"
        t = read_truth(work / f"{name}.truth.npz").to_arrays()
        idx = np.clip(np.rint(t["source_time"] * motion.fps).astype(int), 0, motion.n_frames - 1)
        uv, _ = Camera(t["K"], t["R"], t["t"], size=tuple(int(s) for s in t["size"])).project(keypoint_positions(motion)[idx])
        po = pose.predict_video(PoseTrack(np.asarray(uv, float), 20.0))
        so = sift.predict_video(load_features(work / f"{name}.npz"))
        n = min(len(po["raw"]), len(so["raw"]))
        fused = pose.smooth(*fuse_scores([po["scores"][:n], so["scores"][:n]], [pose.classes_, sift.classes_],
                                         [0.5, 0.5], pose.classes_))
        from vidstyle.evaluation.realmocap import action_frames

        mask = (action_frames(motion) if fam == "punch" else np.ones(motion.n_frames, bool))[idx][:n]
        for rec, out_ in (("pose", po), ("sift", so), ("fusion", fused)):
            row = next(r for r in doc["rows"] if r["clip"] == clip and r["recognizer"] == rec)
            fams = np.array([family_of(str(c)) for c in (pose.classes_ if rec != "sift" else sift.classes_)[out_["smoothed"][:n]]])
            assert row["frames"] == int(mask.sum()) > 0
            assert row["family_counts"][fam] == int(np.sum(fams[mask] == fam))
    # fusion without a second recognizer, a bad pose input, a pose model given as --model: exit 2, no output
    for extra in (["--pose-model", str(tmp_path / "p.joblib"), "--fusion-weight", "0.5"],
                  ["--pose-model", str(tmp_path / "p.joblib"), "--pose-input", "x"],
                  ["--model", str(tmp_path / "p.joblib")]):
        assert main(["evaluate", "real-motion", "--clips", str(tmp_path / "l.csv"), *extra,
                     "--out", str(tmp_path / "bad.json")]) == 2
        assert not (tmp_path / "bad.json").exists()


def test_fused_recognizers_are_named_by_weight_and_power():
    """Several fusion weights and powers: the first power keeps the plain names (what the committed files
    and the validation's stage 1 read), each other one adds ``^P``; a power <= 0 is refused."""
    import pytest

    from vidstyle.errors import ParameterError
    from vidstyle.evaluation.realmotion import Recognizers
    from vidstyle.recognition import defaults as D

    recs = Recognizers(sift=object(), pose=object(), fusion_weight=[0.25, 0.5], fusion_emission_weight=[1.0, 3.0])
    assert recs.fusions() == {"fusion@0.25": (0.25, 1.0), "fusion@0.25^3": (0.25, 3.0),
                              "fusion@0.5": (0.5, 1.0), "fusion@0.5^3": (0.5, 3.0)}
    assert recs.names() == ["sift", "pose", "fusion@0.25", "fusion@0.25^3", "fusion@0.5", "fusion@0.5^3"]
    assert Recognizers(sift=object(), pose=object(), fusion_weight=0.5).fusions() == {
        "fusion": (0.5, D.FUSION_EMISSION_WEIGHT)}
    with pytest.raises(ParameterError):
        Recognizers(sift=object(), pose=object(), fusion_weight=0.5, fusion_emission_weight=0.0).check()
