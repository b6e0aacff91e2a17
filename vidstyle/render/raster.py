"""Per-pixel z-buffer rasteriser for tapered capsules, one frame at a time (compiled loops, numpy references).

Each capsule is drawn as a sphere-swept segment in screen space: for every pixel of its bounding box
the closest point on the projected axis gives the parameter ``t``, the interpolated pixel radius
``r(t)`` and centre depth ``z(t)``. A pixel at distance ``d < r`` from the axis sees the surface at depth
``z(t) - R(t) sqrt(1 - (d/r)^2)`` (``R`` the world radius) with camera-space normal
``(dx/r, dy/r, -sqrt(1 - (d/r)^2))``: exact for spheres, a close approximation for capsules that are
not strongly foreshortened. The nearest surface wins each pixel (z-buffer), so depth order is correct
wherever parts interpenetrate or cross.

Pixels on the silhouette are anti-aliased: a pixel with partial coverage ``0 < c < 1`` competes with the
depth ``z + (1 - c) * BIG``, so it only wins over background (or a lesser-covered fringe) and is blended
with the background by ``c``.

Per pixel the buffer keeps (depth, normal x, normal y, coverage, capsule * 16 + material); shading is
computed once per frame for the winners: Lambert from a fixed light plus ambient, and a one-pixel dark
outline where the depth jumps between different body volumes (the silhouette, a limb in front of the
torso or of another limb; none along the seams where the torso's capsules meet).
"""

from __future__ import annotations

import numpy as np

LIGHT = np.array([-0.45, -0.6, -0.66])  # towards the light, camera coordinates (up-left, in front)
LIGHT = LIGHT / np.linalg.norm(LIGHT)
AMBIENT = 0.38
DIFFUSE = 0.72
OUTLINE = 0.5  # brightness factor of outline pixels
FAR = 1e30  # depth of the background
FRINGE = 1.01e30  # depth penalty of a pixel with zero coverage (loses even against the background)
D, NX, NY, COV, CODE = range(5)
MAT_BITS = 16  # code = capsule * MAT_BITS + material


