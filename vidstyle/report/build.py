"""``vidstyle report``: one self-contained HTML page summarising a pipeline run.

It reads the run directory written by the kickboxing pipeline (``pipelines/kickboxing/dvc.yaml``)::

    RUN/dataset/dataset.json          demo dataset manifest (true chains, labels)
    RUN/metrics/recognition.json      vidstyle evaluate recognition
    RUN/recognized/<video id>.json    vidstyle recognize
    RUN/style/<performer>.json        vidstyle learn-style
    RUN/metrics/style.json            vidstyle evaluate style
    RUN/generated/<performer>.json    vidstyle generate --format json
    RUN/graph/graph.npz               vidstyle build-graph
    RUN/motion/<performer>.mp4        vidstyle synthesize --preview
    RUN/metrics/motion.json           vidstyle evaluate motion
    RUN/metrics/action_style.json     vidstyle evaluate action-style (and RUN/action_style/<label>.png)
    RUN/metrics/inbetween.json        vidstyle evaluate inbetween --graph
    RUN/metrics/timing.json           vidstyle timing (the stage-time table; make demo writes it)

Every section whose inputs are missing says so on the page (the report is also useful on a partial
run); none is silently skipped. Charts are inline SVG, the motion preview an inline animated GIF.
"""

from __future__ import annotations

import io
import json
import logging
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..formats.dataset import Dataset, read_dataset
from ..formats.labels import read_labels
from ..formats.metrics import (
    ACTION_STYLE,
    AUGMG,
    HEADLINE,
    INBETWEEN,
    MOTION,
    RECOGNITION,
    RECONSTRUCT,
    STYLE,
    TIMING,
    read_metrics,
)
from ..formats.recognised import read_recognised
from ..formats.sequence import read_sequence
from ..formats.style import read_style
from . import svg
from .page import Page, data_uri, esc, table

log = logging.getLogger(__name__)


def _load(path: Path, reader, *args):
    """``reader(path)`` (a :mod:`vidstyle.formats` reader: a malformed file is a FormatError), or None
    when the file does not exist."""
    if not path.exists():
        return None
    return reader(path, *args)


def _metrics(path: Path, kind: str) -> dict | None:
    m = _load(path, read_metrics, kind)
    return None if m is None else m.doc


def _missing(what: str, path: Path) -> str:
    return f'<p class="missing">Not available: {esc(what)} ({esc(path)} is missing).</p>'


def _section_metrics(page: Page, title: str, run: Path, name: str, kind: str, what: str) -> dict | None:
    """RUN/metrics/<name>.json of ``kind``, or None after adding section ``title`` saying ``what`` is missing."""
    path = run / "metrics" / f"{name}.json"
    m = _metrics(path, kind)
    if m is None:
        page.add(title, _missing(what, path))
    return m


def gif_from_video(path: Path, max_seconds: float = 10.0, fps: float = 10.0, width: int = 320) -> bytes:
    """An animated GIF (bytes) of the first ``max_seconds`` of a video, at ``fps``, ``width`` pixels wide."""
    import cv2
    from PIL import Image

    from ..video import VideoReader

    frames = []
    with VideoReader(path, fps=fps) as reader:
        stop = min(len(reader), max(1, int(max_seconds * fps)))
        for _, frame in reader.iter_frames(0, stop):
            h, w = frame.shape[:2]
            frame = cv2.resize(frame, (width, int(round(h * width / w))), interpolation=cv2.INTER_AREA)
            # each frame's own 256 colours by fast octree: a fifth of the time of PIL's default median cut
            # for GIF frames (which was half of the report's time), RMS error 1.5 grey levels against 0.9
            frames.append(Image.fromarray(cv2.cvtColor(frame, cv2.COLOR_BGR2RGB)).quantize(
                colors=256, method=Image.Quantize.FASTOCTREE))
        rate = reader.fps or fps
    buf = io.BytesIO()
    frames[0].save(buf, format="GIF", save_all=True, append_images=frames[1:], duration=int(1000 / rate),
                   loop=0, optimize=True)
    return buf.getvalue()


