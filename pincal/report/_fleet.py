"""The fleet report: per-parameter distributions (PNG), Markdown and HTML pages.

Everything is drawn from the fleet document ``fleet.json`` (``pincal fleet run``), so
the report can be rebuilt from it alone. Deviations are shown from the fleet's robust
centre, lengths in mm and angles in mrad; out-of-family units in red.
"""

from __future__ import annotations

import html
import os
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from pincal.report._plots import new_figure, save_figure

__all__ = ["fleet_html", "fleet_markdown", "plot_fleet"]

_FLAGGED = "#c0392b"
_FAMILY = "#34495e"


def plot_fleet(doc: Mapping[str, Any], path: str | os.PathLike[str]) -> Path:
    """Every unit's deviation from the fleet centre, per parameter (lengths | angles).

    Args:
        doc: the fleet document (``parameters`` with name/unit/centre/production_std,
            ``units`` with their ``values`` by name [m, rad]).
        path: the PNG to write (atomically).

    Returns:
        The PNG's path.
    """
    params = list(doc["parameters"])
    units = [u for u in doc["units"] if u.get("values")]
    kinds = [("m", "length deviation [mm]"), ("rad", "angle deviation [mrad]")]
    kinds = [(k, label) for k, label in kinds if any(p["unit"] == k for p in params)]
    fig = new_figure(max(7.0, 0.22 * len(params) + 2.0), 3.2 * max(len(kinds), 1))
    grid = fig.subplots(max(len(kinds), 1), 1, squeeze=False)[:, 0]
    for ax, (kind, label) in zip(grid, kinds, strict=False):
        cols = [p for p in params if p["unit"] == kind]
        x = np.arange(len(cols))
        band = 3e3 * np.array([p["production_std"] for p in cols])
        for i, b in enumerate(band):  # each parameter's own ±3τ, as wide as its column
            ax.fill_between([i - 0.4, i + 0.4], -b, b, color="#d5dbdb", lw=0)
        for u in units:
            dev = [1e3 * (u["values"][p["name"]] - p["centre"]) for p in cols]
            flagged = bool(u.get("out_of_family"))
            jitter = (zlib.crc32(u.get("session", u["id"]).encode()) % 100 - 50) / 250.0
            ax.plot(
                x + jitter,
                dev,
                "o",
                ms=3 if not flagged else 4,
                alpha=0.5 if not flagged else 0.9,
                color=_FLAGGED if flagged else _FAMILY,
            )
        ax.set_xticks(x)
        ax.set_xticklabels([p["name"] for p in cols], rotation=90, fontsize=6)
        ax.set_ylabel(label)
        ax.axhline(0.0, color="k", lw=0.5)
    n_flagged = sum(bool(u.get("out_of_family")) for u in units)
    title = fig.suptitle(
        f"{len(units)} calibrated units: deviation from the fleet centre\n"
        f"({n_flagged} out of family, red; grey: ±3τ production spread)"
    )
    return save_figure(fig, path, grid, title)


def _count(summary: Mapping[str, Any]) -> str:
    ids = summary.get("unit_ids", summary["units"])
    return f"{ids} units" + (f", {summary['units']} sessions" if ids != summary["units"] else "")


def _rows(doc: Mapping[str, Any]) -> list[list[str]]:
    rows = []
    for u in doc["units"]:
        d, p = u.get("distance"), u.get("p_value")
        largest = ", ".join(f"{x['name']} {x['z']:+.1f}σ" for x in u.get("largest", []))
        rows.append(
            [
                u.get("session", u["id"]),
                u["status"],
                {True: "**yes**", False: "no", None: "–"}[u.get("out_of_family")],
                "–" if d is None else f"{d:.1f}",
                "–" if p is None else f"{p:.2g}",
                largest or (u.get("reason") or "")[:120],
            ]
        )
    return rows


_DRIFT_HEAD = ["unit", "sessions", "drifted", "T²", "dof", "p-value", "largest changes"]


_PARAMETER_HEAD = [
    "parameter", "centre", "production σ τ", "median unit σ", "detectable alone (95 %)"
]  # fmt: skip


def _parameter_rows(doc: Mapping[str, Any]) -> list[list[str]]:
    """One row per compared parameter, in mm or mrad."""
    rows = []
    for p in doc["parameters"]:
        unit = "mm" if p["unit"] == "m" else "mrad"
        cells = [f"{1e3 * p['centre']:+.4f} {unit}"]
        for key in ("production_std", "estimate_std", "detectable_error"):
            cells.append(f"{1e3 * p[key]:.4f} {unit}" if key in p else "—")
        rows.append([p["name"], *cells])
    return rows


