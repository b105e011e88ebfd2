"""The JSON that `pincal calibrate --json` prints.

Its text (printed, and written as report.txt) is :func:`pincal.report.calibration_text`.
"""

from __future__ import annotations

from pincal.identification import IdentificationRecord, result_to_dict

__all__ = ["result_json"]


def result_json(result: IdentificationRecord, data_path: str, urdf: str | None = None) -> dict:
    """The identification result as ``identification.json`` (SI values and std).

    Built via :func:`pincal.identification.result_to_dict` with the data
    file (and the calibrated URDF) as annotations.
    """
    notes = {"data": data_path}
    if urdf is not None:
        notes["calibrated_urdf"] = urdf
    return result_to_dict(result, notes)
