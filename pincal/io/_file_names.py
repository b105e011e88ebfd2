"""The names of the files pincal writes, spelled once (the io stage owns every file kind).

A calibration directory (:mod:`pincal.io._calibration_dir`) holds :data:`MANIFEST`,
:data:`CALIBRATED_URDF` + :data:`CALIBRATED_SIDECAR`, :data:`IDENTIFICATION_FILE` and,
for a marker calibration, :data:`NOMINAL_URDF`; other commands add the
:data:`PINCAL_EXTRAS`. Other modules and the CLI use these constants, never the strings.
"""

from __future__ import annotations

__all__ = [
    "CALIBRATED_SIDECAR",
    "CALIBRATED_URDF",
    "CALIBRATION_FORMAT",
    "IDENTIFICATION_FILE",
    "MANIFEST",
    "MODEL_RECORD",
    "NOMINAL_URDF",
    "PINCAL_EXTRAS",
    "VALIDATION_FILE",
]

#: the manifest's ``format`` entry
CALIBRATION_FORMAT = "pincal calibration"
#: the manifest: format, files with their SHA-256, model, preset, noise, values
MANIFEST = "calibration.json"
#: the calibrated model (identified geometry at full precision) and its sidecar
CALIBRATED_URDF = "calibrated.urdf"
CALIBRATED_SIDECAR = "calibrated.yaml"
#: the identification result (``IdentificationResult.to_dict``)
IDENTIFICATION_FILE = "identification.json"
#: the registered start model of a marker calibration (instrument frame + marker set)
NOMINAL_URDF = "nominal.urdf"
#: the model's options (--sidecar, --frame, --lock) as a local sidecar that reloads it
MODEL_RECORD = "model.yaml"
#: files other pincal commands put into a calibration directory (``pincal report``,
#: ``pincal run``); stale once the calibration is replaced, so replaced with it
PINCAL_EXTRAS = frozenset({"campaign.yaml", "report.html", "report.md", "report.json"})
#: `pincal validate --out` in a calibration directory (`pincal run`, the README): an
#: extra too when its content is validate's (a user's file of that name is not)
VALIDATION_FILE = "validation.json"