def _draw_loop(buf, uv, z, rpx, rworld, mat, split, order, head, face_dir, has_face):  # noqa: C901
    # compiled by numba: Rasterizer.draw_numpy pixel by pixel. Every float32 operation of the numpy code is
    # one float64 operation on float32 values rounded back to float32 (f(...)), which is the float32 IEEE
    # result (+ - * / and sqrt are correctly rounded and float64 has more than twice the precision); the
    # Python-float steps of the numpy code (scalars per capsule) are float64 here too, and a Python float
    # meeting a float32 array is first rounded to float32, as numpy 2 does (NEP 50). No fast-math.
    f = np.float32
    H, W = buf.shape[0], buf.shape[1]
    fy0, fy1, fx0, fx1 = H, 0, W, 0
    one, half, zero = f(1.0), f(0.5), f(0.0)
    neg_fringe, fringe = f(-FRINGE), f(FRINGE)
    for c in order:
        ax, ay = uv[c, 0, 0], uv[c, 0, 1]
        bx, by = uv[c, 1, 0], uv[c, 1, 1]
        za, zb = z[c, 0], z[c, 1]
        if not (za > 0 and zb > 0):
            continue
        ra, rb = rpx[c, 0], rpx[c, 1]
        rmax = (ra if ra > rb else rb) + 1.5
        x0 = int(min(ax, bx) - rmax)
        x1 = int(max(ax, bx) + rmax) + 2
        y0 = int(min(ay, by) - rmax)
        y1 = int(max(ay, by) + rmax) + 2
        x0, y0 = max(x0, 0), max(y0, 0)
        x1, y1 = min(x1, W), min(y1, H)
        if x1 <= x0 or y1 <= y0:
            continue
        dx, dy = bx - ax, by - ay
        L2 = dx * dx + dy * dy
        seg = L2 > 1e-9
        kx = f(dx / L2) if seg else zero
        ky = f(dy / L2) if seg else zero
        dx32, dy32, ax32, ay32 = f(dx), f(dy), f(ax), f(ay)
        wa, wb = rworld[c, 0], rworld[c, 1]
        taper = abs(rb - ra) > 1e-6 * (ra + 1e-9)
        drr, ra32, dww, wa32 = f(rb - ra), f(ra), f(wb - wa), f(wa)
        rc = max(ra, 0.5)
        rinv_c, rinv2_c, rp5_c = f(1.0 / rc), f((1.0 / rc) * (1.0 / rc)), f(rc + 0.5)
        dz32, za32 = f(zb - za), f(za)
        ma, mb = mat[c, 0], mat[c, 1]
        code_a, code_b = f(c * MAT_BITS + ma), f(c * MAT_BITS + mb)
        spl32 = f(split[c])
        is_head = head[c] and has_face
        fx_, fy_, fz_ = f(face_dir[0]), f(face_dir[1]), f(face_dir[2])
        drew = False
        for y in range(y0, y1):
            gy = f(f(y) - ay32)
            for x in range(x0, x1):
                gx = f(f(x) - ax32)
                if seg:
                    t = f(f(gx * kx) + f(gy * ky))
                    t = max(t, zero)
                    t = min(t, one)
                    ex = f(gx - f(t * dx32))
                    ey = f(gy - f(t * dy32))
                else:
                    t = zero
                    ex = f(gx + zero)
                    ey = f(gy + zero)
                d2 = f(f(ex * ex) + f(ey * ey))
                sd = f(np.sqrt(np.float64(d2)))
                if taper:
                    r = f(t * drr)
                    r = f(r + ra32)
                    r = max(r, half)
                    rinv = f(one / r)
                    wc = f(f(t * dww) + wa32)
                    cov = f(f(r + half) - sd)
                    q = f(d2 * f(rinv * rinv))
                else:
                    rinv = rinv_c
                    wc = wa32
                    cov = f(rp5_c - sd)
                    q = f(d2 * rinv2_c)
                cov = min(cov, one)
                nx = f(ex * rinv)
                ny = f(ey * rinv)
                q = min(q, one)
                q = f(one - q)
                q = f(np.sqrt(np.float64(q)))
                q = f(q * wc)
                depth = f(f(t * dz32) + za32)
                depth = f(depth - q)
                pen = f(cov * neg_fringe)
                pen = f(pen + fringe)
                d = f(depth + pen)
                if not (d < buf[y, x, 0]):
                    continue
                drew = True
                code = code_a
                if ma != mb and not (t < spl32):
                    code = code_b
                if is_head:
                    nz = f(f(one - f(nx * nx)) - f(ny * ny))
                    nz = f(np.sqrt(np.float64(max(nz, zero))))
                    if f(f(f(nx * fx_) + f(ny * fy_)) - f(nz * fz_)) < f(-0.25):
                        code = code_b
                buf[y, x, 0] = d
                buf[y, x, 1] = nx
                buf[y, x, 2] = ny
                buf[y, x, 3] = cov
                buf[y, x, 4] = code
        if drew:
            if y0 < fy0:
                fy0 = y0
            if y1 > fy1:
                fy1 = y1
            if x0 < fx0:
                fx0 = x0
            if x1 > fx1:
                fx1 = x1
    if fy1 > fy0:
        return fy0, fy1, fx0, fx1
    return 0, 0, 0, 0


