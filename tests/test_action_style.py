"""Fitting a performer's action-level style from 2D (vidstyle.actionmodel.stylefit): global parameters of
demo performers rendered through a known camera, coefficients recovered from a noiseless projected
decode, the prior's pull, the style artifact's action-level part (round trip, schema 1 still loads,
fuzzed reader) and the CLI's exit status on bad input."""

from __future__ import annotations

import copy
import json
from dataclasses import replace

import numpy as np
import pytest

from vidstyle.actionmodel import ActionModel, cut_instances
from vidstyle.actionmodel import defaults as D
from vidstyle.actionmodel.stylefit import (
    GlobalStyleEstimator,
    SegmentFitter,
    fit_action_style,
    mirror_track,
    project,
    video_figures,
)
from vidstyle.errors import ParameterError
from vidstyle.formats import FormatError


def _take(action: str, index: int = 0, **style):
    from vidstyle.demo.dataset import DatasetParams, make_performer
    from vidstyle.demo.timeline import build_take, single_action_plan

    p = make_performer(DatasetParams(seed=0, mocap_fps=60), index)
    if "speed" in style:  # durations were drawn with the old speed: rescale them
        k = p.style.speed / style["speed"]
        p = replace(p, chain=replace(p.chain, duration_frames={a: (m * k, sd * k) for a, (m, sd) in p.chain.duration_frames.items()}))
    p = replace(p, style=replace(p.style, **style))
    rng = np.random.default_rng(7)
    return p, build_take(p, single_action_plan(p, action, 100, rng), rng, video_fps=20, ratio=3)


def _video(take, view: str):
    """(xy (F, 15, 2) at 20 fps through a known camera at ``view``, labels, view)."""
    from vidstyle.mocap.keypoints import keypoint_positions
    from vidstyle.render.camera import Camera

    cam = Camera.for_view(take.motion, view, elevation_deg=10.0)
    pts = keypoint_positions(take.motion)[::3]
    uv, _ = cam.project(pts)
    return np.asarray(uv, float), list(take.labels[::3])[: len(pts)], view


@pytest.fixture(scope="module")
def videos():
    out = {}
    base = dict(guard_height=0.0, stance_width=1.0, lead="orthodox", speed=1.0, amplitude=1.0, crouch=0.0)
    for name, st in (("population", base),
                     ("narrow", dict(base, stance_width=0.85, guard_height=-0.06)),
                     ("wide_southpaw", dict(base, stance_width=1.2, guard_height=0.05, lead="southpaw"))):
        _, take = _take("Jab", 0, **st)
        out[name] = [_video(take, v) for v in ("front", "left", "right")]
    return out


def test_global_style_recovers_lead_stance_and_guard(videos):
    est = GlobalStyleEstimator().fit(videos["population"])
    a = est.estimate(videos["narrow"])
    b = est.estimate(videos["wide_southpaw"])
    assert a.lead == "orthodox" and b.lead == "southpaw"
    assert a.lead_score > 0.2 and b.lead_score < -0.2
    assert a.stance_width < 1.0 < b.stance_width
    assert a.guard_height < 0.0 < b.guard_height
    # the population itself: neutral
    p = est.estimate(videos["population"])
    assert p.stance_width == pytest.approx(1.0, abs=0.02) and p.guard_height == pytest.approx(0.0, abs=0.01)


def test_stance_cue_finds_the_lead_without_jabs_and_with_left_right_swapped(videos):
    # what the pose stage gives: left/right labels swapped in every frame, and a short clip recognised as all
    # guard (no jab to go by); the front foot's image side still tells the lead, the jab rules cannot
    swap = [0, 1, 2, 4, 3, 6, 5, 8, 7, 10, 9, 12, 11, 14, 13]
    est = GlobalStyleEstimator().fit(videos["population"])
    assert est.stance_side_ == {"front": 1.0, "left": -1.0, "right": -1.0}  # the orthodox front foot's side
    for name, lead in (("narrow", "orthodox"), ("wide_southpaw", "southpaw")):
        short = [(xy[:60, swap], ["Guard"] * 60, view) for xy, _labels, view in videos[name]]
        g = est.estimate(short)
        assert g.lead == lead and abs(g.lead_score) > 0.8 and g.n_jabs == 0
    jab_only = GlobalStyleEstimator(lead_cue="jab").fit(videos["population"])
    short = [(xy[:60, swap], ["Guard"] * 60, view) for xy, _labels, view in videos["wide_southpaw"]]
    assert jab_only.estimate(short).lead_score == 0.0  # no jab: no evidence, the threshold's default
    few = GlobalStyleEstimator(min_stance_frames=10_000).fit(videos["population"])  # too few frames: the jab rules
    assert few.estimate(videos["wide_southpaw"]).lead == "southpaw"
    with pytest.raises(Exception, match="lead_cue"):
        GlobalStyleEstimator(lead_cue="feet").fit(videos["population"])


def test_tempo_is_duration_relative_to_the_population(videos):
    est = GlobalStyleEstimator().fit(videos["population"])
    _, slow = _take("Jab", 0, speed=0.7)
    g = est.estimate([_video(slow, "front")])
    assert g.tempo["Jab"] > 1.2


def _labelled(runs):
    """(xy, labels, view) of a track whose labels are the given (label, frames) runs (finite random points:
    durations and steps do not depend on them)."""
    labels = [lab for lab, n in runs for _ in range(n)]
    xy = np.random.default_rng(len(labels)).normal(size=(len(labels), 15, 2))
    return xy, labels, "front"


def test_speed_from_step_lengths_separates_action_tempo_from_the_duration_factor():
    from vidstyle.actionmodel.stylefit import GlobalStyle

    pop = [_labelled([("Guard", 5), ("Step", 12), ("Guard", 3), ("Jab", 15), ("Guard", 4), ("Step", 12),
                      ("Hook", 20), ("Guard", 5)])] * 3
    est = GlobalStyleEstimator().fit(pop)
    assert est.step_frames_ == 12.0 and est.durations_ == {"Jab": 15.0, "Hook": 20.0}
    # steps of 10 frames: 1.2 times the population's speed; a jab of 12 frames: duration factor 0.8, so its
    # own tempo (at the population's speed) is 0.8 * 1.2
    fast = [_labelled([("Guard", 4), ("Step", 10), ("Jab", 12), ("Guard", 3), ("Step", 10), ("Hook", 20), ("Guard", 2)])]
    g = est.estimate(fast)
    assert g.speed == pytest.approx(1.2)
    assert g.tempo == pytest.approx({"Jab": 0.8, "Hook": 1.0})
    assert g.action_tempo == pytest.approx({"Jab": 0.96, "Hook": 1.2})
    back = GlobalStyle.from_dict(g.to_dict())
    assert back.speed == pytest.approx(1.2) and back.action_tempo == pytest.approx(g.action_tempo)
    # no step seen: the speed is unknown, the duration factor stays
    still = est.estimate([_labelled([("Guard", 4), ("Jab", 12), ("Guard", 3)])])
    assert np.isnan(still.speed) and still.action_tempo == {} and still.tempo == pytest.approx({"Jab": 0.8})
    # a style written before the speed existed loads without it
    old = {k: v for k, v in g.to_dict().items() if k not in ("speed", "action_tempo")}
    assert np.isnan(GlobalStyle.from_dict(old).speed) and GlobalStyle.from_dict(old).action_tempo == {}