def _recognition_section(page: Page, run: Path, dataset: Dataset | None) -> None:
    path = run / "metrics" / "recognition.json"
    m = _metrics(path, RECOGNITION)
    if m is None:
        page.add("Action recognition", _missing("recognition metrics", path))
        return
    fa = m.get("frame_accuracy", {})
    rows = [
        ["frame accuracy, raw", fa.get("raw"), 0.64],
        ["frame accuracy, smoothed", fa.get("smoothed"), 0.70],
        ["video accuracy", m.get("video_accuracy"), 0.90],
    ]
    within = _get(m.get("segments"), "smoothed", "boundary_tolerant_accuracy", "1")
    if within is not None:  # metrics written before vidstyle evaluate recognition recorded segments lack it
        rows[2:2] = [["frame accuracy, smoothed, within a frame of the true boundaries", within, None],
                     ["segmental F1@50 (smoothed)", _get(m.get("segments"), "smoothed", "segmental_f1", "50"), None]]
    cam = _metrics(run / "metrics" / "recognition_unseen_camera.json", RECOGNITION)
    if cam is not None:
        cams = ", ".join(f"azimuth {a:g}°" + (f" elevation {e:g}°" if e is not None else "")
                         for a, e in (cam.get("split", {}).get("test_cameras") or []))
        rows += [[f"unseen camera ({cams}): frame accuracy raw", cam.get("frame_accuracy", {}).get("raw"), None],
                 ["unseen camera: frame accuracy smoothed", cam.get("frame_accuracy", {}).get("smoothed"), None],
                 ["unseen camera: video accuracy", cam.get("video_accuracy"), None]]
    split = m.get("split", {})
    owner = {v.id: v.performer for v in (dataset.videos if dataset else [])}
    test_performers = split.get("test_performers") or sorted({owner[v] for v in split.get("test", []) if owner.get(v)})
    body = [
        f"<p>Split: <b>{esc(split.get('kind', '?'))}</b>; test performers "
        f"{esc(', '.join(test_performers) or '–')}; "
        f"{m.get('n_test_videos', '?')} test videos, {m.get('n_test_frames', '?')} frames.</p>",
        table([[r[0], r[1] if r[1] is not None else "–", r[2] if r[2] is not None else "–"] for r in rows], ["metric", "vidstyle", "thesis (Chen 2012)"]),
    ]
    conf = m.get("confusion", {})
    if conf.get("smoothed"):
        classes = conf["classes"]
        body.append('<div class="row">')
        body.append(svg.heatmap(np.array(conf["smoothed"], float), classes, classes, "Confusion (smoothed, row-normalised)",
                                vmax=1.0, xlabel="predicted", ylabel="true"))
        if conf.get("raw"):
            body.append(svg.heatmap(np.array(conf["raw"], float), classes, classes, "Confusion (raw)", vmax=1.0,
                                    xlabel="predicted", ylabel="true"))
        body.append("</div>")
    page.add("Action recognition", "".join(body))

    # timeline of one performance video of a test performer
    if dataset is None:
        return
    test = set(split.get("test", []))
    perf = [v for v in dataset.videos if v.kind == "performance"]
    perf.sort(key=lambda v: (v.id not in test, v.id))
    for v in perf:
        truth = _load(dataset.labels_path(v), read_labels)
        rec = _load(run / "recognized" / f"{v.id}.json", read_recognised, None if truth is None else truth.n_frames)
        if rec is None or truth is None:
            continue
        tracks = {"true": truth.labels, "recognised (raw)": rec.raw if rec.raw is not None else rec.labels,
                  "recognised (smoothed)": rec.labels}
        acc = float(np.mean(np.array(truth.labels) == np.array(rec.labels)))
        page.add(
            f"Timeline: {v.id}",
            f"<p>Performance video of {esc(v.performer)} ({esc(v.view)} view), "
            f"{'unseen' if v.id in test else 'seen'} performer; frame accuracy {acc:.3f}.</p>"
            + svg.timeline(tracks, dataset.classes, truth.fps, title="true vs recognised actions"),
        )
        return
    page.add("Timeline", "<p class=\"missing\">Not available: no recognised performance video.</p>")


