"""A report document: sections of text, images and tables as Markdown + HTML."""

from __future__ import annotations

import html
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from pincal.errors import ReportError
from pincal.io._atomic import atomic_write_bytes

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
    """Paths of a written report."""

    markdown: Path
    html: Path


def _cell(value: object) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


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


def _html_table(table: Table) -> str:
    parts = ["<table>"]
    if table.caption:
        parts.append(f"<caption>{html.escape(table.caption)}</caption>")
    parts.append("<tr>" + "".join(f"<th>{html.escape(str(h))}</th>" for h in table.headers))
    for row in table.rows:
        parts.append("<tr>" + "".join(f"<td>{html.escape(_cell(c))}</td>" for c in row))
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
) -> ReportFiles:
    """Write ``<name>.md`` and ``<name>.html`` into ``directory``.

    Images are referenced by their path relative to ``directory`` (put the PNGs
    there or below so the report can be moved as one folder); missing images are
    an error. Both files are written atomically.
    """
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    md = [f"# {title}", ""]
    body = []
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
            rel = Path(os.path.relpath(image_path.resolve(), out.resolve())).as_posix()
            md += [f"![{image_path.stem}]({rel})", ""]
            body.append(f'<img src="{html.escape(rel)}" alt="{html.escape(image_path.stem)}">')
        for table in section.tables:
            md += [_markdown_table(table), ""]
            body.append(_html_table(table))
    md_path = atomic_write_bytes(out / f"{name}.md", "\n".join(md).encode("utf-8"))
    html_text = _HTML_PAGE.format(title=html.escape(title), body="\n".join(body))
    html_path = atomic_write_bytes(out / f"{name}.html", html_text.encode("utf-8"))
    return ReportFiles(markdown=md_path, html=html_path)
