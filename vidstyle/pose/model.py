"""Pictorial structures for one viewpoint (or the generic set): rotated linear part templates with
logistic calibration, a tree prior with Gaussian pairwise terms in the transformed joint space, and
exact min-sum inference by the generalised distance transform.

Part state ``(x, y, theta)`` with x, y on the feature cell grid (stride ``cell`` pixels) and theta one
of ``n_orient`` directions; scale is the figure's, handled by the caller (image resizing). The
energy of a configuration is

    E(L) = sum_i -alpha s_i(l_i) + sum_(i,j) [ wxy_ij |T_ij(l_i) - T_ji(l_j)|^2 + wt_ij wrap(k_j - k_i - mu_ij)^2 ]
           + prior(k_root)

where ``s_i`` is part i's calibrated detector log-odds, ``T_ij(l_i) = p_i + R(theta_i) b_ij`` the
joint between i and j predicted by the parent and ``T_ji(l_j) = p_j + R(theta_j) a_j`` by the child
(b, a: mean offsets learned from training poses, in cells, rounded to the grid), so minimising over
the child's position is a 2D squared-distance transform of the child's (shifted) cost map, and
minimising over its orientation a small brute-force loop over (k_i, k_j) pairs.
"""

from __future__ import annotations

import math

import numpy as np

from ..mocap.keypoints import KEYPOINTS, PART_KEYPOINTS, PART_NAMES, PART_PARENT_INDEX
from .dt import BIG, brute_dt2d, dt2d, min_plus
from .features import RotatedFeatures, orientation_bin, orientations

N_PARTS = len(PART_NAMES)
WIDTH_RATIO = {"torso": 0.75, "head": 1.1}
CHILD_JOINT = {j: int(PART_KEYPOINTS[j, 0]) for j in range(1, N_PARTS)}
"""keypoint where child part j meets its parent: its proximal end (neck for the head, shoulder ...)."""
DEPTH = np.zeros(N_PARTS, dtype=np.int64)
for _j in range(N_PARTS):
    _p, _d = _j, 0
    while PART_PARENT_INDEX[_p] >= 0:
        _p, _d = int(PART_PARENT_INDEX[_p]), _d + 1
    DEPTH[_j] = _d