def _style_section(page: Page, run: Path, dataset: Dataset | None) -> None:
    m = _metrics(run / "metrics" / "style.json", STYLE)  # read first: a malformed file is an error, always
    styles = sorted((run / "style").glob("*.json")) if (run / "style").is_dir() else []
    if not styles:
        page.add("Behaviour style", _missing("learned styles", run / "style"))
        return
    chains = {p.id: p.chain for p in (dataset.performers if dataset else []) if p.chain is not None}
    body = ['<div class="row">']
    for path in styles[:3]:
        st = read_style(path)
        actions = list(st.actions)
        learned = np.asarray(st.model_a.transition, float)
        who = st.performer or path.stem
        body.append(svg.heatmap(learned, actions, actions, f"{who}: learned (HMM a)",
                                vmax=1.0, xlabel="next action", ylabel="action"))
        chain = chains.get(who)
        if chain is not None:
            true = chain.reordered(actions)[1]
            body.append(svg.heatmap(true, actions, actions, f"{who}: true chain", vmax=1.0,
                                    xlabel="next action", ylabel="action"))
            body.append(f'<p class="note">mean |learned - true| = {np.abs(learned - true).mean():.3f}</p>')
    body.append("</div>")
    if m is not None:
        rows = []
        for source, block in m.get("sources", {}).items():
            s = block.get("summary", {})
            ident = s.get("identification", {}).get("a", {})
            fid = s.get("fidelity", {}).get("a", {})
            ll = s.get("heldout_loglik_per_event", {})
            rows.append([source, s.get("transition_mae", {}).get("a"), ident.get("accuracy_by_heldout_data"),
                         fid.get("jsd_2gram_same"), fid.get("jsd_2gram_other"), ll.get("a"), ll.get("b"), ll.get("bigram")])
        body.append(table(rows, ["labels", "transition MAE (a)", "identification (a)", "JSD 2-gram same",
                                 "JSD 2-gram other", "loglik/event (a)", "(b)", "bigram"]))
        if m.get("recognised_performers"):
            body.append(f'<p class="note">Recognised labels are scored only for the recognizer\'s test performers '
                        f'({esc(", ".join(m["recognised_performers"]))}): no video of theirs trained or tuned it. '
                        f'"ground_truth_test_performers" is the same performers on true labels (identification '
                        f'among {len(m["recognised_performers"])} performers); "ground_truth" is every performer.</p>')
    page.add("Behaviour style: learned vs true transitions", "".join(body))

    gens = sorted((run / "generated").glob("*.json")) if (run / "generated").is_dir() else []
    if gens:
        items = []
        for g in gens:
            seq = read_sequence(g)
            actions = " ".join(seq.actions())
            items.append(f"<p><b>{esc(g.stem)}</b> (seed {esc(seq.seed)}, model {esc(seq.model)}):</p>"
                         f'<div class="seq">{esc(actions)}</div>')
        page.add("Generated action sequences (thesis Table 4 style)", "".join(items))
    else:
        page.add("Generated action sequences", _missing("generated sequences", run / "generated"))


def _motion_section(page: Page, run: Path) -> None:
    gpath = run / "graph" / "graph.npz"
    body = []
    if gpath.is_file():
        from ..formats.motiongraph import read_graph

        g = read_graph(gpath)
        rows = [[k.replace("_", " "), v] for k, v in g.stats.items() if isinstance(v, (int, float))]
        body.append(table(rows, ["motion graph", "value"]))
        body.append(f'<p class="note">labels: {esc(", ".join(g.label_names))}; window {g.window} frames at '
                    f'{g.fps:g} fps</p>')
    else:
        body.append(_missing("motion graph", gpath))
    m = _metrics(run / "metrics" / "motion.json", MOTION)
    if m is not None:
        ms = m.get("summary", {})
        rows = [["walks / frames", f"{ms.get('walks')} / {ms.get('frames')}"],
                ["label fidelity (frames showing the requested action)", ms.get("label_fidelity")],
                ["transitions per second", ms.get("transitions_per_second")]]
        for key, name in (("velocity_jump", "velocity jump"), ("jerk", "jerk"), ("foot_skid", "foot skid")):
            q = ms.get(key, {})
            rows.append([f"{name} at seams / in the clips (median)", q.get("seam_over_original_median")])
        body.append(table(rows, ["synthesized motion", "value"]))
        body.append(f'<details><summary>evaluate motion (metrics/motion.json)</summary><pre class="seq">'
                    f'{esc(json.dumps(m.get("summary", m), indent=1)[:4000])}</pre></details>')
    page.add("Motion graph", "".join(body))

    previews = sorted((run / "motion").glob("*.mp4")) if (run / "motion").is_dir() else []
    if previews:
        items = []
        for p in previews[:2]:
            gif = gif_from_video(p)
            items.append(f'<figure><img class="anim" alt="synthesized motion {esc(p.stem)}" '
                         f'src="{data_uri(gif, "image/gif")}"><figcaption>{esc(p.stem)}</figcaption></figure>')
        page.add("Synthesized motion", '<div class="row">' + "".join(items) + "</div>")
    else:
        page.add("Synthesized motion", _missing("motion preview", run / "motion"))


