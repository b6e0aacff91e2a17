"""ActionModel: encode/decode round trip, BIC on a known mixture, reproducible sampling, planted feet on
the floor, the model file (round trip and fuzz) and the CLI's exit status on bad input."""

from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np
import pytest

from vidstyle.actionmodel import ActionModel, cut_instances
from vidstyle.actionmodel.model import fit_gmm_bic
from vidstyle.formats import FormatError
from vidstyle.formats.actionmodel import parse_actionmodel, read_actionmodel


@pytest.fixture(scope="module")
def clips():
    from vidstyle.demo.clip import performer_clip
    from vidstyle.motiongraph.graph import Clip

    out = []
    for a in ("Jab", "LowKick"):
        _, take = performer_clip(seed=0, index=0, action=a, seconds=6, fps=60)
        out.append(Clip(f"p00_{a}", take.motion, take.labels))
    return out


@pytest.fixture(scope="module")
def iset(clips):
    return cut_instances(clips)


@pytest.fixture(scope="module")
def model(iset):
    return ActionModel(random_state=0).fit(iset)


@pytest.fixture(scope="module")
def full_model(iset):
    return ActionModel(variance=1.0, random_state=0, labels=("Jab",)).fit(iset)


def test_estimator_conventions(model):
    p = model.get_params()
    assert p["random_state"] == 0 and p["variance"] == model.variance
    assert set(model.labels_) == {"Jab", "LowKick"}
    clone = ActionModel(**p)
    assert clone.get_params() == p
    assert not hasattr(clone, "models_")


def test_labels_fitted_on_workers_give_the_same_model(model, iset, tmp_path):
    # n_jobs spreads the labels over workers; each label's fit is seeded by the label alone, so the model
    # file is the same bytes (fit times aside), and n_jobs is a run setting the file does not keep
    par = ActionModel(random_state=0, n_jobs=2).fit(iset)
    assert par.labels_ == model.labels_ and par.skipped_ == model.skipped_
    for label in model.labels_:
        a, b = model.models_[label], par.models_[label]
        for k in ("gmm_weights", "gmm_means", "gmm_covariances", "spatial_components", "temporal_components",
                  "ref_rotations", "keyframes"):
            assert np.array_equal(getattr(a, k), getattr(b, k)), (label, k)
        b.fit_seconds = a.fit_seconds
    model.save(tmp_path / "serial.npz")
    par.save(tmp_path / "workers.npz")
    assert (tmp_path / "serial.npz").read_bytes() == (tmp_path / "workers.npz").read_bytes()
    assert "n_jobs" not in read_actionmodel(tmp_path / "workers.npz").params


def test_kick_is_segmented_at_the_contact_change(model):
    """The rear foot leaves the floor during a low kick: two primitives (both feet, then one)."""
    assert model.models_["Jab"].signature == [[True, True]]
    kick = model.models_["LowKick"].signature
    assert len(kick) >= 2 and kick[0] == [True, True] and not all(kick[1])


def test_encode_decode_with_all_variance_reproduces_the_aligned_instance(full_model, iset):
    for inst in iset.of("Jab"):
        al = full_model.align(inst, "Jab")
        z = full_model.encode(inst, "Jab")
        back = full_model.decode_aligned(z, "Jab")
        q, r = back.rotations, al.rotations
        assert np.abs(np.abs(np.sum(q * r, -1)) - 1).max() < 1e-9  # same rotations (up to sign)
        np.testing.assert_allclose(back.root, al.root, atol=1e-9)
        np.testing.assert_allclose(back.warp, al.warp, atol=1e-9)


def test_reduced_model_reconstructs_better_than_the_mean(iset):
    from vidstyle.actionmodel.metrics import mpjpe

    model = ActionModel(variance=0.9, random_state=0, labels=("Jab",)).fit(iset)
    assert model.models_["Jab"].n_spatial < model.models_["Jab"].n_instances - 1
    errs, base = [], []
    for inst in iset.of("Jab"):
        z = model.encode(inst, "Jab")
        errs.append(mpjpe(model.decode(z, "Jab", n_frames=inst.n_frames), inst.motion))
        base.append(mpjpe(model.decode(0 * z, "Jab", n_frames=inst.n_frames), inst.motion))
    assert np.mean(errs) < np.mean(base)


def test_bic_picks_two_components_of_a_known_mixture():
    rng = np.random.default_rng(0)
    a = rng.normal([0, 0, 0], 1.0, (300, 3))
    b = rng.normal([6, -5, 4], 1.0, (300, 3))
    w, mu, cov, bics, kind = fit_gmm_bic(np.concatenate([a, b]), 5, "full", 0)
    assert len(w) == 2 and kind == "full" and int(np.argmin(bics)) == 1
    assert sorted(np.round(mu[:, 0]).tolist()) == [0.0, 6.0]
    one = fit_gmm_bic(a, 5, "full", 0)
    assert len(one[0]) == 1


