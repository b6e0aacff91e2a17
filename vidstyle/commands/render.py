"""``vidstyle render``: mocap (BVH) -> video + per-frame ground-truth sidecar."""

from __future__ import annotations

import logging
import re
from pathlib import Path

import numpy as np
import typer

from ..errors import InputError

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:
    app.command("render")(render)


def parse_size(text: str) -> tuple[int, int]:
    """``"160x120"`` -> ``(160, 120)``."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*", text or "")
    if not m:
        raise InputError(f"--size: expected WIDTHxHEIGHT such as 160x120, got {text!r}")
    w, h = int(m.group(1)), int(m.group(2))
    if not (2 <= w <= 8192 and 2 <= h <= 8192):
        raise InputError(f"--size: {w}x{h} is out of range (2..8192 per side)")
    return w, h


def load_labels(path: Path, n_frames: int) -> tuple[list[str], np.ndarray | None]:
    """Labels (one per mocap frame) and transition flags of a labels file (:mod:`vidstyle.formats.labels`)."""
    from ..formats.labels import check_length, read_labels

    track = read_labels(path)
    check_length(track, n_frames, "the motion")
    flags = None
    if track.transitions is not None:
        flags = np.zeros(n_frames, dtype=bool)
        flags[track.transitions] = True
    return track.labels, flags


def _appearance(spec: str):
    from ..render import Appearance

    if spec == "default":
        return Appearance()
    if re.fullmatch(r"\d+", spec):
        return Appearance.random(int(spec))
    path = Path(spec)
    if path.suffix.lower() == ".json":
        from ..fileio import read_json

        try:
            return Appearance.from_dict(read_json(path))
        except (TypeError, ValueError) as e:
            raise InputError(f"{path}: not a valid appearance ({e})") from None
    raise InputError(f"--appearance: expected 'default', a seed (integer) or a .json file, got {spec!r}")


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
    from ..mocap import read_bvh
    from ..render import Camera, render_to_file
    from ..render.background import parse_background
    from ..render.camera import parse_view
    from ..video import CODECS

    wh = parse_size(size)
    if out.suffix.lower() not in CODECS:
        raise InputError(f"--out {out}: video must end in {', '.join(CODECS)}")
    if not (fps > 0 and np.isfinite(fps)):
        raise InputError(f"--fps: must be positive, got {fps}")
    if not noise >= 0:
        raise InputError(f"--noise: must be >= 0, got {noise}")
    try:
        parse_view(view)
        parse_background(background)
    except ValueError as e:
        raise InputError(f"{e}") from None
    look = _appearance(appearance)
    motion = read_bvh(motion_file)
    if motion.n_frames == 0:
        raise InputError(f"{motion_file}: the motion has no frames")
    lab, trans = load_labels(labels, motion.n_frames) if labels is not None else (None, None)
    try:
        camera = Camera.for_view(motion, view=view, elevation_deg=elevation, distance=distance, size=wh)
        side = render_to_file(motion, out, camera=camera, fps=fps, appearance=look, background=background,
                              noise_sigma=noise, seed=seed, labels=lab, transitions=trans)
    except ValueError as e:
        raise InputError(f"{motion_file}: {e}") from None
    log.info("wrote %s and %s", out, side)