def _recognised(runs):
    """(xy, labels, view, confidence) of recognised labels: (label, frames, confidence of every frame) runs."""
    xy, labels, view = _labelled([(lab, n) for lab, n, _ in runs])
    return xy, labels, view, np.array([c for _, n, c in runs for _ in range(n)])


def test_recognised_runs_below_the_confidence_threshold_do_not_measure_speed_or_tempo():
    pop = [_labelled([("Guard", 5), ("Step", 12), ("Guard", 3), ("Jab", 15), ("Guard", 4)])] * 2
    # the runs' own lengths (the random points have no motion to time), every length measured
    est = GlobalStyleEstimator(min_run_confidence=0.5, step_min_run_confidence=None, run_timing="labels",
                               max_run_factor=None, min_run_factor=None).fit(pop)
    # the performer's real steps last 15 frames (speed 12 / 15) and jabs 18; the recognizer also reports two
    # spurious 7-frame steps and a 6-frame jab at low confidence
    perf = _recognised([("Guard", 4, 0.9), ("Step", 15, 0.8), ("Guard", 3, 0.9), ("Step", 7, 0.3), ("Guard", 3, 0.9),
                        ("Jab", 18, 0.7), ("Guard", 2, 0.9), ("Step", 7, 0.4), ("Jab", 6, 0.2), ("Guard", 3, 0.9),
                        ("Step", 15, 0.6)])
    g = est.estimate([perf])
    assert g.speed == pytest.approx(12 / 15) and g.tempo == pytest.approx({"Jab": 18 / 15})
    # the same labels without their confidence (true labels) are all trusted: median steps of (15, 7, 7, 15)
    t = est.estimate([perf[:3]])
    assert t.speed == pytest.approx(12 / 11) and t.tempo == pytest.approx({"Jab": 12 / 15})
    # a threshold of 0 (for the steps too: None is "the same") trusts every run, as true labels are
    assert (GlobalStyleEstimator(min_run_confidence=0.0, step_min_run_confidence=None, run_timing="labels",
                                 min_run_factor=None).fit(pop).estimate([perf]).speed == pytest.approx(12 / 11))


def test_step_runs_have_their_own_confidence_threshold():
    pop = [_labelled([("Guard", 5), ("Step", 12), ("Guard", 3), ("Jab", 15), ("Guard", 4)])] * 2
    # steps of 15 frames at confidence 0.8 and 0.6, spurious 7-frame steps at 0.35 and 0.45; jabs of 18 at 0.35
    # and of 12 at 0.8
    perf = _recognised([("Guard", 4, 0.9), ("Step", 15, 0.8), ("Guard", 3, 0.9), ("Step", 7, 0.35), ("Guard", 3, 0.9),
                        ("Jab", 18, 0.35), ("Guard", 2, 0.9), ("Step", 7, 0.45), ("Jab", 12, 0.8), ("Guard", 3, 0.9),
                        ("Step", 15, 0.6)])

    def est(**kw):
        return GlobalStyleEstimator(run_timing="labels", max_run_factor=None, min_run_factor=None, **kw).fit(pop)

    # one threshold of 0.3: every run measures, steps (15, 7, 7, 15): median 11; jabs (18, 12): 15
    g = est(min_run_confidence=0.3, step_min_run_confidence=None).estimate([perf])
    assert g.speed == pytest.approx(12 / 11) and g.tempo == pytest.approx({"Jab": 1.0})
    # steps at 0.5: the spurious steps drop out (speed 12 / 15); the jabs keep the actions' 0.3
    g = est(min_run_confidence=0.3, step_min_run_confidence=0.5).estimate([perf])
    assert g.speed == pytest.approx(12 / 15) and g.tempo == pytest.approx({"Jab": 1.0})
    # and the other way round: steps at 0.4 keep the 0.45 one (15, 7, 15), the jabs at 0.5 lose the 18
    g = est(min_run_confidence=0.5, step_min_run_confidence=0.4).estimate([perf])
    assert g.speed == pytest.approx(12 / 15) and g.tempo == pytest.approx({"Jab": 12 / 15})
    g = est(min_run_confidence=0.5, step_min_run_confidence=0.0).estimate([perf])
    assert g.speed == pytest.approx(12 / 11)
    with pytest.raises(ParameterError, match="step_min_run_confidence"):
        est(step_min_run_confidence=-0.1).estimate([perf])
    # the default is the validated one (validation/tempo_runs.json)
    assert GlobalStyleEstimator().step_min_run_confidence == D.STYLE_STEP_MIN_RUN_CONFIDENCE


def test_recognised_runs_much_shorter_than_the_populations_do_not_measure():
    pop = [_labelled([("Guard", 5), ("Step", 12), ("Guard", 3), ("Jab", 15), ("Guard", 4)])] * 2
    # confident runs: steps of 14, 13 and two fragments of 6 and 7; jabs of 16, 17 and one of 5
    perf = _recognised([("Guard", 4, 0.9), ("Step", 14, 0.8), ("Guard", 3, 0.9), ("Step", 6, 0.8), ("Guard", 3, 0.9),
                        ("Jab", 16, 0.7), ("Guard", 2, 0.9), ("Step", 7, 0.8), ("Jab", 5, 0.8), ("Guard", 3, 0.9),
                        ("Step", 13, 0.8), ("Guard", 2, 0.9), ("Jab", 17, 0.8)])

    def est(**kw):
        return GlobalStyleEstimator(run_timing="labels", max_run_factor=None, min_run_confidence=0.3,
                                    step_min_run_confidence=None, **kw).fit(pop)

    g = est(min_run_factor=None).estimate([perf])  # steps (14, 6, 7, 13): median 10; jabs (16, 5, 17): 16
    assert g.speed == pytest.approx(12 / 10) and g.tempo == pytest.approx({"Jab": 16 / 15})
    # a floor of 0.7 of the population's lengths (8.4 and 10.5 frames) leaves the fragments out
    g = est(min_run_factor=0.7).estimate([perf])
    assert g.speed == pytest.approx(12 / 13.5) and g.tempo == pytest.approx({"Jab": 16.5 / 15})
    # true labels (no confidence) are never floored
    assert est(min_run_factor=0.7).estimate([perf[:3]]).speed == pytest.approx(12 / 10)
    for bad in (0.0, 1.0, 1.5):
        with pytest.raises(ParameterError, match="min_run_factor"):
            est(min_run_factor=bad).estimate([perf])


