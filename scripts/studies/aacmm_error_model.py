"""Seed 004: reproduce Table 2 (error model of the articulated-arm CMM) and the
sensitivity experiment, with pincal's model and identification Jacobian.

Usage:
    python scripts/studies/aacmm_error_model.py

For each of the paper's 20 configurations: our nominal probe coordinates (DH model
``models/aacmm``), the norm of the actual error (model with Table 1's errors minus
nominal, exact) and of the first-order prediction ``‖J·Δ‖`` (J from
``pincal.identification_jacobian``, Δ = Table 1 errors as the 28 ``dh`` parameters),
beside the paper's printed P, E and ΔP. Rows 9 and 10 are OCR-damaged in the source
(row 9 lists five joint angles; row 10's x has a misread digit) and row 13's nominal
does not reproduce: they are flagged in the output. Row 9 is printed "(90 0 - 90 0 90)";
the script inserts one angle at each of the six positions (−180..180° in 1° steps) and
lists every insertion whose nominal probe point lies within 1 mm of the printed
(300, 150, −250): only a 0 inserted as joint 1, before the printed 90, i.e. the
reading (0, 90, 0, −90, 0, 90), which reproduces the point to round-off.

Sensitivity experiment: each class of DH errors (Δd, Δa, Δα, Δθ) in turn is scaled
×10 and ×0.1 (the others kept at Table 1); the mean error norm over the 20
configurations shows which classes dominate.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

import pincal

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "scripts" / "data" / "seed004.yaml"
ERRORS = ROOT / "models" / "aacmm" / "table1_errors.yaml"
CLASSES = {"d": "Δd", "a": "Δa", "alpha": "Δα", "theta": "Δθ"}


@dataclass(frozen=True)
class Table2Row:
    """One configuration: ours [mm] beside the paper's [mm]."""

    row: int
    joints_deg: tuple[float, ...]
    nominal: np.ndarray  # (3,) our nominal probe coordinates [mm]
    actual_error: float  # ‖P_actual − P_nominal‖ [mm]
    first_order: float  # ‖J·Δ‖ [mm]
    paper_P: np.ndarray
    paper_E: float
    paper_dP: float
    flags: tuple[str, ...]


def dh_class(name: str) -> str:
    """DH class (``a``, ``d``, ``alpha``, ``theta``) of an aacmm ``dh`` parameter name."""
    joint, dof = name.split(".")
    if joint.endswith("_ax"):
        return {"tx": "a", "rx": "alpha"}[dof]
    return {"tz": "d", "offset": "theta", "rz": "theta"}[dof]


def setup():
    """(mechanism, dh ParameterSet, Table 1 values (28,) [SI], Table 2 entries)."""
    mech = pincal.load_mechanism("aacmm")
    params = pincal.parameters(mech, "dh")
    values_by_name = yaml.safe_load(ERRORS.read_text())["values"]
    values = np.array([values_by_name[n] for n in params.names], dtype=float)
    table2 = yaml.safe_load(DATA.read_text())["table2"]
    return mech, params, values, table2


def joints_of(entry: dict) -> list[float]:
    """Joint angles [deg] of a Table 2 entry (row 9: the reconstructed six)."""
    return entry.get("joints_reconstructed", entry["joints"])


def probe_positions(mech: pincal.Mechanism, q_rows: np.ndarray) -> np.ndarray:
    """(m, 3) probe positions [m] at joint rows (m, 6) [rad]."""
    return np.array([mech.forward(q).translation for q in q_rows])


def error_norms(mech, params, values, q_rows) -> tuple[np.ndarray, np.ndarray]:
    """Actual (exact) and first-order error norms (m,) [m] for parameter ``values``."""
    nominal = probe_positions(mech, q_rows)
    actual = probe_positions(params.apply(mech, values), q_rows)
    J = pincal.identification_jacobian(mech, params, q_rows)  # (3m, n) [m per unit]
    first = (J @ values).reshape(-1, 3)
    return np.linalg.norm(actual - nominal, axis=1), np.linalg.norm(first, axis=1)


def table2_rows() -> list[Table2Row]:
    mech, params, values, table2 = setup()
    q_rows = np.radians([joints_of(e) for e in table2])
    nominal = probe_positions(mech, q_rows) * 1e3
    actual, first = error_norms(mech, params, values, q_rows)
    out = []
    for k, e in enumerate(table2):
        out.append(
            Table2Row(
                row=int(e["row"]),
                joints_deg=tuple(float(v) for v in joints_of(e)),
                nominal=nominal[k],
                actual_error=float(actual[k] * 1e3),
                first_order=float(first[k] * 1e3),
                paper_P=np.array(e["P"], dtype=float),
                paper_E=float(e["E"]),
                paper_dP=float(e["dP"]),
                flags=tuple(e.get("flags", ())),
            )
        )
    return out