def test_sampling_is_reproducible(model):
    a = model.sample("LowKick", 3, random_state=7)
    b = model.sample("LowKick", 3, random_state=7)
    c = model.sample("LowKick", 3, random_state=8)
    for x, y in zip(a, b):
        assert x.n_frames == y.n_frames
        np.testing.assert_array_equal(x.rotations, y.rotations)
        np.testing.assert_array_equal(x.translations, y.translations)
    # another seed draws other instances: at least one of the three differs in length or in its rotations
    differs = [x.n_frames != y.n_frames or not np.allclose(x.rotations, y.rotations) for x, y in zip(a, c)]
    assert len(a) == len(c) == 3 and True in differs
    assert model.skeleton_.same_hierarchy(a[0].skeleton)


def test_sampled_planted_feet_are_on_the_floor_and_still(model):
    from vidstyle.mocap.kinematics import forward_kinematics
    from vidstyle.mocap.retarget import leg_length

    leg = leg_length(model.skeleton_)
    for label in model.labels_:
        lm = model.models_[label]
        for z in model.sample_coefficients(label, 4, random_state=1):
            al = model.decode_aligned(z, label)
            from vidstyle.actionmodel.warp import invert_warp

            u = invert_warp(al.warp, al.n_frames)
            planted = model.contacts_at(label, u)
            m = model.decode(z, label, pin=True)
            pos = forward_kinematics(m, return_matrices=False)[0]
            assert planted.any()
            for f, ankle in enumerate(model.ankles_):
                y = pos[planted[:, f], ankle, 1]
                assert np.abs(y - model.contact_height_).max() < 1e-3 * leg
                # within a planted run the ankle does not slide
                runs = np.flatnonzero(planted[1:, f] & planted[:-1, f])
                slide = np.linalg.norm(pos[runs + 1, ankle][:, [0, 2]] - pos[runs, ankle][:, [0, 2]], axis=-1)
                assert slide.max(initial=0) < 1e-3 * leg
        assert lm.n_components >= 1


def test_log_prior_prefers_the_mean(model):
    lm = model.models_["Jab"]
    z0 = lm.gmm_means[int(np.argmax(lm.gmm_weights))]
    far = z0 + 10.0
    assert model.log_prior(z0, "Jab") > model.log_prior(far, "Jab")
    zs = model.sample_coefficients("Jab", 5, random_state=0)
    assert model.log_prior(zs, "Jab").shape == (5,)


def test_bad_parameters_and_labels(model, iset):
    from vidstyle.errors import InputError, ParameterError

    for kw in ({"variance": 0}, {"variance": 1.5}, {"slope_limit": 0}, {"covariance_type": "tied"}):
        with pytest.raises(ParameterError):
            ActionModel(**kw).fit(iset)
    with pytest.raises(ParameterError):
        model.sample("Nope", 1)
    with pytest.raises(InputError):
        ActionModel(labels=("Nope",)).fit(iset)
    with pytest.raises(ParameterError):
        model.encode(iset.of("Jab")[0].motion[:1], "Jab")


# ----------------------------------------------------------------------------- the model file
def test_file_round_trip(model, tmp_path):
    path = tmp_path / "m.npz"
    model.save(path)
    back = ActionModel.load(path)
    assert back.get_params() == model.get_params() and back.labels_ == model.labels_
    z = model.sample_coefficients("LowKick", 3, random_state=0)
    np.testing.assert_allclose(back.log_prior(z, "LowKick"), model.log_prior(z, "LowKick"))
    a, b = model.sample("LowKick", 2, random_state=3), back.sample("LowKick", 2, random_state=3)
    for x, y in zip(a, b):
        np.testing.assert_allclose(x.rotations, y.rotations, atol=1e-12)
    assert not list(tmp_path.glob(".*tmp*"))  # atomic write left no temporary


def _arrays(model, tmp_path) -> dict:
    path = tmp_path / "base.npz"
    model.save(path)
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


