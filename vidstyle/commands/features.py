"""``vidstyle features``: salient points and 3D SIFT descriptors, one ``.npz`` per video."""

from __future__ import annotations

import logging
from pathlib import Path

import typer

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:
    @app.command("features")
    def features(
        videos: list[Path] = typer.Argument(..., help="Input videos (anything FFmpeg decodes: mp4, mkv, avi, mov, ...)."),
        out: Path = typer.Option(
            ..., "--out", "-o", help="Output directory; writes <video stem>.npz per video."
        ),
        jobs: int = typer.Option(-1, "--jobs", "-j", help="Videos processed in parallel (-1: all cores)."),
        scheduler: str = typer.Option(
            None, "--scheduler", help="Dask scheduler address (tcp://HOST:PORT): run the videos on that "
            "cluster instead of local workers; its workers must see the same paths.",
        ),
        variant: str = typer.Option(
            # scovanner2007 is the default because it recognises better on the demo's validation performers
            # (scripts/validate_recognition.py; pipelines/kickboxing/validation/recognition.json holds the
            # scores). Turning every neighbourhood to its dominant orientation, as the thesis variant does,
            # discards the direction of motion, which is what tells a jab from a hook.
            "scovanner2007",
            "--variant",
            help="Descriptor: 'scovanner2007' (default; the authors' released code: no rotation, 80 icosahedral "
            "bins, uint8, 640-D), 'thesis' (8x4 bins, rotation-invariant, float32, 256-D) or "
            "'sift2d' (ablation: 2D SIFT of "
            "the frame patch, 4x4 cells x 8 bins, rotation-invariant, 128-D).",
        ),
        fps: float = typer.Option(
            20.0, "--fps", help="Working frame rate: the nearest decoded frame to each tick of a clock at "
            "this rate (the method's 20 fps; a slower video keeps its own frames; 0: every decoded frame).",
        ),
        height: int = typer.Option(
            120, "--height", help="Working frame height in pixels, width keeping the aspect ratio (120 keeps "
            "the demo's 160x120 and turns a 1080x1920 phone clip into 68x120; 0: the video's own size).",
        ),
        points: int = typer.Option(10, "--points", "-n", help="Salient points per frame (default: chosen on validation performers and a validation camera, pipelines/kickboxing/validation/recognition.json; thesis: 10)."),
        threshold: float = typer.Option(
            0.05,
            "--threshold",
            help="Silhouette threshold on |frame(t+1) - frame(t-1)|, intensities in [0, 1].",
        ),
        min_distance: float = typer.Option(
            5.0, "--min-distance", help="Minimum distance in pixels between the points of one frame."
        ),
        flow: str = typer.Option(
            "dis", "--flow", help="Optical flow: dis, dis-ultrafast, dis-medium, farneback."
        ),
        subregions: int = typer.Option(
            2, "--subregions", help="Thesis variant: sub-regions per axis (2 -> 2x2x2 -> 256-D; 4 -> 1024-D)."
        ),
        subregion_size: float = typer.Option(
            4.0, "--subregion-size", help="Thesis variant: sub-region edge in pixels and frames."
        ),
        smooth: float = typer.Option(
            1.0, "--smooth", help="Thesis variant: Gaussian smoothing sigma of the volume before gradients."
        ),
    ) -> None:
        """Extract per-frame salient points (largest optical flow on the frame-difference silhouette) and
        their 3D SIFT descriptors from each VIDEO at a working rate and size, streaming the video in
        windows of frames (memory does not grow with its length), writing OUT/<stem>.npz (schema
        vidstyle.features 2: points, descriptors, working fps/size, the decoded frame index of every
        working frame)."""
        from ..errors import InputError
        from ..features.descriptors import REGISTRY
        from ..features.extract import run_features
        from ..features.salient import SalientParams
        from ..features.sift3d import Sift3DParams

        if variant not in REGISTRY:
            raise InputError(f"--variant: expected one of {', '.join(REGISTRY)}, got {variant!r}")
        if jobs == 0:
            raise InputError("--jobs: must be a positive number of workers or -1 for all cores")
        if fps < 0 or height < 0 or 0 < height < 8:
            raise InputError("--fps must be >= 0 and --height 0 or at least 8")
        if variant != "thesis" and (subregions != 2 or subregion_size != 4.0 or smooth != 1.0):
            raise InputError(f"--variant {variant}: --subregions/--subregion-size/--smooth do not apply")
        salient = SalientParams(n_points=points, threshold=threshold, min_distance=min_distance, flow=flow)
        sift = (
            Sift3DParams(n_subregions=subregions, subregion_size=subregion_size, smooth_sigma=smooth)
            if variant == "thesis"
            else None
        )
        from ._flags import as_flags

        with as_flags(jobs="--jobs", scheduler="--scheduler", variant="--variant", fps="--fps",
                      height="--height"):
            done = run_features(
                [str(v) for v in videos], out, jobs=jobs, variant=variant, salient=salient, params=sift,
                scheduler=scheduler, fps=fps or None, height=height or None,
            )
        total = sum(d["points"] for d in done)
        log.info("features: %d video(s), %d points -> %s", len(done), total, out)
