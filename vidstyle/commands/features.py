"""``vidstyle features``: salient points and 3D SIFT descriptors, one ``.npz`` per video."""

from __future__ import annotations

import logging
from pathlib import Path

import typer

from ..features import defaults as D
from ._numbers import jobs_option, number

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:
    @app.command("features")
    def features(
        videos: list[Path] = typer.Argument(..., help="Input videos (anything FFmpeg decodes: mp4, mkv, avi, mov, ...)."),
        out: Path = typer.Option(
            ..., "--out", "-o", help="Output directory; writes <video stem>.npz per video."
        ),
        jobs: int = jobs_option(-1, help="Videos processed in parallel (-1 = all cores)."),
        scheduler: str = typer.Option(
            None, "--scheduler", help="Dask scheduler address (tcp://HOST:PORT): run the videos on that "
            "cluster instead of local workers; its workers must see the same paths.",
        ),
        variant: str = typer.Option(
            # scovanner2007 is the default because it recognises better on the demo's validation performers
            # (scripts/validate_recognition.py; pipelines/kickboxing/validation/recognition.json holds the
            # scores). Turning every neighbourhood to its dominant orientation, as the thesis variant does,
            # discards the direction of motion, which is what tells a jab from a hook.
            D.VARIANT,
            "--variant",
            help="Descriptor: 'scovanner2007' (default; the authors' released code: no rotation, 80 icosahedral "
            "bins, uint8, 640-D), 'thesis' (8x4 bins, rotation-invariant, float32, 256-D) or "
            "'sift2d' (ablation: 2D SIFT of "
            "the frame patch, 4x4 cells x 8 bins, rotation-invariant, 128-D).",
        ),
        fps: float = number(
            D.WORKING_FPS, "--fps", integer=False, lo=0, hi=1000, help="Working frame rate: the nearest decoded frame to each tick of a clock at "
            "this rate (the method's 20 fps; a slower video keeps its own frames; 0: every decoded frame).",
        ),
        height: int = number(
            D.WORKING_HEIGHT, "--height", lo=8, hi=8640, also=(0,), help="Working frame height in pixels, width keeping the aspect ratio (120 keeps "
            "the demo's 160x120 and turns a 1080x1920 phone clip into 68x120; 0: the video's own size).",
        ),
        points: int = number(D.N_POINTS, "--points", "-n", lo=1, hi=10000, help="Salient points per frame (default: chosen on validation performers and a validation camera, pipelines/kickboxing/validation/recognition.json; thesis: 10)."),
        threshold: float = number(
            D.THRESHOLD,
            "--threshold", lo=0, hi=1,
            help="Silhouette threshold on |frame(t+1) - frame(t-1)|, intensities in [0, 1].",
        ),
        min_distance: float = number(
            D.MIN_DISTANCE, "--min-distance", integer=False, lo=0, hi=10000, help="Minimum distance in pixels between the points of one frame."
        ),
        flow: str = typer.Option(
            D.FLOW, "--flow", help="Optical flow: dis, dis-ultrafast, dis-medium, farneback."
        ),
        subregions: int = number(
            D.SUBREGIONS, "--subregions", lo=1, hi=16, help="Thesis variant: sub-regions per axis (2 -> 2x2x2 -> 256-D; 4 -> 1024-D)."
        ),
        subregion_size: float = number(
            D.SUBREGION_SIZE, "--subregion-size", integer=False, lo=0, lo_open=True, hi=1000, help="Thesis variant: sub-region edge in pixels and frames."
        ),
        smooth: float = number(
            D.SMOOTH, "--smooth", integer=False, lo=0, hi=100, help="Thesis variant: Gaussian smoothing sigma of the volume before gradients."
        ),
    ) -> None:
        """Extract per-frame salient points (largest optical flow on the frame-difference silhouette) and
        their 3D SIFT descriptors from each VIDEO at a working rate and size, streaming the video in
        windows of frames (memory does not grow with its length), writing OUT/<stem>.npz (schema
        vidstyle.features 2: points, descriptors, working fps/size, the decoded frame index of every
        working frame)."""
        from ..features.extract import extract_videos
        from ._flags import as_flags

        with as_flags(jobs="--jobs", scheduler="--scheduler", variant="--variant", fps="--fps",
                      height="--height"):
            done = extract_videos(
                videos, out, variant=variant, fps=fps, height=height, points=points, threshold=threshold,
                min_distance=min_distance, flow=flow, subregions=subregions, subregion_size=subregion_size,
                smooth=smooth, jobs=jobs, scheduler=scheduler,
            )
        total = sum(d["points"] for d in done)
        log.info("features: %d video(s), %d points -> %s", len(done), total, out)
