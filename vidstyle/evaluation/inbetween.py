"""In-betweening on held-out mocap windows, scored like the LAFAN1 benchmark (Harvey et al. 2020,
``ubisoft-laforge-animation-dataset``, ``lafan1/benchmarks.py``, ``extract.py``, ``utils.py``).

Windows (:func:`windows`): clips at 30 fps, sliding windows of ``WINDOW`` = 65 frames every ``OFFSET`` = 40
(the test set; the training statistics use 50 / 20, as ``get_train_stats``). Each window is moved so
its root's mean floor position (x, z) over the window is the origin, then turned about the vertical so
the character faces one direction at the last context frame (``N_PAST - 1``; LAFAN1's ``rotate_at_frame``
uses its root's forward axis, here the hips/shoulders facing of :meth:`vidstyle.mocap.Motion.facing_angles`).

For a gap of ``n`` frames the input is the context: frame ``N_PAST - 1`` is the start key, frame
``N_PAST + n`` the end key (the first future frame); the method fills frames ``N_PAST .. N_PAST + n - 1``,
which are scored:

* **L2Q**: global joint quaternions of the gap frames (forward kinematics), made sign-continuous over
  time (each quaternion in the hemisphere of the frame before, starting from the ground truth's start key
  for both), then per frame the L2 norm over all joints' 4 components of (prediction - truth), averaged
  over frames and windows: ``mean(sqrt(sum_{j,c} (q - q*)^2))``;
* **L2P**: global joint positions of the gap frames, each coordinate normalised by the training set's mean
  and standard deviation of that coordinate (over training windows and their frames, after the same
  centring and turning), then per frame the L2 norm over all joints' 3 coordinates, averaged:
  ``mean(sqrt(sum_{j,c} ((p - mu)/sigma - (p* - mu)/sigma)^2))``.

These are LAFAN1's definitions; the numbers are not comparable to LAFAN1's (other data, skeleton, joints).
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ..inbetween import defaults as D
from ..mocap import Motion, Skeleton, forward_kinematics
from ..mocap.quat import continuous_quaternions

log = logging.getLogger(__name__)

N_PAST = 10
N_FUTURE = 10
GAPS = D.EVAL_GAPS
WINDOW = 65
OFFSET = 40
TRAIN_WINDOW = 50
TRAIN_OFFSET = 20
FPS = 30.0
#: CMU subjects by role (each in one role only): the library the methods learn from, the validation subject
#: parameters are chosen on, the test subjects scored once (:mod:`vidstyle.inbetween.defaults`)
SPLIT = D.EVAL_SPLIT


# ---------------------------------------------------------------------------------------------- metrics
def global_pose(skeleton: Skeleton, rotations: np.ndarray, roots: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Global joint quaternions (F, J, 4) (x, y, z, w) and positions (F, J, 3) of local frames."""
    m = Motion(skeleton, rotations, None, FPS, root_positions=roots)
    pos, mats = forward_kinematics(m)
    F, J = rotations.shape[:2]
    q = Rotation.from_matrix(mats.reshape(-1, 3, 3)).as_quat().reshape(F, J, 4)
    return q, pos


def _shared_skeleton(wins: list[Motion]) -> Skeleton | None:
    """The one skeleton object every window of ``wins`` has, else None: their frames can then go through
    one call of the per-frame kinematics, with the same values as window by window."""
    return wins[0].skeleton if wins and all(w.skeleton is wins[0].skeleton for w in wins) else None


def _global_poses(wins: list[Motion], rotations: list[np.ndarray], roots: list[np.ndarray]):
    """:func:`global_pose` of each (rotations, roots) pair (on its window's skeleton), in order; pairs whose
    windows share one skeleton go through one call (:func:`_shared_skeleton`)."""
    sk = _shared_skeleton(wins)
    if sk is not None:
        q, pos = global_pose(sk, np.concatenate(rotations), np.concatenate(roots))
        cuts = np.cumsum([len(r) for r in rotations])[:-1]
        return list(zip(np.split(q, cuts), np.split(pos, cuts)))
    return [global_pose(w.skeleton, r, p) for w, r, p in zip(wins, rotations, roots)]