def test_a_label_whose_runs_are_all_doubtful_keeps_its_most_confident_run():
    pop = [_labelled([("Guard", 5), ("Step", 12), ("Guard", 3), ("Hook", 20), ("Guard", 4)])]
    est = GlobalStyleEstimator(min_run_confidence=0.5, run_timing="labels", max_run_factor=None).fit(pop)
    perf = _recognised([("Guard", 3, 0.9), ("Hook", 30, 0.2), ("Guard", 3, 0.9), ("Hook", 24, 0.45),
                        ("Guard", 3, 0.9), ("Step", 10, 0.9)])
    assert est.estimate([perf]).tempo == pytest.approx({"Hook": 24 / 20})
    # the runs and their mean confidence, over the video's frames (runs of one label counted one by one)
    f = video_figures(*perf[:2], perf[3])
    assert f["runs"] == [("Hook", 30, pytest.approx(0.2)), ("Hook", 24, pytest.approx(0.45)), ("Step", 10, pytest.approx(0.9))]
    conf = perf[3].copy()
    conf[3:33] = np.linspace(0.0, 1.0, 30)  # the first hook's frames: mean 0.5
    assert video_figures(*perf[:2], conf)["runs"][0][2] == pytest.approx(0.5)
    assert all(np.isnan(c) for _, _, c in video_figures(*perf[:2])["runs"])
    with pytest.raises(ParameterError, match="min_run_confidence"):
        GlobalStyleEstimator(min_run_confidence=1.5).fit(pop).estimate([perf])


def test_population_tempo_reference_is_the_mean_of_each_performers_own_ratio():
    # performer a: steps of 10, jabs of 10 (ratio 1.0); performer b, slower: steps of 15, jabs of 18 (1.2).
    # Grouped by performer, the reference ratio is their mean 1.1 and the step length their mean 12.5
    a = [_labelled([("Guard", 3), ("Step", 10), ("Jab", 10), ("Guard", 3), ("Step", 10), ("Jab", 10)])] * 2
    b = [_labelled([("Guard", 3), ("Step", 15), ("Jab", 18), ("Guard", 3)])]
    est = GlobalStyleEstimator().fit(a + b, groups=["a", "a", "b"])
    assert est.step_frames_ == pytest.approx(12.5) and est.action_step_ratio_ == pytest.approx({"Jab": 1.1})
    g = est.estimate([_labelled([("Guard", 2), ("Step", 12), ("Jab", 13), ("Guard", 2), ("Step", 12), ("Jab", 14)])])
    assert g.speed == pytest.approx(12.5 / 12) and g.action_tempo == pytest.approx({"Jab": 13.5 / 12 / 1.1})
    with pytest.raises(ParameterError, match="groups"):
        GlobalStyleEstimator().fit(a + b, groups=["a", "b"])


def test_action_tempo_equals_the_true_tempo_over_the_population_mean_and_the_metric_scores_that():
    from vidstyle.evaluation.actionstyle import population_tempo, summarise

    # a generator like the demo's: a step lasts 12 / speed frames, a jab 20 * tempo / speed
    truth = {"p": {"tempo": [0.9], "speed": 1.0}, "q": {"tempo": [1.0], "speed": 1.0},
             "r": {"tempo": [1.2], "speed": 1.0}, "t": {"tempo": [0.9], "speed": 1.5}}

    def video(who):
        sp, tj = truth[who]["speed"], truth[who]["tempo"][0]
        return _labelled([("Guard", 3), ("Step", round(12 / sp)), ("Jab", round(20 * tj / sp)), ("Guard", 3)])

    pop = ["p", "q", "r"]
    est = GlobalStyleEstimator().fit([video(w) for w in pop], groups=pop)
    ref = population_tempo(truth, pop, ["Jab"])
    assert ref == pytest.approx({"Jab": (0.9 + 1.0 + 1.2) / 3})
    g = est.estimate([video("t")])
    assert g.speed == pytest.approx(1.5) and g.action_tempo["Jab"] == pytest.approx(0.9 / ref["Jab"])

    # estimates exact against the population-relative truth, populations differing in their mean tempo:
    # that correlation is 1, the one against the absolute tempo is not
    def row(tempo, pop_mean):
        return {"lead": "orthodox", "lead_true": "orthodox", "guard_height": 0.0, "guard_height_true": 0.0,
                "stance_width": 0.0, "stance_width_true": 0.0, "crouch": 0.0, "crouch_true": 0.0,
                "tempo_true": {"Jab": tempo}, "duration_factor_true": {"Jab": tempo}, "tempo": {"Jab": tempo},
                "relative_tempo": {"Jab": 1.0}, "action_tempo": {"Jab": tempo / pop_mean},
                "population_tempo_true": {"Jab": pop_mean}, "speed_true": 1.0, "speed": None, "labels": {}}

    rows = [row(t, m) for t, m in [(0.9, 0.95), (1.1, 0.95), (0.95, 1.1), (1.15, 1.1), (1.0, 1.02), (0.88, 1.02)]]
    out = summarise(rows, ["Jab"])
    assert out["action_tempo_population_r"] == pytest.approx(1.0)
    assert out["action_tempo_r"] < 0.9


def test_mirror_track_is_an_involution():
    xy = np.random.default_rng(0).normal(size=(4, 15, 2))
    assert np.allclose(mirror_track(mirror_track(xy)), xy)


@pytest.fixture(scope="module")
def model():
    from vidstyle.motiongraph.graph import Clip

    clips = []
    for i in (0, 2):
        _, take = _take("Jab", i, lead="orthodox")
        clips.append(Clip(f"p{i:02d}_Jab", take.motion, take.labels))
    return ActionModel(random_state=0, labels=("Jab",)).fit(cut_instances(clips))


def test_coefficients_recovered_from_a_noiseless_projected_decode(model):
    f = SegmentFitter(model, "Jab", n_fit=3, prior_weight=0.0, loss_scale=0.5, max_nfev=60)
    f._g = 0
    z_true = np.array([1.2, -0.8, 0.6])
    n = 12
    P3 = f.keypoints(f.full(z_true), n)
    xy = project(P3, 0.4, 30.0, np.array([80.0, 60.0]), f.elevation)
    r = f.fit(xy, rounds=3)
    assert np.abs(r["z"][:3] - z_true).max() < 0.15
    assert abs(r["yaw"] - 0.4) < 0.05 and abs(r["scale"] - 30.0) < 1.0


