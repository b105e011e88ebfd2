"""Where a ``pincal run`` campaign reads and writes, checked before the first step.

The calibration directory ``<out>`` holds only its own files; the inputs the campaign
generates (pose design, simulated measurements, imported sockets, validation poses,
cross-validation folds) go to ``<out>-inputs/`` beside it.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from pincal.cli._campaign import Campaign

__all__ = ["Paths", "campaign_paths", "check_campaign_outputs"]


@dataclass(frozen=True)
class Paths:
    """Where the steps read and write (generated inputs in ``<out>-inputs/`` beside ``<out>``)."""

    out: Path
    design: Path
    data: Path
    validation: Path | None
    validation_json: Path


def campaign_paths(c: Campaign, out: Path) -> Paths:
    """The step paths of campaign ``c`` writing into ``out``."""
    from pincal.io import VALIDATION_FILE

    inputs = out.parent / f"{out.name}-inputs"  # the calibration directory holds only its own files
    data = Path(c.measurements.file) if c.measurements.file else inputs / "measurements.csv"
    if c.sockets is not None:  # the plain table, imported; absolute: validate --cv reads it
        data = (inputs / "sockets.csv").resolve()
    v = c.validation
    val = None if v.source == "none" else Path(v.file) if v.file else inputs / "validation.csv"
    return Paths(out, inputs / "design.csv", data, val, out / VALIDATION_FILE)


def _writable_ancestor(path: Path) -> Path:
    """The nearest existing ancestor of ``path`` (the directory that gets the new entries)."""
    for parent in path.parents:
        if parent.exists():
            return parent
    return Path(path.anchor or ".")


def check_campaign_outputs(c: Campaign, p: Paths) -> None:
    """Refuse, before the first step, any output location a step would refuse or damage.

    Checks the calibration directory (not the file system root, replaceable: see
    :func:`pincal.io.check_replaceable`), the generated-inputs folder ``<out>-inputs/``,
    every file a step writes there (and its side files) against the campaign's inputs,
    and that the parent directories are writable.

    Raises:
        CampaignError: naming the location and what to change.
    """
    from pincal.cli._paths import guard_paths
    from pincal.cli.common import model_input
    from pincal.errors import CampaignError, PincalError
    from pincal.io import check_replaceable

    out = p.out.resolve()
    if out.parent == out:
        raise CampaignError(
            f"out: {str(p.out)!r} is the file system root; give a directory of its own, "
            "e.g. out: campaign-out (the generated inputs go to OUT-inputs/ beside it)"
        )
    inputs = p.design.parent
    generated = {"design": p.design if c.design else None}
    if c.measurements.file is None or c.sockets is not None:
        generated["measurements"] = p.data
    if c.validation.source == "simulated" and c.validation.file is None:
        generated["validation"] = p.validation
    sides: dict[str, tuple[str, ...]] = {"design": (".commands.csv", ".json")}
    if c.sockets is not None:  # the imported sockets file has no side file
        sides["measurements"] = ()
    implied = {f"the {k} step's {s} file": Path(v).with_suffix(s)
               for k, v in generated.items() if v is not None
               for s in sides.get(k, (".truth.json",))}  # fmt: skip
    try:
        check_replaceable(p.out)
        if inputs.exists() and not inputs.is_dir():
            raise CampaignError(
                f"{str(inputs)!r} (out's inputs folder) exists and is not a directory"
            )
        guard_paths(
            {"model": model_input(c.model), "measurements.file": c.measurements.file,
             "validation.file": c.validation.file},
            {f"{k} file": v for k, v in generated.items()},
            out_dirs={"out": p.out},
            implied=implied,
        )  # fmt: skip
    except PincalError as exc:
        raise CampaignError(f"campaign output: {exc}") from exc
    for where in (out, inputs.resolve()):
        base = _writable_ancestor(where)
        if not os.access(base, os.W_OK | os.X_OK):
            raise CampaignError(
                f"campaign output: cannot create {str(where)!r}: {str(base)!r} is not writable; "
                "choose another out"
            )
