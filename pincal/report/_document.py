"""A report document: sections of text, images and tables as Markdown, HTML and JSON.

The HTML page is self-contained: images are embedded as base64 ``data:`` URIs, so the
file can be copied, mailed or archived alone. The Markdown and JSON hold the same
tables (same numbers, same units in the headers).
"""

from __future__ import annotations

import base64
import html
import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, SupportsFloat, cast

from pincal.errors import ReportError
from pincal.io import atomic_write_bytes

__all__ = ["ReportFiles", "Section", "Table", "write_report"]


@dataclass(frozen=True)
class Table:
    """A table for a report: ``rows`` are sequences of cells (str or numbers)."""

    headers: Sequence[str]
    rows: Sequence[Sequence[object]]
    caption: str = ""


@dataclass(frozen=True)
class Section:
    """One report section: a heading, paragraphs of text, images and tables."""

    title: str
    text: str = ""
    images: Sequence[str | os.PathLike] = field(default_factory=tuple)
    tables: Sequence[Table] = field(default_factory=tuple)


@dataclass(frozen=True)
class ReportFiles:
    """Paths of a written report (``json`` None when not written)."""

    markdown: Path
    html: Path
    json: Path | None = None


def _cell(value: object) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _json_cell(value: object) -> object:
    """A table cell as JSON: numbers as numbers (NaN as null), the rest as text."""
    if isinstance(value, bool) or value is None:
        return value
    if isinstance(value, (int, float)):
        return float(value) if math.isfinite(float(value)) else None
    try:
        f = float(cast(SupportsFloat, value))  # numpy scalars
    except (TypeError, ValueError):
        return str(value)
    return f if math.isfinite(f) else None


def _data_uri(path: Path) -> str:
    kind = {".png": "image/png", ".svg": "image/svg+xml", ".jpg": "image/jpeg"}.get(
        path.suffix.lower(), "application/octet-stream"
    )
    return f"data:{kind};base64," + base64.b64encode(path.read_bytes()).decode("ascii")


def _markdown_table(table: Table) -> str:
    lines = []
    if table.caption:
        lines.append(f"*{table.caption}*\n")
    lines.append("| " + " | ".join(str(h) for h in table.headers) + " |")
    lines.append("|" + "|".join(" --- " for _ in table.headers) + "|")
    for row in table.rows:
        cells = [_cell(c).replace("|", "\\|") for c in row]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


#: a cell longer than this [characters] is prose: aligned left, not as a number
_PROSE = 40


def _html_cell(text: str) -> str:
    """A ``<td>``; prose (a finding, a note) left-aligned, numbers and words right."""
    mark = ' class="text"' if len(text) > _PROSE else ""
    return f"<td{mark}>{html.escape(text)}</td>"


def _html_table(table: Table) -> str:
    parts = ["<table>"]
    if table.caption:
        parts.append(f"<caption>{html.escape(table.caption)}</caption>")
    parts.append("<tr>" + "".join(f"<th>{html.escape(str(h))}</th>" for h in table.headers))
    for row in table.rows:
        parts.append("<tr>" + "".join(_html_cell(_cell(c)) for c in row))
    parts.append("</table>")
    return "\n".join(parts)


_HTML_PAGE = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ font: 15px/1.5 sans-serif; max-width: 60em; margin: 2em auto; padding: 0 1em;
  color: #222; }}
img {{ max-width: 100%; border: 1px solid #ddd; margin: 0.5em 0; }}
table {{ border-collapse: collapse; margin: 0.8em 0; }}
th, td {{ border: 1px solid #bbb; padding: 2px 8px; text-align: right; }}
th {{ background: #eee; }}
td:first-child, td.text {{ text-align: left; }}
p.note {{ color: #555; font-size: 90%; }}
caption {{ caption-side: top; font-style: italic; text-align: left; }}
</style>
</head>
<body>
<h1>{title}</h1>
{body}
</body>
</html>
"""


def write_report(
    directory: str | os.PathLike,
    sections: Sequence[Section],
    *,
    title: str = "pincal calibration report",
    name: str = "report",
    markdown_images: bool = True,
    json_data: dict | None = None,
) -> ReportFiles:
    """Write ``<name>.md``, ``<name>.html`` (and ``<name>.json``) into ``directory``.

    The HTML embeds every image as a base64 ``data:`` URI (one self-contained file);
    the Markdown references images by their path relative to ``directory`` (or, with
    ``markdown_images`` False, leaves them out and points to the HTML). Missing images
    are an error. All files are written atomically.

    Args:
        directory: output folder (created).
        sections: the report's sections.
        title: page title.
        name: file stem of the written files (``<name>.md``, ``<name>.html``, ...).
        markdown_images: link the images from the Markdown (they must then stay).
        json_data: when given, ``<name>.json`` is written with it plus ``title`` and the
            sections' text and tables (the same numbers as the HTML and Markdown).

    Returns:
        ReportFiles.

    Raises:
        ReportError: an image does not exist.
    """
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    md = [f"# {title}", ""]
    body = []
    doc_sections = []
    for section in sections:
        md += [f"## {section.title}", ""]
        body.append(f"<h2>{html.escape(section.title)}</h2>")
        if section.text:
            md += [section.text, ""]
            for paragraph in section.text.split("\n\n"):
                body.append(f"<p>{html.escape(paragraph)}</p>")
        for image in section.images:
            image_path = Path(image)
            if not image_path.is_absolute():
                image_path = out / image_path
            if not image_path.is_file():
                raise ReportError(f"image {str(image)!r} of section {section.title!r} not found")
            if markdown_images:
                rel = Path(os.path.relpath(image_path.resolve(), out.resolve())).as_posix()
                md += [f"![{image_path.stem}]({rel})", ""]
            alt = html.escape(image_path.stem)
            body.append(f'<img src="{_data_uri(image_path)}" alt="{alt}">')
        if section.images and not markdown_images:
            md += [f"*Plots ({len(section.images)}): see {name}.html.*", ""]
        for table in section.tables:
            md += [_markdown_table(table), ""]
            body.append(_html_table(table))
        doc_sections.append(
            {
                "title": section.title,
                "text": section.text,
                "tables": [
                    {
                        "caption": t.caption,
                        "headers": [str(h) for h in t.headers],
                        "rows": [[_json_cell(c) for c in row] for row in t.rows],
                    }
                    for t in section.tables
                ],
            }
        )
    md_path = atomic_write_bytes(out / f"{name}.md", "\n".join(md).encode("utf-8"))
    html_text = _HTML_PAGE.format(title=html.escape(title), body="\n".join(body))
    html_path = atomic_write_bytes(out / f"{name}.html", html_text.encode("utf-8"))
    json_path = None
    if json_data is not None:
        doc = _finite({"title": title, **json_data, "sections": doc_sections})
        text = json.dumps(doc, indent=1, ensure_ascii=False, allow_nan=False)
        json_path = atomic_write_bytes(out / f"{name}.json", (text + "\n").encode("utf-8"))
    return ReportFiles(markdown=md_path, html=html_path, json=json_path)


def _finite(value: Any) -> Any:
    """``value`` with every NaN or infinite float replaced by None (JSON has neither)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value
