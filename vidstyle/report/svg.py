"""Inline SVG charts for the self-contained HTML report (no plotting library, no external files)."""

from __future__ import annotations

import html
from typing import Sequence

import numpy as np

# Okabe-Ito palette plus neutrals: distinguishable for colour-blind readers
PALETTE = ["#E69F00", "#56B4E9", "#009E73", "#F0E442", "#0072B2", "#D55E00", "#CC79A7", "#999999",
           "#000000", "#8DD3C7", "#BEBADA", "#FB8072"]


def _esc(s: object) -> str:
    return html.escape(str(s), quote=True)


def _blues(v: float) -> str:
    """White -> dark blue for v in [0, 1]."""
    v = float(np.clip(v, 0.0, 1.0))
    r = int(round(255 - v * (255 - 8)))
    g = int(round(255 - v * (255 - 69)))
    b = int(round(255 - v * (255 - 148)))
    return f"#{r:02x}{g:02x}{b:02x}"


def heatmap(
    matrix: np.ndarray,
    row_labels: Sequence[str],
    col_labels: Sequence[str],
    title: str = "",
    vmax: float | None = None,
    fmt: str = "{:.2f}",
    cell: int = 44,
    xlabel: str = "",
    ylabel: str = "",
) -> str:
    """A matrix as an annotated SVG heatmap (rows top to bottom, columns left to right)."""
    m = np.asarray(matrix, dtype=float)
    R, C = m.shape
    vmax = float(np.nanmax(m)) if vmax is None and m.size else (vmax or 1.0)
    vmax = vmax if vmax > 0 else 1.0
    left, top = 110, 40 if title else 16
    width = left + C * cell + 20
    height = top + R * cell + 90
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
             f'viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="11" role="img">']
    if title:
        parts.append(f'<text x="{left}" y="20" font-size="13" font-weight="bold">{_esc(title)}</text>')
    for i in range(R):
        y = top + i * cell
        parts.append(f'<text x="{left - 6}" y="{y + cell / 2 + 4}" text-anchor="end">{_esc(row_labels[i])}</text>')
        for j in range(C):
            x = left + j * cell
            v = m[i, j]
            colour = _blues(v / vmax) if np.isfinite(v) else "#eeeeee"
            text_colour = "#ffffff" if np.isfinite(v) and v / vmax > 0.55 else "#222222"
            label = fmt.format(v) if np.isfinite(v) else "–"
            parts.append(f'<rect x="{x}" y="{y}" width="{cell}" height="{cell}" fill="{colour}" stroke="#ffffff"/>')
            parts.append(f'<text x="{x + cell / 2}" y="{y + cell / 2 + 4}" text-anchor="middle" '
                         f'fill="{text_colour}">{_esc(label)}</text>')
    ybase = top + R * cell + 8
    for j in range(C):
        x = left + j * cell + cell / 2
        parts.append(f'<text x="{x}" y="{ybase}" text-anchor="end" transform="rotate(-45 {x} {ybase})">'
                     f'{_esc(col_labels[j])}</text>')
    if xlabel:
        parts.append(f'<text x="{left + C * cell / 2}" y="{height - 4}" text-anchor="middle" '
                     f'font-style="italic">{_esc(xlabel)}</text>')
    if ylabel:
        parts.append(f'<text x="12" y="{top + R * cell / 2}" text-anchor="middle" font-style="italic" '
                     f'transform="rotate(-90 12 {top + R * cell / 2})">{_esc(ylabel)}</text>')
    parts.append("</svg>")
    return "".join(parts)


def timeline(
    tracks: dict[str, Sequence[str]],
    classes: Sequence[str],
    fps: float,
    width: int = 900,
    row_height: int = 26,
    title: str = "",
) -> str:
    """Label sequences (one per track, one label per frame) as coloured runs over time, with a legend."""
    n = max((len(t) for t in tracks.values()), default=0)
    colours = {c: PALETTE[i % len(PALETTE)] for i, c in enumerate(classes)}
    left, top = 140, 30 if title else 10
    plot_w = width - left - 10
    height = top + len(tracks) * (row_height + 6) + 60
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
             f'viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="11" role="img">']
    if title:
        parts.append(f'<text x="{left}" y="18" font-size="13" font-weight="bold">{_esc(title)}</text>')
    scale = plot_w / max(n, 1)
    for k, (name, labels) in enumerate(tracks.items()):
        y = top + k * (row_height + 6)
        parts.append(f'<text x="{left - 6}" y="{y + row_height / 2 + 4}" text-anchor="end">{_esc(name)}</text>')
        start = 0
        for i in range(1, len(labels) + 1):
            if i == len(labels) or labels[i] != labels[start]:
                x = left + start * scale
                w = max((i - start) * scale, 0.5)
                c = colours.get(labels[start], "#dddddd")
                parts.append(f'<rect x="{x:.2f}" y="{y}" width="{w:.2f}" height="{row_height}" fill="{c}">'
                             f'<title>{_esc(labels[start])}: frames {start}-{i - 1}</title></rect>')
                start = i
    axis_y = top + len(tracks) * (row_height + 6)
    seconds = n / fps if fps else 0
    step = max(1, int(np.ceil(seconds / 10)))
    for s in range(0, int(seconds) + 1, step):
        x = left + s * fps * scale
        parts.append(f'<line x1="{x:.1f}" y1="{axis_y}" x2="{x:.1f}" y2="{axis_y + 4}" stroke="#444"/>')
        parts.append(f'<text x="{x:.1f}" y="{axis_y + 15}" text-anchor="middle">{s}s</text>')
    lx = left
    ly = axis_y + 34
    for c in classes:
        parts.append(f'<rect x="{lx}" y="{ly - 9}" width="10" height="10" fill="{colours[c]}"/>')
        parts.append(f'<text x="{lx + 14}" y="{ly}">{_esc(c)}</text>')
        lx += 18 + 7 * len(str(c)) + 10
    parts.append("</svg>")
    return "".join(parts)