def _augmg_section(page: Page, run: Path, dataset: Dataset | None = None) -> None:
    """Method 2: per 2D source, retrieval of the marked transition pose and the transition error of
    AugMG against the plain motion graph (metrics/augmg.json), and the motion synthesised on the AugMG
    graph."""
    path = run / "metrics" / "augmg.json"
    m = _metrics(path, AUGMG)
    if m is None:
        page.add("AugMG: transitions through the performer's own poses", _missing("AugMG metrics", path))
        return
    names = {"model": "estimated 2D pose (pictorial structures)", "blazepose": "estimated 2D pose (BlazePose)",
             "gt": "true 2D pose", "noisy": "true 2D + 5 % noise"}
    rows = []
    for src, r in m["by_source"].items():
        rows.append([names.get(src, src), r.get("queries"), r.get("retrieval_mpjpe_mm"), r.get("recall_at_1"),
                     r.get("recall_at_10"), r.get("transition_plain_mm"), r.get("transition_augmg_mm"),
                     r.get("accepted"), r.get("transition_reduction")])
    params = m.get("params") or {}
    body = [table(rows, ["2D source", "queries", "retrieval MPJPE (mm)", "recall@1", "recall@10",
                         "plain transition error (mm)", "AugMG transition error (mm)", "accepted",
                         "reduction"]),
            f'<p class="note">{esc(str(params.get("queries", "?")))} held-out transitions against '
            f'{esc(str(params.get("library_frames", "?")))} library frames; transition error = mean joint '
            f'position error against the performer\'s true transition, same endpoints (metrics/augmg.json)</p>']
    previews = sorted((run / "motion_augmg").glob("*.mp4")) if (run / "motion_augmg").is_dir() else []
    for p in previews[:1]:
        gif = gif_from_video(p)
        body.append(f'<figure><img class="anim" alt="motion on the AugMG graph {esc(p.stem)}" '
                    f'src="{data_uri(gif, "image/gif")}"><figcaption>{esc(p.stem)}, synthesised on the graph '
                    f'with enhancement edges</figcaption></figure>')
    body.append(_augmg_transitions_html(run, dataset))
    page.add("AugMG: transitions through the performer's own poses", "".join(body))


ANIM_JS = """
(function(){var data=JSON.parse(document.getElementById('augmg-anim-data').textContent);
var bones=data.bones,colors={library:'#6a3d9a',plain:'#999999',augmg:'#d95f02',truth:'#1b9e77'};
function draw(ctx,pose,box,color){var s=box.s,ox=box.ox,oy=box.oy;ctx.strokeStyle=color;ctx.lineWidth=2;
 ctx.beginPath();for(var b=0;b<bones.length;b++){var p=pose[bones[b][0]],q=pose[bones[b][1]];
 ctx.moveTo(ox+s*p[0],oy+s*p[1]);ctx.lineTo(ox+s*q[0],oy+s*q[1]);}ctx.stroke();}
function fit(frames,w,h){var x0=1e9,x1=-1e9,y0=1e9,y1=-1e9;frames.forEach(function(f){f.forEach(function(p){
 x0=Math.min(x0,p[0]);x1=Math.max(x1,p[0]);y0=Math.min(y0,p[1]);y1=Math.max(y1,p[1]);});});
 var s=0.85*Math.min(w/Math.max(x1-x0,1e-6),h/Math.max(y1-y0,1e-6));
 return {s:s,ox:w/2-s*(x0+x1)/2,oy:h/2-s*(y0+y1)/2};}
var canvases=document.querySelectorAll('canvas.augmg-anim');var t=0;
function tick(){canvases.forEach(function(c){var e=data.entries[+c.dataset.entry],ctx=c.getContext('2d');
 var W=c.width/4,H=c.height;ctx.clearRect(0,0,c.width,c.height);var n=e.truth.length,f=t%(n+6);if(f>=n)f=n-1;
 var all=e.truth.concat(e.plain,e.augmg),box=fit(all,W,H-16),lb=fit([e.library],W,H-16);
 draw(ctx,e.library,lb,colors.library);
 [['plain',1],['augmg',2],['truth',3]].forEach(function(k){ctx.save();ctx.translate(k[1]*W,0);
  draw(ctx,e[k[0]][f],box,colors[k[0]]);ctx.restore();});
 ctx.fillStyle='#333';ctx.font='11px sans-serif';
 ['matched library pose','plain','AugMG'+(e.accepted?'':' (= plain)'),'true'].forEach(function(l,i){
  ctx.fillText(l,i*W+4,H-4);});});t++;}
tick();setInterval(tick,100);})();
"""


def _frame_with_pose(video: Path, frame: int, pose: np.ndarray, scale: int = 2) -> bytes | None:
    """PNG of ``video``'s frame ``frame`` (decoded index) with the 2D pose (15, 2) drawn on it."""
    import cv2

    from ..augmg.keypoints import BONE_INDEX
    from ..video import VideoReader

    if not video.is_file():
        return None
    with VideoReader(video) as reader:
        if frame >= len(reader):
            return None
        img = reader.frame(frame)
    img = cv2.resize(img, (img.shape[1] * scale, img.shape[0] * scale), interpolation=cv2.INTER_NEAREST)
    pts = np.round(np.asarray(pose) * scale).astype(int)
    for a, b in BONE_INDEX:
        cv2.line(img, tuple(pts[a]), tuple(pts[b]), (0, 200, 255), 2, cv2.LINE_AA)
    for p in pts:
        cv2.circle(img, tuple(p), 2, (0, 0, 255), -1, cv2.LINE_AA)
    ok, buf = cv2.imencode(".png", img)
    return buf.tobytes() if ok else None