def _mutations(arrays, rng):
    keys = sorted(arrays)
    for _ in range(150):
        a = dict(arrays)
        k = keys[int(rng.integers(len(keys)))]
        op = int(rng.integers(7))
        v = a[k]
        if op == 0:
            del a[k]
        elif op == 1:
            a[k] = np.array("garbage")
        elif op == 2 and v.dtype.kind == "f" and v.size:
            v = v.copy()
            v.flat[int(rng.integers(v.size))] = np.nan
            a[k] = v
        elif op == 3 and v.ndim:
            a[k] = v[:-1]
        elif op == 4:
            a[k] = np.zeros((2, 2, 2))
        elif op == 5 and v.dtype.kind == "U":
            text = str(v)
            cut = int(rng.integers(len(text) + 1))
            a[k] = np.array(text[:cut] + "}" + text[cut:])
        elif op == 6 and v.dtype.kind in "fi" and v.size:
            v = v.astype(np.float64) * -1.0
            a[k] = v
        yield k, a


def test_fuzzed_arrays_raise_only_formaterror(model, tmp_path):
    arrays = _arrays(model, tmp_path)
    parse_actionmodel(arrays, "ok.npz")
    rng = np.random.default_rng(0)
    for k, a in _mutations(arrays, rng):
        try:
            rec = parse_actionmodel(a, "fuzz.npz")
        except FormatError as e:
            assert str(e).startswith("fuzz.npz") and "\n" not in str(e)
            continue
        ActionModel.from_record(rec)  # what the reader accepts builds a model


def test_fuzzed_bytes_raise_only_formaterror(model, tmp_path):
    path = tmp_path / "m.npz"
    model.save(path)
    data = path.read_bytes()
    rng = np.random.default_rng(1)
    for i in range(40):
        b = bytearray(data)
        for _ in range(int(rng.integers(1, 8))):
            b[int(rng.integers(len(b)))] = int(rng.integers(256))
        if i % 5 == 0:
            b = b[: int(rng.integers(len(b)))]
        p = tmp_path / f"f{i}.npz"
        p.write_bytes(bytes(b))
        try:
            read_actionmodel(p)
        except FormatError as e:
            assert str(p) in str(e)


def test_pickled_member_is_refused(tmp_path):
    buf = io.BytesIO()
    np.save(buf, np.array([object()], dtype=object), allow_pickle=True)
    p = tmp_path / "p.npz"
    with zipfile.ZipFile(p, "w") as zf:
        zf.writestr("kind.npy", buf.getvalue())
    with pytest.raises(FormatError):
        read_actionmodel(p)


# ----------------------------------------------------------------------------- the CLI
def _main(args):
    from vidstyle.cli import main

    return main(args)


def test_cli_fits_and_samples(clips, tmp_path, capsys):
    from vidstyle.mocap import read_bvh, write_bvh

    bvh = tmp_path / "clip.bvh"
    write_bvh(clips[0].motion, bvh)
    csv = tmp_path / "clips.csv"
    runs = []
    labels = clips[0].labels
    s = 0
    for t in range(1, len(labels) + 1):
        if t == len(labels) or labels[t] != labels[s]:
            if labels[s] == "Jab":
                runs.append((s, t))
            s = t
    csv.write_text("file,label,start,end\n" + "".join(f"clip.bvh,Jab,{a},{b}\n" for a, b in runs))
    out = tmp_path / "m.npz"
    assert _main(["fit-actions", str(csv), "--out", str(out), "--variance", "0.9", "--seed", "0"]) == 0
    assert _main(["sample-action", str(out), "--label", "Jab", "-n", "2", "--seed", "0",
                  "--out-dir", str(tmp_path / "s")]) == 0
    files = sorted((tmp_path / "s").glob("*.bvh"))
    assert len(files) == 2 and read_bvh(files[0]).n_frames > 5
    assert (tmp_path / "s" / "Jab_000.labels.json").is_file()


@pytest.mark.parametrize("args", [
    ["fit-actions", "missing.bvh", "--out", "m.npz"],
    ["fit-actions", "bad.csv", "--out", "m.npz"],
    ["fit-actions", "ok.bvh", "--out", "m.npz", "--variance", "1.5"],
    ["fit-actions", "ok.bvh", "--out", "m.txt"],
    ["sample-action", "missing.npz", "--label", "Jab", "--out-dir", "o"],
    ["sample-action", "bad.npz", "--label", "Jab", "--out-dir", "o"],
    ["sample-action", "m.npz", "--label", "Nope", "--out-dir", "o"],
    ["sample-action", "m.npz", "--label", "Jab", "-n", "0", "--out-dir", "o"],
])
def test_cli_bad_input_exits_2(args, model, tmp_path, capsys, monkeypatch):
    from vidstyle.mocap import write_bvh

    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.csv").write_text("name,what\nx,y\n")
    (tmp_path / "bad.npz").write_bytes(b"not a zip")
    model.save(tmp_path / "m.npz")
    from vidstyle.mocap import Motion

    write_bvh(Motion(model.skeleton_, np.tile([0, 0, 0, 1.0], (3, model.skeleton_.n_joints, 1))), tmp_path / "ok.bvh")
    assert _main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len([line for line in err if "error" in line]) == 1