def _shade_loop(buf, y0, y1, x0, x1, jump, group, light, consts, shade, material):
    # compiled by numba: Rasterizer.finish pixel by pixel over the bbox, the same float32 operations in the
    # same order (numpy 2 rounds a Python float meeting a float32 array to float32 first: light, consts
    # and jump come as float32). consts: DIFFUSE, AMBIENT, OUTLINE
    f = np.float32
    one, zero = f(1.0), f(0.0)
    lx, ly, lz = light[0], light[1], light[2]
    diffuse, ambient, outline = consts[0], consts[1], consts[2]
    ng = group.shape[0]
    for y in range(y0, y1):
        for x in range(x0, x1):
            code = np.int32(buf[y, x, 4])  # truncation, as astype(np.int32)
            cap = code >> 4
            material[y - y0, x - x0] = code - cap * 16
            nx, ny = buf[y, x, 1], buf[y, x, 2]
            nz2 = f(nx * nx)
            nz2 = f(nz2 + f(ny * ny))
            if not (nz2 <= one):  # np.minimum(nz2, 1.0)
                nz2 = one
            nz2 = f(np.sqrt(f(one - nz2)))
            lam = f(nx * lx)
            lam = f(lam + f(ny * ly))
            lam = f(lam - f(nz2 * lz))
            if not (lam >= zero):  # np.maximum(lam, 0.0); the sign of a zero does not survive + AMBIENT
                lam = zero
            lam = f(f(lam * diffuse) + ambient)
            d = buf[y, x, 0]
            g = group[cap if cap >= 0 else ng + cap]
            edge = False
            for dy, dx in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                yy, xx = y + dy, x + dx
                if yy < y0 or yy >= y1 or xx < x0 or xx >= x1:
                    continue
                c2 = np.int32(buf[yy, xx, 4]) >> 4
                if f(buf[yy, xx, 0] - d) > jump and group[c2 if c2 >= 0 else ng + c2] != g:
                    edge = True
            if edge:
                lam = f(lam * outline)
            shade[y - y0, x - x0] = lam


def _composite_loop(out, bg, buf, y0, y1, x0, x1, shade, material, palette, field, oy, ox, noisy):
    # compiled by numba: out = bg, Rasterizer.composite, NoiseBank.add, np.clip(0, 255) and astype(np.uint8)
    # pixel by pixel, the same float32 operations in the same order; out is the (H, W, 3) uint8 frame
    f = np.float32
    lo, hi = f(0.0), f(255.0)
    H, W = out.shape[0], out.shape[1]
    for y in range(H):
        inside_y = y0 <= y < y1
        for x in range(W):
            inside = inside_y and x0 <= x < x1
            for c in range(3):
                v = bg[y, x, c]
                if inside:
                    col = f(palette[material[y - y0, x - x0], c] * shade[y - y0, x - x0])
                    col = f(col - v)
                    col = f(col * buf[y, x, 3])
                    v = f(v + col)
                if noisy:
                    v = f(v + field[oy + y, ox + x, c])
                if v < lo:
                    v = lo
                elif v > hi:
                    v = hi
                out[y, x, c] = np.uint8(v)


# the kernels' float32 constants (as numpy 2 rounds the Python floats meeting float32 arrays), made once
_LIGHT32 = LIGHT.astype(np.float32)
_SHADING32 = np.array([DIFFUSE, AMBIENT, OUTLINE], dtype=np.float32)
_NO_NOISE = np.zeros((1, 1, 3), dtype=np.float32)

_KERNEL: list = []
_FRAME_KERNELS: list = []


def _frame_kernels():
    """The compiled :func:`_shade_loop` and :func:`_composite_loop`, or None without numba."""
    if not _FRAME_KERNELS:
        from ..compiled import compile_kernel

        a, b = compile_kernel(_shade_loop), compile_kernel(_composite_loop)
        _FRAME_KERNELS.append(None if a is None or b is None else (a, b))
    return _FRAME_KERNELS[0]


def _draw_kernel():
    """:func:`_draw_loop` compiled (:func:`vidstyle.compiled.compile_kernel`), or None without numba."""
    if not _KERNEL:
        from ..compiled import compile_kernel

        _KERNEL.append(compile_kernel(_draw_loop))
    return _KERNEL[0]