def test_linearisation_is_the_forward_difference_of_each_decode(model):
    f = SegmentFitter(model, "Jab", n_fit=5)
    f._g = 0
    zf = np.array([0.4, -0.3, 0.2, 0.1, -0.6])
    K0, J = f.linearisation(zf, 14)
    assert np.allclose(K0, f.keypoints(f.full(zf), 14), rtol=0, atol=1e-12)
    for i in range(5):
        z = zf.copy()
        z[i] += 0.05
        col = (f.keypoints(f.full(z), 14) - f.keypoints(f.full(zf), 14)).ravel() / 0.05
        assert np.allclose(J[:, i], col, rtol=0, atol=1e-9)


@pytest.mark.parametrize("prior_weight,loss_scale", [(0.0, 0.5), (0.01, 0.05), (1.0, 0.2)])
def test_residual_jacobian_is_the_derivative_of_the_residuals(model, prior_weight, loss_scale):
    # the fit's exact Jacobian against scipy's central differences, at a point far from the solution, with
    # missing keypoints and a residual at exactly zero (the robust loss's slope there is 1)
    from scipy.optimize._numdiff import approx_derivative

    f = SegmentFitter(model, "Jab", n_fit=4, prior_weight=prior_weight, loss_scale=loss_scale)
    f._g = 0
    lm = model.models_["Jab"]
    n = 10
    zc = np.array([0.5, -0.4, 0.3, 0.1])
    K0, J = f.linearisation(zc, n)
    xy = project(K0, 0.3, 30.0, np.array([80.0, 60.0]), f.elevation)
    xy += np.random.default_rng(2).normal(0.0, 3.0, xy.shape)
    xy[0, 0] = project(K0, 0.3, 30.0, np.array([80.0, 60.0]), f.elevation)[0, 0]
    vis = np.ones(xy.shape[:2], bool)
    vis[3, 2:6] = False
    xy[~vis] = np.nan
    L = np.linalg.inv(np.linalg.cholesky(lm.gmm_covariances[0]))
    resid, jac = f._residuals(K0, J, zc, np.where(vis[..., None], xy, 0.0), vis, 25.0, L, lm.gmm_means[0])
    for q in (np.concatenate([zc, [0.3, np.log(30.0), 80.0, 60.0]]),
              np.concatenate([zc + [0.7, -0.2, 0.1, 0.5], [-1.1, np.log(24.0), 70.0, 66.0]])):
        num = approx_derivative(resid, q, method="3-point", rel_step=1e-7)  # small steps: the loss is sharp
        assert jac(q).shape == num.shape
        assert np.allclose(jac(q), num, rtol=1e-5, atol=1e-5)


def test_missing_keypoints_are_ignored(model):
    f = SegmentFitter(model, "Jab", n_fit=3, prior_weight=0.0, loss_scale=0.5, max_nfev=60)
    f._g = 0
    z_true = np.array([1.0, 0.5, -0.5])
    P3 = f.keypoints(f.full(z_true), 12)
    xy = project(P3, -0.3, 30.0, np.array([80.0, 60.0]), f.elevation)
    rng = np.random.default_rng(1)
    xy[rng.random(xy.shape[:2]) < 0.2] = np.nan
    xy[rng.random(xy.shape[:2]) < 0.03] += 40.0  # outliers: the Cauchy loss holds
    r = f.fit(xy, rounds=3)
    assert np.abs(r["z"][:3] - z_true).max() < 0.3


def test_prior_pulls_toward_the_mean_as_its_weight_grows(model):
    z_true = np.array([2.0, -1.5, 1.0])
    base = SegmentFitter(model, "Jab", n_fit=3, prior_weight=0.0)
    base._g = 0
    xy = project(base.keypoints(base.full(z_true), 12), 0.0, 30.0, np.array([80.0, 60.0]), base.elevation)
    mu = model.models_["Jab"].gmm_means[0][:3]
    d = [np.linalg.norm(SegmentFitter(model, "Jab", n_fit=3, prior_weight=w).fit(xy)["z"][:3] - mu)
         for w in (0.0, 0.01, 1.0, 100.0)]
    assert all(a >= b - 1e-6 for a, b in zip(d, d[1:])), d
    assert d[-1] < 0.2 * d[0]


# ----------------------------------------------------------------------------- the style artifact
@pytest.fixture(scope="module")
def style(model, videos):
    from vidstyle.formats.framelabels import FrameLabels
    from vidstyle.style.artifact import Style
    from vidstyle.style.learn import style_params

    _, t1 = _take("Jab", 0)
    _, t2 = _take("Hook", 0)
    tracks = [FrameLabels(list(t.labels[::3]), ("Jab", "Hook", "Guard", "Step"), 20.0) for t in (t1, t2)]
    s = Style.from_tracks(tracks, style_params(n_init=1, n_iter=5, modes="1"))
    est = GlobalStyleEstimator().fit(videos["population"])
    s.action_style = fit_action_style(model, est, videos["wide_southpaw"], {"n_fit": 3}, max_segments=2)
    s.action_style.model = "model.npz"
    return s


def test_style_round_trip_with_action_style(style, tmp_path):
    from vidstyle.style.artifact import Style

    p = tmp_path / "style.json"
    style.save(p)
    doc = json.loads(p.read_text())
    assert doc["schema_version"] == 2 and doc["action_style"]["global"]["lead"] == "southpaw"
    back = Style.load(p)
    a, b = style.action_style, back.action_style
    assert b.global_style.lead == "southpaw"
    assert b.global_style.stance_width == pytest.approx(a.global_style.stance_width, abs=1e-6)
    assert np.allclose(b.coefficients["Jab"], a.coefficients["Jab"])
    assert b.counts == a.counts


def test_schema_1_file_still_loads(style):
    from vidstyle.style.artifact import Style

    doc = style.to_dict()
    doc["schema_version"] = 1
    doc.pop("action_style")
    s = Style.from_dict(doc)
    assert s.action_style is None and s.actions == style.actions


