#!/usr/bin/env python
"""Whole video to 3D beyond the demo's renders (issue 29): CMU subjects the library never saw, and the real
pose2sim take reconstructed from each calibrated view alone against the 3D triangulated from all four.

- CMU: :func:`vidstyle.evaluation.reconstruct.evaluate_cmu_heldout`. The library: every clip of subjects
  01, 02, 05, 06; the test: the first 20 s of every clip of subjects 07 and 08 (each subject in one
  role), filmed by the reconstruction's camera model at seeded cameras; true 2D and true 2D plus 5 %
  torso noise.
- CMU rendered: the same subjects' clips rendered by ``vidstyle demo make-cmu-dataset`` (front view, at
  most 4 windows of 4 s per subject and action), 2D poses estimated on the renders by the shipped
  pictorial structures and by BlazePose (every frame; cached), scored by
  :func:`vidstyle.evaluation.reconstruct.evaluate` on subjects 07 and 08's videos against the library of
  subjects 01, 02, 05, 06 (skeletons: the library's and the subject's own).
- Real: :func:`vidstyle.evaluation.reconstruct.evaluate_real`. The library: all 86 CMU clips (no subject
  of them is the pose2sim performer); BlazePose 2D of each view (cached as scripts/real_reference.py
  caches them), against the triangulated reference; BlazePose's own 3D world landmarks scored alike.

    python scripts/reconstruct_heldout.py [--skip-real] [--skip-cmu] [--skip-cmu-rendered]

A skipped part keeps what ``--out`` already holds for the same seed. Writes ``--out`` (default
``pipelines/kickboxing/results/reconstruct_heldout.json``); logs on stderr.
"""

from __future__ import annotations

import argparse
import importlib.util
import logging
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("GLOG_minloglevel", "2")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vidstyle.errors import VidstyleError
from vidstyle.formats.validation import RECONSTRUCT_HELDOUT, read_validation, validation_header, write_validation

log = logging.getLogger("reconstruct_heldout")
ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
CMU = SHARED / "mocap" / "cmu"
DEFAULT_OUT = ROOT / "pipelines" / "kickboxing" / "results" / "reconstruct_heldout.json"


def _real_reference_module():
    spec = importlib.util.spec_from_file_location("real_reference", Path(__file__).with_name("real_reference.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--skip-real", action="store_true")
    ap.add_argument("--skip-cmu", action="store_true")
    ap.add_argument("--skip-cmu-rendered", action="store_true")
    ap.add_argument("--cache", type=Path, default=Path(os.environ.get("TMPDIR", "/tmp")) / "vidstyle_reconstruct_heldout")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s", stream=sys.stderr)
    from vidstyle.evaluation.reconstruct import evaluate_cmu_heldout, evaluate_real

    doc = {**validation_header(RECONSTRUCT_HELDOUT), "script": "scripts/reconstruct_heldout.py", "seed": args.seed}
    if args.out.is_file():  # a skipped part keeps what the file holds (the same seed's)
        old = read_validation(args.out, RECONSTRUCT_HELDOUT)
        if old.get("seed") == args.seed:
            for part, skipped in (("cmu", args.skip_cmu), ("cmu_rendered", args.skip_cmu_rendered),
                                  ("real", args.skip_real)):
                if skipped and part in old:
                    doc[part] = old[part]
                    log.info("%s: kept from %s", part, args.out)
    try:
        if not args.skip_cmu:
            doc["cmu"] = evaluate_cmu_heldout(CMU, LIBRARY_SUBJECTS, TEST_SUBJECTS, seed=args.seed, jobs=args.jobs)
        if not args.skip_cmu_rendered:
            doc["cmu_rendered"] = cmu_rendered(args.cache, args.seed, args.jobs)
        if not args.skip_real:
            rr = _real_reference_module()
            poses = rr.poses_of_videos(rr.VIDEOS, rr.DEFAULT_CACHE, False, args.jobs)
            doc["real"] = evaluate_real(rr.CALIBRATION, poses, rr.VIDEOS, [CMU], jobs=args.jobs)
    except VidstyleError as e:
        log.error("%s", e)
        return 2
    write_validation(args.out, doc)
    for part in ("cmu", "cmu_rendered", "real"):
        for r in (doc.get(part) or {}).get("runs", []):
            if r["data"].startswith(("cmu held-out", "real pose2sim", "demo test performers")):
                log.info("%s %s %s: root-relative MPJPE %s mm, PA %s mm, accel %s, skate %s", r["data"], r["source"],
                         r["method"], _f(r["mpjpe_root_relative_mm"]), _f(r["pa_mpjpe_mm"]),
                         _f(r["acceleration_error_mm_per_frame2"]), _f(r["foot_skate_mm_per_frame"]))
    log.info("wrote %s", args.out)
    return 0


LIBRARY_SUBJECTS = ["01", "02", "05", "06"]
TEST_SUBJECTS = ["07", "08"]


def cmu_rendered(cache: Path, seed: int, jobs: int) -> dict:
    """Held-out CMU subjects rendered to video, with estimated 2D (module docstring)."""
    from vidstyle.demo.cmu import CMUParams, make_cmu_dataset, parse_actions
    from vidstyle.evaluation.reconstruct import evaluate
    from vidstyle.formats.dataset import read_dataset
    from vidstyle.formats.poses import write_poses
    from vidstyle.pose.run import estimate_video

    ds = cache / f"cmu_dataset_seed{seed}"
    if not (ds / "dataset.json").is_file():
        make_cmu_dataset(CMU, ds, CMUParams(seed=seed, classes=parse_actions("walk,run,jump,punch,dance,basketball"),
                                            views=("front",), max_per_subject=4), overwrite=True, jobs=jobs)
    dataset = read_dataset(ds)
    videos = sorted(v.id for v in dataset.videos if v.performer in {f"s{s}" for s in TEST_SUBJECTS})
    dirs = []
    for backend in ("ps", "blazepose"):
        d = cache / f"poses_{backend}_seed{seed}"
        d.mkdir(parents=True, exist_ok=True)
        for v in videos:
            path = d / f"{v}.poses.json"
            if not path.is_file():
                write_poses(path, estimate_video(ds / dataset.by_id()[v].video, backend, jobs=jobs))
        dirs.append(d)
    lib = sorted(str(f) for s in LIBRARY_SUBJECTS for f in CMU.glob(f"{s}_*.bvh"))
    out = evaluate(ds, lib, videos=videos, poses_dirs=dirs, methods=("nn", "olng", "subsequence"), seed=seed,
                   unit_mm=56.44, jobs=jobs)
    for r in out["runs"]:
        if r["data"] == "demo test performers":
            r["data"] = "cmu rendered held-out subjects"
    out["library_subjects"], out["test_subjects"] = LIBRARY_SUBJECTS, TEST_SUBJECTS
    from vidstyle.pose.defaults import PS_SCALES
    from vidstyle.reconstruct.defaults import VIEW_DWELL_S, VIEW_STEP_COST

    # the 2D: the pictorial structures at the pose command's default zooms, their views tracked as the
    # reconstruction tracks them by default
    out["ps_scales"], out["view_step_cost"], out["view_dwell_s"] = list(PS_SCALES), VIEW_STEP_COST, VIEW_DWELL_S
    return out


def _f(x):
    return "-" if x is None else f"{x:.1f}"


if __name__ == "__main__":
    sys.exit(main())