def row9_insertions(tol_mm: float = 1.0, step_deg: int = 1) -> list[tuple[int, int, float]]:
    """Single-angle insertions into row 9's five printed angles that reproduce its point.

    Returns:
        (joint number 1..6 of the inserted angle, inserted angle [deg], distance of the
        nominal probe point from the printed P [mm]) for each insertion within ``tol_mm``.
    """
    mech, _, _, table2 = setup()
    (entry,) = [e for e in table2 if e["row"] == 9]
    printed, target = list(entry["joints"]), np.array(entry["P"], dtype=float)
    hits = []
    for pos in range(len(printed) + 1):
        for angle in range(-180, 181, step_deg):
            q = np.radians([*printed[:pos], angle, *printed[pos:]])
            dist = float(np.linalg.norm(mech.forward(q).translation * 1e3 - target))
            if dist <= tol_mm:
                hits.append((pos + 1, angle, dist))
    return hits


@dataclass(frozen=True)
class SensitivityRow:
    """Mean error norms [mm] over the 20 configurations with one DH class scaled."""

    quantity: str
    alone: float  # only this class's errors (others zero), exact
    times10: float  # this class ×10, the others as in Table 1
    times01: float  # this class ×0.1, the others as in Table 1


def sensitivity() -> tuple[float, list[SensitivityRow]]:
    """Baseline mean error norm [mm] and one row per DH class."""
    mech, params, values, table2 = setup()
    q_rows = np.radians([joints_of(e) for e in table2])
    classes = np.array([dh_class(n) for n in params.names])

    def mean_error(v):
        return float(np.mean(error_norms(mech, params, v, q_rows)[0]) * 1e3)

    rows = []
    for cls in CLASSES:
        mask = classes == cls
        rows.append(
            SensitivityRow(
                quantity=cls,
                alone=mean_error(np.where(mask, values, 0.0)),
                times10=mean_error(np.where(mask, 10 * values, values)),
                times01=mean_error(np.where(mask, 0.1 * values, values)),
            )
        )
    return mean_error(values), rows


def _fmt3(v: np.ndarray) -> str:
    return " ".join(f"{x:9.3f}" for x in v)


def main() -> int:
    rows = table2_rows()
    print("Seed 004 Table 2 — ours beside the paper's (lengths in mm)")
    print("E = ‖P_actual − P_nominal‖ (exact, Table 1 errors); ΔP = ‖J·Δ‖ (first order)")
    header = (
        f"{'row':>3} {'joints [deg]':<28} {'P ours (x y z)':<30} {'P paper (x y z)':<30} "
        f"{'E ours':>7} {'E pap.':>7} {'ΔP ours':>7} {'ΔP pap.':>7} {'1st/ex−1':>8}  note"
    )
    print(header)
    for r in rows:
        notes = []
        if "ocr_damaged_joints" in r.flags:
            notes.append("OCR: 5 angles printed; leading 0 restored")
        if "ocr_damaged_coordinates" in r.flags:
            notes.append("OCR: printed x misread (1 digit)")
        if "nominal_mismatch" in r.flags:
            notes.append("printed P does not reproduce")
        joints = " ".join(f"{v:g}" for v in r.joints_deg)
        rel = r.first_order / r.actual_error - 1
        print(
            f"{r.row:>3} {joints:<28} {_fmt3(r.nominal):<30} {_fmt3(r.paper_P):<30} "
            f"{r.actual_error:7.3f} {r.paper_E:7.3f} {r.first_order:7.3f} {r.paper_dP:7.3f} "
            f"{rel:+8.2%}  {'; '.join(notes)}"
        )
    intact = [r for r in rows if not r.flags]
    dev = max(np.abs(r.nominal - r.paper_P).max() for r in intact)
    e_gap = np.array(
        [r.actual_error - r.paper_E for r in rows if "nominal_mismatch" not in r.flags]
    )
    rel = max(abs(r.first_order / r.actual_error - 1) for r in rows)
    print(f"\nintact rows ({len(intact)}): max |P ours − P paper| = {dev:.4f} mm")
    print(
        f"E ours − E paper: max |·| {np.abs(e_gap).max():.3f} mm, RMS "
        f"{np.sqrt(np.mean(e_gap**2)):.3f} mm (the paper's E does not follow exactly from its "
        "Table 1; see models/aacmm/README.md)"
    )
    print(f"first order vs exact (ours): max relative deviation {rel:.3%} over all 20 rows")
    hits = row9_insertions()
    print(
        "row 9, printed (90 0 - 90 0 90): one angle inserted at every position, "
        "-180..180 deg in 1 deg steps; insertions within 1 mm of the printed P: "
        + "; ".join(f"{a:g} deg as joint {j} ({d:.1e} mm)" for j, a, d in hits)
    )

    base, sens = sensitivity()
    print(f"\nSensitivity experiment: mean ‖E‖ over the 20 configurations = {base:.3f} mm")
    print(f"{'class':<6} {'alone':>8} {'×10':>8} {'×0.1':>8}   (mm; ×10/×0.1: others at Table 1)")
    for s in sens:
        print(f"{CLASSES[s.quantity]:<6} {s.alone:8.3f} {s.times10:8.3f} {s.times01:8.3f}")
    order = sorted(sens, key=lambda s: -s.alone)
    print(
        "dominant classes: "
        + " > ".join(f"{CLASSES[s.quantity]} ({s.alone:.3f} mm)" for s in order)
        + ". Angular errors (Δθ, Δα, ~1 mrad on ~1 m lever arms) dominate the "
        "length errors (Δa, Δd, ~0.1 mm)."
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