def _mutations(doc, rng):
    a = doc["action_style"]
    yield lambda d: d["action_style"]["global"].__setitem__("lead", "lefty")
    yield lambda d: d["action_style"]["global"].__setitem__("stance_width", "wide")
    yield lambda d: d["action_style"].__setitem__("labels", [])
    lab = next(iter(a["labels"]))
    yield lambda d: d["action_style"]["labels"][lab].__setitem__("coefficients", [])
    yield lambda d: d["action_style"]["labels"][lab].__setitem__("spread", [1.0])
    yield lambda d: d["action_style"]["labels"][lab].__setitem__("spread", [-1.0] * len(a["labels"][lab]["coefficients"]))
    yield lambda d: d["action_style"]["labels"][lab].__setitem__("segments", 0)
    yield lambda d: d["action_style"]["labels"][lab].__setitem__("coefficients", ["x"] * len(a["labels"][lab]["coefficients"]))
    yield lambda d: d["action_style"].pop("global")
    yield lambda d: d.__setitem__("schema_version", 3)
    for _ in range(20):  # random keys replaced by junk
        path = [k for k in ("model", "params", "global", "labels")]
        k = path[int(rng.integers(len(path)))]
        junk = [None, 3, "s", [1, 2], {"a": 1}][int(rng.integers(5))]
        if k == "model" and (junk is None or isinstance(junk, str)):
            continue
        if k == "params" and isinstance(junk, dict):
            continue
        yield lambda d, k=k, junk=junk: d["action_style"].__setitem__(k, junk)


def test_fuzzed_action_style_raises_format_error(style):
    from vidstyle.fileio import json_default
    from vidstyle.formats.style import parse_style

    doc = json.loads(json.dumps(style.to_dict(), default=json_default))
    parse_style(doc, "ok.json")
    rng = np.random.default_rng(0)
    for mutate in _mutations(doc, rng):
        d = copy.deepcopy(doc)
        mutate(d)
        with pytest.raises(FormatError) as e:
            parse_style(d, "bad.json")
        assert "bad.json" in str(e.value)


def test_realise_keeps_a_southpaw_southpaw(style, model):
    from vidstyle.mocap.keypoints import keypoint_positions

    m = style.action_style.realise(model, "Jab", 20)
    pts = keypoint_positions(m)
    # the jab: the right wrist (a southpaw's lead) travels further than the left
    travel = [np.linalg.norm(pts[:, w] - pts[0, w], axis=-1).max() for w in (7, 8)]
    assert travel[1] > travel[0]


# ----------------------------------------------------------------------------- the CLI
def _main(args):
    from vidstyle.cli import main

    return main(args)


def test_learn_style_bad_input_exits_2(tmp_path, model, capsys):
    from vidstyle.demo.dataset import label_document
    from vidstyle.formats.labels import write_labels

    labs = []
    for a in ("Jab", "Hook"):
        _, take = _take(a, 0)
        labs.append(tmp_path / f"p00_{a.lower()}_front.json")
        write_labels(labs[-1], label_document(list(take.labels[::3]), 20.0, take.chain,
                                              video=f"videos/p00_{a.lower()}_front.mp4", performer="p00"))
    lab = labs[0]
    (tmp_path / "p00_hook_front.poses.json").write_text("{}")
    out = tmp_path / "style.json"
    # --poses-dir without --action-model
    assert _main(["learn-style", str(lab), "--out", str(out), "--poses-dir", str(tmp_path)]) == 2
    # a missing pose file
    mp = tmp_path / "m.npz"
    model.save(mp)
    capsys.readouterr()
    assert _main(["learn-style", *map(str, labs), "--out", str(out), "--poses-dir", str(tmp_path), "--action-model", str(mp),
                  "--modes", "1", "--n-init", "1"]) == 2
    err = capsys.readouterr().err
    assert "pose file not found" in err and err.count("error:") == 1
    # a damaged action model
    (tmp_path / "p00_jab_front.poses.json").write_text("{}")
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    assert _main(["learn-style", *map(str, labs), "--out", str(out), "--poses-dir", str(tmp_path), "--action-model", str(bad),
                  "--modes", "1", "--n-init", "1"]) == 2
    assert "bad.npz" in capsys.readouterr().err
    # a damaged pose file
    assert _main(["learn-style", *map(str, labs), "--out", str(out), "--poses-dir", str(tmp_path), "--action-model", str(mp),
                  "--modes", "1", "--n-init", "1"]) == 2
    assert "poses.json" in capsys.readouterr().err
    assert not out.exists()


def test_sample_action_with_style(style, model, tmp_path, capsys):
    from vidstyle.mocap import read_bvh

    mp, sp = tmp_path / "m.npz", tmp_path / "style.json"
    model.save(mp)
    style.save(sp)
    assert _main(["sample-action", str(mp), "--label", "Jab", "-n", "2", "--seed", "0", "--style", str(sp),
                  "--out-dir", str(tmp_path / "s")]) == 0
    m = read_bvh(tmp_path / "s" / "Jab_000.bvh")
    assert m.n_frames > 5
    plain = tmp_path / "plain.json"
    doc = style.to_dict()
    doc["action_style"] = None
    from vidstyle.style.artifact import Style

    Style.from_dict(doc).save(plain)
    assert _main(["sample-action", str(mp), "--label", "Jab", "--style", str(plain), "--out-dir", str(tmp_path / "t")]) == 2
    assert "no action-level style" in capsys.readouterr().err


def test_learn_style_with_poses_end_to_end(tmp_path, model):
    """learn-style LABELS --poses-dir --action-model: the style file gains the action-level part, and a
    southpaw's jabs come out southpaw."""
    from vidstyle.demo.dataset import label_document
    from vidstyle.formats.labels import write_labels
    from vidstyle.formats.poses import PoseFrame, Poses, write_poses
    from vidstyle.style.artifact import Style

    labs = []
    for a in ("Jab", "Hook"):
        _, take = _take(a, 0, lead="southpaw")
        xy, labels, _ = _video(take, "front")
        stem = f"p00_{a.lower()}_front"
        labs.append(tmp_path / f"{stem}.json")
        write_labels(labs[-1], label_document(labels, 20.0, take.chain, video=f"videos/{stem}.mp4", performer="p00",
                                              view="front"))
        pts = np.concatenate([xy, np.ones(xy.shape[:2] + (1,))], axis=-1)
        write_poses(tmp_path / f"{stem}.poses.json",
                    Poses(f"videos/{stem}.mp4", "ps", [PoseFrame(i, "front", p) for i, p in enumerate(pts)]))
    mp = tmp_path / "m.npz"
    model.save(mp)
    out = tmp_path / "style.json"
    assert _main(["learn-style", *map(str, labs), "--out", str(out), "--poses-dir", str(tmp_path),
                  "--action-model", str(mp), "--modes", "1", "--n-init", "1"]) == 0
    s = Style.load(out)
    assert s.action_style is not None and "Jab" in s.action_style.coefficients
    assert s.action_style.global_style.lead == "southpaw"  # labelled rule: no population given


