"""Several demo performers in one scene, filmed by calibrated cameras, with every person's true 2D pose:
the take on which following one performer is measured (``vidstyle demo make-crowd``).

Two (or more) procedural performers are placed on the floor facing each other as sparring partners and
rendered separately by the same cameras over the same background and noise (same seed); the frames are
then composited per frame front to back by each person's distance to the camera (a person occludes
another as a whole, which holds for people standing apart). The cameras stand around the pair at equal
azimuths, a little above them, each far enough to see everyone. Written into ``out``:

- ``cam01.mp4 ... camNN.mp4``: the videos;
- ``calibration.toml``: the cameras (OpenCV / Pose2Sim TOML, :mod:`vidstyle.formats.calibration`; mm);
- ``truth.npz``: ``keypoints2d`` (V, P, F, 15, 2) every person's true keypoints in every view (pixels),
  ``depth`` (V, P, F) each person's root depth, ``keypoints3d`` (P, F, 15, 3) in mm, ``performers`` (P,)
  ids, ``fps``.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from ..fileio import staged_dir
from ..formats.calibration import Calibration, CameraCalibration, calibration_toml
from ..mocap import Motion, forward_kinematics
from ..mocap.keypoints import keypoint_positions
from ..mocap.placement import Placement
from .dataset import DatasetParams, make_performer, make_take
from .skeleton import UNIT_M

KEYPOINTS_FILE = "truth.npz"


def _placed(motion: Motion, placement: Placement) -> Motion:
    rot, root = placement.apply_frames(motion.rotations, motion.translations[:, 0])
    return Motion(motion.skeleton, rot, motion.translations, motion.fps, root_positions=root)


def _face(motion: Motion, angle: float, x: float, z: float) -> Motion:
    """The motion turned to face ``angle`` (radians, about +Y; 0 = +Z) with its start root at (x, z)."""
    facing = float(np.median(motion.facing_angles()))
    p = Placement.facing(facing, motion.translations[0, 0], angle, origin=True)
    return _placed(_placed(motion, p), Placement(0.0, x, z))


def scene_motions(n_people: int = 2, seconds: float = 6.0, fps: float = 20.0, seed: int = 0,
                  spacing_m: float = 1.8) -> tuple[list[Motion], list[str]]:
    """``n_people`` demo performers' performance takes, standing ``spacing_m`` apart on a circle, facing
    its centre (sparring partners for two)."""
    params = DatasetParams(seed=seed, fps=int(fps), performance_seconds=seconds, render=False)
    motions, ids = [], []
    radius = spacing_m / UNIT_M / (2 * math.sin(math.pi / n_people)) if n_people > 1 else 0.0
    for i in range(n_people):
        performer = make_performer(params, i)
        take = make_take(params, performer, i, 100)
        a = 2 * math.pi * i / n_people
        x, z = radius * math.sin(a), radius * math.cos(a)
        motions.append(_face(take.motion, a + math.pi, x, z))
        ids.append(performer.id)
    return motions, ids


def scene_cameras(motions: list[Motion], n_views: int = 4, size: tuple[int, int] = (320, 240),
                  elevation_deg: float = 12.0, first_azimuth_deg: float = 30.0):
    """Render cameras around the group: equal azimuths (world), each seeing every joint of everyone."""
    from ..render.camera import Camera

    pos = np.concatenate([forward_kinematics(m)[0] for m in motions], axis=1)
    # for_view's azimuth is relative to the first motion's facing: turn it into a world azimuth
    facing = math.degrees(float(np.median(motions[0].facing_angles())))
    cams = []
    for v in range(n_views):
        az = first_azimuth_deg + 360.0 * v / n_views
        cams.append(Camera.for_view(motions[0], view=az - facing, elevation_deg=elevation_deg, size=size,
                                    positions=pos, margin=0.05))
    return cams


def to_calibration(cams, names: list[str]) -> Calibration:
    """Render cameras (world units of the demo skeleton) as a calibration in millimetres."""
    mm = UNIT_M * 1000.0
    return Calibration([CameraCalibration(n, tuple(c.size), c.K.copy(), c.R.copy(), c.t * mm, np.zeros(5))
                        for n, c in zip(names, cams)])


def make_crowd(out: str | os.PathLike, n_people: int = 2, n_views: int = 4, seconds: float = 6.0,
               fps: float = 20.0, size: tuple[int, int] = (320, 240), seed: int = 0) -> Path:
    """Write the scene (module docstring) into ``out`` (replaced whole, atomically)."""
    from ..render import Appearance, render_motion
    from ..video import write_video

    out = Path(out)
    motions, ids = scene_motions(n_people, seconds, fps, seed)
    cams = scene_cameras(motions, n_views, size)
    names = [f"cam{v + 1:02d}" for v in range(n_views)]
    kp3 = np.stack([keypoint_positions(m.resample(fps) if abs(m.fps - fps) > 1e-6 else m) for m in motions])
    F = kp3.shape[1]
    kp2 = np.empty((n_views, n_people, F, 15, 2))
    depth = np.empty((n_views, n_people, F))
    with staged_dir(out, overwrite=True) as tmp:
        for v, cam in enumerate(cams):
            layers = []
            for p, m in enumerate(motions):
                frames, truth, masks = render_motion(m, cam, fps=fps, appearance=Appearance.random(seed * 1000 + p + 1),
                                                     seed=seed * 1000 + v, return_masks=True)
                layers.append((frames[:F], masks[:F]))
                uv, z = cam.project(kp3[p])
                kp2[v, p], depth[v, p] = uv, z.mean(axis=1)
            video = []
            for f in range(F):
                order = np.argsort(-depth[v, :, f])  # far to near
                img = layers[order[0]][0][f].copy()
                for p in order[1:]:
                    fr, mk = layers[p]
                    sel = mk[f] >= 0
                    img[sel] = fr[f][sel]
                video.append(img)
            write_video(video, tmp / f"{names[v]}.mp4", fps)
        (tmp / "calibration.toml").write_text(calibration_toml(to_calibration(cams, names)))
        np.savez_compressed(tmp / KEYPOINTS_FILE, keypoints2d=kp2.astype(np.float32), depth=depth.astype(np.float32),
                            keypoints3d=(kp3 * UNIT_M * 1000.0).astype(np.float32), performers=np.array(ids),
                            fps=np.float64(fps), views=np.array(names))
    return out