def _drift_rows(doc: Mapping[str, Any]) -> list[list[str]]:
    rows = []
    for d in doc.get("drift", []):
        moved = ", ".join(
            f"{x['name']} {1e3 * x['change']:+.4f} {'mm' if x['unit'] == 'm' else 'mrad'} "
            f"({x['z']:+.1f}σ)"
            for x in d["largest"]
        )
        rows.append(
            [
                d["id"],
                f"{d['before']} → {d['after']}",
                "**yes**" if d["drifted"] else "no",
                f"{d['distance']:.1f}",
                str(d["dof"]),
                f"{d['p_value']:.2g}",
                moved,
            ]
        )
    return rows


def _drift_markdown(doc: Mapping[str, Any]) -> list[str]:
    lines = ["", "## Drift between sessions", "", doc.get("drift_test", ""), ""]
    rows = _drift_rows(doc)
    if rows:
        lines += ["| " + " | ".join(_DRIFT_HEAD) + " |", "|---" * len(_DRIFT_HEAD) + "|"]
        lines += ["| " + " | ".join(r) + " |" for r in rows]
    return lines


def _table_html(head: list[str], rows: list[list[str]], flag_col: int) -> str:
    esc = html.escape
    body = "".join(
        "<tr"
        + (' class="flag"' if "**yes**" in r[flag_col] else "")
        + ">"
        + "".join(f"<td>{esc(c.replace('**', ''))}</td>" for c in r)
        + "</tr>"
        for r in rows
    )
    return "<table><tr>" + "".join(f"<th>{esc(h)}</th>" for h in head) + f"</tr>{body}</table>"


def fleet_markdown(doc: Mapping[str, Any], png: str = "fleet_parameters.png") -> str:
    """The fleet report as Markdown (summary, the test, units, parameter spread).

    Args:
        doc: the fleet document.
        png: the distribution plot's file name beside the page.

    Returns:
        The Markdown text.
    """
    s, t = doc["summary"], doc["test"]
    lines = [
        f"# Fleet report: {doc['model']} ({_count(s)})",
        "",
        f"- calibrated: {s['calibrated']}, refused by the quality gate: {s['refused']}, "
        f"failed: {s['failed']}",
        f"- out of family: {s['out_of_family']} ({', '.join(s['out_of_family_ids']) or 'none'})",
        f"- drifted between sessions: {s.get('drifted', 0)} of {s.get('drift_compared', 0)} "
        f"compared ({', '.join(s.get('drifted_ids', [])) or 'none'})",
        "",
        "## The test",
        "",
        t["description"],
        "",
        f"![per-parameter distributions]({png})",
        "",
        "## Units",
        "",
        "| unit | status | out of family | distance D | p-value | largest deviations / reason |",
        "|---|---|---|---|---|---|",
    ]
    lines += ["| " + " | ".join(r) + " |" for r in _rows(doc)]
    lines += ["", "## Parameters", ""]
    lines += ["| " + " | ".join(_PARAMETER_HEAD) + " |", "|---" * len(_PARAMETER_HEAD) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in _parameter_rows(doc)]
    lines += _drift_markdown(doc)
    return "\n".join(lines) + "\n"


def fleet_html(doc: Mapping[str, Any], png: str = "fleet_parameters.png") -> str:
    """The fleet report as one HTML page (the PNG beside it).

    Args:
        doc: the fleet document.
        png: the distribution plot's file name beside the page.

    Returns:
        The HTML text.
    """
    s, t = doc["summary"], doc["test"]
    esc = html.escape
    head = ["unit", "status", "out of family", "distance D", "p-value", "largest / reason"]
    drift = _drift_rows(doc)
    drifted = f"<h2>Drift between sessions</h2><p>{esc(doc.get('drift_test', ''))}</p>" + (
        _table_html(_DRIFT_HEAD, drift, 2) if drift else ""
    )
    return (
        "<!doctype html><html><head><meta charset='utf-8'>"
        f"<title>Fleet report: {esc(doc['model'])}</title><style>"
        "body{font-family:sans-serif;max-width:70em;margin:auto}"
        "td,th{padding:2px 8px;border-bottom:1px solid #ddd}"
        f".flag{{color:{_FLAGGED};font-weight:bold}}</style></head><body>"
        f"<h1>Fleet report: {esc(doc['model'])} ({esc(_count(s))})</h1>"
        f"<p>calibrated {s['calibrated']}, refused by the gate {s['refused']}, failed "
        f"{s['failed']}; <b>out of family: {s['out_of_family']}</b> "
        f"({esc(', '.join(s['out_of_family_ids']) or 'none')})"
        f"; drifted between sessions: {s.get('drifted', 0)} of {s.get('drift_compared', 0)} "
        f"compared ({esc(', '.join(s.get('drifted_ids', [])) or 'none')})</p>"
        f"<p>{esc(t['description'])}</p><img src='{esc(png)}' style='max-width:100%'>"
        + _table_html(head, _rows(doc), 2)
        + "<h2>Parameters</h2>"
        + _table_html(_PARAMETER_HEAD, _parameter_rows(doc), 0)
        + drifted
        + "</body></html>\n"
    )