def test_learn_action_style_reads_the_labels_confidence_and_leaves_doubtful_runs_out(tmp_path, model):
    """A recognised-label file's per-frame confidence reaches the tempo: a spurious low-confidence Jab run
    added to a take's labels changes the tempo only when the file carries no confidence."""
    from vidstyle.actionmodel.stylefit import GlobalStyleEstimator, label_runs, learn_action_style
    from vidstyle.demo.dataset import label_document
    from vidstyle.formats.labels import write_labels
    from vidstyle.formats.poses import PoseFrame, Poses, write_poses

    _, take = _take("Jab", 1, lead="orthodox")
    xy, labels, _ = _video(take, "front")
    labels = list(labels)
    true_jabs = [e - s for lab, s, e in label_runs(labels) if lab == "Jab"]
    guard = max((r for r in label_runs(labels) if r[0] == "Guard"), key=lambda r: r[2] - r[1])
    fake = range(guard[1] + 1, guard[1] + 3)  # a 2-frame "Jab" inside the longest guard pause
    for i in fake:
        labels[i] = "Jab"
    conf = [0.1 if i in fake else 0.9 for i in range(len(labels))]
    pts = np.concatenate([xy, np.ones(xy.shape[:2] + (1,))], axis=-1)
    write_poses(tmp_path / "v.poses.json", Poses("videos/v.mp4", "ps", [PoseFrame(i, "front", p) for i, p in enumerate(pts)]))
    mp = tmp_path / "m.npz"
    model.save(mp)
    est = GlobalStyleEstimator.from_model(model, 20.0, run_timing="labels")  # the runs' lengths, to see the fake one
    tempo = {}
    for name, extra in (("recognised", {"confidence": conf}), ("true", {})):
        doc = label_document(labels, 20.0, take.chain, video="videos/v.mp4", performer="p01", view="front")
        f = tmp_path / f"{name}.json"
        write_labels(f, {**doc, **extra})
        tempo[name] = learn_action_style([f], tmp_path, mp, est).global_style.tempo["Jab"]
    ref = est.durations_["Jab"]
    assert len(true_jabs) >= 2 and np.median(true_jabs + [2]) != np.median(true_jabs)  # the fake run would show
    assert tempo["recognised"] == pytest.approx(float(np.median(true_jabs)) / ref)
    assert tempo["true"] == pytest.approx(float(np.median(true_jabs + [2])) / ref)


