"""Stage 7b — export a calibration to a controller's own kinematic parameters.

A registry of controller formats (one class each, with the equations it assumes):
``linuxcnc-genhexkins`` (hexapod strut ends), ``generic-table`` (every joint
placement and zero offset, any machine), ``dh-standard`` / ``dh-modified`` (a DH table
fitted to a serial arm's joint axes), ``dh-offsets-lengths`` (zero offsets and link
lengths on the nominal DH table), ``klipper-delta`` / ``linuxcnc-lineardeltakins``
(linear deltas), ``rotary-delta`` (a per-arm table of a rotary delta) and
``volumetric-map`` (an error map and command corrections on a workspace grid). Each
export is a projection, reported with the RMS and max pose difference over the
workspace and what the format cannot express.
"""

from __future__ import annotations

from pincal.export._format import ControllerFormat, Projection
from pincal.export._machine import CalibratedMachine
from pincal.export._registry import FORMATS, Export, export_calibration, write_export

__all__ = [
    "FORMATS",
    "CalibratedMachine",
    "ControllerFormat",
    "Export",
    "Projection",
    "export_calibration",
    "write_export",
]
