"""Render a motion to video frames with per-frame ground truth (see :mod:`vidstyle.render`)."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..fileio import atomic_path
from ..formats.truth import truth_arrays
from ..mocap import Motion, facing_directions, forward_kinematics
from .appearance import Appearance
from .background import NoiseBank, make_background
from .body import TORSO_KINDS, BodyModel, build_body
from .camera import Camera
from .raster import Rasterizer
from ..video import CODECS, VideoWriter

SIDECAR_SUFFIX = ".truth.npz"


def sidecar_path(video: str | os.PathLike) -> Path:
    """``clip.mp4`` -> ``clip.truth.npz`` (beside the video)."""
    video = Path(video)
    return video.with_name(video.stem + SIDECAR_SUFFIX)


def _map_labels(labels, n_src: int, src_fps: float, times: np.ndarray) -> np.ndarray:
    out = np.full(len(times), "", dtype=object)
    if labels is None:
        return out.astype(str)
    labels = list(labels)
    if len(labels) != n_src:
        raise ValueError(f"labels: {len(labels)} given for {n_src} motion frames")
    idx = np.clip(np.rint(times * src_fps).astype(np.int64), 0, n_src - 1)
    out[:] = [str(labels[i]) if labels[i] is not None else "" for i in idx]
    return out.astype(str)


def _map_transitions(transitions, n_src: int, src_fps: float, fps: float, n_out: int) -> np.ndarray:
    out = np.zeros(n_out, dtype=bool)
    if transitions is None:
        return out
    tr = np.asarray(transitions)
    if tr.dtype != bool:
        raise ValueError("transitions must be a per-motion-frame bool array")
    if tr.shape != (n_src,):
        raise ValueError(f"transitions: {tr.shape} given for {n_src} motion frames")
    # every flagged source frame marks the video frame nearest in time (none is lost when downsampling)
    k = np.flatnonzero(tr)
    out[np.clip(np.rint(k / src_fps * fps).astype(np.int64), 0, n_out - 1)] = True
    return out


class RenderJob:
    """Everything precomputed (vectorised over frames) for rendering one motion from one camera
    (:func:`render_motion` and :func:`render_to_file` build one; ``scripts/bench_render.py`` times its
    parts). ``frames()`` yields the rendered frames."""

    def __init__(self, motion: Motion, camera: Camera, fps: float, appearance: Appearance | None,
                 background, noise_sigma: float, seed: int, labels, transitions) -> None:
        if not (fps and fps > 0 and math.isfinite(fps)):
            raise ValueError(f"fps must be positive, got {fps}")
        if motion.n_frames == 0:
            raise ValueError("motion has no frames")
        if not noise_sigma >= 0:
            raise ValueError(f"noise_sigma must be >= 0, got {noise_sigma}")
        src = motion
        if abs(motion.fps - fps) > 1e-6 * fps:
            motion = motion.resample(fps)
        self.motion = motion
        self.camera = camera
        self.fps = float(fps)
        self.appearance = appearance if appearance is not None else Appearance()
        F = motion.n_frames
        self.n_frames = F
        times = np.arange(F) / self.fps
        self.source_time = np.minimum(times, src.duration)
        self.labels = _map_labels(labels, src.n_frames, src.fps, self.source_time)
        self.transition = _map_transitions(transitions, src.n_frames, src.fps, self.fps, F)

        body = build_body(motion.skeleton, self.appearance)
        self.body: BodyModel = body
        pos, mats = forward_kinematics(motion)
        self.joints3d = pos
        kp = body.keypoints(pos, mats)
        ends = body.capsule_ends(kp)  # (F, C, 2, 3)
        cam = camera.to_camera(ends)
        z = cam[..., 2]
        Kf = camera.K
        with np.errstate(divide="ignore", invalid="ignore"):
            zs = np.where(z > 1e-9, z, np.nan)
            u = Kf[0, 0] * cam[..., 0] / zs + Kf[0, 2]
            v = Kf[1, 1] * cam[..., 1] / zs + Kf[1, 2]
            self.rpx = (Kf[1, 1] * body.radii[None] / zs).astype(np.float64)
        self.uv = np.stack([u, v], axis=-1)
        self.z = np.nan_to_num(z, nan=-1.0)
        self.order = np.argsort(-self.z.mean(axis=2), axis=1, kind="stable")  # far to near
        self.ends = ends
        face = facing_directions(motion)
        self.face_cam = face @ camera.R.T

        j2d, jz = camera.project(pos)
        self.joints2d = j2d
        self.depth = jz
        # thickness of the body around each joint: largest radius of the capsules that touch it
        own = np.zeros(motion.n_joints)
        for c in range(body.n_capsules):
            for e in range(2):
                w = body.weights[2 * c + e]
                for j in np.flatnonzero(np.abs(w[: motion.n_joints]) > 0.5):
                    own[j] = max(own[j], body.radii[c, e])
        own[own == 0] = 0.03 * body.height
        self.own_radius = own
        self.visible = np.zeros((F, motion.n_joints), dtype=bool)  # filled by frames()

        rng = np.random.default_rng(seed)
        W, H = camera.size
        self.bg, self.background_desc = make_background(background, (W, H), rng)
        self.bg += 0.5  # rounding offset for the final truncating conversion
        self.noise = NoiseBank((W, H), noise_sigma, rng, n_fields=min(8, F))
        self.palette = np.zeros((16, 3), dtype=np.float32)  # indexed by material code (see raster)
        pal = self.appearance.palette()
        self.palette[: len(pal)] = pal
        self.raster = Rasterizer(W, H)
        self.outline_jump = 0.02 * body.height
        # capsule -> body volume for outlines (torso capsules form one volume); last entry: background
        grp = [0 if k in TORSO_KINDS else c + 1 for c, k in enumerate(body.kind)]
        self.outline_group = np.array(grp + [-1], dtype=np.int32)
        self.mask_dtype = np.int8 if motion.n_joints <= 127 else np.int16

    def frames(self, with_masks: bool = False) -> Iterator[tuple[np.ndarray, np.ndarray | None]]:
        """Yield ``(frame, mask or None)`` per video frame; fills ``self.visible`` as it goes."""
        body, ras = self.body, self.raster
        W, H = self.camera.size
        radii = body.radii.astype(np.float64)
        mat, split, head = body.material, body.split, body.is_head
        bg = np.ascontiguousarray(self.bg, dtype=np.float32)
        # joint pixels (rounded) for the visibility test; joints outside the image read pixel (0, 0)
        uv = self.joints2d
        ok = np.all(np.isfinite(uv), axis=2) & (self.depth > 0)
        col = np.rint(np.where(ok, uv[..., 0], -1)).astype(np.int64)
        row = np.rint(np.where(ok, uv[..., 1], -1)).astype(np.int64)
        ok &= (col >= 0) & (col < W) & (row >= 0) & (row < H)
        col[~ok] = 0
        row[~ok] = 0
        seen = np.empty((self.n_frames, self.motion.n_joints, 5), dtype=np.float32)
        for f in range(self.n_frames):
            ras.draw(self.uv[f], self.z[f], self.rpx[f], radii, mat, split, self.order[f], head, self.face_cam[f])
            frame = np.empty((H, W, 3), dtype=np.uint8)
            ras.render_frame(frame, bg, self.palette, self.outline_jump, self.outline_group, self.noise)
            seen[f] = ras.buf[row[f], col[f]]
            mask = ras.part_mask(body.owner, self.mask_dtype) if with_masks else None
            yield frame, mask
        self.visible = self._visibility(seen, ok)

    def _visibility(self, seen: np.ndarray, in_image: np.ndarray, block: int = 256) -> np.ndarray:
        """(F, J) visible: the joint's pixel shows the figure (coverage >= 0.5), and the surface seen
        there belongs to the joint's own body part:

        - the front-most capsule at the pixel contains the joint, or
        - it belongs to the same body volume as a capsule containing the joint (the torso is one volume
          of several capsules) and the joint lies in the near half of that volume (so the spine seen
          from the side is visible, the far hip is not), or
        - nothing lies in front of the joint by more than the thickness of the parts around it.
        """
        from .raster import CODE, COV, MAT_BITS, D

        F = in_image.shape[0]
        body = self.body
        H = body.height
        group = self.outline_group[:-1]  # capsule -> body volume
        G = int(group.max()) + 1
        onehot = np.zeros((body.n_capsules, G))
        onehot[np.arange(body.n_capsules), group] = 1.0
        onehot /= onehot.sum(axis=0, keepdims=True).clip(min=1.0)
        cid_all = np.floor(seen[..., CODE] / MAT_BITS).astype(np.int64)
        on_all = in_image & (cid_all >= 0) & (seen[..., COV] >= 0.5)
        out = np.zeros(in_image.shape, dtype=bool)
        for s0 in range(0, F, block):
            sl = slice(s0, min(s0 + block, F))
            a, b = self.ends[sl, :, 0], self.ends[sl, :, 1]  # (f, C, 3)
            p = self.joints3d[sl]  # (f, J, 3)
            ab = b - a
            L2 = np.einsum("fck,fck->fc", ab, ab)
            ap = p[:, :, None, :] - a[:, None]  # (f, J, C, 3)
            t = np.einsum("fjck,fck->fjc", ap, ab) / np.where(L2 > 0, L2, 1.0)[:, None]
            np.clip(t, 0.0, 1.0, out=t)
            dist = np.linalg.norm(ap - t[..., None] * ab[:, None], axis=-1)
            rad = body.radii[:, 0] + (body.radii[:, 1] - body.radii[:, 0]) * t
            contain = dist <= 1.15 * rad + 0.01 * H  # (f, J, C)
            cid = np.maximum(cid_all[sl], 0)
            fi = np.arange(cid.shape[0])[:, None]
            ji = np.arange(cid.shape[1])[None, :]
            inside = contain[fi, ji, cid]
            gstar = group[cid]  # (f, J)
            same = contain & (group[None, None, :] == gstar[..., None])
            in_volume = same.any(axis=-1)
            zc = (self.z[sl].mean(axis=2)) @ onehot  # (f, G) centre depth of each volume
            near_half = self.depth[sl] <= np.take_along_axis(zc, gstar, axis=1) + 0.03 * H
            front = seen[sl, :, D] >= self.depth[sl] - 1.1 * self.own_radius
            out[sl] = on_all[sl] & (inside | (in_volume & near_half) | front)
        return out

    def truth(self) -> dict[str, np.ndarray]:
        cam = self.camera
        sk = self.motion.skeleton
        return {
            "joints2d": self.joints2d.astype(np.float32),
            "joints3d": self.joints3d.astype(np.float32),
            "visible": self.visible.copy(),
            "depth": self.depth.astype(np.float32),
            "joint_names": np.array(sk.names, dtype=str),
            "parents": sk.parents.astype(np.int64),
            "K": cam.K.copy(),
            "R": cam.R.copy(),
            "t": cam.t.copy(),
            "azimuth_deg": np.float64(cam.azimuth_deg),
            "elevation_deg": np.float64(cam.elevation_deg),
            "facing_deg": np.float64(cam.facing_deg),
            "fps": np.float64(self.fps),
            "size": np.array(cam.size, dtype=np.int64),
            "labels": self.labels,
            "transition": self.transition.copy(),
            "source_time": self.source_time.astype(np.float64),
            "part_owner": self.body.owner.astype(np.int64),
            "appearance": np.array(json.dumps(self.appearance.to_dict())),
            "background": np.array(self.background_desc),
        }


def render_motion(
    motion: Motion,
    camera: Camera,
    fps: float = 20.0,
    appearance: Appearance | None = None,
    background="plain",
    noise_sigma: float = 2.0,
    seed: int = 0,
    labels: Sequence[str] | None = None,
    transitions: np.ndarray | None = None,
    return_masks: bool = False,
):
    """Render ``motion`` seen by ``camera`` at ``fps``.

    Returns ``(frames, truth)``: frames (F, H, W, 3) uint8 BGR and the ground-truth dict (sidecar
    schema in :mod:`vidstyle.render`); with ``return_masks=True`` also (F, H, W) part-id masks
    (int8; the joint index owning the front-most body part at the pixel, -1 for background).
    """
    job = RenderJob(motion, camera, fps, appearance, background, noise_sigma, seed, labels, transitions)
    W, H = camera.size
    frames = np.empty((job.n_frames, H, W, 3), dtype=np.uint8)
    masks = np.empty((job.n_frames, H, W), dtype=job.mask_dtype) if return_masks else None
    for f, (frame, mask) in enumerate(job.frames(return_masks)):
        frames[f] = frame
        if masks is not None:
            masks[f] = mask
    truth = job.truth()
    return (frames, truth, masks) if return_masks else (frames, truth)


def render_to_file(
    motion: Motion,
    out: str | os.PathLike,
    view: str | float = "front",
    size: tuple[int, int] = (160, 120),
    fps: float = 20.0,
    elevation_deg: float = 10.0,
    distance: float | None = None,
    camera: Camera | None = None,
    appearance: Appearance | None = None,
    background="plain",
    noise_sigma: float = 2.0,
    seed: int = 0,
    labels: Sequence[str] | None = None,
    transitions: np.ndarray | None = None,
    background_encode: bool = False,
) -> Path:
    """Render to a video file plus its ground-truth sidecar ``<stem>.truth.npz``; returns the sidecar
    path. ``background_encode``: the encoder on a thread of its own beside the renderer (the same file;
    faster where a core is free, e.g. one large preview, not a pool of workers already on every core).

    The camera is ``Camera.for_view(motion, view, elevation_deg, distance, size)`` unless ``camera`` is
    given (then ``view``, ``size``, ``elevation_deg`` and ``distance`` are ignored). Other options as in
    :func:`render_motion`. Frames are streamed to the encoder (long 640x480 previews do not fill
    memory); both files are written to temporary names and renamed only when complete.
    """
    out = Path(out)
    if out.suffix.lower() not in CODECS:
        raise InputError(f"{out}: video must end in {', '.join(CODECS)}")
    if camera is None:
        camera = Camera.for_view(motion, view=view, elevation_deg=elevation_deg, distance=distance, size=size)
    job = RenderJob(motion, camera, fps, appearance, background, noise_sigma, seed, labels, transitions)
    side = sidecar_path(out)
    # the writer renames its temporary file when its block ends without error; an error anywhere
    # (rendering, the sidecar) leaves neither file
    with atomic_path(side, suffix=".npz") as tmp_side, VideoWriter(out, job.fps, background=background_encode) as writer:
        for frame, _ in job.frames(False):
            writer.write(frame)
        truth = job.truth()
        truth["seed"] = np.int64(seed)
        truth["noise_sigma"] = np.float64(noise_sigma)
        np.savez_compressed(tmp_side, **truth_arrays(truth, side))
    return side


def load_truth(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """Read a sidecar (``.truth.npz``, or the video path beside which it lies) into a dict."""
    from ..formats.truth import read_truth

    return read_truth(path).to_arrays()