CMU_CLIP = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap" / "cmu" / "01_06.bvh"


@pytest.mark.skipif(not CMU_CLIP.is_file(), reason="../shared/data/mocap/cmu/01_06.bvh (CMU BVH) is absent")
def test_cmu_clip_through_a_label_csv(tmp_path):
    """A real CMU clip labelled by frame ranges in a label CSV: instances are cut and segmented at their
    contact changes, and the model fits, samples on the CMU skeleton and keeps planted feet still."""
    from vidstyle.actionmodel import load_labelled
    from vidstyle.actionmodel.metrics import naturalness

    csv = tmp_path / "c.csv"
    csv.write_text("file,label,start,end\n" + "".join(f"{CMU_CLIP},move,{1000 + k * 100},{1090 + k * 100}\n"
                                                      for k in range(8)))
    clips = load_labelled([csv])
    m = ActionModel(random_state=0, min_instances=2, max_components=2).fit(clips)
    assert m.labels_ == ["move"] and m.skeleton_.n_joints == clips[0].motion.skeleton.n_joints
    s = m.sample("move", 2, random_state=0)
    assert all(x.n_frames > 2 for x in s)
    nat = naturalness(s[0], m.contact_height_)
    assert nat["slide_mm_per_frame"] is None or nat["slide_mm_per_frame"] < 0.5


def test_naturalness_of_known_motions(model):
    """A motionless stance: no slide, no velocity variance, feet at their height; a root gliding at constant
    speed: every planted-foot step is that speed, velocity variance still 0 (constant velocity)."""
    from vidstyle.actionmodel.metrics import naturalness, nearest_distances, time_normalised_positions
    from vidstyle.mocap import Motion

    inst = model.models_["Jab"]
    rot = np.repeat(inst.ref_rotations[:1], 30, axis=0)
    root = np.repeat(inst.ref_root[:1], 30, axis=0)
    still = Motion(model.skeleton_, rot, None, 60.0, root_positions=root)
    n = naturalness(still, model.contact_height_)
    assert n["slide_mm_per_frame"] == pytest.approx(0.0, abs=1e-9)
    assert n["velocity_variance_mm2"] == pytest.approx(0.0, abs=1e-12)
    glide = Motion(model.skeleton_, rot, None, 60.0, root_positions=root + np.outer(np.arange(30), [0, 0, 0.01]))
    g = naturalness(glide, model.contact_height_, unit_mm=10.0)
    assert g["velocity_variance_mm2"] == pytest.approx(0.0, abs=1e-9)
    if g["slide_mm_per_frame"] is not None:  # slow enough to count as planted
        assert g["slide_mm_per_frame"] == pytest.approx(0.1, rel=1e-6)
    a, b = time_normalised_positions(still), time_normalised_positions(glide)
    d = nearest_distances([a, b], [a, b], leave_one_out=True)
    assert d[0] == pytest.approx(d[1]) and d[0] > 0
    assert nearest_distances([a], [a, b])[0] == 0


def test_cli_defaults_are_the_library_defaults(clips, tmp_path):
    """fit-actions with no options writes the model ActionModel() fits (every array equal; only the
    measured fit seconds differ)."""
    from vidstyle.actionmodel import load_labelled
    from vidstyle.mocap import write_bvh

    bvh = tmp_path / "p00_jab.bvh"
    write_bvh(clips[0].motion, bvh)
    labels = clips[0].labels
    csv = tmp_path / "c.csv"
    s, rows = 0, []
    for t in range(1, len(labels) + 1):
        if t == len(labels) or labels[t] != labels[s]:
            rows.append(f"p00_jab.bvh,{labels[s]},{s},{t}\n")
            s = t
    csv.write_text("file,label,start,end\n" + "".join(rows))
    assert _main(["fit-actions", str(csv), "--out", str(tmp_path / "cli.npz")]) == 0
    ActionModel().fit(load_labelled([csv])).save(tmp_path / "lib.npz")
    a, b = read_actionmodel(tmp_path / "cli.npz"), read_actionmodel(tmp_path / "lib.npz")
    assert a.params == b.params and a.labels == b.labels
    for label in a.labels:
        for k, v in a.models[label].items():
            if k == "meta":
                assert {x: y for x, y in v.items() if x != "fit_seconds"} == \
                    {x: y for x, y in b.models[label]["meta"].items() if x != "fit_seconds"}
            else:
                np.testing.assert_array_equal(v, b.models[label][k])