def _view(points: np.ndarray, entry) -> list:
    """(F, 15, 2) image coordinates of 3D keypoints (F, 15, 3) of a transition seen from the entry's
    viewpoint relative to the true transition's first frame (its pelvis above the origin, facing +Z):
    the same camera for the plain, AugMG and true transitions, so their travel is comparable."""
    from ..augmg.keypoints import KP
    from ..augmg.projection import facing_of_keypoints, project

    first = entry.truth[:1]
    f0 = float(facing_of_keypoints(first)[0])
    rel = points - first[0, KP["pelvis"]] * np.array([1.0, 0.0, 1.0])
    c, s = np.cos(f0), np.sin(f0)
    norm = np.stack([c * rel[..., 0] - s * rel[..., 2], rel[..., 1], s * rel[..., 0] + c * rel[..., 2]], axis=-1)
    return np.round(project(norm, entry.viewpoint_deg, 10.0), 4).tolist()


def _augmg_transitions_html(run: Path, dataset: Dataset | None) -> str:
    """Per annotated transition: the video frame with its estimated pose, the matched library pose and
    the plain, AugMG and true transitions side by side (canvas animations of projected keypoints, the
    data embedded as JSON) from RUN/augmg/transitions.json (vidstyle evaluate augmg --transitions)."""
    from ..augmg.keypoints import BONE_INDEX
    from ..formats.augmg_transitions import read_augmg_transitions

    path = run / "augmg" / "transitions.json"
    doc = _load(path, read_augmg_transitions)
    if doc is None:
        return _missing("AugMG transitions", path)
    videos = {}
    if dataset is not None:
        videos = {v.id: run / "dataset" / v.video for v in dataset.videos if getattr(v, "video", None)}
    entries, cards = [], []
    for i, e in enumerate(doc.entries):
        entries.append({"library": np.round(e.library2d, 4).tolist(), "plain": _view(e.plain, e),
                        "augmg": _view(e.augmg, e), "truth": _view(e.truth, e), "accepted": e.accepted})
        png = _frame_with_pose(videos[e.video], e.frame, e.pose2d) if e.video in videos else None
        img = (f'<img alt="frame {e.frame} of {esc(e.video)} with its estimated pose" src="{data_uri(png, "image/png")}">'
               if png is not None else '<p class="missing">video frame not available</p>')
        status = ("enhancement accepted" if e.accepted else "enhancement rejected: plain transition kept")
        cards.append(
            f'<figure class="augmg-entry" data-video="{esc(e.video)}" data-frame="{e.frame}">{img}'
            f'<canvas class="augmg-anim" data-entry="{i}" width="520" height="150"></canvas>'
            f'<figcaption>{esc(e.video)} frame {e.frame}: {esc(e.from_action)} &rarr; {esc(e.to_action)} '
            f'(true kind: {esc(e.kind)}); reference {esc(e.reference_clip)} @ {e.reference_time:.2f} s; '
            f'{status}; error plain {e.plain_mm:.0f} mm, AugMG {e.augmg_mm:.0f} mm</figcaption></figure>')
    payload = json.dumps({"bones": BONE_INDEX.tolist(), "entries": entries}, separators=(",", ":"))
    payload = payload.replace("</", "<\\/")
    return (f'<h3>Annotated transitions ({len(doc.entries)}, 2D source: {esc(doc.source)})</h3>'
            f'<div class="row">{"".join(cards)}</div>'
            f'<script type="application/json" id="augmg-anim-data">{payload}</script>'
            f'<script>{ANIM_JS}</script>')


def _seconds(v) -> str:
    return "" if v is None else f"{v:.1f}"


def timing_section(page: Page, run: Path) -> None:
    """The stage-time table of the run (metrics/timing.json, :mod:`vidstyle.timing`): per stage its status,
    wall time, CPU time, peak RSS and invocations."""
    path = run / "metrics" / "timing.json"
    m = _metrics(path, TIMING)
    if m is None:
        page.add("Stage times", _missing("stage times (make demo writes them with vidstyle timing)", path))
        return
    if not m["recorded"]:
        page.add("Stage times", f'<p class="missing">Not recorded: this run kept no timing records '
                 f'({esc(m["records_dir"])}); <code>make demo</code> sets VIDSTYLE_TIMINGS to keep them.</p>')
        return
    rows = [[s["stage"], s["status"], _seconds(s["wall_seconds"]), _seconds(s["cpu_seconds"]),
             "" if s["peak_rss_mb"] is None else f"{s['peak_rss_mb']:.0f}", s["invocations"]]
            for s in m["stages"]]
    ran = [s for s in m["stages"] if s["invocations"]]
    rows.append(["total", f"{len(ran)} stage(s) with runs", _seconds(m["stages_wall_seconds"]),
                 _seconds(m["cpu_seconds"]), "", sum(s["invocations"] for s in m["stages"])])
    notes = [("Each vidstyle process times itself (wall time from its start, CPU time of the process and its "
              "children, peak resident memory); a stage's wall time runs from its first process's start to its "
              "last one's end. skipped: DVC found the stage up to date; running: the stage that made this table "
              "(the report itself).")]
    if m.get("run_wall_seconds") is not None:
        notes.append(f"The run took {m['run_wall_seconds']:.1f} s of wall time, "
                     f"{max(m['run_wall_seconds'] - m['stages_wall_seconds'], 0):.1f} s of it outside vidstyle "
                     "processes (DVC, the shell).")
    body = (table(rows, ["stage", "status", "wall s", "CPU s", "peak RSS MB", "processes"])
            + "".join(f'<p class="note">{esc(n)}</p>' for n in notes))
    page.add("Stage times", body)