def sign_continuous(q: np.ndarray, anchor: np.ndarray | None = None) -> np.ndarray:
    """(F, J, 4) quaternions with each in the hemisphere of the previous frame's; with ``anchor`` (J, 4)
    the chain starts from it (the anchor itself is not returned)."""
    if anchor is None:
        return continuous_quaternions(q)
    return continuous_quaternions(np.concatenate([anchor[None], q]))[1:]


def l2q(pred: np.ndarray, truth: np.ndarray) -> float:
    """LAFAN1 L2Q of sign-fixed global quaternions ``(..., F, J, 4)``: mean over windows and frames of the
    L2 norm over joints and components."""
    return float(np.mean(np.sqrt(np.sum((pred - truth) ** 2, axis=(-2, -1)))))


def l2p(pred: np.ndarray, truth: np.ndarray, mean: np.ndarray, std: np.ndarray) -> float:
    """LAFAN1 L2P of global positions ``(..., F, J, 3)`` normalised per coordinate by ``mean`` and ``std``
    (J, 3): mean over windows and frames of the L2 norm over joints and coordinates."""
    a = (pred - mean) / std
    b = (truth - mean) / std
    return float(np.mean(np.sqrt(np.sum((a - b) ** 2, axis=(-2, -1)))))


# ---------------------------------------------------------------------------------------------- data
def load_subject_motions(folder: str | Path, subjects, skeleton: Skeleton | None = None,
                         fps: float = FPS) -> tuple[list[Motion], list[str], Skeleton]:
    """The CMU clips of ``subjects`` (file prefix ``NN_``) in ``folder``: T-pose frame dropped, resampled
    to ``fps``, retargeted onto ``skeleton`` (default: the first clip's)."""
    from ..mocap import read_bvh
    from ..mocap.retarget import retarget
    from ..motiongraph.graph import has_tpose_first_frame

    files = sorted(p for s in subjects for p in Path(folder).glob(f"{s}_*.bvh"))
    out, names = [], []
    for f in files:
        m = read_bvh(f)
        if has_tpose_first_frame(m):
            m = m[1:]
        if skeleton is None:
            skeleton = m.skeleton
        m, _ = retarget(m, skeleton, str(f))
        out.append(m.resample(fps))
        names.append(f.stem)
    return out, names, skeleton


def windows(motion: Motion, window: int = WINDOW, offset: int = OFFSET, n_past: int = N_PAST) -> list[Motion]:
    """LAFAN1's sliding windows (``i + window < frames``), centred on the window's mean root (x, z) and
    turned to face +Z at frame ``n_past - 1``."""
    out = []
    i = 0
    while i + window < motion.n_frames:
        w = motion[i : i + window]
        mean = w.root_positions[:, [0, 2]].mean(axis=0)
        w = w.translate(np.array([-mean[0], 0.0, -mean[1]]))
        # the facing of that one frame (per-frame kinematics: the same angle as the whole window's)
        w = w.rotate_about_vertical(-float(w[n_past - 1 : n_past].facing_angles()[0]))
        out.append(w)
        i += offset
    return out


def position_stats(wins: list[Motion]) -> tuple[np.ndarray, np.ndarray]:
    """(J, 3) mean and standard deviation of global joint positions over the windows' frames."""
    # positions only (no quaternions); one forward-kinematics call when the windows share a skeleton
    sk = _shared_skeleton(wins)
    if sk is not None:
        m = Motion(sk, np.concatenate([w.rotations for w in wins]), None, FPS,
                   root_positions=np.concatenate([w.root_positions for w in wins]))
        pos = forward_kinematics(m, return_matrices=False)[0]
    else:
        pos = np.concatenate([global_pose(w.skeleton, w.rotations, w.root_positions)[1] for w in wins])
    std = pos.std(axis=0)
    return pos.mean(axis=0), np.where(std > 1e-9, std, 1.0)