def test_without_a_population_recognised_runs_are_timed_against_the_models_mean_instance(model):
    """``from_model`` times recognised runs by their motion against the action model's own mean jab: runs the
    recognizer cut a frame short at each end measure (nearly) what the true runs do; their own lengths do not."""
    from vidstyle.actionmodel.stylefit import GlobalStyleEstimator, label_runs, model_videos

    assert {v[1][len(v[1]) // 2] for v in model_videos(model, 20.0)} == {"Jab"}
    _, take = _take("Jab", 1, lead="orthodox")  # a performer the model did not see
    xy, labels, view = _video(take, "front")
    labels = list(labels)
    cut = list(labels)
    for lab, s, e in label_runs(labels):
        if lab == "Jab":
            cut[s] = cut[e - 1] = "Guard"
    conf = np.full(len(cut), 0.9)
    est = GlobalStyleEstimator.from_model(model, 20.0, min_run_confidence=0.0, max_run_factor=None, min_run_factor=None)
    assert est.motion_ratio_["Jab"] > 1.0
    true = est.estimate([(xy, labels, view)]).tempo["Jab"]  # true labels: the runs' own lengths
    timed = est.estimate([(xy, cut, view, conf)]).tempo["Jab"]
    runs = est.set_params(run_timing="labels").estimate([(xy, cut, view, conf)]).tempo["Jab"]
    assert runs < 0.9 * true  # two frames of ~10 lost
    assert abs(timed - true) < 0.5 * abs(runs - true)


def test_restyle_motion_replaces_actions_only(style, model):
    """synthesize --style's core: action runs become the performer's way (a southpaw here), other frames stay."""
    from vidstyle.actionmodel.stylefit import restyle_motion
    from vidstyle.mocap.keypoints import keypoint_positions

    _, take = _take("Jab", 1, lead="orthodox")  # an orthodox performer's take stands in for a graph walk
    m = take.motion
    labels = list(take.labels)
    out, runs = restyle_motion(m, labels, style.action_style, model)
    assert out.n_frames == m.n_frames and runs and all(lab == "Jab" for lab, _, _ in runs)
    inside = np.zeros(m.n_frames, bool)
    for _, s, e in runs:
        inside[s:e] = True
    assert np.allclose(out.rotations[~inside], m.rotations[~inside])
    assert not np.allclose(out.rotations[inside], m.rotations[inside])
    # the replaced jabs are thrown with the right hand (southpaw), the originals with the left
    a, b = keypoint_positions(m), keypoint_positions(out)
    _, s, e = runs[0]
    travel = lambda p, w: np.linalg.norm(p[s:e, w] - p[s, w], axis=-1).max()
    assert travel(a, 7) > travel(a, 8) and travel(b, 8) > travel(b, 7)


def test_synthesize_style_bad_input_exits_2(tmp_path, capsys):
    assert _main(["synthesize", "--graph", str(tmp_path / "g.npz"), "--sequence", str(tmp_path / "s.json"),
                  "--out", str(tmp_path / "o.bvh"), "--style", str(tmp_path / "style.json")]) == 2
    assert "--action-model" in capsys.readouterr().err


def test_fit_actions_mirror_makes_an_orthodox_model(tmp_path):
    """fit-actions --mirror p01: a southpaw's jabs enter the model mirrored (left hand leads in its mean)."""
    from vidstyle.demo.dataset import label_document
    from vidstyle.formats.labels import write_labels
    from vidstyle.mocap import write_bvh
    from vidstyle.mocap.keypoints import keypoint_positions

    for name, lead in (("p00_jab", "orthodox"), ("p01_jab", "southpaw")):
        _, take = _take("Jab", 0, lead=lead)
        write_bvh(take.motion, tmp_path / f"{name}.bvh")
        write_labels(tmp_path / f"{name}.labels.json", label_document(list(take.labels), 60.0, take.chain, bvh=f"{name}.bvh"))
    out = tmp_path / "m.npz"
    assert _main(["fit-actions", str(tmp_path / "p00_jab.bvh"), str(tmp_path / "p01_jab.bvh"), "--mirror", "p01",
                  "--only", "Jab", "--out", str(out)]) == 0
    m = ActionModel.load(out)
    pts = keypoint_positions(m.decode(m.models_["Jab"].gmm_means[0], "Jab"))
    travel = [np.linalg.norm(pts[:, w] - pts[0, w], axis=-1).max() for w in (7, 8)]
    assert travel[0] > 1.5 * travel[1]


@pytest.fixture(scope="module")
def action_style_run(tmp_path_factory):
    """A small demo dataset (4 performers: one per recognition set; split seed 0), its styles, pose files
    that hold each video's true 2D and recognised-label files that hold the true labels."""
    import shutil

    from vidstyle.demo.dataset import DatasetParams, make_dataset
    from vidstyle.evaluation.poserecognition import true_keypoints
    from vidstyle.formats.dataset import read_dataset
    from vidstyle.formats.poses import PoseFrame, Poses, write_poses

    root = tmp_path_factory.mktemp("action_style_run")
    ds_dir = root / "dataset"
    make_dataset(ds_dir, DatasetParams.small(performances=1, performance_seconds=20.0), jobs=2)
    ds = read_dataset(ds_dir / "dataset.json")
    (root / "poses").mkdir()
    (root / "recognized").mkdir()
    for v in json.loads((ds_dir / "dataset.json").read_text())["videos"]:
        xy = true_keypoints(ds, v["id"])
        pts = np.concatenate([xy, np.ones(xy.shape[:2] + (1,))], axis=-1)
        write_poses(root / "poses" / f"{v['id']}.poses.json",
                    Poses(v["video"], "ps", [PoseFrame(i, v["view"], p) for i, p in enumerate(pts)]))
        shutil.copy(ds_dir / v["labels"], root / "recognized" / f"{v['id']}.json")
    assert _main(["learn-style", "--dataset", str(ds_dir), "--out-dir", str(root / "style"), "--modes", "1",
                  "--n-init", "1", "--jobs", "1"]) == 0
    return root


@pytest.mark.slow
def test_evaluate_action_style_end_to_end(action_style_run, tmp_path):
    """vidstyle evaluate action-style: pose files that hold the true 2D (to the file's 0.001 px) with the true
    labels fit what the true input fits (the pose-file path reads the same tracks, frame for frame); the metrics file is valid and the headline
    has the action_style figures; the written style carries the action-level part and names the model
    written beside it, which loads; the figure is a PNG."""
    from vidstyle.actionmodel import ActionModel
    from vidstyle.formats.metrics import ACTION_STYLE, read_metrics
    from vidstyle.report.build import headline_metrics
    from vidstyle.style.artifact import Style

    run = action_style_run
    out = tmp_path / "run" / "metrics" / "action_style.json"
    od = tmp_path / "run" / "action_style"
    assert _main(["evaluate", "action-style", "--dataset", str(run / "dataset"), "--seed", "0",
                  "--poses-dir", str(run / "poses"), "--labels-dir", str(run / "recognized"),
                  "--style-dir", str(run / "style"), "--out-dir", str(od), "--out", str(out), "--jobs", "1"]) == 0
    doc = read_metrics(out, ACTION_STYLE).doc
    t, e = doc["rows"]["true"], doc["rows"]["estimated"]
    assert [r["performer"] for r in t] == [r["performer"] for r in e] == doc["splits"]["0"]["T"]
    for a, b in zip(t, e):
        assert a["lead"] == b["lead"] == a["lead_true"]
        assert a["guard_height"] == pytest.approx(b["guard_height"], rel=1e-2)
        assert a["stance_width"] == pytest.approx(b["stance_width"], rel=1e-3)
        assert a["segments"] == b["segments"]
        for label in a["labels"]:
            assert a["labels"][label]["fitted_mean_mm"] == pytest.approx(b["labels"][label]["fitted_mean_mm"], rel=2e-2)
            assert a["labels"][label]["fitted_mean_mm"] < a["labels"][label]["unfitted_mean_true_lead_mm"] * 5
    assert doc["action_style"]["lead_accuracy"] == 1.0 and doc["action_style"]["input"] == "true"
    assert doc["styles_input"] == "estimated"
    head = headline_metrics(tmp_path / "run")
    assert head["action_style"]["lead_accuracy"] == 1.0
    assert head["action_style"]["estimated_lead_accuracy"] == 1.0
    p = doc["splits"]["0"]["T"][0]
    s = Style.load(od / f"{p}.json")
    assert s.action_style is not None and s.action_style.model == str(od / "actions.npz")
    s.action_style.check_model(ActionModel.load(od / "actions.npz"))
    assert (od / "Jab.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("args, needle", [
    (["--inputs", "estimated"], "--poses-dir"),
    (["--inputs", "sideways"], "--inputs"),
    (["--inputs", "true", "--style-dir", "x"], "--out-dir"),
])
def test_evaluate_action_style_bad_options_exit_2(tmp_path, capsys, args, needle):
    (tmp_path / "dataset").mkdir()
    (tmp_path / "dataset" / "dataset.json").write_text("{}")
    assert _main(["evaluate", "action-style", "--dataset", str(tmp_path / "dataset"), *args,
                  "--out", str(tmp_path / "m.json")]) == 2
    err = capsys.readouterr().err
    assert needle in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "m.json").exists()


