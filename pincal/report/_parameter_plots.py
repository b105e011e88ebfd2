"""Plots of identified parameters: values with ±2σ bars and their correlations (PNG).

Drawn and written like every plot of :mod:`pincal.report._plots` (Agg canvas,
atomic PNG); values in SI units (m, rad), shown in the chosen display units.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from pincal.errors import ReportError
from pincal.report._plots import AFTER, TRUE, checked_vector, new_figure, save_figure, unit_of

__all__ = ["plot_correlation", "plot_parameters"]


def _parameter_kind(name: str) -> str:
    dof = name.rsplit(".", 1)[-1]
    if dof in ("rx", "ry", "rz") or dof.startswith(("alpha", "theta")):
        return "angle"
    return "length"


def plot_parameters(
    names: Sequence[str],
    values: Sequence[float] | np.ndarray,
    std: Sequence[float] | np.ndarray,
    true: Sequence[float] | np.ndarray | None = None,
    path: str | os.PathLike | None = None,
    *,
    kinds: Sequence[str] | None = None,
    length_unit: str = "mm",
    angle_unit: str = "mrad",
    title: str = "Identified parameters (±2σ)",
) -> Path:
    """Identified parameter values with ±2σ bars, lengths and angles in separate panels.

    Args:
        names: parameter names, shape (L,) (``<joint>.<dof>``).
        values: identified values, shape (L,) [m or rad].
        std: standard deviations, shape (L,) [m or rad].
        true: true values (simulation), shape (L,), drawn as markers, or None.
        path: PNG file to write (required).
        kinds: ``"length"`` or ``"angle"`` per parameter; by default inferred from
            the dof (``rx, ry, rz`` → angle, otherwise length).
        length_unit: display unit of the length panel (e.g. ``"mm"``).
        angle_unit: display unit of the angle panel (e.g. ``"mrad"``).
        title: figure title.
    """
    if path is None:
        raise ReportError("path is required")
    names = [str(n) for n in names]
    v = checked_vector(values, "values")
    s = checked_vector(std, "std")
    t = None if true is None else checked_vector(true, "true")
    for what, arr in (("values", v), ("std", s), ("true", t)):
        if arr is not None and arr.size != len(names):
            raise ReportError(f"{what} has {arr.size} entries but there are {len(names)} names")
    if np.any(s < 0):
        raise ReportError("std must be non-negative")
    kinds = list(kinds) if kinds is not None else [_parameter_kind(n) for n in names]
    if len(kinds) != len(names) or not set(kinds) <= {"length", "angle"}:
        raise ReportError("kinds must hold 'length' or 'angle' for each name")
    groups = [
        (kind, unit, [i for i, k in enumerate(kinds) if k == kind])
        for kind, unit in (("length", length_unit), ("angle", angle_unit))
    ]
    groups = [g for g in groups if g[2]]
    height = 1.5 + 0.22 * len(names) + 0.6 * len(groups)
    fig = new_figure(7.5, max(3.0, height))
    axes = fig.subplots(
        len(groups), 1, squeeze=False, height_ratios=[len(g[2]) + 2 for g in groups]
    )[:, 0]
    for ax, (kind, unit, idx) in zip(axes, groups, strict=True):
        factor, label = unit_of(unit)
        y = np.arange(len(idx))[::-1]
        ax.errorbar(
            v[idx] * factor,
            y,
            xerr=2 * s[idx] * factor,
            fmt="o",
            color=AFTER,
            ecolor=AFTER,
            capsize=3,
            ms=4,
            label="identified ±2σ",
        )
        if t is not None:
            ax.plot(t[idx] * factor, y, "x", color=TRUE, ms=7, mew=2, label="true")
        ax.axvline(0.0, color="0.6", lw=0.8)
        ax.set_yticks(y)
        ax.set_yticklabels([names[i] for i in idx], fontsize=8)
        ax.set_xlabel(f"{kind} [{label}]")
        ax.grid(axis="x", alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    axes[0].set_title(title)
    return save_figure(fig, path, axes)


def plot_correlation(
    names: Sequence[str], covariance: np.ndarray, path: str | os.PathLike
) -> Path:
    """Heat map of the parameter correlations ``C_ij / (σ_i σ_j)`` of a (L, L) covariance."""
    C = np.asarray(covariance, dtype=float)
    if C.ndim != 2 or C.shape != (len(names), len(names)) or not len(names):
        raise ReportError(f"covariance must be ({len(names)}, {len(names)}), got {C.shape}")
    s = np.sqrt(np.clip(np.diag(C), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        R = np.nan_to_num(C / np.outer(s, s), nan=0.0)
    size = min(12.0, 3.0 + 0.18 * len(names))
    fig = new_figure(size + 1.2, size)
    ax = fig.add_subplot()
    im = ax.imshow(R, vmin=-1.0, vmax=1.0, cmap="RdBu_r")
    ticks = np.arange(len(names))
    font = 8 if len(names) <= 40 else 5
    ax.set_xticks(ticks, [str(n) for n in names], rotation=90, fontsize=font)
    ax.set_yticks(ticks, [str(n) for n in names], fontsize=font)
    fig.colorbar(im, ax=ax, shrink=0.8, fraction=0.05, pad=0.02, label="correlation")
    ax.set_title("Parameter correlations")
    return save_figure(fig, path, [ax])
