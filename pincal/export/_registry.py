"""The registry of controller formats and the one export function.

An export writes a header comment (model, calibration, the projection report of
:mod:`pincal.export._format`) then the format's numbers, atomically (whole or not at
all). The poses judged and the poses a format fits over are two separate random draws
(seeds ``seed`` and ``seed + 1``) of :func:`pincal.model.sample_actuators`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pincal.errors import ExportError
from pincal.export._dh_pendant import OffsetsLengthsDH
from pincal.export._dh_table import ModifiedDH, StandardDH
from pincal.export._format import ControllerFormat, Projection, projection
from pincal.export._genhexkins import GenHexKins
from pincal.export._linear_delta import KlipperDelta, LinuxCncLinearDelta
from pincal.export._machine import CalibratedMachine
from pincal.export._rotary_delta import RotaryDelta
from pincal.export._table import GenericTable
from pincal.export._volumetric import VolumetricMap
from pincal.io import atomic_write_text
from pincal.model import sample_actuators

__all__ = ["FORMATS", "Export", "export_calibration", "write_export"]

#: format name → format (one class each)
FORMATS: dict[str, ControllerFormat] = {
    f.name: f
    for f in (
        GenHexKins(),
        GenericTable(),
        StandardDH(),
        ModifiedDH(),
        OffsetsLengthsDH(),
        KlipperDelta(),
        LinuxCncLinearDelta(),
        RotaryDelta(),
        VolumetricMap(),
    )
}


@dataclass(frozen=True)
class Export:
    """An export: the file text (header included) and its projection."""

    text: str
    projection: Projection


def export_calibration(
    machine: CalibratedMachine, format_name: str, *, poses: int = 200, seed: int = 0
) -> Export:
    """The text of ``machine`` in ``format_name`` and how far it is from the model.

    Args:
        machine: the calibration.
        format_name: a key of :data:`FORMATS`.
        poses: random workspace poses the projection is judged on (≥ 1).
        seed: their seed (the fitted-over poses use ``seed + 1``).

    Raises:
        ExportError: unknown format, or a machine the format cannot describe.
        ModelFileError: too few reachable workspace poses.
    """
    fmt = FORMATS.get(format_name)
    if fmt is None:
        raise ExportError(f"unknown export format {format_name!r}; known: {sorted(FORMATS)}")
    mech = machine.calibrated
    q_eval = sample_actuators(mech, poses, np.random.default_rng(seed))
    q_fit = sample_actuators(mech, max(poses, 64), np.random.default_rng(seed + 1))
    built = fmt.build(machine, q_fit)
    proj = projection(fmt.name, built, machine, q_eval)
    head = [
        f"pincal export --format {fmt.name}: {fmt.summary}",
        f"model {machine.model!r}, calibration {machine.source}"
        + (f", preset {machine.preset!r}" if machine.preset else ""),
        *proj.lines(),
    ]
    header = "".join(f"# {line}\n" for line in head)
    return Export(header + built.body, proj)


def write_export(export: Export, out: str | Path) -> Path:
    """Write ``export`` to ``out`` atomically."""
    return atomic_write_text(out, export.text)
