#!/usr/bin/env python
"""The triangulated 3D reference of the real pose2sim take and the figures of BlazePose's own 3D against
it (issue 29: the baseline "(b)" a reconstruction from one view is compared with).

Steps: ``vidstyle pose --backend blazepose`` on every frame of each calibrated view (cached under
``--cache``; or ``--poses`` files given), :func:`vidstyle.reconstruct.reference.triangulated_reference`
with the take's calibration, and :func:`vidstyle.reconstruct.reference.summary`: coverage of the reference
per view, reprojection errors (px), each bone's length over time (mean and std, mm: a sanity check of the
triangulation), the world's up axis and ankle level, and per view the root-relative MPJPE (mm) of that
view's BlazePose world keypoints against the reference, after one Kabsch rotation for the whole take (the
baseline), with the camera's own rotation, and after a rotation per frame.

    python scripts/real_reference.py                              # the shared pose2sim take
    python scripts/real_reference.py --poses a.json b.json ...    # from poses files (names contain the cameras)

Writes ``--out`` (default ``pipelines/kickboxing/results/reconstruct_reference_real.json``); nothing on
stdout.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("GLOG_minloglevel", "2")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vidstyle.errors import VidstyleError
from vidstyle.formats.validation import RECONSTRUCT_REFERENCE, validation_header, write_validation

log = logging.getLogger("real_reference")
ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT.parent / "shared" / "data" / "video" / "real"
CALIBRATION = REAL / "pose2sim_single_Calib.qca.txt"
VIDEOS = [REAL / f"pose2sim_single_cam0{i}.mp4" for i in range(1, 5)]
DEFAULT_OUT = ROOT / "pipelines" / "kickboxing" / "results" / "reconstruct_reference_real.json"
DEFAULT_CACHE = Path(os.environ.get("TMPDIR", "/tmp")) / "vidstyle_real_reference"


def _usable(path: Path, video: Path) -> bool:
    """A cached poses file of ``video`` with BlazePose's world keypoints on every posed frame."""
    from vidstyle.formats import FormatError
    from vidstyle.formats.poses import read_poses

    if not path.is_file() or path.stat().st_mtime < video.stat().st_mtime:
        return False
    try:
        p = read_poses(path)
    except FormatError:
        return False
    return p.backend == "blazepose" and all(f.world is not None for f in p.frames if f.found)


def poses_of_videos(videos: list[Path], cache: Path, fresh: bool, jobs: int) -> list[Path]:
    """``vidstyle pose --backend blazepose`` (every frame, the performer followed) of each video, kept in
    ``cache`` as ``<video stem>.poses.json``."""
    from vidstyle.formats.poses import write_poses
    from vidstyle.pose.run import estimate_video

    out = []
    for video in videos:
        path = cache / f"{video.stem}.poses.json"
        if fresh or not _usable(path, video):
            t = time.time()
            write_poses(path, estimate_video(video, "blazepose", jobs=jobs))
            log.info("%s: %s (%.0f s)", video.name, path, time.time() - t)
        else:
            log.info("%s: cached %s", video.name, path)
        out.append(path)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calibration", type=Path, default=CALIBRATION)
    ap.add_argument("--videos", type=Path, nargs="+", default=VIDEOS, help="The calibrated views' videos.")
    ap.add_argument("--poses", type=Path, nargs="+", default=None, help="Use these poses files instead of the "
                    "videos (blazepose, with world keypoints; a file whose name contains a camera's name is that "
                    "camera's).")
    ap.add_argument("--cache", type=Path, default=DEFAULT_CACHE, help="Where the videos' poses files are kept.")
    ap.add_argument("--fresh", action="store_true", help="Estimate the poses again even when cached.")
    ap.add_argument("--min-score", type=float, default=0.0, help="2D keypoints at or below this score are not "
                    "triangulated.")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    from vidstyle.reconstruct.reference import summary, triangulated_reference

    try:
        poses = args.poses or poses_of_videos(args.videos, args.cache, args.fresh, args.jobs)
        t = time.time()
        ref = triangulated_reference(args.calibration, poses, min_score=args.min_score)
        log.info("triangulated in %.1f s", time.time() - t)
        doc = {**validation_header(RECONSTRUCT_REFERENCE), "script": "scripts/real_reference.py", **summary(ref)}
    except VidstyleError as e:
        log.error("%s", e)
        return 2
    doc["files"] = [Path(p).name for p in doc["files"]]  # the cache's place is not a result
    doc["calibration"] = Path(doc["calibration"]).name
    write_validation(args.out, doc)
    for name, v in doc["per_view"].items():
        b = v.get("blazepose_world_mpjpe_mm", {})
        log.info("%s: %d/%d keypoints with a reference, reprojection %s px, BlazePose world MPJPE %s mm "
                 "(sequence Kabsch), %s mm (camera rotation), %s mm (per frame)", name,
                 v["keypoints_with_reference"], doc["frames"] * doc["keypoints"], v["reprojection_px_agreeing"],
                 b.get("sequence_kabsch"), b.get("camera_rotation"), b.get("per_frame_procrustes"))
    log.info("wrote %s", args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