# ---------------------------------------------------------------------------------------------- runs
def score_methods(methods: dict, wins: list[Motion], gaps=GAPS, mean=None, std=None, n_past: int = N_PAST,
                  per_window: bool = False) -> dict:
    """L2P, L2Q and milliseconds per request of each method (``name -> fitted in-betweener`` or ``None``
    for slerp) on every window and gap (``per_window``: also each window's L2P and L2Q)."""
    from ..inbetween.keyframes import inbetween_pair
    from ..inbetween.poses import Keypose

    res: dict = {name: {} for name in methods}
    for n in gaps:
        e = n_past + n
        truth_q, truth_p, anchors = [], [], []
        for gq, gp in _global_poses(wins, [w.rotations[: e + 1] for w in wins], [w.root_positions[: e + 1] for w in wins]):
            gq = sign_continuous(gq)
            truth_q.append(gq[n_past:e])
            truth_p.append(gp[n_past:e])
            anchors.append(gq[n_past - 1])
        truth_q, truth_p = np.stack(truth_q), np.stack(truth_p)
        for name, model in methods.items():
            rots, roots, secs = [], [], []
            for w in wins:
                r, p = w.rotations, w.root_positions
                start = Keypose(r[n_past - 1], p[n_past - 1], Keypose(r[n_past - 2], p[n_past - 2]))
                end = Keypose(r[e], p[e], following=Keypose(r[e + 1], p[e + 1]) if e + 1 < len(r) else None)
                t0 = time.perf_counter()
                rot, root = inbetween_pair(model, start, end, n + 2, free_end=False)
                secs.append(time.perf_counter() - t0)
                rots.append(rot[1:-1])
                roots.append(root[1:-1])
            pq, pp = [], []
            for (gq, gp), anchor in zip(_global_poses(wins, rots, roots), anchors):
                pq.append(sign_continuous(gq, anchor))
                pp.append(gp)
            pq, pp = np.stack(pq), np.stack(pp)
            res[name][str(n)] = {"l2p": l2p(pp, truth_p, mean, std), "l2q": l2q(pq, truth_q),
                                 "ms_per_request": 1000.0 * float(np.median(secs)), "windows": len(wins)}
            if per_window:
                res[name][str(n)]["per_window_l2p"] = [l2p(a, b, mean, std) for a, b in zip(pp, truth_p)]
                res[name][str(n)]["per_window_l2q"] = [l2q(a, b) for a, b in zip(pq, truth_q)]
            log.info("gap %d %s: L2P %.3f L2Q %.3f (%.1f ms)", n, name, res[name][str(n)]["l2p"],
                     res[name][str(n)]["l2q"], res[name][str(n)]["ms_per_request"])
    return res


def library_graph(folder: str | Path, subjects, cache: str | Path | None = None, seed: int = 0):
    """The motion graph of the library subjects' clips (30 fps; CMU ``clips.csv`` labels), from ``cache``
    when that file exists (written there otherwise)."""
    from ..motiongraph import MotionGraph, build_graph

    if cache is not None and Path(cache).is_file():
        return MotionGraph.load(cache)
    files = sorted(str(p) for s in subjects for p in Path(folder).glob(f"{s}_*.bvh"))
    labels = [str(Path(folder) / "clips.csv")] if (Path(folder) / "clips.csv").is_file() else []
    graph = build_graph(files, labels, fps=FPS, random_state=seed)
    if cache is not None:
        Path(cache).parent.mkdir(parents=True, exist_ok=True)
        graph.save(cache)
    return graph


def prepare(folder: str | Path, library_subjects, eval_subjects, seed: int = 0, graph_cache=None) -> dict:
    """What every scoring run needs: the library ``graph``, the evaluation windows ``wins`` (and their clip
    ``names``) and the training position statistics ``mean``, ``std``."""
    graph = library_graph(folder, library_subjects, graph_cache, seed)
    train, _, _ = load_subject_motions(folder, library_subjects, graph.skeleton_)
    mean, std = position_stats([w for m in train for w in windows(m, TRAIN_WINDOW, TRAIN_OFFSET)])
    evals, names, _ = load_subject_motions(folder, eval_subjects, graph.skeleton_)
    per_clip = [windows(m) for m in evals]
    wins = [w for ws in per_clip for w in ws]
    subject = [nm.split("_")[0] for nm, ws in zip(names, per_clip) for _ in ws]
    if not wins:
        raise ValueError("no evaluation windows")
    return {"graph": graph, "wins": wins, "names": names, "mean": mean, "std": std, "subject": subject,
            "library_subjects": list(library_subjects), "eval_subjects": list(eval_subjects)}


