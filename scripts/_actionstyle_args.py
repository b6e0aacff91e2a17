"""Command-line options shared by the scripts that validate the action-level style on the pipeline's
pose-stage 2D (validate_action_style_poses.py, validate_lead_cue.py)."""

from __future__ import annotations

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def pose_run_arguments(ap: argparse.ArgumentParser, out: str) -> None:
    """--run, --seed, --frames, --poses and --out (default ``pipelines/kickboxing/validation/<out>``)."""
    ap.add_argument("--run", type=Path, default=ROOT / "pipelines" / "kickboxing" / "out",
                    help="The pipeline's run directory (dataset/, recognized/).")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--frames", type=int, default=200, help="First frames of each take (params.yaml reconstruct.frames).")
    ap.add_argument("--poses", type=Path, default=None, help="Keep the pose files here (default: a temporary directory).")
    ap.add_argument("--out", type=Path, default=ROOT / "pipelines" / "kickboxing" / "validation" / out)
