"""A self-contained HTML page: inline CSS, inline SVG, images as data URIs, no network access.

The page records its own health for automated checks: a tiny script at the top collects uncaught errors
and ``console.error`` calls into ``document.body.dataset.errors`` and sets ``data-rendered="ok"`` once
loaded, so ``chromium --headless --dump-dom`` shows whether it rendered cleanly.
"""

from __future__ import annotations

import base64
import html
from dataclasses import dataclass, field

CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:0;color:#1d1d1f;background:#fafafa}
header{background:#14213d;color:#fff;padding:18px 32px}
header h1{margin:0;font-size:22px} header p{margin:4px 0 0;opacity:.8}
main{max-width:1100px;margin:0 auto;padding:12px 32px 48px}
section{background:#fff;border:1px solid #e3e3e3;border-radius:8px;padding:16px 20px;margin:18px 0}
h2{font-size:17px;margin:0 0 10px} .row{display:flex;flex-wrap:wrap;gap:18px;align-items:flex-start}
table{border-collapse:collapse;font-size:13px} td,th{border-bottom:1px solid #eee;padding:4px 10px;text-align:left}
th{background:#f3f3f3} .num{text-align:right;font-variant-numeric:tabular-nums}
.seq{font-family:ui-monospace,monospace;font-size:12px;background:#f6f8fa;padding:6px 8px;border-radius:4px;
     overflow-wrap:anywhere} .note{color:#666;font-size:12px} img.anim{image-rendering:auto;border:1px solid #ddd}
.missing{color:#a33}
"""

HEALTH_JS = """
(function(){var errs=[];function add(m){errs.push(String(m));
 if(document.body){document.body.dataset.errors=errs.join(' | ');}}
 window.addEventListener('error',function(e){add(e.message||'error');});
 var ce=console.error;console.error=function(){add([].slice.call(arguments).join(' '));ce.apply(console,arguments);};
 window.addEventListener('load',function(){document.body.dataset.rendered='ok';
 if(errs.length){document.body.dataset.errors=errs.join(' | ');}});})();
"""


def esc(s: object) -> str:
    return html.escape(str(s), quote=True)


def data_uri(data: bytes, mime: str) -> str:
    return f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}"


@dataclass
class Page:
    title: str
    subtitle: str = ""
    sections: list[tuple[str, str]] = field(default_factory=list)

    def add(self, heading: str, body_html: str) -> None:
        self.sections.append((heading, body_html))

    def render(self) -> str:
        out = [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>{esc(self.title)}</title><style>{CSS}</style>",
            f"<script>{HEALTH_JS}</script></head><body>",
            f"<header><h1>{esc(self.title)}</h1><p>{esc(self.subtitle)}</p></header><main>",
        ]
        for heading, body in self.sections:
            out.append(f"<section><h2>{esc(heading)}</h2>{body}</section>")
        out.append("</main></body></html>")
        return "\n".join(out)


def table(rows: list[list[object]], header: list[str] | None = None) -> str:
    out = ["<table>"]
    if header:
        out.append("<tr>" + "".join(f"<th>{esc(h)}</th>" for h in header) + "</tr>")
    for row in rows:
        cells = []
        for v in row:
            if isinstance(v, float):
                cells.append(f'<td class="num">{v:.3f}</td>')
            elif isinstance(v, int):
                cells.append(f'<td class="num">{v}</td>')
            else:
                cells.append(f"<td>{esc(v)}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</table>")
    return "".join(out)
