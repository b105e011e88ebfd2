"""The plain-text report of a held-out validation (printed by `pincal validate`).

Rendered from :class:`pincal.validation.HeldOutValidation` and the calibration directory
it checks; errors in mm / mrad, each block over its measured components.
"""

from __future__ import annotations

from collections.abc import Sequence

from pincal.identification import COVARIANCE_KINDS
from pincal.io import CalibrationDirectory
from pincal.report._sections import block_label
from pincal.validation import ORIENTATION_CONVENTION, HeldOutValidation, MarkerErrors

__all__ = ["marker_errors_text", "validation_text"]


def _fmt(v: float | None, width: int = 9, digits: int = 4) -> str:
    return f"{'-':>{width}s}" if v is None else f"{v:{width}.{digits}f}"


def _iso_components(v: HeldOutValidation) -> str:
    """The line naming the components the ISO 9283 table judges and the angle convention."""
    pos = [c for c in v.components if c in ("x", "y", "z")]
    rot = ["abc"["xyz".index(c[1])] for c in v.components if c in ("rx", "ry", "rz")]
    text = f"  AP_p, RP_l over {' '.join(pos) or '(no position measured)'}; "
    if not rot:
        return text + "orientation not measured (AP_a/b/c '-')"
    return text + f"AP_{'/'.join(rot)} only (measured): {ORIENTATION_CONVENTION}"


def validation_text(
    validation: HeldOutValidation,
    calibration: CalibrationDirectory,
    data: str,
    independent: bool,
    max_rows: int = 40,
) -> str:
    """The validation report: nominal and calibrated errors, Cramér–Rao, ISO 9283 rows.

    Args:
        validation: the validation of ``calibration`` on the file ``data``.
        calibration: the calibration directory validated.
        data: the held-out measurement file (as named to the user).
        independent: False when ``data`` was used for fitting (a warning line is shown).
        max_rows: ISO 9283 rows shown (the rest counted).

    Returns:
        The text [mm, mrad], ending with a newline.
    """
    hp, hr = validation.has_position, validation.has_orientation
    b, a = validation.before.summary(hp, hr), validation.after.summary(hp, hr)
    p = validation.predicted
    comps = tuple(validation.components)
    pos = f"{block_label('position', comps)} [mm]"
    ori = f"{block_label('orientation', comps)} [mrad]"
    poses = sum(len(g) for g in validation.groups)
    # a marker calibration: both rows keep the calibrated instrument frame and marker
    what = "robot" if calibration.manifest.get("markers") else "model"
    lines = [
        f"pincal validate {calibration.path} ({calibration.model}, "
        f"preset {calibration.preset}) on {data}: {poses} poses, "
        f"{len(validation.groups)} commanded, components {' '.join(comps)}",
    ]
    if not independent:
        lines.append("  WARNING: this file was used for fitting; the validation is not independent")
    lines += [
        f"                        {pos:22s} {ori}",
        "                        RMS        max         RMS        max",
        f"  nominal {what}      {_fmt(b['rms_position_mm'])}  {_fmt(b['max_position_mm'])}"
        f"   {_fmt(b['rms_orientation_mrad'])}  {_fmt(b['max_orientation_mrad'])}",
        f"  calibrated {what}   {_fmt(a['rms_position_mm'])}  {_fmt(a['max_position_mm'])}"
        f"   {_fmt(a['rms_orientation_mrad'])}  {_fmt(a['max_orientation_mrad'])}",
    ]

    def num(key: str) -> float | None:
        value = p[key]
        return None if value is None else float(value)

    kind = str(p.get("covariance") or "cramer-rao")
    name = "Cramér–Rao" if kind == "cramer-rao" else "predicted"
    if p.get("withheld"):
        lines.append(f"  {name} prediction not given: {p['withheld']}")
    else:
        lines += [
            f"  {name + ' (model)':18s} {_fmt(num('model_rms_position_mm'))}  {'':9s}"
            f"   {_fmt(num('model_rms_orientation_mrad'))}",
            f"  {name + ' + noise':18s} {_fmt(num('observed_rms_position_mm'))}  {'':9s}"
            f"   {_fmt(num('observed_rms_orientation_mrad'))}",
            f"  (predicted from the {COVARIANCE_KINDS.get(kind, kind)})",
        ]
    lines += [
        "",
        "  ISO 9283 pose accuracy per commanded pose (AP: mean attained − commanded;"
        " RP_l = l̄ + 3 S_l over repeats)",
        _iso_components(validation),
        "  pose  n   AP_p nominal  AP_p calibrated   AP_a      AP_b      AP_c    RP_l",
        "                 [mm]        [mm]         calibrated [mrad]            [mm]",
    ]
    rows = list(enumerate(validation.groups))
    for j, group in rows[:max_rows]:
        c = validation.after.ap[j]
        lines.append(
            f"  {j:4d} {len(group):2d} {_fmt(validation.before.ap[j]['AP_p_mm'], 12)}"
            f"  {_fmt(c['AP_p_mm'], 12)}   {_fmt(c['AP_a_mrad'], 8, 3)}  "
            f"{_fmt(c['AP_b_mrad'], 8, 3)}  {_fmt(c['AP_c_mrad'], 8, 3)} "
            f"{_fmt(validation.repeatability_mm[j], 7)}"
        )
    if len(rows) > max_rows:
        lines.append(f"  … {len(rows) - max_rows} more (--json gives all)")
    return "\n".join(lines) + "\n"


def marker_errors_text(errors: Sequence[MarkerErrors]) -> str:
    """One line per further marker: RMS nominal / calibrated and max calibrated [mm]."""
    lines = []
    for e in errors:
        d = e.to_dict()
        lines.append(f"  marker {' '.join(e.columns)}: position RMS nominal "
                     f"{d['before_rms_position_mm']:.4f} mm, calibrated "
                     f"{d['after_rms_position_mm']:.4f} mm (max "
                     f"{d['after_max_position_mm']:.4f} mm); the table above: the first "
                     "marker\n")  # fmt: skip
    return "".join(lines)