@pytest.mark.slow
def test_evaluate_action_style_unknown_label_exits_2_before_fitting(action_style_run, tmp_path, capsys):
    out = tmp_path / "m.json"
    assert _main(["evaluate", "action-style", "--dataset", str(action_style_run / "dataset"), "--label", "Headbutt",
                  "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "Headbutt" in err and len(err.strip().splitlines()) == 1 and not out.exists()


def test_evaluate_action_style_missing_dataset_exits_2(tmp_path, capsys):
    assert _main(["evaluate", "action-style", "--dataset", str(tmp_path / "nope"), "--out", str(tmp_path / "m.json")]) == 2
    assert "dataset.json" in capsys.readouterr().err
    assert not (tmp_path / "m.json").exists()


def test_dtw_mpjpe_is_zero_for_a_time_warped_copy_and_the_offset_for_a_shifted_one():
    from vidstyle.evaluation.actionstyle import dtw_mpjpe

    rng = np.random.default_rng(0)
    seq = np.cumsum(rng.normal(size=(30, 4, 3)), axis=0)  # a random walk: no two frames alike
    warped = np.repeat(seq, [2 if i % 3 == 0 else 1 for i in range(30)], axis=0)  # slower in places
    assert dtw_mpjpe(warped, seq) == pytest.approx(0.0, abs=1e-12)
    # every joint moved by the same 3-4-0 vector: the aligned frames are the same, each 5 apart
    assert dtw_mpjpe(seq + np.array([3.0, 4.0, 0.0]), seq) == pytest.approx(5.0)


# ----------------------------------------------------------------------------- timing runs from the motion
def _bump(n_frames: int, t0: float, dur: float) -> np.ndarray:
    """sin^2 rise and fall over [t0, t0 + dur] (sub-frame start and length), sampled at whole frames."""
    t = np.arange(n_frames, dtype=np.float64)
    u = np.clip((t - t0) / dur, 0.0, 1.0)
    return np.sin(np.pi * u) ** 2


def test_motion_width_is_the_analytic_width_whatever_the_runs_ends():
    from vidstyle.actionmodel.stylefit import motion_width

    for dur, t0, level in ((12.0, 20.3, 0.3), (17.6, 15.8, 0.2), (9.4, 30.5, 0.5)):
        d = 2.0 * _bump(80, t0, dur)
        # sin^2(pi u) = level at u = asin(sqrt(level)) / pi, so the width is dur * (1 - 2u)
        expected = dur * (1.0 - 2.0 * np.arcsin(np.sqrt(level)) / np.pi)
        s, e = int(round(t0)), int(round(t0 + dur))
        for ds, de in ((0, 0), (2, -2), (-2, 1), (3, 0)):  # a recognizer's ends, a few frames off
            w = motion_width(d, s + ds, e + de, level)
            assert w == pytest.approx(expected, abs=0.12 * dur / 10)
    # a side that never falls below the level near the run, or meets a missing frame: not measurable
    d = 2.0 * _bump(60, 10.0, 12.0)
    d[:16] = 2.0
    assert np.isnan(motion_width(d, 10, 22, 0.3))
    d = 2.0 * _bump(60, 10.0, 12.0)
    d[20] = np.nan
    assert np.isnan(motion_width(d, 10, 22, 0.3))


def _moving(runs, dur_of=None, amp=0.8):
    """(xy, labels, view) of a still figure (torso 1) whose lead wrist swings out and back (a sin^2 bump)
    over each ``Jab`` run, the swing lasting ``dur_of(run length)`` frames centred on the run."""
    labels = [lab for lab, n in runs for _ in range(n)]
    F = len(labels)
    base = np.zeros((15, 2))
    base[1] = (0.0, -1.0)  # neck above the pelvis (image y down)
    base[0] = (0.0, -1.4)
    for k, (x, y) in {3: (-0.3, -1.0), 4: (0.3, -1.0), 5: (-0.4, -0.7), 6: (0.4, -0.7), 7: (-0.3, -0.9),
                      8: (0.3, -0.9), 9: (-0.15, 0.0), 10: (0.15, 0.0), 11: (-0.2, 0.5), 12: (0.2, 0.5),
                      13: (-0.2, 1.0), 14: (0.2, 1.0)}.items():
        base[k] = (x, y)
    xy = np.repeat(base[None], F, axis=0)
    t = 0
    for lab, n in runs:
        if lab == "Jab":
            dur = n if dur_of is None else dur_of(n)
            xy[:, 7, 0] -= amp * _bump(F, t + 0.5 * (n - dur), dur)
        t += n
    return xy, labels, "front"


def test_recognised_runs_are_timed_by_their_motion_not_by_their_ends():
    pop = [_moving([("Guard", 10), ("Jab", 15), ("Guard", 10), ("Jab", 15), ("Guard", 10)])] * 2
    est = GlobalStyleEstimator(run_timing="motion", motion_level=0.3, motion_filter=3, min_run_confidence=0.0,
                               max_run_factor=None).fit(pop)
    assert est.durations_ == {"Jab": 15.0} and est.motion_ratio_["Jab"] > 1.0
    assert est.motion_weights_["Jab"][7] == est.motion_weights_["Jab"][8] > 0  # left and right weigh alike
    # the performer's jabs last 18 frames (tempo 1.2); the recognizer cut each run two frames short at both ends
    xy, labels, view = _moving([("Guard", 10), ("Jab", 18), ("Guard", 10), ("Jab", 18), ("Guard", 10)])
    cut = ["Guard" if lab == "Jab" and (labels[max(0, i - 2)] != "Jab" or labels[min(len(labels) - 1, i + 2)] != "Jab")
           else lab for i, lab in enumerate(labels)]
    assert cut.count("Jab") == 2 * 14
    conf = np.full(len(cut), 0.9)
    assert est.estimate([(xy, cut, view, conf)]).tempo["Jab"] == pytest.approx(1.2, abs=0.02)
    # the run's own length says 14 / 15; true labels (no confidence) keep their runs' lengths too
    runs_only = est.set_params(run_timing="labels")
    runs_only.fit(pop)
    assert runs_only.estimate([(xy, cut, view, conf)]).tempo["Jab"] == pytest.approx(14 / 15)
    est.set_params(run_timing="motion").fit(pop)
    assert est.estimate([(xy, cut, view)]).tempo["Jab"] == pytest.approx(14 / 15)
    with pytest.raises(ParameterError, match="run_timing"):
        GlobalStyleEstimator(run_timing="beats").fit(pop)
    with pytest.raises(ParameterError, match="motion_level"):
        GlobalStyleEstimator(motion_level=1.0).fit(pop)


def test_recognised_runs_much_longer_than_the_populations_do_not_measure():
    pop = [_labelled([("Guard", 5), ("Hook", 20), ("Guard", 4)])]
    est = GlobalStyleEstimator(run_timing="labels", min_run_confidence=0.0, max_run_factor=1.8).fit(pop)
    # two hooks joined into one 40-frame run (2x the population's 20) and a real 22-frame hook
    perf = _recognised([("Guard", 3, 0.9), ("Hook", 40, 0.8), ("Guard", 3, 0.9), ("Hook", 22, 0.8), ("Guard", 3, 0.9)])
    assert est.estimate([perf]).tempo == pytest.approx({"Hook": 22 / 20})
    assert est.set_params(max_run_factor=None).estimate([perf]).tempo == pytest.approx({"Hook": 31 / 20})
    with pytest.raises(ParameterError, match="max_run_factor"):
        est.set_params(max_run_factor=0.5).estimate([perf])
    # a performer far slower than the population: every hook is out of bounds, so all of them count
    slow = _recognised([("Guard", 3, 0.9), ("Hook", 40, 0.8), ("Guard", 3, 0.9), ("Hook", 44, 0.8), ("Guard", 3, 0.9)])
    assert est.set_params(max_run_factor=1.8).estimate([slow]).tempo == pytest.approx({"Hook": 42 / 20})
    # and far faster, against the floor
    fast = _recognised([("Guard", 3, 0.9), ("Hook", 10, 0.8), ("Guard", 3, 0.9), ("Hook", 12, 0.8), ("Guard", 3, 0.9)])
    assert est.set_params(min_run_factor=0.7).estimate([fast]).tempo == pytest.approx({"Hook": 11 / 20})