def part_geometry(kp: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(..., 15, 2) keypoints -> part centres (..., 10, 2), orientations (..., 10), lengths (..., 10)."""
    a = kp[..., PART_KEYPOINTS[:, 0], :]
    b = kp[..., PART_KEYPOINTS[:, 1], :]
    d = b - a
    return (a + b) / 2.0, np.arctan2(d[..., 1], d[..., 0]) % (2 * math.pi), np.linalg.norm(d, axis=-1)


def _to_frame(v: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Image vectors (..., 2) -> part frame (along the axis, across it)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * v[..., 0] + s * v[..., 1], -s * v[..., 0] + c * v[..., 1]], axis=-1)


def _from_frame(v: np.ndarray, theta: np.ndarray) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], axis=-1)


def shift_maps(maps: np.ndarray, dy: int, dx: int, fill: float = BIG) -> np.ndarray:
    """out[..., y, x] = maps[..., y + dy, x + dx] (``fill`` outside)."""
    H, W = maps.shape[-2:]
    out = np.full_like(maps, fill)
    ys, ye = max(0, -dy), min(H, H - dy)
    xs, xe = max(0, -dx), min(W, W - dx)
    if ys < ye and xs < xe:
        out[..., ys:ye, xs:xe] = maps[..., ys + dy:ye + dy, xs + dx:xe + dx]
    return out


class PictorialStructures:
    """Part detectors + tree prior for one set of training frames (one viewpoint, or all of them).

    Parameters (stored as given): ``n_orient`` orientation bins, ``cell`` stride in pixels, ``C``
    logistic regularisation, ``neg_per_pos`` random negatives per positive, ``hard_rounds`` rounds of
    hard-negative mining, ``seed``, ``dt`` ("envelope" = Felzenszwalb-Huttenlocher, "brute" =
    separable enumeration, same result), ``unary_weight`` (alpha: the unary terms' weight against
    the prior, chosen on validation), ``orient`` ("rotate": one upright template per part applied
    to rotated copies of the frame, Andriluka et al.; "mixture": one template per part and
    orientation on the unrotated frame, Yang & Ramanan; :meth:`fit` only).
    Learned: ``templates_`` (list of (h, w, C) arrays), ``bias_``, ``offsets_`` (parent-side joint
    offsets b), ``child_offsets_`` (a), ``distal_`` (distal end offsets), ``wxy_``, ``wt_``, ``mu_``,
    ``root_prior_``.
    """

    def __init__(self, n_orient: int = 12, cell: int = 4, C: float = 0.05, neg_per_pos: int = 12,
                 hard_rounds: int = 1, seed: int = 0, dt: str = "envelope", unary_weight: float = 1.0,
                 orient: str = "rotate") -> None:
        self.n_orient = n_orient
        self.cell = cell
        self.C = C
        self.neg_per_pos = neg_per_pos
        self.hard_rounds = hard_rounds
        self.seed = seed
        self.dt = dt
        self.unary_weight = unary_weight
        self.orient = orient

    # ------------------------------------------------------------------ training
    def fit_geometry(self, keypoints: np.ndarray) -> PictorialStructures:
        kp = np.asarray(keypoints, dtype=np.float64) / self.cell  # cells
        c, th, L = part_geometry(kp)
        K = self.n_orient
        self.lengths_ = np.median(L, axis=0) * self.cell  # px
        self.offsets_ = np.zeros((N_PARTS, 2))
        self.child_offsets_ = np.zeros((N_PARTS, 2))
        self.distal_ = np.zeros((N_PARTS, 2))
        self.proximal_ = np.zeros((N_PARTS, 2))
        self.wxy_ = np.zeros(N_PARTS)
        self.wt_ = np.zeros(N_PARTS)
        self.mu_ = np.zeros(N_PARTS)
        for j in range(N_PARTS):
            self.proximal_[j] = np.median(_to_frame(kp[:, PART_KEYPOINTS[j, 0]] - c[:, j], th[:, j]), axis=0)
            self.distal_[j] = np.median(_to_frame(kp[:, PART_KEYPOINTS[j, 1]] - c[:, j], th[:, j]), axis=0)
        for j in range(1, N_PARTS):
            i = int(PART_PARENT_INDEX[j])
            joint = kp[:, CHILD_JOINT[j]]
            b = _to_frame(joint - c[:, i], th[:, i])
            a = _to_frame(joint - c[:, j], th[:, j])
            self.offsets_[j] = np.median(b, axis=0)
            self.child_offsets_[j] = np.median(a, axis=0)
            ki = orientation_bin(th[:, i], K)
            kj = orientation_bin(th[:, j], K)
            # residual between the joint predicted by the parent and by the child, at the binned angles
            ang = orientations(K)
            pi_ = c[:, i] + _from_frame(np.broadcast_to(self.offsets_[j], b.shape), ang[ki])
            pj_ = c[:, j] + _from_frame(np.broadcast_to(self.child_offsets_[j], a.shape), ang[kj])
            var = np.mean((pi_ - pj_) ** 2) / 1.0 + 0.25
            self.wxy_[j] = 1.0 / (2.0 * var)
            d = (kj - ki) % K
            mu = math.atan2(np.sin(d * 2 * math.pi / K).mean(), np.cos(d * 2 * math.pi / K).mean()) * K / (2 * math.pi)
            self.mu_[j] = mu
            dev = (d - mu + K / 2) % K - K / 2
            self.wt_[j] = 1.0 / (2.0 * (np.mean(dev ** 2) + 0.5))
        kr = orientation_bin(th[:, 0], K)
        hist = np.bincount(kr, minlength=K) + 0.5
        self.root_prior_ = -np.log(hist / hist.sum())
        # template sizes (cells, odd)
        self.sizes_ = []
        for j, name in enumerate(PART_NAMES):
            Lc = self.lengths_[j] / self.cell
            h = int(2 * math.ceil((Lc + 1.5) / 2) + 1) if Lc > 1 else 3
            w = int(2 * round(max(3.0, WIDTH_RATIO.get(name, 0.55) * Lc + 1.0) / 2) + 1)
            self.sizes_.append((h, w))
        return self

    def _samples(self, feats: RotatedFeatures, kp: np.ndarray, j: int, rng, n_neg: int):
        c, th, L = part_geometry(kp[None])
        c, th, L = c[0, j], th[0, j], L[0, j]
        h, w = self.sizes_[j]
        K = self.n_orient
        k = int(orientation_bin(th, K))
        pos = feats.window(k, c, h, w)
        negs = []
        H, W = feats.H, feats.W
        tries = 0
        while len(negs) < n_neg and tries < 4 * n_neg:
            tries += 1
            kk = int(rng.integers(K))
            xy = np.array([rng.uniform(0, W - 1), rng.uniform(0, H - 1)])
            dk = min((kk - k) % K, (k - kk) % K)
            if np.linalg.norm(xy - c) < 0.3 * max(L, 4) and dk <= 1:
                continue
            win = feats.window(kk, xy, h, w)
            if win is not None:
                negs.append(win)
        return pos, negs

    def fit(self, images: list[np.ndarray], keypoints: np.ndarray, feats: list[RotatedFeatures] | None = None,
            backgrounds: list[np.ndarray] | None = None) -> PictorialStructures:
        """``images``: gray frames; ``keypoints`` (N, 15, 2) px. ``feats`` may pass precomputed
        :class:`RotatedFeatures` (same ``n_orient``/``cell``)."""
        rng = np.random.default_rng(self.seed)
        kp = np.asarray(keypoints, dtype=np.float64)
        self.fit_geometry(kp)
        if self.orient not in ("rotate", "mixture"):
            raise ValueError(f"orient must be 'rotate' or 'mixture', got {self.orient!r}")
        if feats is None:
            feats = [RotatedFeatures(im, self.n_orient, self.cell, rotate=self.orient == "rotate") for im in images]
        if self.orient == "mixture":
            return self._fit_mixture(feats, kp, rng)
        self.templates_ = []
        self.bias_ = np.zeros(N_PARTS)
        for j in range(N_PARTS):
            P, Nn = [], []
            for f, k in zip(feats, kp):
                p, n = self._samples(f, k, j, rng, self.neg_per_pos)
                if p is not None:
                    P.append(p)
                Nn.extend(n)
            X = np.vstack(P + Nn)
            y = np.r_[np.ones(len(P)), np.zeros(len(Nn))]
            from sklearn.linear_model import LogisticRegression  # here: inference needs no scikit-learn

            clf = LogisticRegression(C=self.C, max_iter=300, class_weight="balanced")
            clf.fit(X, y)
            h, w = self.sizes_[j]
            self.templates_.append(clf.coef_[0].reshape(h, w, -1).astype(np.float32))
            self.bias_[j] = float(clf.intercept_[0])
        for _ in range(self.hard_rounds):
            self._mine_hard(feats, kp, rng)
        return self

    def _fit_mixture(self, feats, kp, rng) -> PictorialStructures:
        """Per part and orientation bin k a logistic template on the unrotated cells (square windows
        of the part's length): positives are the part's windows of bins k-1..k+1, negatives random
        windows plus the part's own windows at orientations at least 3 bins away."""
        K = self.n_orient
        self.sizes_ = [(h, h) for h, _w in self.sizes_]
        self.templates_, self.bias_ = [], np.zeros((N_PARTS, K))
        for j in range(N_PARTS):
            h, w = self.sizes_[j]
            P, bins, Nn = [], [], []
            for f, k in zip(feats, kp):
                p, n = self._samples(f, k, j, rng, self.neg_per_pos)
                if p is not None:
                    P.append(p)
                    bins.append(int(orientation_bin(part_geometry(k[None])[1][0, j], K)))
                Nn.extend(n)
            P, bins, Nn = np.array(P), np.array(bins), np.array(Nn)
            temps = []
            for k in range(K):
                dk = np.minimum((bins - k) % K, (k - bins) % K)
                pos, far = P[dk <= 1], P[dk >= 3]
                if len(pos) < 3:
                    temps.append(np.zeros((h, w, feats[0].feats.shape[-1]), np.float32))
                    self.bias_[j, k] = -10.0
                    continue
                X = np.vstack([pos, Nn, far])
                y = np.r_[np.ones(len(pos)), np.zeros(len(Nn) + len(far))]
                from sklearn.linear_model import LogisticRegression

                clf = LogisticRegression(C=self.C, max_iter=300, class_weight="balanced").fit(X, y)
                temps.append(clf.coef_[0].reshape(h, w, -1).astype(np.float32))
                self.bias_[j, k] = float(clf.intercept_[0])
            self.templates_.append(temps)
        return self

    def _mine_hard(self, feats, kp, rng) -> None:
        """Retrain every part with the highest-scoring false positives of the current templates."""
        for j in range(N_PARTS):
            P, Nn = [], []
            h, w = self.sizes_[j]
            for f, k in zip(feats, kp):
                p, n = self._samples(f, k, j, rng, self.neg_per_pos // 2)
                if p is None:
                    continue
                P.append(p)
                Nn.extend(n)
                S = self._part_scores(f, j)  # (K, Hc, Wc)
                c, th, L = part_geometry(k[None])
                kt = int(orientation_bin(th[0, j], self.n_orient))
                gy, gx = self._grid(f)
                d = np.hypot(gx * self.cell + (self.cell - 1) / 2 - c[0, j, 0], gy * self.cell + (self.cell - 1) / 2 - c[0, j, 1])
                K = self.n_orient
                dk = np.minimum((np.arange(K) - kt) % K, (kt - np.arange(K)) % K)
                near = (d[None] < 0.3 * max(L[0, j], 4)) & (dk[:, None, None] <= 1)
                S = np.where(near, -np.inf, S)
                flat = np.argsort(S.ravel())[::-1][:4]
                for idx in flat:
                    kk, yy, xx = np.unravel_index(idx, S.shape)
                    xy = np.array([xx * self.cell + (self.cell - 1) / 2, yy * self.cell + (self.cell - 1) / 2])
                    win = f.window(int(kk), xy, h, w)
                    if win is not None:
                        Nn.append(win)
            X = np.vstack(P + Nn)
            y = np.r_[np.ones(len(P)), np.zeros(len(Nn))]
            from sklearn.linear_model import LogisticRegression  # here: inference needs no scikit-learn

            clf = LogisticRegression(C=self.C, max_iter=300, class_weight="balanced")
            clf.fit(X, y)
            self.templates_[j] = clf.coef_[0].reshape(h, w, -1).astype(np.float32)
            self.bias_[j] = float(clf.intercept_[0])

    # ------------------------------------------------------------------ scoring
    def _grid(self, f: RotatedFeatures) -> tuple[np.ndarray, np.ndarray]:
        Hc, Wc = f.H // self.cell, f.W // self.cell
        return np.mgrid[0:Hc, 0:Wc]

    def _part_scores(self, f: RotatedFeatures, j: int) -> np.ndarray:
        """(K, Hc, Wc) log-odds of part j at every frame cell and orientation."""
        return score_models({"m": self}, f, parts=[j])["m"][0]

    def score_maps(self, f: RotatedFeatures) -> np.ndarray:
        """(10, K, Hc, Wc) part log-odds."""
        return score_models({"m": self}, f)["m"]

    # ------------------------------------------------------------------ inference
    def rounded_offsets(self, off: np.ndarray) -> np.ndarray:
        """(K, 2) integer (dx, dy) cell offsets of a part-frame offset at each orientation."""
        key = (self.n_orient, float(off[0]), float(off[1]))
        cache = self.__dict__.setdefault("_offset_cache", {})
        if key not in cache:
            ang = orientations(self.n_orient)
            v = _from_frame(np.broadcast_to(off, (self.n_orient, 2)), ang)
            cache[key] = np.rint(v).astype(np.int64)
        return cache[key]

    def infer(self, scores: np.ndarray) -> dict:
        """Exact minimum of the energy given ``scores`` (10, K, H, W). Returns states (10, 3) as
        (k, y, x), the energy, and the unary scores at the states."""
        K = self.n_orient
        H, W = scores.shape[-2:]
        cost = -float(getattr(self, "unary_weight", 1.0)) * np.asarray(scores, dtype=np.float64)
        total = cost.copy()
        back = {}
        dtf = dt2d if self.dt == "envelope" else brute_dt2d
        kk = np.arange(K)
        for depth in sorted(set(DEPTH.tolist()), reverse=True):
            if depth == 0:
                break
            js = [j for j in range(N_PARTS) if DEPTH[j] == depth]
            # child's cost by its joint position: J(k, q) = total(k, q - R_k a)
            shifted = []
            for j in js:
                a = self.rounded_offsets(self.child_offsets_[j])
                shifted.append(np.stack([shift_maps(total[j, k], -a[k, 1], -a[k, 0]) for k in range(K)]))
            Jm = np.stack(shifted)  # (n, K, H, W)
            wrow = np.repeat(np.array([self.wxy_[j] for j in js]), K).reshape(len(js), K)
            D, ay, ax = _dt_rows(dtf, Jm, wrow)
            for n, j in enumerate(js):
                i = int(PART_PARENT_INDEX[j])
                # orientation: E(ki, q) = min_kj D(kj, q) + wt wrap(kj - ki - mu)^2
                dev = (kk[None, :] - kk[:, None] - self.mu_[j] + K / 2) % K - K / 2  # [ki, kj]
                pen = self.wt_[j] * dev ** 2
                E, kbest = min_plus(D[n], pen)  # (ki, H, W)
                b = self.rounded_offsets(self.offsets_[j])
                msg = np.stack([shift_maps(E[k], b[k, 1], b[k, 0]) for k in range(K)])
                total[i] += msg
                back[j] = (kbest, ay[n], ax[n])
        root = total[0] + self.root_prior_[:, None, None]
        k0, y0, x0 = np.unravel_index(int(root.argmin()), root.shape)
        energy = float(root[k0, y0, x0])
        states = np.zeros((N_PARTS, 3), dtype=np.int64)
        states[0] = (k0, y0, x0)
        for j in range(1, N_PARTS):  # parents come before children in PART_NAMES order
            i = int(PART_PARENT_INDEX[j])
            ki, yi, xi = states[i]
            b = self.rounded_offsets(self.offsets_[j])[ki]
            qy, qx = yi + b[1], xi + b[0]
            kbest, ay, ax = back[j]
            qy_c, qx_c = int(np.clip(qy, 0, H - 1)), int(np.clip(qx, 0, W - 1))
            kj = int(kbest[ki, qy_c, qx_c])
            py, px = int(ay[kj, qy_c, qx_c]), int(ax[kj, qy_c, qx_c])
            a = self.rounded_offsets(self.child_offsets_[j])[kj]
            states[j] = (kj, py - a[1], px - a[0])
        unary = np.array([scores[j, states[j, 0], int(np.clip(states[j, 1], 0, H - 1)),
                                 int(np.clip(states[j, 2], 0, W - 1))] for j in range(N_PARTS)])
        return {"states": states, "energy": energy, "unary": unary}

    def energy(self, scores: np.ndarray, states: np.ndarray) -> float:
        """Energy of one configuration (for brute-force checks)."""
        K = self.n_orient
        H, W = scores.shape[-2:]
        e = 0.0
        for j in range(N_PARTS):
            k, y, x = states[j]
            if not (0 <= y < H and 0 <= x < W):
                return math.inf
            e -= float(getattr(self, "unary_weight", 1.0)) * scores[j, k, y, x]
        e += self.root_prior_[states[0, 0]]
        for j in range(1, N_PARTS):
            i = int(PART_PARENT_INDEX[j])
            ki, yi, xi = states[i]
            kj, yj, xj = states[j]
            b = self.rounded_offsets(self.offsets_[j])[ki]
            a = self.rounded_offsets(self.child_offsets_[j])[kj]
            qi = np.array([xi + b[0], yi + b[1]])
            qj = np.array([xj + a[0], yj + a[1]])
            if not (0 <= qj[1] < H and 0 <= qj[0] < W and 0 <= qi[1] < H and 0 <= qi[0] < W):
                return math.inf
            dev = (kj - ki - self.mu_[j] + K / 2) % K - K / 2
            e += self.wxy_[j] * float(np.sum((qi - qj) ** 2)) + self.wt_[j] * dev ** 2
        return e

    def keypoints(self, states: np.ndarray, unary: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """(15, 3) keypoints (x, y px at the working size divided by ``scale``, score) of a solution."""
        ang = orientations(self.n_orient)
        c = np.stack([states[:, 2] * self.cell + (self.cell - 1) / 2.0,
                      states[:, 1] * self.cell + (self.cell - 1) / 2.0], -1).astype(np.float64)
        th = ang[states[:, 0]]
        acc = np.zeros((len(KEYPOINTS), 2))
        n = np.zeros(len(KEYPOINTS))
        sc = np.zeros(len(KEYPOINTS))
        p = 1.0 / (1.0 + np.exp(-unary))
        for j in range(N_PARTS):
            for end, off in ((0, self.proximal_[j]), (1, self.distal_[j])):
                kpi = PART_KEYPOINTS[j, end]
                acc[kpi] += c[j] + _from_frame(off * self.cell, th[j])
                n[kpi] += 1
                sc[kpi] += p[j]
        xy = acc / n[:, None] / scale
        return np.column_stack([xy, sc / n])


_GRID_CACHE: dict = {}


def canvas_maps(f: RotatedFeatures, cell: int):
    """Per orientation k: float32 (col, row) canvas cell coordinates under every frame cell centre
    (for ``cv2.remap``)."""
    key = (f.H, f.W, f.S, f.n_orient, cell, getattr(f, "rotate", True))
    if key not in _GRID_CACHE:
        Hc, Wc = f.H // cell, f.W // cell
        gy, gx = np.mgrid[0:Hc, 0:Wc]
        px = np.stack([gx * cell + (cell - 1) / 2.0, gy * cell + (cell - 1) / 2.0], -1).reshape(-1, 2)
        out = []
        for k in range(f.n_orient):
            q = (f.to_canvas(k, px) - (cell - 1) / 2.0) / cell
            out.append((q[:, 0].reshape(Hc, Wc).astype(np.float32), q[:, 1].reshape(Hc, Wc).astype(np.float32)))
        _GRID_CACHE[key] = (Hc, Wc, out)
    return _GRID_CACHE[key]


def score_models(models: dict, f: RotatedFeatures, parts: list[int] | None = None) -> dict:
    """Log-odds maps (len(parts), K, Hc, Wc) of each model's part templates on one frame: every
    template is correlated with each orientation copy's cells (``cv2.filter2D`` per channel, the
    window centred on the cell, as in training), and the response read back under the frame's own
    cell grid (bilinear ``cv2.remap``; -20 outside the canvas)."""
    import cv2

    parts = list(range(N_PARTS)) if parts is None else parts
    cell = next(iter(models.values())).cell
    Hc, Wc, maps = canvas_maps(f, cell)
    K = f.n_orient
    out = {}
    for name, m in models.items():
        res = np.empty((len(parts), K, Hc, Wc), dtype=np.float32)
        mixture = getattr(m, "orient", "rotate") == "mixture"
        for n, j in enumerate(parts):
            for k in range(K):
                T = m.templates_[j][k] if mixture else m.templates_[j]
                F = f.feats[f.copy_index(k)]
                R = np.zeros(F.shape[:2], dtype=np.float32)
                for ch in range(F.shape[2]):
                    R += cv2.filter2D(F[..., ch], cv2.CV_32F, T[..., ch], borderType=cv2.BORDER_CONSTANT)
                mx, my = maps[k]
                res[n, k] = cv2.remap(R, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=-20.0)
            res[n] += (m.bias_[j][:, None, None] if mixture else m.bias_[j])
        out[name] = res
    return out


def _dt_rows(dtf, maps: np.ndarray, w: np.ndarray):
    """Distance transforms of (n, K, H, W) maps with isotropic weights w (n, K), in one batched call."""
    return dtf(maps, w, w)
