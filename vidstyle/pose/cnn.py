"""Convolutional part detectors for the pictorial structures (``vidstyle train-pose --detector cnn``).

The HOG cells + linear templates of :mod:`vidstyle.pose.model` are capacity-bound: six times more
training frames moved their validation PCP by less than a point (``scripts/validate_pose.py``'s
detector table). This module replaces only the *unary terms*: a small fully convolutional network
(PyTorch, CPU) reads the colour frame at the working size and gives, for each of the 15 keypoints,
a log-probability map over the feature cell grid (stride 4, the grid the tree prior works on), plus
the frame's viewpoint (front / left / right / back) from a global-pooling head.

The tree prior, its exact min-sum inference (the generalised distance transform) and the
per-viewpoint models stay those of :class:`~vidstyle.pose.model.PictorialStructures`; the unary of
part ``j`` at state (orientation k, cell y, x) is the sum of its two endpoint keypoints'
log-probabilities at ``(x, y) + R(theta_k) * offset`` (proximal and distal offsets learned with the
tree geometry), so the tree decides which detections belong together (left/right, which limb) and the
network says where joints are. The solution's keypoints are then refined to the heatmap's
probability-weighted mean within ``refine`` cells (the 45-degree orientation bins would otherwise
quantise a limb's end), and each keypoint's score is the heatmap's probability mass within one cell of
it.

Network (``KeypointNet``): 3x3 convolutions with batch norm and ReLU, two stride-2 stages
(16, 32, ``channels``) then dilated 3x3 convolutions (dilation 2, 4, 8, 2) so that the receptive field
covers the whole figure (needed to tell the performer's left from right), a 1x1 keypoint head and a
linear viewpoint head on the pooled features. Training: spatial softmax cross-entropy against a
Gaussian (``sigma`` cells) around each true keypoint, plus the viewpoint cross-entropy; AdamW with a
one-cycle schedule; horizontal flips (left/right keypoints and views swapped) and per-channel gain /
offset jitter; seeded (torch and numpy generators), single-process, ``threads`` intra-op threads.

The weights are kept as numpy arrays (the model pickles without torch objects; torch is imported
only to train and to run).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from typing import ClassVar

import numpy as np

from ..mocap.keypoints import KEYPOINTS, PART_KEYPOINTS
from .data import VIEW_NAMES
from .defaults import AUGMENTS, CNN_DEFAULTS, DEFAULTS
from .estimator import PoseModel, check_common_params

log = logging.getLogger(__name__)

CELL = 4
LOG_FLOOR = -20.0  # log-probability outside the frame
#: keypoint order under a horizontal flip (the performer's left becomes the image's other side)
FLIP_KEYPOINTS = [KEYPOINTS.index(n.replace("left", "@").replace("right", "left").replace("@", "right"))
                  for n in KEYPOINTS]
FLIP_VIEWS = [VIEW_NAMES.index({"left": "right", "right": "left"}.get(v, v)) for v in VIEW_NAMES]


def _torch():
    try:
        import torch
    except ImportError as exc:  # pragma: no cover - torch is a dependency
        raise RuntimeError("the cnn pose detector needs PyTorch (pip install torch==2.13.0)") from exc
    return torch


def _build_net(channels: int, stride: int = CELL):
    """The network; ``stride`` 4 gives the heatmaps on the tree's cell grid, 2 adds an upsampling head
    (the stride-4 features, upsampled and reduced, plus the stride-2 features, then a 3x3 block) that
    gives them at twice that resolution."""
    torch = _torch()
    nn = torch.nn
    F = torch.nn.functional

    def block(i, o, s=1, d=1):
        return nn.Sequential(nn.Conv2d(i, o, 3, s, padding=d, dilation=d, bias=False), nn.BatchNorm2d(o),
                             nn.ReLU(inplace=True))

    class KeypointNet(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            c = channels
            self.body = nn.Sequential(block(3, 16), block(16, 32, 2), block(32, 32), block(32, c, 2), block(c, c),
                                      block(c, c, d=2), block(c, c, d=4), block(c, c, d=8), block(c, c, d=2))
            if stride == 2:
                self.up = nn.Conv2d(c, 32, 1)
                self.fine = block(32, 32)
            self.kp = nn.Conv2d(32 if stride == 2 else c, len(KEYPOINTS), 1)
            self.view = nn.Linear(c, len(VIEW_NAMES))

        def forward(self, x):
            if stride == 2:
                f2 = self.body[:3](x)
                f = self.body[3:](f2)
                h = self.fine(F.interpolate(self.up(f), size=f2.shape[2:], mode="bilinear", align_corners=False) + f2)
                return self.kp(h), self.view(f.mean(dim=(2, 3)))
            f = self.body(x)
            return self.kp(f), self.view(f.mean(dim=(2, 3)))

    return KeypointNet()


def to_input(frames_bgr: np.ndarray):
    """(N, H, W, 3) uint8 BGR -> float tensor (N, 3, H, W) in [-0.5, 0.5]."""
    torch = _torch()
    x = np.ascontiguousarray(np.asarray(frames_bgr, dtype=np.float32).transpose(0, 3, 1, 2)) / 255.0 - 0.5
    return torch.from_numpy(x)


def random_affine(frames_bgr: np.ndarray, keypoints: np.ndarray, rng: np.random.Generator,
                  scale: tuple[float, float] = (0.8, 1.25), rotate_deg: float = 20.0,
                  margin: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Geometric training augmentation: each frame (N, H, W, 3) uint8 is scaled by a factor drawn
    log-uniformly from ``scale`` and rotated by up to +-``rotate_deg`` about its keypoints' centre, then
    shifted by a uniform offset that keeps every keypoint at least ``margin`` px inside the frame (none
    when the figure is too large for that). Borders are reflected (the backgrounds are textures). Returns
    the warped frames and keypoints (N, 15, 2), the keypoints mapped by the same affine maps."""
    import cv2

    X = np.asarray(frames_bgr)
    kp = np.asarray(keypoints, dtype=np.float64)
    n, H, W = X.shape[:3]
    out = np.empty_like(X)
    kout = np.empty_like(kp)
    lo, hi = np.log(scale[0]), np.log(scale[1])
    for i in range(n):
        s = float(np.exp(rng.uniform(lo, hi)))
        a = float(rng.uniform(-rotate_deg, rotate_deg))
        c = kp[i].mean(axis=0)
        M = cv2.getRotationMatrix2D((float(c[0]), float(c[1])), a, s)
        k = kp[i] @ M[:, :2].T + M[:, 2]
        for d, size in ((0, W), (1, H)):
            lo_t, hi_t = margin - k[:, d].min(), size - 1 - margin - k[:, d].max()
            t = rng.uniform(lo_t, hi_t) if lo_t <= hi_t else 0.0
            M[d, 2] += t
            k[:, d] += t
        out[i] = cv2.warpAffine(X[i], M, (W, H), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT_101)
        kout[i] = k
    return out, kout