def fit_methods(graph, methods, seed: int = 0, markov_params: dict | None = None) -> dict:
    """``name -> fitted in-betweener`` (``None`` for slerp)."""
    from ..inbetween import GraphInbetweener, MarkovInbetweener
    from ..inbetween.poses import SlerpInbetweener

    models = {}
    for name in methods:
        if name == "markov":
            models[name] = MarkovInbetweener(random_state=seed, **(markov_params or {})).fit(graph)
        elif name == "slerp_hermite":
            models[name] = SlerpInbetweener("hermite")
        elif name == "graph":
            models[name] = GraphInbetweener().fit(graph)
        elif name == "slerp":
            models[name] = None
        else:
            raise ValueError(f"unknown method {name!r}")
    return models


def benchmark(data: dict, methods=D.EVAL_METHODS, gaps=GAPS, seed: int = 0,
              markov_params: dict | None = None, per_window: bool = False) -> dict:
    """Scores of ``methods`` on prepared ``data`` (:func:`prepare`): the metrics document's body
    (``split``, ``gaps``, ``methods``, ``params``)."""
    models = fit_methods(data["graph"], methods, seed, markov_params)
    params = {f"{k}_params": m.get_params() for k, m in models.items() if m is not None}
    return {
        "split": {"library_subjects": data["library_subjects"], "eval_subjects": data["eval_subjects"],
                  "eval_clips": data["names"], "windows": len(data["wins"]), "library_frames": int(data["graph"].n_frames)},
        "gaps": list(gaps),
        "methods": score_methods(models, data["wins"], gaps, data["mean"], data["std"], per_window=per_window),
        "params": {"fps": FPS, "window": WINDOW, "offset": OFFSET, "n_past": N_PAST, "train_window": TRAIN_WINDOW,
                   "train_offset": TRAIN_OFFSET, **params},
    }


def evaluate(folder: str | Path, library_subjects=SPLIT["library"], test_subjects=SPLIT["test"], gaps=GAPS,
             methods=D.EVAL_METHODS, seed: int = 0, graph_cache=None, command: str = "") -> dict:
    """The in-betweening metrics document (``vidstyle.metrics.inbetween``, without its header): the
    methods at their defaults (:mod:`vidstyle.inbetween.defaults`) on the test subjects' windows."""
    data = prepare(folder, library_subjects, test_subjects, seed, graph_cache)
    body = benchmark(data, methods, gaps, seed, per_window=True)
    subj = np.array(data["subject"])
    by_subject = {}
    for s in sorted(set(data["subject"])):
        sel = subj == s
        by_subject[s] = {"windows": int(sel.sum()), **{
            m: {str(g): {"l2p": float(np.mean(np.array(v[str(g)]["per_window_l2p"])[sel])),
                         "l2q": float(np.mean(np.array(v[str(g)]["per_window_l2q"])[sel]))} for g in gaps}
            for m, v in body["methods"].items()}}
    for v in body["methods"].values():
        for g in gaps:
            v[str(g)].pop("per_window_l2p")
            v[str(g)].pop("per_window_l2q")
    return {"seed": seed, "command": command, **body, "goal": markov_goal(body["methods"], gaps), "by_subject": by_subject,
            "speed": {"unit": "ms per request (median over windows), one thread",
                      **{m: {str(g): v[str(g)]["ms_per_request"] for g in gaps} for m, v in body["methods"].items()}}}


def markov_goal(methods: dict, gaps) -> dict[str, bool]:
    """The issue's goal per gap and measure: Molina Tanco's Markov method below SLERP, on L2P and on L2Q
    (empty without both methods)."""
    if "markov" not in methods or "slerp" not in methods:
        return {}
    return {f"markov_below_slerp_{m}_{g}": methods["markov"][str(g)][m] < methods["slerp"][str(g)][m]
            for m in ("l2p", "l2q") for g in gaps}


def graph_motions(graph) -> list[Motion]:
    """The library clips of a fitted motion graph as motions (each clip's frames, in order)."""
    clip = np.asarray(graph.frame_clip_)
    cuts = np.flatnonzero(np.diff(clip)) + 1
    out = []
    for a, b in zip(np.concatenate([[0], cuts]), np.concatenate([cuts, [len(clip)]])):
        out.append(Motion(graph.skeleton_, np.asarray(graph.rotations_[a:b]), None, float(graph.fps),
                          root_positions=np.asarray(graph.root_positions_[a:b])))
    return out