def _reconstruct_section(page: Page, run: Path) -> None:
    """Whole video to 3D (``vidstyle reconstruct``): the pooled errors per 2D source, method and skeleton
    (metrics/reconstruct.json), one video's frames with the reconstruction projected over them
    (RUN/reconstruct/*.preview.mp4) and its 3D against the truth (RUN/reconstruct/compare.mp4)."""
    title = "Whole video to 3D motion (reconstruct)"
    m = _section_metrics(page, title, run, "reconstruct", RECONSTRUCT, "reconstruct metrics")
    if m is None:
        return
    names = {"true2d": "true 2D pose", "ps": "estimated 2D (pictorial structures)", "blazepose": "estimated 2D (BlazePose)"}
    rows = [[names.get(r["source"], r["source"]), r["method"], r["skeleton"], r["frames"],
             r.get("mpjpe_root_relative_mm"), r.get("mpjpe_mm"), r.get("pa_mpjpe_mm"),
             r.get("acceleration_error_mm_per_frame2"), r.get("foot_skate_mm_per_frame")]
            for r in m["runs"] if r["data"] == "demo test performers"]
    params = m.get("params") or {}
    body = [table(rows, ["2D source", "method", "skeleton", "frames", "root-relative MPJPE (mm)", "MPJPE (mm)",
                         "PA-MPJPE (mm)", "acceleration error (mm/frame²)", "foot skate (mm/frame)"]),
            f'<p class="note">{esc(", ".join(m.get("videos") or []))}: the first {esc(str(params.get("max_frames")))} '
            f'frames of each, against {esc(str(params.get("library_frames", "?")))} indexed library frames. Skeleton '
            f'"library": the output skeleton is the library\'s (the performer\'s body unknown, as for any video); '
            f'"height": the same, scaled to the performer\'s standing height (reconstruct --height, when a user '
            f'knows it); "performer": the take\'s own skeleton given (the motion\'s error alone) '
            f'(metrics/reconstruct.json)</p>']
    folder = run / "reconstruct"
    for p, caption in [*((p, f"{p.stem}: the video with the reconstruction projected over it (yellow) and the "
                          "reconstruction from the side") for p in sorted(folder.glob("*.preview.mp4"))[:1]),
                       *((p, "the reconstruction (orange) against the true 3D motion (grey), front and side")
                         for p in [folder / "compare.mp4"] if p.is_file())]:
        gif = gif_from_video(p)
        body.append(f'<figure><img class="anim" alt="{esc(p.stem)}" src="{data_uri(gif, "image/gif")}">'
                    f'<figcaption>{esc(caption)}</figcaption></figure>')
    page.add(title, "".join(body))