def gaussian_targets(keypoints: np.ndarray, grid: tuple[int, int], sigma: float, cell: int = CELL) -> np.ndarray:
    """(N, 15, Hc, Wc) normalised Gaussians (``sigma`` in cells) around keypoints (N, 15, 2) px on the
    grid of ``cell``-px cells (centre of cell (x, y) at pixel x * cell + (cell - 1) / 2)."""
    Hc, Wc = grid
    gy, gx = np.mgrid[0:Hc, 0:Wc]
    c = (np.asarray(keypoints, dtype=np.float64) - (cell - 1) / 2.0) / cell
    d2 = (gx - c[..., 0, None, None]) ** 2 + (gy - c[..., 1, None, None]) ** 2
    h = np.exp(-d2 / (2.0 * sigma ** 2))
    return (h / np.maximum(h.sum(axis=(-1, -2), keepdims=True), 1e-12)).astype(np.float32)


class HeatmapCNN:
    """Keypoint heatmaps and viewpoint from a colour frame (see the module docstring).

    Parameters: ``channels``, ``epochs``, ``batch_size``, ``lr`` (peak of the one-cycle schedule),
    ``sigma`` (target width, in cells of the tree's 4-px grid), ``view_weight`` (viewpoint loss weight),
    ``seed``, ``threads``, ``stride`` (heatmap cell in px: 4, the tree's grid, or 2 with the upsampling
    head of :func:`_build_net`), ``augment`` (``"flip"``: horizontal flips and colour jitter; ``"affine"``:
    also :func:`random_affine`'s scale, rotation and shift).
    Learned: ``weights_`` (name -> numpy array, the network's state), ``size_`` (W, H) it was trained
    at, ``loss_`` (mean training loss of every epoch)."""

    def __init__(self, channels: int = 48, epochs: int = 10, batch_size: int = 32, lr: float = 3e-3,
                 sigma: float = 1.0, view_weight: float = 0.5, seed: int = 0, threads: int = 2,
                 stride: int = CELL, augment: str = "flip") -> None:
        if stride not in (2, CELL):
            raise ValueError(f"stride must be 2 or {CELL}, got {stride}")
        if augment not in AUGMENTS:
            raise ValueError(f"augment must be one of {AUGMENTS}, got {augment!r}")
        self.stride = stride
        self.augment = augment
        self.channels = channels
        self.epochs = epochs
        self.batch_size = batch_size
        self.lr = lr
        self.sigma = sigma
        self.view_weight = view_weight
        self.seed = seed
        self.threads = threads

    def get_params(self) -> dict:
        return {k: getattr(self, k) for k in ("channels", "epochs", "batch_size", "lr", "sigma", "view_weight",
                                               "seed", "threads", "stride", "augment")}

    def fit(self, frames_bgr: np.ndarray, keypoints: np.ndarray, views: list[str]) -> HeatmapCNN:
        """Train on (N, H, W, 3) uint8 frames (H, W multiples of 4), keypoints (N, 15, 2) px, view names."""
        from ..logutil import progress

        torch = _torch()
        F = torch.nn.functional
        X = np.asarray(frames_bgr)
        if X.ndim != 4 or X.shape[-1] != 3 or X.shape[1] % CELL or X.shape[2] % CELL:
            raise ValueError(f"frames must be (N, H, W, 3) with H, W multiples of {CELL}, got {X.shape}")
        kp = np.asarray(keypoints, dtype=np.float64)
        v = np.array([VIEW_NAMES.index(s) for s in views])
        n, H, W = X.shape[:3]
        if len(kp) != n or len(v) != n or n < self.batch_size:
            raise ValueError(f"need at least batch_size={self.batch_size} frames with keypoints and views, got {n}")
        torch.manual_seed(self.seed)
        rng = np.random.default_rng(self.seed)
        prev_threads = torch.get_num_threads()
        torch.set_num_threads(max(1, int(self.threads)))
        try:
            net = _build_net(self.channels, self.stride)
            opt = torch.optim.AdamW(net.parameters(), lr=self.lr / 1.5, weight_decay=1e-4)
            per_epoch = n // self.batch_size
            sched = torch.optim.lr_scheduler.OneCycleLR(opt, self.lr, total_steps=self.epochs * per_epoch)
            flip_kp, flip_v = np.array(FLIP_KEYPOINTS), np.array(FLIP_VIEWS)
            st = self.stride
            grid = (H // st, W // st)
            sigma = self.sigma * CELL / st  # the same width in pixels at either stride
            self.loss_ = []
            for _ep in progress(range(self.epochs), "training pose cnn"):
                net.train()
                perm = rng.permutation(n)
                total = 0.0
                for b in range(per_epoch):
                    idx = perm[b * self.batch_size:(b + 1) * self.batch_size]
                    x, k, vv = X[idx].copy(), kp[idx].copy(), v[idx].copy()
                    flip = rng.random(len(idx)) < 0.5
                    x[flip] = x[flip][:, :, ::-1]
                    k[flip] = k[flip][:, flip_kp]
                    k[flip, :, 0] = W - 1 - k[flip, :, 0]
                    vv[flip] = flip_v[vv[flip]]
                    if self.augment == "affine":
                        x, k = random_affine(x, k, rng)
                    xt = to_input(x)
                    gain = torch.from_numpy(rng.uniform(0.8, 1.2, (len(idx), 3, 1, 1)).astype(np.float32))
                    off = torch.from_numpy(rng.uniform(-0.1, 0.1, (len(idx), 3, 1, 1)).astype(np.float32))
                    xt = xt * gain + off
                    tgt = torch.from_numpy(gaussian_targets(k, grid, sigma, st))
                    out, vl = net(xt)
                    logp = F.log_softmax(out.flatten(2), dim=2)
                    loss = -(tgt.flatten(2) * logp).sum(2).mean() + self.view_weight * F.cross_entropy(
                        vl, torch.from_numpy(vv))
                    opt.zero_grad()
                    loss.backward()
                    opt.step()
                    sched.step()
                    total += float(loss.detach())
                self.loss_.append(total / per_epoch)
                log.info("pose cnn epoch %d: loss %.3f", len(self.loss_), self.loss_[-1])
            net.eval()
            self.weights_ = {k: t.detach().cpu().numpy().copy() for k, t in net.state_dict().items()}
        finally:
            torch.set_num_threads(prev_threads)
        self.size_ = (W, H)
        self._net = None
        return self

    def _module(self):
        net = self.__dict__.get("_net")
        if net is None:
            torch = _torch()
            net = _build_net(self.channels, getattr(self, "stride", CELL))
            net.load_state_dict({k: torch.from_numpy(np.asarray(a)) for k, a in self.weights_.items()})
            net.eval()
            self._net = net
        return net

    def __getstate__(self) -> dict:
        d = dict(self.__dict__)
        d.pop("_net", None)
        return d

    def __setstate__(self, state: dict) -> None:
        state.setdefault("augment", "flip")  # networks trained before the parameter existed
        self.__dict__.update(state)

    def predict(self, frames_bgr: np.ndarray, batch: int = 32, threads: int = 1,
                flip: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(log-probability heatmaps (N, 15, H/s, W/s) at the network's stride s, viewpoint
        log-probabilities (N, 4)) of (N, H, W, 3) uint8 frames, on ``threads`` intra-op threads (1: the
        pose command runs one worker per core). ``flip``: test-time flip, the mean log-probabilities of
        the frame and of its mirror image (mapped back: columns reversed, left and right keypoints and
        views swapped), renormalised; W must then be a multiple of the stride."""
        torch = _torch()
        F = torch.nn.functional
        X = np.asarray(frames_bgr)
        if X.ndim == 3:
            X = X[None]
        net = self._module()
        heat, views = [], []
        prev = torch.get_num_threads()
        torch.set_num_threads(max(1, int(threads)))
        try:
            with torch.no_grad():
                for i in range(0, len(X), batch):
                    out, vl = net(to_input(X[i:i + batch]))
                    s = out.shape
                    h = F.log_softmax(out.flatten(2), dim=2).reshape(s)
                    v = F.log_softmax(vl, dim=1)
                    if flip:
                        fo, fv = net(to_input(np.ascontiguousarray(X[i:i + batch][:, :, ::-1])))
                        fh = F.log_softmax(fo.flatten(2), dim=2).reshape(s).flip(3)[:, FLIP_KEYPOINTS]
                        h = F.log_softmax(((h + fh) / 2).flatten(2), dim=2).reshape(s)
                        v = F.log_softmax((v + F.log_softmax(fv, dim=1)[:, FLIP_VIEWS]) / 2, dim=1)
                    heat.append(h.numpy())
                    views.append(v.numpy())
        finally:
            torch.set_num_threads(prev)
        return np.concatenate(heat), np.concatenate(views)


def part_unaries(logheat: np.ndarray, m) -> np.ndarray:
    """(10, K, Hc, Wc) unary scores of the parts of pictorial structures ``m`` from keypoint
    log-probability maps (15, Hc, Wc): part j at (k, y, x) scores the log-probabilities of its
    proximal and distal keypoints at ``(x, y) + R(theta_k) offset`` (offsets rounded to cells)."""
    from .model import N_PARTS, shift_maps

    K = m.n_orient
    out = np.empty((N_PARTS, K) + logheat.shape[1:], dtype=np.float32)
    for j in range(N_PARTS):
        a, b = int(PART_KEYPOINTS[j, 0]), int(PART_KEYPOINTS[j, 1])
        da, db = m.rounded_offsets(m.proximal_[j]), m.rounded_offsets(m.distal_[j])
        for k in range(K):
            out[j, k] = (shift_maps(logheat[a], int(da[k, 1]), int(da[k, 0]), LOG_FLOOR)
                         + shift_maps(logheat[b], int(db[k, 1]), int(db[k, 0]), LOG_FLOOR))
    return out


def coarse_logheat(logheat: np.ndarray, stride: int) -> np.ndarray:
    """Log-probability maps on the tree's 4-px grid from maps at ``stride`` px (2 or 4): each coarse
    cell's probability is the sum of its sub-cells' (a log-sum-exp over 2x2 blocks; an odd last row or
    column of sub-cells is dropped with its mass)."""
    from scipy.special import logsumexp

    if stride == CELL:
        return logheat
    f = CELL // stride
    K, H, W = logheat.shape
    Hc, Wc = H // f, W // f
    b = logheat[:, :Hc * f, :Wc * f].astype(np.float64).reshape(K, Hc, f, Wc, f)
    return logsumexp(b, axis=(2, 4)).astype(np.float32)


def refine_keypoints(points_px: np.ndarray, logheat: np.ndarray, scale: float, radius: int = 2,
                     cell: int = CELL) -> np.ndarray:
    """Keypoints (15, >=2) at the input size (``scale``: working / input) moved to the heatmap's
    probability-weighted mean within ``radius`` cells of each (0: not moved); returns (15, 3) with the
    score = the probability mass within 4 px (one cell of the tree's grid) of the (refined) point.
    ``logheat`` is on a grid of ``cell``-px cells."""
    K, Hc, Wc = logheat.shape
    r_mass = max(1, CELL // cell)
    p = np.exp(logheat.astype(np.float64))
    out = np.zeros((K, 3))
    for i in range(K):
        cx = (points_px[i, 0] * scale - (cell - 1) / 2.0) / cell
        cy = (points_px[i, 1] * scale - (cell - 1) / 2.0) / cell
        x0, y0 = int(np.clip(round(cx), 0, Wc - 1)), int(np.clip(round(cy), 0, Hc - 1))
        ys = slice(max(0, y0 - radius), min(Hc, y0 + radius + 1))
        xs = slice(max(0, x0 - radius), min(Wc, x0 + radius + 1))
        w = p[i, ys, xs]
        gy, gx = np.mgrid[ys, xs]
        tot = w.sum()
        if radius > 0 and tot > 1e-12:
            mx, my = float((w * gx).sum() / tot), float((w * gy).sum() / tot)
        else:
            mx, my = float(cx), float(cy)
        xi, yi = int(np.clip(round(mx), 0, Wc - 1)), int(np.clip(round(my), 0, Hc - 1))
        mass = float(p[i, max(0, yi - r_mass):yi + r_mass + 1, max(0, xi - r_mass):xi + r_mass + 1].sum())
        out[i] = ((mx * cell + (cell - 1) / 2.0) / scale, (my * cell + (cell - 1) / 2.0) / scale,
                  min(1.0, mass))
    return out


def argmax_keypoints(logheat: np.ndarray, scale: float = 1.0, cell: int = CELL) -> np.ndarray:
    """(15, 3) keypoints at each heatmap's maximum (no tree prior), refined like the tree's."""
    Wc = logheat.shape[2]
    am = logheat.reshape(len(logheat), -1).argmax(axis=1)
    pts = np.stack([(am % Wc) * cell + (cell - 1) / 2.0, (am // Wc) * cell + (cell - 1) / 2.0], -1) / scale
    return refine_keypoints(pts, logheat, scale, radius=2 * CELL // cell, cell=cell)


class CnnFrame:
    """A frame prepared for :class:`CnnPoseModel`: the working-size BGR image (padded to multiples of
    4 at the right and bottom), its keypoint log-probability maps on the tree's grid (``logheat``) and
    at the network's stride (``fine``, ``stride`` px; the same array at stride 4) and viewpoint
    log-probabilities."""

    def __init__(self, bgr: np.ndarray, logheat: np.ndarray, view_logp: np.ndarray,
                 fine: np.ndarray | None = None, stride: int = CELL) -> None:
        self.bgr = bgr
        self.logheat = logheat
        self.view_logp = view_logp
        self.fine = logheat if fine is None else fine
        self.stride = stride


class _PartMaps(Mapping):
    """Tree name -> part unaries (:func:`part_unaries`) of one frame, computed on first use: the pose
    command needs only the chosen viewpoint's, the evaluation all of them."""

    def __init__(self, logheat: np.ndarray, models: dict) -> None:
        self._logheat = logheat
        self._models = models
        self._maps: dict = {}

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self._maps:
            self._maps[name] = part_unaries(self._logheat, self._models[name])
        return self._maps[name]

    def __iter__(self):
        return iter(self._models)

    def __len__(self) -> int:
        return len(self._models)


def _pad4(img: np.ndarray) -> np.ndarray:
    H, W = img.shape[:2]
    ph, pw = (-H) % CELL, (-W) % CELL
    if ph or pw:
        img = np.pad(img, ((0, ph), (0, pw), (0, 0)), mode="edge")
    return img


class CnnParts:
    """Part detector strategy of :class:`CnnPoseModel` (``detector="cnn"``): the unary terms are
    :class:`HeatmapCNN`'s keypoint log-probabilities (:func:`part_unaries`), the viewpoint features its
    viewpoint head's, the solution's keypoints refined on the full-resolution heatmaps (``refine``); no
    person prior (the network sees colour). Stateless: the network is the model's ``cnn_``."""

    needs_colour = True
    uses_foreground = False

    def fit(self, model, samples, jobs: int = -1, scheduler: str | None = None) -> CnnPoseModel:
        from ..errors import InputError
        from .estimator import GENERIC
        from .model import PictorialStructures

        views = {s.view for s in samples}
        missing = [v for v in VIEW_NAMES if v not in views]
        if missing:
            raise InputError(f"training frames have no {', '.join(missing)} view")
        if any(s.bgr is None for s in samples):
            raise ValueError("the cnn detector trains on colour frames (render_samples(..., keep_bgr=True))")
        model.models_ = {}
        for name in VIEW_NAMES + (GENERIC,):
            kp = np.stack([s.keypoints for s in samples if name in (s.view, GENERIC)])
            m = PictorialStructures(model.n_orient, CELL, seed=model.seed, dt=model.dt, unary_weight=model.unary_weight)
            model.models_[name] = m.fit_geometry(kp)
        frames, kps = [], []
        for s in samples:
            f, sc = self._resize(model, s.bgr)
            frames.append(f)
            kps.append(np.asarray(s.keypoints, dtype=np.float64) * sc)
        shapes = {f.shape for f in frames}
        if len(shapes) != 1:
            raise ValueError(f"training frames must share one size, got {sorted(shapes)}")
        model.cnn_ = HeatmapCNN(model.channels, model.epochs, model.batch_size, model.lr, model.sigma, seed=model.seed,
                               threads=model.threads, stride=model.stride, augment=model.augment).fit(np.stack(frames), np.stack(kps), [s.view for s in samples])
        model.n_train_frames_ = len(samples)
        return model

    def _resize(self, model, frame: np.ndarray) -> tuple[np.ndarray, float]:
        import cv2

        bgr, s = model.to_work_size(frame if frame.ndim == 3 else cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR))
        return _pad4(bgr), s

    def prepare(self, model, frame: np.ndarray) -> tuple[CnnFrame, float]:
        bgr, s = self._resize(model, frame)
        heat, views = model.cnn_.predict(bgr[None], flip=bool(model.flip_test))
        st = int(getattr(model.cnn_, "stride", CELL))
        return CnnFrame(bgr, coarse_logheat(heat[0], st), views[0], heat[0], st), s

    def view_features(self, model, f: CnnFrame, full: bool | None = None, which: str | None = None) -> tuple[dict, dict]:
        return {"cnn": f.view_logp}, _PartMaps(f.logheat, model.models_)

    def foreground_map(self, model, frame, background, f):
        return None

    def solve(self, model, model_name: str, S: np.ndarray, scale: float, fg=None, f: CnnFrame | None = None,
              fg_weight: float | None = None) -> np.ndarray:
        m = model.models_[model_name]
        r = m.infer(S)
        pts = m.keypoints(r["states"], r["unary"], scale=scale)
        if f is not None:
            pts = refine_keypoints(pts, f.fine, scale, radius=int(model.refine) * CELL // f.stride, cell=f.stride)
        return pts


class CnnViewpoint:
    """The viewpoint classifier of :class:`CnnPoseModel`: the network's viewpoint head (its log-probabilities,
    ``view_features(...)["cnn"]``), renormalised; nothing else is learned."""

    NEEDS = ("cnn",)

    def input_of(self, feats: dict):
        return np.asarray(feats["cnn"], dtype=np.float64)[None]

    def _proba(self, X) -> np.ndarray:
        p = np.exp(np.atleast_2d(np.asarray(X, dtype=np.float64)))
        return p / p.sum(axis=1, keepdims=True)

    def predict(self, X) -> np.ndarray:
        return np.array(VIEW_NAMES)[self._proba(X).argmax(axis=1)]

    def scores(self, X) -> list[dict[str, float]]:
        return [{v: float(round(x, 4)) for v, x in zip(VIEW_NAMES, row)} for row in self._proba(X)]


class CnnPoseModel(PoseModel):
    """Pictorial structures whose unary terms come from :class:`HeatmapCNN` (module docstring), with
    its viewpoint head as the viewpoint classifier (``viewpoint="cnn"``). The same interface as
    :class:`~vidstyle.pose.estimator.PoseModel` (``estimate``, ``prepare``, ``view_features``,
    ``classify_view``, ``solve``), so ``vidstyle pose`` and ``evaluate pose`` run it unchanged: it is a
    :class:`PoseModel` composed with the :class:`CnnParts` part detectors and the :class:`CnnViewpoint`
    classifier, and adds only its parameters (constructor, checks).

    Parameters: ``n_orient`` (part orientation bins of the tree), ``unary_weight`` (detectors vs tree
    prior), ``refine`` (cells of the tree's grid of the final keypoint refinement, 0 = none),
    ``flip_test`` (test-time flip of :meth:`HeatmapCNN.predict`), ``dt``, and the network's
    (:class:`HeatmapCNN`: ``channels``, ``epochs``, ``batch_size``, ``lr``, ``sigma``, ``threads``,
    ``stride``, ``augment``), ``seed``; defaults :data:`vidstyle.pose.defaults.CNN_DEFAULTS` (``scripts/validate_pose.py``'s
    detector stage). No person prior (``fg_weight`` is 0: the network sees colour). Learned: ``models_``
    (tree geometry per viewpoint and generic), ``cnn_``, ``n_train_frames_``."""

    PARAMS = ("detector", "n_orient", "unary_weight", "refine", "flip_test", "dt", "channels", "epochs", "batch_size",
              "lr", "sigma", "threads", "stride", "augment", "seed")
    VIEWPOINTS = ("cnn",)
    VIEWPOINT_CLASSIFIERS: ClassVar[dict] = {"cnn": lambda m: CnnViewpoint()}

    def __init__(self, n_orient: int = DEFAULTS["n_orient"], unary_weight: float = CNN_DEFAULTS["unary_weight"],
                 refine: int = CNN_DEFAULTS["refine"], dt: str = "envelope", channels: int = CNN_DEFAULTS["channels"],
                 epochs: int = CNN_DEFAULTS["epochs"], batch_size: int = 32, lr: float = 3e-3, sigma: float = 1.0,
                 threads: int = 2, seed: int = 0, stride: int = CNN_DEFAULTS["stride"],
                 flip_test: bool = CNN_DEFAULTS["flip_test"], augment: str = CNN_DEFAULTS["augment"]) -> None:
        self.detector = "cnn"
        self.augment = augment
        self.stride = stride
        self.flip_test = flip_test
        self.n_orient = n_orient
        self.unary_weight = unary_weight
        self.refine = refine
        self.dt = dt
        self.channels = channels
        self.epochs = epochs
        self.batch_size = batch_size
        self.lr = lr
        self.sigma = sigma
        self.threads = threads
        self.seed = seed
        self.cell = CELL
        self.viewpoint = "cnn"
        self.fg_weight = 0.0

    def __setstate__(self, state: dict) -> None:
        state.setdefault("stride", CELL)  # models saved before these parameters existed
        state.setdefault("flip_test", False)
        state.setdefault("augment", "flip")
        self.__dict__.update(state)

    def check_params(self) -> CnnPoseModel:
        """:class:`ParameterError` naming the first parameter this model cannot train with (run by
        :meth:`fit` and :meth:`fit_specs` before any work)."""
        from ..errors import ParameterError

        check_common_params(self)
        if not self.refine >= 0:
            raise ParameterError("refine", f"must be at least 0, got {self.refine}")
        if not self.epochs >= 1:
            raise ParameterError("epochs", "must be at least 1")
        if not 8 <= self.channels <= 256:
            raise ParameterError("channels", f"{self.channels} is not between 8 and 256")
        if self.stride not in (2, CELL):
            raise ParameterError("stride", f"{self.stride} is not 2 or {CELL}")
        if self.augment not in AUGMENTS:
            raise ParameterError("augment", f"{self.augment!r} is not one of {', '.join(AUGMENTS)}")
        return self


__all__ = ["AUGMENTS", "FLIP_KEYPOINTS", "FLIP_VIEWS", "CnnFrame", "CnnParts", "CnnPoseModel", "CnnViewpoint",
           "HeatmapCNN", "argmax_keypoints", "coarse_logheat", "gaussian_targets", "part_unaries", "random_affine",
           "refine_keypoints"]
