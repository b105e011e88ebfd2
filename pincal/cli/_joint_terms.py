"""Joint terms on the command line: ``--payload``, the calibration's record, compensation.

A calibration with joint terms (``calibrate --model geometric+compliance``…) keeps
``calibrated.urdf`` as the geometric part and records the terms in ``joint_terms.yaml``
(name, value, 2σ, unit, and the payload they were fitted under); the values themselves
are read back from ``identification.json``. A payload given with ``--payload`` becomes
a link of the nominal model (stored as ``nominal.urdf``), so the compliance's load is
the same when the calibration is used. A thermal term (``+temperature``) is applied by
``compensate --temperature °C`` (without it: at the reference 20 °C, where it vanishes).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import click

if TYPE_CHECKING:
    from pincal.compensation import JointTermCorrection
    from pincal.identification import IdentificationRecord
    from pincal.io import CalibrationDirectory
    from pincal.model import Mechanism, Payload

__all__ = [
    "TERMS_FILE",
    "THERMAL_SPAN_C",
    "calibration_terms",
    "carrying",
    "check_terms_record",
    "compliance_note",
    "payload_option",
    "read_payload",
    "temperature_note",
    "temperature_option",
    "terms_record",
    "terms_texts",
]

TERMS_FILE = "joint_terms.yaml"
#: temperatures [°C] `info` spreads its random poses over to analyse a thermal term
THERMAL_SPAN_C = (18.0, 28.0)


def payload_option(help_text: str) -> Callable:
    """The ``--payload MASS[,X,Y,Z]`` option (kg; centre of mass in m in the tool frame)."""
    return click.option("--payload", default=None, metavar="MASS[,X,Y,Z]", help=help_text)


def temperature_option(help_text: str) -> Callable:
    """The ``--temperature °C`` option (the machine temperature at the targets)."""
    return click.option(
        "--temperature", type=float, default=None, metavar="CELSIUS", help=help_text
    )


def read_payload(text: str | None) -> Payload | None:
    """The parsed ``--payload`` (None when not given); a bad value is a usage error."""
    if text is None:
        return None
    from pincal.errors import ParameterError
    from pincal.model import Payload

    try:
        return Payload.parse(text)
    except ParameterError as exc:
        raise click.BadParameter(str(exc), param_hint="--payload") from None


def carrying(mech: Mechanism, payload: Payload | None) -> Mechanism:
    """``mech`` with ``payload`` on its tool (``mech`` itself without one)."""
    if payload is None:
        return mech
    from pincal.model import with_payload

    return with_payload(mech, payload)


def terms_record(result: IdentificationRecord, model: str, payload: Payload | None) -> str:
    """``joint_terms.yaml``: the identified joint terms with units (SI) and the payload."""
    import yaml

    from pincal.model import joint_term_units

    units = joint_term_units()
    terms: list[dict[str, Any]] = [
        {"name": name, "value": float(v), "two_sigma": 2 * float(s), "unit": unit}
        for name, v, s, unit in result.table()
        if unit in units and unit not in ("m", "rad")
    ]
    doc = {
        "model": model,
        "payload": None
        if payload is None
        else {"mass_kg": payload.mass, "com_m_tool_frame": list(payload.com)},
        "applies": "joint q = command u + B(u)·θ; calibrated.urdf is the geometric part",
        "terms": terms,
    }
    if any(t["unit"] == "1/K" for t in terms):
        from pincal.model import THERMAL_REFERENCE_C

        doc["thermal"] = (
            f"lengths scale by 1 + α (T − T0), T0 = {THERMAL_REFERENCE_C:g} °C: a prismatic "
            f"joint's stroke (δq = α ΔT q), a revolute joint's URDF origin translation (the "
            f"link into it); compensate --temperature gives T"
        )
    head = "# pincal joint terms (values SI; compensate applies them)\n"
    return head + yaml.safe_dump(doc, sort_keys=False, allow_unicode=True)


def terms_texts(
    result: IdentificationRecord, model: str, terms: tuple[str, ...], payload: Payload | None
) -> dict[str, str]:
    """``{TERMS_FILE: record}`` for a calibration with joint terms or a payload, else {}."""
    return {TERMS_FILE: terms_record(result, model, payload)} if terms or payload else {}


def calibration_terms(
    cal: CalibrationDirectory,
    payload: Payload | None,
    temperature: float | None = None,
    per_pose: bool = False,
) -> tuple[JointTermCorrection | None, str]:
    """The joint terms of a calibration directory, and a line saying what they are.

    Args:
        cal: the calibration.
        payload: the load at the targets, replacing the calibration's; None: keep it.
        temperature: the machine temperature at the targets [°C]; None: the thermal
            terms' reference (20 °C, where they vanish).
        per_pose: the thermal terms are evaluated at each pose's temperature (a
            ``temperature_C`` column); said in the line.

    Returns:
        (correction, description); (None, "") for a geometric calibration.
    """
    from pincal.compensation import JointTermCorrection
    from pincal.model import joint_term_units, with_payload

    units = joint_term_units() - {"m", "rad"}
    if not any(u in units for u in cal.result.units):
        if temperature is not None:
            raise click.BadParameter(
                f"calibration {str(cal.path)!r} has no joint terms: a temperature changes its "
                f"commands only with a thermal term (calibrate --model geometric+temperature)",
                param_hint="--temperature",
            )
        if payload is not None:
            raise click.BadParameter(
                f"calibration {str(cal.path)!r} has no joint terms: a payload changes its "
                f"commands only with a compliance (calibrate --model geometric+compliance)",
                param_hint="--payload",
            )
        return None, ""
    nominal: Mechanism = cal.nominal()
    if payload is not None:
        nominal = with_payload(nominal, payload, replace=True)
    check_terms_record(cal)
    terms = JointTermCorrection.from_names(nominal, cal.result.names, cal.result.full_values)
    terms = terms.at_temperature(temperature)
    load = payload.describe() if payload is not None else "the calibration's load"
    kinds = sorted({n.rpartition(".")[2] for n in terms.params.names})
    if payload is not None and not any("compliance" in k for k in kinds):
        raise click.BadParameter(
            f"calibration {str(cal.path)!r} has joint terms ({', '.join(kinds)}) but no "
            f"compliance: a payload changes its predictions only with a compliance "
            f"(calibrate --model geometric+compliance); drop --payload",
            param_hint="--payload",
        )
    line = f"{len(terms.params)} joint terms ({', '.join(kinds)}) at {load}"
    if "1/K" in terms.params.units:
        from pincal.model import THERMAL_REFERENCE_C

        if per_pose:
            line += ", at each pose's temperature_C"
        elif temperature is not None:
            line += f", {temperature:g} °C"
        else:
            line += f", {THERMAL_REFERENCE_C:g} °C (the reference: no expansion; --temperature)"
    elif temperature is not None:
        raise click.BadParameter(
            f"calibration {str(cal.path)!r} has no thermal term (calibrate --model "
            f"geometric+temperature): --temperature does not change its commands",
            param_hint="--temperature",
        )
    return terms, line


def compliance_note(terms: tuple[str, ...], payload: Payload | None) -> str | None:
    """What a compliance term can and cannot tell apart (None without one)."""
    what = {
        "compliance": "compliance: δq = c·τ, τ the load the actuators hold",
        "strut-compliance": "strut-compliance: δL = c·F, F the axial load of each "
        "fixed-length strut (from the loop-closure forces)",
    }
    said = [text for kind, text in what.items() if kind in terms]
    if not said:
        return None
    load = "the links' weight" + (f" and the {payload.describe()}" if payload else "")
    return (
        f"{'; '.join(said)} ({load}, given); a payload mass and a compliance scale the "
        f"same load, so they separate only with poses that change the load (e.g. measured "
        f"with and without the payload): with the payload given, c is identified; a wrong "
        f"payload mass biases c"
    )


def temperature_note(terms: tuple[str, ...]) -> str | None:
    """What a thermal term can and cannot tell apart (None without one)."""
    if "temperature" not in terms:
        return None
    return (
        "temperature: lengths scale by 1 + α (T − T0) with the per-pose temperature column "
        "temperature_C (°C, T0 = 20 °C); a coefficient is separable from the length itself "
        "only when the temperature varies across the poses (a constant column is refused); "
        f"info analyses random poses at {THERMAL_SPAN_C[0]:g}–{THERMAL_SPAN_C[1]:g} °C, "
        "calibrate on the data's own temperatures"
    )


def check_terms_record(cal: CalibrationDirectory) -> None:
    """``joint_terms.yaml`` says what the calibration applies: its terms and payload.

    The values applied are read from ``identification.json`` and the payload from the
    nominal model (``nominal.urdf``); the record beside them is what a reader sees. Each
    term's value [SI] and the payload (mass [kg], centre [m]) must agree to 1e-9
    relative, else the directory was edited (and re-hashed) and is refused.

    Raises:
        CalibrationDirectoryError: the record disagrees (the first difference named).
    """
    import math
    import xml.etree.ElementTree as ET

    from pincal._yaml import load_yaml
    from pincal.errors import CalibrationDirectoryError

    path = cal.path / TERMS_FILE
    if not path.is_file():
        return
    doc = load_yaml(path, "joint terms record", CalibrationDirectoryError)
    fix = "the directory was edited after calibrate wrote it; re-run `pincal calibrate`"
    if not isinstance(doc, dict) or not isinstance(doc.get("terms"), list):
        raise CalibrationDirectoryError(f"{path}: expected a mapping with a 'terms' list; {fix}")

    def close(a: object, b: float) -> bool:
        return isinstance(a, int | float) and math.isclose(float(a), b, rel_tol=1e-9)

    values = dict(zip(cal.result.names, map(float, cal.result.full_values), strict=True))
    for t in doc["terms"]:
        name = t.get("name") if isinstance(t, dict) else None
        if name not in values or not close(t.get("value"), values[name]):
            said = values.get(name) if isinstance(name, str) else None
            raise CalibrationDirectoryError(
                f"{path}: term {name!r} reads {t.get('value') if isinstance(t, dict) else t!r}"
                f", identification.json {said!r}; {fix}"
            )
    load = doc.get("payload")
    link = ET.fromstring(cal.nominal().urdf_xml).find("link[@name='payload']/inertial")
    if load is None and link is None:
        return
    ok = False
    if isinstance(load, dict) and link is not None:
        mass, origin = link.find("mass"), link.find("origin")
        xyz = origin.get("xyz", "0 0 0") if origin is not None else "0 0 0"
        com = [float(v) for v in xyz.split()]
        recorded = load.get("com_m_tool_frame")
        ok = mass is not None and close(load.get("mass_kg"), float(mass.get("value", "nan")))
        ok = ok and isinstance(recorded, list) and len(recorded) == len(com) == 3
        ok = ok and all(close(a, b) for a, b in zip(recorded or [], com, strict=False))
    if not ok:
        raise CalibrationDirectoryError(
            f"{path}: the payload {load!r} is not the one the calibration's nominal model "
            f"carries; {fix}"
        )
