"""Write annotations/demo.json: the bundled demo's transition-frame marks, as a person would make them.

For each chosen performance video of the kickboxing pipeline's dataset (pipelines/kickboxing/params.yaml:
seed 0, performances filmed from the front), every styled transition (the performer's own crouch / hop /
step back between two actions) gets one mark at the frame a person would pick: the *most distinctive*
pose of the transition (largest mean keypoint displacement from the guard just before it), give or take
a frame (people are not frame-exact: +-1 frame, seeded). About one mark in six is marked ``discarded``
(a person rejecting an unclear frame), so the demo also exercises the "plain transition stays" path.
Videos are tied to their sha256 and frame count; the takes are re-rendered here exactly as
``vidstyle demo make-dataset`` renders them (same seeds, deterministic encoder).

    python scripts/make_demo_annotations.py            # p03..p06, performance 0
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from vidstyle.demo.actions import ACTIONS
from vidstyle.demo.dataset import DatasetParams, generate_take, make_performer, make_take
from vidstyle.formats.annotations import (
    Annotations,
    Transition,
    VideoAnnotations,
    file_sha256,
    write_annotations,
)
from vidstyle.mocap.keypoints import KEYPOINT_INDEX, keypoint_positions
from vidstyle.parallel import limit_threads

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "annotations" / "demo.json"
VIDEO_DIR = "../pipelines/kickboxing/out/dataset/videos"  # relative to annotations/


def pipeline_params(path: Path = REPO / "pipelines/kickboxing/params.yaml") -> DatasetParams:
    import yaml

    p = yaml.safe_load(Path(path).read_text())
    d = p["dataset"]
    return DatasetParams(seed=int(p["seed"]), performers=int(d["performers"]), views=tuple(d["views"].split(",")),
                         single_seconds=float(d["single_seconds"]), performances=int(d["performances"]),
                         performance_seconds=float(d["performance_seconds"]),
                         performance_views=tuple(d["performance_views"].split(",")))


def person_frame(pts: np.ndarray, t: dict, ratio: int, rng: np.random.Generator) -> int:
    """The video frame of the transition's most distinctive pose, +-1 frame."""
    s, e = t["start"], t["end"]
    pel = KEYPOINT_INDEX["pelvis"]
    rel = pts - pts[:, pel:pel + 1] * np.array([1.0, 0.0, 1.0])
    before = rel[s * ratio - 1]
    dev = [np.linalg.norm(rel[f * ratio] - before, axis=1).mean() for f in range(s, e)]
    f = s + int(np.argmax(dev)) + int(rng.integers(-1, 2))
    return int(min(max(f, s), e - 1))


def main(performers=(3, 4, 5, 6), take: int = 100, params_path: Path = REPO / "pipelines/kickboxing/params.yaml",
         out: Path = OUT, video_dir: str = VIDEO_DIR) -> None:
    params = pipeline_params(params_path)
    rng = np.random.default_rng(np.random.SeedSequence([params.seed, 14, 3]))
    ratio = params.mocap_fps // params.fps
    videos = []
    with tempfile.TemporaryDirectory() as tmp:
        for sub in ("videos", "labels", "mocap"):
            (Path(tmp) / sub).mkdir()
        for i in performers:
            with limit_threads(1):  # as parallel_map runs make_dataset's takes: the same bytes
                entries = generate_take((params, i, take, tmp))
            p = make_performer(params, i)
            tk = make_take(params, p, i, take)
            pts = keypoint_positions(tk.motion)
            for entry in entries:
                video = Path(tmp) / entry["video"]
                marks, seen = [], set()
                for t in tk.transitions:
                    vt = {**t, "start": t["start"] // ratio, "end": t["end"] // ratio}
                    f = person_frame(pts, vt, ratio, rng)
                    if f in seen:
                        continue
                    seen.add(f)
                    status = "discarded" if rng.random() < 1 / 6 else "accepted"
                    marks.append(Transition(f, t["from"], t["to"], status))
                videos.append(VideoAnnotations(f"{video_dir}/{Path(entry['video']).name}", file_sha256(video),
                                               entry["frames"], float(params.fps), marks))
                print(f"{entry['id']}: {len(marks)} marks", flush=True)
    out.parent.mkdir(exist_ok=True)
    write_annotations(out, Annotations(list(ACTIONS), videos))
    print(f"wrote {out}")


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("performers", nargs="*", type=int, default=[3, 4, 5, 6], help="performer indices")
    ap.add_argument("--params", type=Path, default=REPO / "pipelines/kickboxing/params.yaml",
                    help="the pipeline's params.yaml (its dataset section and seed)")
    ap.add_argument("--out", type=Path, default=OUT, help="annotations file to write")
    ap.add_argument("--video-dir", default=VIDEO_DIR, help="where the videos are, relative to --out's directory")
    a = ap.parse_args()
    main(tuple(a.performers), params_path=a.params, out=a.out, video_dir=a.video_dir)