class Rasterizer:
    """Reusable buffers for one image size. :meth:`draw` fills them for one frame."""

    def __init__(self, width: int, height: int) -> None:
        self.W, self.H = int(width), int(height)
        self.buf = np.empty((self.H, self.W, 5), dtype=np.float32)
        self.buf[...] = (FAR, 0.0, 0.0, 0.0, -1.0)
        self.xs = np.arange(self.W, dtype=np.float32)
        self.ys = np.arange(self.H, dtype=np.float32)[:, None]
        self.bbox = (0, 0, 0, 0)  # y0, y1, x0, x1 of the last frame's figure
        self.shade: np.ndarray | None = None  # (h, w) shading of the bbox after :meth:`finish`
        self.material: np.ndarray | None = None

    # views of the buffer -------------------------------------------------------------------------
    @property
    def depth(self) -> np.ndarray:
        """(H, W) depth of the front-most surface (>= FAR / 2 where there is none)."""
        return self.buf[..., D]

    @property
    def coverage(self) -> np.ndarray:
        return self.buf[..., COV]

    @property
    def capsule(self) -> np.ndarray:
        """(H, W) int front-most capsule id (-1 = none)."""
        return np.floor(self.buf[..., CODE] / MAT_BITS).astype(np.int32)

    def clear(self) -> None:
        y0, y1, x0, x1 = self.bbox
        if y1 > y0 and x1 > x0:
            self.buf[y0:y1, x0:x1] = (FAR, 0.0, 0.0, 0.0, -1.0)
        self.bbox = (0, 0, 0, 0)

    def draw(self, uv, z, rpx, rworld, mat, split, order, head, face_dir) -> None:
        """Draw one frame.

        uv (C, 2, 2) pixel end points, z (C, 2) depths, rpx (C, 2) pixel radii, rworld (C, 2) world radii,
        mat (C, 2) materials, split (C,), order: capsule indices to draw (far to near), head (C,) bool,
        face_dir (3,) camera-space forward direction of the face (hair on the back of the head).

        Runs the compiled per-pixel kernel (:func:`_draw_loop`, numba) when numba is installed: the same
        float32 operations in the same order as :meth:`draw_numpy`, so the buffer is the same to the bit
        (tests/test_render_raster_kernel.py), about 8x faster at the demo's 160x120.
        """
        kernel = _draw_kernel()
        if kernel is None:  # pragma: no cover - numba is a dependency
            self.draw_numpy(uv, z, rpx, rworld, mat, split, order, head, face_dir)
            return
        self.clear()
        fd = np.zeros(3) if face_dir is None else np.asarray(face_dir, dtype=np.float64)
        self.bbox = tuple(kernel(
            self.buf, np.ascontiguousarray(uv, dtype=np.float64), np.ascontiguousarray(z, dtype=np.float64),
            np.ascontiguousarray(rpx, dtype=np.float64), np.ascontiguousarray(rworld, dtype=np.float64),
            np.ascontiguousarray(mat, dtype=np.int64), np.ascontiguousarray(split, dtype=np.float64),
            np.ascontiguousarray(order, dtype=np.int64), np.ascontiguousarray(head, dtype=np.bool_), fd,
            face_dir is not None))

    def draw_numpy(self, uv, z, rpx, rworld, mat, split, order, head, face_dir) -> None:
        """:meth:`draw` in numpy, one capsule at a time (the reference of the compiled kernel)."""
        self.clear()
        W, H = self.W, self.H
        buf, xs, ys = self.buf, self.xs, self.ys
        fy0, fy1, fx0, fx1 = H, 0, W, 0
        uvl, zl, rl, rwl = uv.tolist(), z.tolist(), rpx.tolist(), rworld.tolist()
        matl, spl, headl = mat.tolist(), split.tolist(), head.tolist()
        for c in order.tolist():
            (ax, ay), (bx, by) = uvl[c]
            za, zb = zl[c]
            if not (za > 0 and zb > 0):
                continue  # behind the camera
            ra, rb = rl[c]
            rmax = (ra if ra > rb else rb) + 1.5
            x0 = int(min(ax, bx) - rmax)
            x1 = int(max(ax, bx) + rmax) + 2
            y0 = int(min(ay, by) - rmax)
            y1 = int(max(ay, by) + rmax) + 2
            x0, y0 = max(x0, 0), max(y0, 0)
            x1, y1 = min(x1, W), min(y1, H)
            if x1 <= x0 or y1 <= y0:
                continue
            dx, dy = bx - ax, by - ay
            L2 = dx * dx + dy * dy
            gx = xs[x0:x1] - ax  # (w,)
            gy = ys[y0:y1] - ay  # (h, 1)
            if L2 > 1e-9:
                t = gx * (dx / L2) + gy * (dy / L2)
                np.maximum(t, 0.0, out=t)
                np.minimum(t, 1.0, out=t)
                ex = gx - t * dx
                ey = gy - t * dy
            else:
                t = np.zeros((y1 - y0, x1 - x0), dtype=np.float32)
                ex = gx + t
                ey = gy + t
            d2 = ex * ex
            d2 += ey * ey
            rec = np.empty((y1 - y0, x1 - x0, 5), dtype=np.float32)
            wa, wb = rwl[c]
            if abs(rb - ra) > 1e-6 * (ra + 1e-9):
                r = t * (rb - ra)
                r += ra
                np.maximum(r, 0.5, out=r)
                rinv = 1.0 / r
                wc = t * (wb - wa)
                wc += wa
                cov = (r + 0.5) - np.sqrt(d2)
            else:
                r = max(ra, 0.5)
                rinv = 1.0 / r
                wc = wa
                cov = (r + 0.5) - np.sqrt(d2)
            np.minimum(cov, 1.0, out=rec[..., COV])
            # surface depth: z(t) - R(t) sqrt(1 - (d/r)^2)
            np.multiply(ex, rinv, out=rec[..., NX])
            np.multiply(ey, rinv, out=rec[..., NY])
            q = d2 * (rinv * rinv)
            np.minimum(q, 1.0, out=q)
            np.subtract(1.0, q, out=q)
            np.sqrt(q, out=q)  # = sqrt(1 - (d/r)^2) = -normal z
            q *= wc
            depth = t * (zb - za)
            depth += za
            depth -= q
            # partial coverage: pushed far back so fringes only win over background
            pen = rec[..., COV] * -FRINGE
            pen += FRINGE
            np.add(depth, pen, out=rec[..., D])
            reg = buf[y0:y1, x0:x1]
            win = rec[..., D] < reg[..., D]
            if not win.any():
                continue
            ma, mb = matl[c]
            if ma == mb:
                rec[..., CODE] = c * MAT_BITS + ma
            else:
                np.copyto(rec[..., CODE], np.where(t < spl[c], float(c * MAT_BITS + ma), float(c * MAT_BITS + mb)))
            if headl[c] and face_dir is not None:
                # hair on the back of the head: normal pointing away from the face
                fx_, fy_, fz_ = (float(v) for v in face_dir)
                nz = np.sqrt(np.maximum(1.0 - rec[..., NX] ** 2 - rec[..., NY] ** 2, 0.0))
                back = rec[..., NX] * fx_ + rec[..., NY] * fy_ - nz * fz_ < -0.25
                rec[..., CODE][back] = c * MAT_BITS + mb
            np.copyto(reg, rec, where=win[..., None])
            if y0 < fy0:
                fy0 = y0
            if y1 > fy1:
                fy1 = y1
            if x0 < fx0:
                fx0 = x0
            if x1 > fx1:
                fx1 = x1
        self.bbox = (fy0, fy1, fx0, fx1) if fy1 > fy0 else (0, 0, 0, 0)

    def finish(self, jump: float, group: np.ndarray) -> None:
        """Shade the frame's figure: Lambert + ambient, and outlines where a 4-connected neighbour
        belongs to another body volume (``group[capsule]``, ``group[-1]`` for background) and lies more
        than ``jump`` (world units) deeper."""
        y0, y1, x0, x1 = self.bbox
        if y1 <= y0:
            self.shade = self.material = None
            return
        reg = self.buf[y0:y1, x0:x1]
        code = reg[..., CODE].astype(np.int32)
        cap = code >> 4 if MAT_BITS == 16 else code // MAT_BITS
        self.material = (code - cap * MAT_BITS).astype(np.intp)
        nx, ny = reg[..., NX], reg[..., NY]
        lx, ly, lz = (float(v) for v in LIGHT)
        nz2 = nx * nx
        nz2 += ny * ny
        np.minimum(nz2, 1.0, out=nz2)
        np.subtract(1.0, nz2, out=nz2)
        np.sqrt(nz2, out=nz2)
        lam = nx * lx
        lam += ny * ly
        lam -= nz2 * lz
        np.maximum(lam, 0.0, out=lam)
        lam *= DIFFUSE
        lam += AMBIENT
        d = reg[..., D]
        g = group[cap]
        edge = np.zeros(d.shape, dtype=bool)
        edge[:-1] |= ((d[1:] - d[:-1]) > jump) & (g[1:] != g[:-1])
        edge[1:] |= ((d[:-1] - d[1:]) > jump) & (g[:-1] != g[1:])
        edge[:, :-1] |= ((d[:, 1:] - d[:, :-1]) > jump) & (g[:, 1:] != g[:, :-1])
        edge[:, 1:] |= ((d[:, :-1] - d[:, 1:]) > jump) & (g[:, :-1] != g[:, 1:])
        lam[edge] *= OUTLINE
        self.shade = lam

    def render_frame(self, out: np.ndarray, bg: np.ndarray, palette: np.ndarray, jump: float, group: np.ndarray,
                     noise=None) -> None:
        """The drawn frame as an image: ``out`` ((H, W, 3) uint8) = the shaded figure (:meth:`finish`)
        blended over ``bg`` ((H, W, 3) float32, +0.5 for the truncating conversion; :meth:`composite`), plus
        ``noise`` (a :class:`~vidstyle.render.background.NoiseBank`: its next field), clipped to [0, 255].

        Runs the compiled kernels (:func:`_shade_loop`, :func:`_composite_loop`) when numba is installed:
        the same float32 operations in the same order as :meth:`render_frame_numpy`, the same bytes
        (tests/test_render_raster_kernel.py)."""
        kernels = _frame_kernels()
        if kernels is None:  # pragma: no cover - numba is a dependency
            self.render_frame_numpy(out, bg, palette, jump, group, noise)
            return
        shade_k, comp_k = kernels
        y0, y1, x0, x1 = self.bbox
        h, w = max(y1 - y0, 0), max(x1 - x0, 0)
        shade = np.empty((h, w), dtype=np.float32)
        material = np.empty((h, w), dtype=np.intp)
        if h and w:
            shade_k(self.buf, y0, y1, x0, x1, np.float32(jump), np.ascontiguousarray(group, dtype=np.int32),
                    _LIGHT32, _SHADING32, shade, material)
        self.shade, self.material = (shade, material) if h and w else (None, None)
        field, oy, ox = noise.pick() if noise is not None else (None, 0, 0)
        comp_k(out, bg, self.buf, y0, y1, x0, x1, shade, material, palette,
               _NO_NOISE if field is None else field, oy, ox, field is not None)

    def render_frame_numpy(self, out: np.ndarray, bg: np.ndarray, palette: np.ndarray, jump: float, group: np.ndarray,
                           noise=None) -> None:
        """:meth:`render_frame` in numpy (the reference of the compiled kernels)."""
        img = bg.copy()
        self.finish(jump, group)
        self.composite(img, palette)
        if noise is not None:
            noise.add(img)
        np.clip(img, 0.0, 255.0, out=img)
        out[...] = img.astype(np.uint8)

    def composite(self, out: np.ndarray, palette: np.ndarray) -> None:
        """Blend the shaded figure over ``out`` ((H, W, 3) float32, modified in place)."""
        y0, y1, x0, x1 = self.bbox
        if y1 <= y0 or self.shade is None:
            return
        col = palette[self.material]  # palette must have MAT_BITS rows (background code -1 -> row 15)
        col *= self.shade[..., None]
        reg = out[y0:y1, x0:x1]
        col -= reg
        col *= self.buf[y0:y1, x0:x1, COV, None]  # in [0, 1] wherever a capsule won
        reg += col

    def part_mask(self, owner: np.ndarray, dtype=np.int8) -> np.ndarray:
        """(H, W) part ids (the owning joint of the front-most capsule; -1 = background). A pixel belongs
        to the figure when its centre lies inside a capsule (coverage >= 0.5)."""
        mask = np.full((self.H, self.W), -1, dtype=dtype)
        y0, y1, x0, x1 = self.bbox
        if y1 > y0:
            reg = self.buf[y0:y1, x0:x1]
            cid = np.floor(reg[..., CODE] / MAT_BITS).astype(np.int64)
            on = (cid >= 0) & (reg[..., COV] >= 0.5)
            mask[y0:y1, x0:x1] = np.where(on, owner[np.maximum(cid, 0)], -1)
        return mask