def _action_style_section(page: Page, run: Path) -> None:
    """Each test performer's action-level style (``vidstyle evaluate action-style``): the summary per input
    and the per-performer fits (metrics/action_style.json), and one action of each performer: true, from
    their fitted style, and the unfitted model's (RUN/action_style/<label>.png)."""
    title = "How each performer does an action (action-level style)"
    m = _section_metrics(page, title, run, "action_style", ACTION_STYLE, "action-style metrics")
    if m is None:
        return
    names = {"true": "true 2D, true labels", "estimated": "pose-stage 2D, recognised labels"}

    def mm(x):
        return None if x is None else round(float(x), 1)

    rows = [[names.get(k, k), s.get("performers"), s.get("lead_accuracy"), s.get("guard_height_r"),
             s.get("stance_width_r"), s.get("duration_factor_r"), mm(s.get("fitted_mean_mm")),
             mm(s.get("unfitted_mean_mm")), mm(s.get("unfitted_mean_true_lead_mm")), s.get("mpjpe_reduction")]
            for k, s in (m.get("by_input") or {}).items()]
    body = [table(rows, ["input", "performers", "lead accuracy", "guard height r", "stance width r",
                         "duration factor r", "generated MPJPE: fitted (mm)", "unfitted (mm)",
                         "unfitted, true lead (mm)", "reduction"])]
    prow = []
    for k, rs in (m.get("rows") or {}).items():
        for r in rs:
            labs = (r.get("labels") or {}).values()
            fit = [v["fitted_mean_mm"] for v in labs if v.get("fitted_mean_mm") is not None]
            unf = [v["unfitted_mean_mm"] for v in labs if v.get("unfitted_mean_mm") is not None]
            prow.append([r.get("performer"), names.get(k, k), r.get("videos"), f"{r.get('lead')} ({r.get('lead_true')})",
                         f"{r.get('guard_height', float('nan')):.3f} ({r.get('guard_height_true', float('nan')):.3f})",
                         f"{r.get('stance_width', float('nan')):.3f} ({r.get('stance_width_true', float('nan')):.3f})",
                         sum((r.get("segments") or {}).values()),
                         mm(np.mean(fit)) if fit else None, mm(np.mean(unf)) if unf else None])
    body.append(table(prow, ["performer", "input", "videos", "lead (true)", "guard height (true)",
                             "stance width (true)", "segments fitted", "fitted MPJPE (mm)", "unfitted MPJPE (mm)"]))
    split = (m.get("splits") or {}).get(str(m.get("seed")), {})
    body.append(f'<p class="note">Test performers {esc(", ".join(split.get("T", [])))} of split seed '
                f'{esc(str(m.get("seed")))}; the orthodox action model and the population figures come from the '
                f'training performers {esc(", ".join(sorted(split.get("A", []) + split.get("B", []))))} only. '
                'Generated MPJPE: the performer\'s action generated from their fitted style (or the unfitted model\'s '
                'mean; "true lead": that mean mirrored for a southpaw) against their true instances of the same '
                'action, after DTW alignment, mean over actions. Guard and stance are relative to the training '
                'population (metrics/action_style.json)</p>')
    folder = run / "action_style"
    for png in sorted(folder.glob("*.png"))[:1]:
        body.append(f'<figure><img alt="{esc(png.stem)}" style="max-width:100%" '
                    f'src="{data_uri(png.read_bytes(), "image/png")}"><figcaption>{esc(png.stem)} of each test '
                    'performer from above and from the side: true (black), generated from their fitted style (blue), '
                    'the unfitted model (red)</figcaption></figure>')
    page.add(title, "".join(body))


def _inbetween_section(page: Page, run: Path) -> None:
    """Keyframe to keyframe (``vidstyle evaluate inbetween --graph``): L2P / L2Q per gap and method on windows
    of held-out takes, the pipeline's motion graph as the library (metrics/inbetween.json)."""
    title = "Motion between keyframes (in-betweening)"
    m = _section_metrics(page, title, run, "inbetween", INBETWEEN, "in-betweening metrics")
    if m is None:
        return
    gaps = m["gaps"]
    names = {"markov": "Markov chain over pose clusters (Molina Tanco & Hilton 2000; coverage-gated)", "graph": "motion graph shortest path",
             "slerp": "SLERP + linear root (baseline)", "slerp_hermite": "SLERP + the keys' Hermite root path (baseline)"}
    rows = [[names.get(k, k), *(round(v[str(g)]["l2p"], 3) for g in gaps), *(round(v[str(g)]["l2q"], 3) for g in gaps),
             *(round(v[str(g)]["ms_per_request"], 1) for g in gaps)] for k, v in m["methods"].items()]
    sp = m.get("split") or {}
    body = table(rows, ["method", *(f"L2P, {g} frames" for g in gaps), *(f"L2Q, {g} frames" for g in gaps),
                        *(f"ms, {g} frames" for g in gaps)])
    body += (f'<p class="note">{esc(str(sp.get("windows")))} windows of 65 frames at 30 fps from '
             f'{esc(", ".join(sp.get("eval_clips") or []))} (performers the library does not include); the gap '
             f'between the last context frame and the first future frame is filled from the library of '
             f'{esc(str(sp.get("library_frames")))} frames ({esc(str(sp.get("library")))}). LAFAN1\'s L2P (global '
             'positions normalised by the library\'s statistics) and L2Q (global quaternions); lower is better '
             '(metrics/inbetween.json)</p>')
    page.add(title, body)


def _get(doc: dict | None, *keys):
    for k in keys:
        if not isinstance(doc, dict) or k not in doc:
            return None
        doc = doc[k]
    return doc


