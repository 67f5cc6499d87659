"""A self-contained HTML page from a Markdown report: plots and videos embedded.

The Markdown is rendered by Python-Markdown (tables, fenced code); every local
image or video it links (``![x](plot.png)``, ``![x](trial.gif)``, ``![x](trial.mp4)``)
is inlined as a ``data:`` URI, so the page can be mailed or archived as one file.
"""

from __future__ import annotations

import base64
import html
import re
from pathlib import Path

import markdown

from learning.atomic import atomic_open

__all__ = ["markdown_to_html", "write_html_report"]

_MIME = {".png": "image/png", ".gif": "image/gif", ".jpg": "image/jpeg", ".jpeg": "image/jpeg",
         ".svg": "image/svg+xml", ".mp4": "video/mp4", ".webm": "video/webm"}
_IMG = re.compile(r'<img alt="([^"]*)" src="([^"]+)"\s*/?>')
_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 1100px; margin: 0.8em auto; padding: 0 1em;
       color: #222; line-height: 1.4; font-size: 15px; }
h1 { font-size: 1.45em; margin: 0.2em 0 0.3em; }
h2 { font-size: 1.2em; margin: 0.8em 0 0.3em; }
ul { margin: 0.3em 0; padding-left: 1.4em; }
p { margin: 0.5em 0; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.9em; max-width: 100%; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.5em; text-align: right; }
div.table { max-width: 100%; overflow-x: auto; }
th:first-child, td:first-child { text-align: left; }
img, video { max-width: 100%; }
code, pre { background: #f4f4f4; }
pre { padding: 0.6em; overflow-x: auto; }
"""


def _inline(match: re.Match, base: Path, missing: list[str]) -> str:
    alt, src = match.group(1), match.group(2)
    if re.match(r"^[a-z]+:", src):  # already a URI (data:, http:) — leave it
        return match.group(0)
    path = (base / src).resolve()
    mime = _MIME.get(path.suffix.lower())
    if mime is None or not path.is_file():
        missing.append(src)
        return f"<p><em>[{html.escape(alt or src)}: file not found]</em></p>"
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    if mime.startswith("video/"):
        return (f'<video controls loop muted autoplay title="{html.escape(alt)}">'
                f'<source src="data:{mime};base64,{data}" type="{mime}"></video>')
    return f'<img alt="{html.escape(alt)}" src="data:{mime};base64,{data}"/>'


_TABLE = re.compile(r"<table>.*?</table>", re.S)


def _narrow_table(table: str) -> str:
    """A table that fits a narrow page: its cells may wrap after an underscore (``random_<wbr>handover``)
    as well as at spaces, and what still does not fit scrolls inside its own box, never cut off."""
    table = re.sub(r">([^<]+)<", lambda m: ">" + m.group(1).replace("_", "_<wbr>") + "<", table)
    return f'<div class="table">{table}</div>'


def markdown_to_html(text: str, base_dir: str | Path, title: str = "mpcshare report") -> tuple[str, list[str]]:
    """Render ``text`` and inline the local files it links (relative to ``base_dir``).

    Returns ``(page, missing)``: the HTML page and the links that could not be inlined.
    """
    body = markdown.markdown(text, extensions=["tables", "fenced_code"], output_format="html")
    missing: list[str] = []
    body = _IMG.sub(lambda m: _inline(m, Path(base_dir), missing), body)
    body = _TABLE.sub(lambda m: _narrow_table(m.group(0)), body)
    page = (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head>\n"
            f"<body>\n{body}\n</body></html>\n")
    return page, missing


def write_html_report(markdown_path: str | Path, html_path: str | Path | None = None) -> list[str]:
    """Write the self-contained HTML version of ``markdown_path``; returns links not inlined."""
    md_path = Path(markdown_path)
    out = Path(html_path) if html_path is not None else md_path.with_suffix(".html")
    page, missing = markdown_to_html(md_path.read_text(encoding="utf-8"), md_path.parent)
    with atomic_open(out, "w") as f:
        f.write(page)
    return missing