def evaluate_on_graph(graph, clips, gaps=GAPS, methods=("markov", "slerp"), seed: int = 0, max_windows: int | None = None,
                      command: str = "", library: str = "") -> dict:
    """The in-betweening metrics document (without its header) with a fitted motion graph as the library
    (e.g. the pipeline's) and held-out BVH ``clips`` (retargeted onto the graph's skeleton, at the graph's
    frame rate) as the windows: position statistics from the graph's own clips' training windows, up to
    ``max_windows`` evaluation windows (an even spread over all; ``None``: all)."""
    from ..mocap import read_bvh
    from ..mocap.retarget import retarget
    from ..motiongraph.graph import has_tpose_first_frame

    if abs(float(graph.fps) - FPS) > 1e-6:
        raise ValueError(f"the graph is at {graph.fps:g} fps; the benchmark's windows are at {FPS:g} fps")
    library_names = set((getattr(graph, "clips_", None) or {}).get("names") or [])
    inside = sorted(Path(f).stem for f in clips if Path(f).stem in library_names)
    if inside:
        raise ValueError(f"{', '.join(inside)}: among the graph's own clips (the windows must be held out)")
    train = graph_motions(graph)
    mean, std = position_stats([w for m in train for w in windows(m, TRAIN_WINDOW, TRAIN_OFFSET)])
    wins, names, per = [], [], []
    for f in clips:
        m = read_bvh(f)
        if has_tpose_first_frame(m):
            m = m[1:]
        m, _ = retarget(m, graph.skeleton_, str(f))
        ws = windows(m.resample(FPS))
        wins += ws
        per += [Path(f).stem] * len(ws)
        names.append(Path(f).stem)
    if not wins:
        raise ValueError("no evaluation window (each clip needs more than 65 frames at 30 fps)")
    if max_windows is not None and len(wins) > max_windows:
        keep = np.unique(np.linspace(0, len(wins) - 1, max_windows).round().astype(int))
        wins, per = [wins[i] for i in keep], [per[i] for i in keep]
    models = fit_methods(graph, methods, seed)
    params = {f"{k}_params": m.get_params() for k, m in models.items() if m is not None}
    res = score_methods(models, wins, gaps, mean, std)
    goal = markov_goal(res, gaps)
    return {"seed": seed, "command": command,
            "split": {"library": library or "motion graph", "library_frames": int(graph.n_frames), "eval_clips": names,
                      "windows": len(wins), "windows_per_clip": {n: per.count(n) for n in names}},
            "gaps": list(gaps), "methods": res,
            "params": {"fps": FPS, "window": WINDOW, "offset": OFFSET, "n_past": N_PAST, "train_window": TRAIN_WINDOW,
                       "train_offset": TRAIN_OFFSET, "max_windows": max_windows, **params},
            "goal": goal,
            "speed": {"unit": "ms per request (median over windows), one thread",
                      **{m: {str(g): v[str(g)]["ms_per_request"] for g in gaps} for m, v in res.items()}}}


def table(doc: dict) -> str:
    """The metrics document as a text table (rows: method; columns: L2P and L2Q per gap, ms)."""
    gaps = doc["gaps"]
    head = f"{'method':>8} | " + " ".join(f"L2P@{g:<3}" for g in gaps) + " | " + " ".join(f"L2Q@{g:<3}" for g in gaps) \
        + " | " + " ".join(f"ms@{g:<4}" for g in gaps)
    lines = [head, "-" * len(head)]
    for name, res in doc["methods"].items():
        lines.append(f"{name:>8} | " + " ".join(f"{res[str(g)]['l2p']:7.3f}" for g in gaps) + " | "
                     + " ".join(f"{res[str(g)]['l2q']:7.3f}" for g in gaps) + " | "
                     + " ".join(f"{res[str(g)]['ms_per_request']:7.1f}" for g in gaps))
    for s, block in doc.get("by_subject", {}).items():
        lines.append(f"subject {s} ({block['windows']} windows):")
        for name in doc["methods"]:
            lines.append(f"{name:>8} | " + " ".join(f"{block[name][str(g)]['l2p']:7.3f}" for g in gaps) + " | "
                         + " ".join(f"{block[name][str(g)]['l2q']:7.3f}" for g in gaps))
    return "\n".join(lines)
