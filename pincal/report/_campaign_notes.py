"""What a campaign adds to a calibration report: validation, simulated truth, pose design.

``pincal demo`` writes these into ``identification.json`` itself; a campaign run step by
step (``pincal run``, or by hand) has them in the files its other steps wrote: the
validation JSON of ``pincal validate --out``, the ``<data>.truth.json`` of ``pincal
simulate`` and the ``<poses>.json`` of ``pincal poses``. :func:`campaign_notes` turns
them into the report annotations :func:`pincal.report.calibration_report` reads, so the
campaign's report carries the same sections as the demo's.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from pincal._files import read_bytes
from pincal.errors import InputFileError, InputLimitError, ReportError

__all__ = ["campaign_notes"]

_MAX_BYTES = 50_000_000
_KEYS = ("rms_position_mm", "max_position_mm", "rms_orientation_mrad", "max_orientation_mrad")


def read_json_object(
    path: str | os.PathLike, what: str, limit: int = _MAX_BYTES
) -> dict[str, Any]:
    """A JSON file holding one object, read bounded (no FIFOs or devices).

    Raises:
        ReportError: missing or oversized file, invalid JSON, not an object (file named).
    """
    try:
        raw = read_bytes(Path(path), what, limit)
    except (InputFileError, InputLimitError) as exc:
        raise ReportError(str(exc)) from None
    try:
        data = json.loads(raw.decode("utf-8-sig"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ReportError(f"{what} {str(path)!r} is not valid JSON: {exc}") from None
    if not isinstance(data, dict):
        raise ReportError(
            f"{what} {str(path)!r} must hold a JSON object, got {type(data).__name__}"
        )
    return data


def _validation(doc: dict[str, Any], path: str) -> dict[str, Any]:
    """Annotations from ``pincal validate --json`` / ``--out`` (mm, mrad → report keys).

    A held-out file gives the ``validation_*`` annotations, ``--cv K`` the
    ``cross_validation`` one; a file of ``validate --cv`` alone has no ``before``.
    """
    cv = {"cross_validation": doc["cv"]} if "cv" in doc else {}
    if cv and "before" not in doc:
        return cv
    try:
        before, after = doc["before"], doc["after"]
        per_pose = doc["per_pose"]
        comps = list(doc["components"])
        errors = {
            side: {
                "position": [v * 1e-3 for v in per_pose[f"{side}_position_mm"]],
                "orientation": [v * 1e-3 for v in per_pose[f"{side}_orientation_mrad"]],
            }
            for side in ("before", "after")
        }
    except (KeyError, TypeError) as exc:
        raise ReportError(
            f"validation file {path!r} is not the JSON of `pincal validate --out` "
            f"(missing or malformed {exc})"
        ) from None
    source = f"held-out file {doc.get('data', '?')}, {doc.get('poses', '?')} poses"
    if doc.get("independent") is False:
        source += "; NOT independent: it was used for fitting"
    return {
        "validation_before": {k: before.get(k) for k in _KEYS},
        "validation_after": {k: after.get(k) for k in _KEYS},
        "validation_components": comps,
        "validation_errors": errors,
        "validation_predicted": doc.get("predicted"),
        "validation_source": source,
        **cv,
    }


def campaign_notes(
    validation: str | os.PathLike | None = None,
    truth: str | os.PathLike | None = None,
    design: str | os.PathLike | None = None,
) -> dict[str, Any]:
    """Report annotations from a campaign's validation, truth and pose-design files.

    Args:
        validation: JSON written by ``pincal validate --out`` (summaries in mm / mrad,
            per-pose errors, Cramér–Rao prediction, measured components).
        truth: ``<data>.truth.json`` of ``pincal simulate`` (true parameter values [SI]).
        design: ``<poses>.json`` of ``pincal poses`` (index and its history).

    Returns:
        ``validation_*``, ``truth`` and ``index_history`` annotations (those given).

    Raises:
        ReportError: a file that is missing, not JSON or not of the expected kind.
    """
    notes: dict[str, Any] = {}
    if validation is not None:
        notes.update(_validation(read_json_object(validation, "validation file"), str(validation)))
    if truth is not None:
        doc = read_json_object(truth, "truth file")
        try:
            notes["truth"] = {str(p["name"]): float(p["value"]) for p in doc["parameters"]}
        except (KeyError, TypeError, ValueError) as exc:
            raise ReportError(
                f"truth file {str(truth)!r} is not a `pincal simulate` truth file ({exc})"
            ) from None
    if design is not None:
        doc = read_json_object(design, "pose design file")
        if not isinstance(doc.get("index"), str) or not isinstance(doc.get("history"), list):
            raise ReportError(
                f"pose design file {str(design)!r} is not the JSON of `pincal poses` "
                "(needs 'index' and 'history')"
            )
        notes["index_history"] = {doc["index"]: doc["history"]}
    return notes