def headline_metrics(run: Path) -> dict:
    """The few numbers of a run worth a column in ``dvc metrics show`` (the full documents stay in
    RUN/metrics/*.json). Missing inputs give ``None``."""
    run = Path(run)
    rec = _metrics(run / "metrics" / "recognition.json", RECOGNITION)
    sty = _metrics(run / "metrics" / "style.json", STYLE)
    mot = _metrics(run / "metrics" / "motion.json", MOTION)
    out: dict = {"kind": HEADLINE, "schema_version": 1,
                 "seed": _get(rec, "seed") if rec else _get(sty, "seed")}
    cam = _metrics(run / "metrics" / "recognition_unseen_camera.json", RECOGNITION)
    out["recognition"] = {
        "frame_accuracy_raw": _get(rec, "frame_accuracy", "raw"),
        "frame_accuracy_smoothed": _get(rec, "frame_accuracy", "smoothed"),
        "frame_accuracy_within_1_frame": _get(rec, "segments", "smoothed", "boundary_tolerant_accuracy", "1"),
        "segmental_f1_50": _get(rec, "segments", "smoothed", "segmental_f1", "50"),
        "video_accuracy": _get(rec, "video_accuracy"),
        "test_frames": _get(rec, "n_test_frames"),
        "unseen_camera_frame_accuracy_smoothed": _get(cam, "frame_accuracy", "smoothed"),
        "unseen_camera_video_accuracy": _get(cam, "video_accuracy"),
    }
    style = {}
    # *_recognised: the recognizer's test performers only; *_truth_test: the same performers' ground truth
    for source, short in (("ground_truth", "truth"), ("ground_truth_test_performers", "truth_test"),
                          ("recognised", "recognised")):
        s = _get(sty, "sources", source, "summary")
        style[f"transition_mae_{short}"] = _get(s, "transition_mae", "a")
        style[f"identification_{short}"] = _get(s, "identification", "a", "accuracy_by_heldout_data")
        style[f"heldout_loglik_{short}"] = _get(s, "heldout_loglik_per_event", "a")
    style["recognised_performers"] = _get(sty, "recognised_performers")
    out["style"] = style
    ms = _get(mot, "summary")
    out["motion"] = {
        "graph_frames": _get(mot, "graph_stats", "frames"),
        "transitions_in_scc": _get(mot, "graph_stats", "transitions_in_scc"),
        "label_fidelity": _get(ms, "label_fidelity"),
        "velocity_jump_seam_over_clip": _get(ms, "velocity_jump", "seam_over_original_median"),
        "foot_skid_seam_over_clip": _get(ms, "foot_skid", "seam_over_original_median"),
    }
    aug = _metrics(run / "metrics" / "augmg.json", AUGMG)
    if aug is not None:
        h = aug.get("headline") or {}
        out["augmg"] = {"retrieval_mpjpe": h.get("augmg.retrieval_mpjpe"),
                        "transition_error_plain": h.get("augmg.transition_error_plain"),
                        "transition_error_augmg": h.get("augmg.transition_error_augmg")}
        for key in ("retrieval_mpjpe", "transition_error_augmg"):
            if h.get(f"augmg.blazepose.{key}") is not None:
                out["augmg"][f"blazepose_{key}"] = h[f"augmg.blazepose.{key}"]
    ast = _metrics(run / "metrics" / "action_style.json", ACTION_STYLE)
    if ast is not None:  # vidstyle evaluate action-style (issue 30 item 2)
        a = ast.get("action_style") or {}
        out["action_style"] = {k: a.get(k) for k in ("lead_accuracy", "mpjpe_reduction", "mpjpe_reduction_vs_true_lead",
                                                      "estimated_lead_accuracy", "estimated_mpjpe_reduction", "input")
                               if k in a}
    inb = _metrics(run / "metrics" / "inbetween.json", INBETWEEN)
    if inb is not None:  # vidstyle evaluate inbetween --graph (issue 30 item 3)
        out["inbetween"] = {f"{k}_l2p_{g}": v[str(g)]["l2p"] for k, v in inb["methods"].items() for g in inb["gaps"]}
    rc = _metrics(run / "metrics" / "reconstruct.json", RECONSTRUCT)
    if rc is not None:
        h = rc.get("headline") or {}
        out["reconstruct"] = {k.split(".", 1)[1]: v for k, v in h.items() if k.startswith("reconstruct.")}
    return out


def build_report(run: Path) -> str:
    """HTML text of the report of run directory ``run``."""
    run = Path(run)
    if not run.is_dir():
        raise InputError(f"{run}: run directory not found")
    dataset = _load(run / "dataset" / "dataset.json", read_dataset)
    subtitle = "vidstyle pipeline run"
    if dataset is not None:
        subtitle = (f"demo dataset: {len(dataset.performers)} performers, {len(dataset.videos)} videos, seed "
                    f"{dataset.seed} — run directory {run}")
    page = Page("vidstyle: learning a performer's action style from video", subtitle)
    _recognition_section(page, run, dataset)
    _style_section(page, run, dataset)
    _motion_section(page, run)
    _augmg_section(page, run, dataset)
    _reconstruct_section(page, run)
    _action_style_section(page, run)
    _inbetween_section(page, run)
    timing_section(page, run)
    return page.render()
