"""``vidstyle mocap``: inspect and convert BVH files."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import typer

from ..errors import InputError

log = logging.getLogger(__name__)

mocap_app = typer.Typer(help="Inspect and convert motion capture (BVH) files.", no_args_is_help=True)


def register(app: typer.Typer) -> None:
    app.add_typer(mocap_app, name="mocap")


@mocap_app.command("info")
def info(
    file: Path = typer.Argument(..., help="BVH file."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table."),
) -> None:
    """Joints, frames, fps, duration, bounding box (joints and End Sites, all frames), leg length, and
    where the 15 body keypoints sit on the skeleton (by name or by topology)."""
    from ..mocap import read_bvh
    from ..mocap.describe import describe

    summary = describe(read_bvh(file), file)
    keypoints, keypoint_error = summary["keypoints"], summary["keypoint_error"]
    if as_json:
        typer.echo(json.dumps(summary, indent=2))
        return
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    table = Table(title=escape(str(file)), show_header=False)
    for key in ("joints", "frames", "fps", "duration_s", "channels", "end_sites", "leg_length", "bbox_min", "bbox_max"):
        val = summary[key]
        table.add_row(key, f"{val:g}" if isinstance(val, float) else str(val))
    if keypoints is None:
        table.add_row("keypoints", escape(f"not mapped: {keypoint_error}"))
    else:
        for k, m in keypoints.items():
            where = f"{m['joint']} End Site" if m["end_site"] else m["joint"]
            table.add_row(f"keypoint {k}", escape(f"{where} (by {m['how']})"))
    Console().print(table)


@mocap_app.command("positions")
def positions(
    file: Path = typer.Argument(..., help="BVH file."),
    out: Path = typer.Option(..., "--out", "-o", help="OUT.npy (frames x joints x 3) or OUT.csv."),
) -> None:
    """Global joint positions (frames x joints x 3, joints in file order) to .npy or .csv.

    The CSV has one row per frame and columns ``<joint>_x, <joint>_y, <joint>_z`` for every joint.
    """
    import numpy as np

    from ..fileio import atomic_path, write_npy
    from ..mocap import global_positions, read_bvh

    suffix = out.suffix.lower()
    if suffix not in (".npy", ".csv"):
        raise InputError(f"{out}: output must end in .npy or .csv")
    motion = read_bvh(file)
    pos = global_positions(motion)
    if suffix == ".npy":
        write_npy(out, pos.astype(np.float64))
    else:
        header = ",".join(f"{n}_{a}" for n in motion.skeleton.names for a in "xyz")
        with atomic_path(out) as tmp:
            np.savetxt(tmp, pos.reshape(motion.n_frames, -1), delimiter=",", header=header, comments="", fmt="%.6f")
    log.info("wrote %s (%d frames x %d joints x 3)", out, motion.n_frames, motion.n_joints)


@mocap_app.command("convert")
def convert(
    src: Path = typer.Argument(..., help="Input BVH."),
    dst: Path = typer.Argument(..., help="Output BVH."),
    fps: float = typer.Option(None, "--fps", help="Resample to this frame rate (slerp)."),
    mirror: bool = typer.Option(False, "--mirror", help="Swap left and right (mirror image)."),
    normalize_facing: bool = typer.Option(
        False, "--normalize-facing", help="Rotate about the vertical so frame 0 faces +Z, root over the origin."
    ),
    start: int = typer.Option(None, "--start", help="First frame to keep (0-based)."),
    stop: int = typer.Option(None, "--stop", help="Frame after the last to keep."),
) -> None:
    """Rewrite a BVH, optionally cut, resampled, mirrored or facing-normalised."""
    from ..mocap.describe import convert as convert_bvh

    motion = convert_bvh(src, dst, start=start, stop=stop, fps=fps, mirror=mirror, normalize_facing=normalize_facing)
    log.info("wrote %s (%d frames at %g fps)", dst, motion.n_frames, motion.fps)
