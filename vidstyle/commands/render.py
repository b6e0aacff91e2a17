"""``vidstyle render``: mocap (BVH) -> video + per-frame ground-truth sidecar."""

from __future__ import annotations

import logging
import re
from pathlib import Path

import typer

from ..errors import InputError
from ._flags import as_flags

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:
    app.command("render")(render)


def parse_size(text: str, flag: str = "--size") -> tuple[int, int]:
    """``"160x120"`` -> ``(160, 120)``; errors name ``flag``."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*", text or "")
    if not m:
        raise InputError(f"{flag}: expected WIDTHxHEIGHT such as 160x120, got {text!r}")
    w, h = int(m.group(1)), int(m.group(2))
    if not (2 <= w <= 8192 and 2 <= h <= 8192):
        raise InputError(f"{flag}: {w}x{h} is out of range (2..8192 per side)")
    return w, h


def render(
    motion_file: Path = typer.Argument(..., metavar="MOTION.bvh", help="Motion to render (BVH)."),
    out: Path = typer.Option(..., "--out", "-o", help="Video to write (.mp4 or .avi); the sidecar "
                             "<stem>.truth.npz is written beside it."),
    view: str = typer.Option("front", "--view", help="front, left, right, back or an azimuth in degrees "
                             "relative to the performer's facing (+90 = their left side)."),
    elevation: float = typer.Option(10.0, "--elevation", help="Camera elevation in degrees."),
    distance: float = typer.Option(None, "--distance", help="Camera distance (motion units); default: "
                                   "fit the whole clip in the image."),
    size: str = typer.Option("160x120", "--size", help="WIDTHxHEIGHT in pixels."),
    fps: float = typer.Option(20.0, "--fps", help="Video frame rate (the motion is resampled)."),
    background: str = typer.Option("plain", "--background", help="plain or texture (or texture:brick|grass|gravel)."),
    appearance: str = typer.Option("default", "--appearance", help="Performer look: 'default', an integer "
                                   "seed for a random look, or an appearance .json."),
    noise: float = typer.Option(2.0, "--noise", help="Sensor noise sigma (grey levels)."),
    seed: int = typer.Option(0, "--seed", help="Seed of background choice and noise."),
    labels: Path = typer.Option(None, "--labels", help='Labels JSON of the motion (vidstyle.formats.labels: '
                                '"labels" one per mocap frame, optional "transitions" frame indices), e.g. a '
                                'demo mocap/<take>.labels.json.'),
) -> None:
    """Render a BVH motion to video with per-frame ground truth (2D/3D joints, visibility, camera, labels)."""
    from ..render.bvh import render_bvh

    with as_flags(out="--out", noise_sigma="--noise", elevation_deg="--elevation"):
        side = render_bvh(motion_file, out, view=view, elevation_deg=elevation, distance=distance,
                          size=parse_size(size), fps=fps, background=background, appearance=appearance,
                          noise_sigma=noise, seed=seed, labels=labels)
    log.info("wrote %s and %s", out, side)
