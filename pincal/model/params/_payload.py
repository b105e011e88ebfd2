"""A payload carried by the tool: a point mass fixed to the measured frame.

The payload becomes part of the model — a URDF link ``payload`` with an
``<inertial>`` and a fixed joint ``payload_joint`` on the measured frame's link — so
Pinocchio's gravity and equilibrium (the compliance term,
:mod:`pincal.model.params._term_compliance`) include it, and applying parameter values keeps
it. A payload already in the user's URDF (any link with an ``<inertial>``) needs
nothing from here.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from pincal.errors import ParameterError
from pincal.model._mechanism import Mechanism

__all__ = ["PAYLOAD_LINK", "Payload", "with_payload"]

PAYLOAD_LINK = "payload"
#: largest payload mass [kg] (a 100 t flight-simulator hexapod load; more is a typing slip)
MAX_PAYLOAD_KG = 1e5
#: largest distance of the payload's centre of mass from the tool frame [m]
MAX_PAYLOAD_ARM = 10.0


@dataclass(frozen=True)
class Payload:
    """A point mass on the tool.

    Attributes:
        mass: [kg], 0 ≤ mass ≤ :data:`MAX_PAYLOAD_KG`.
        com: (3,) centre of mass in the measured (tool) frame [m], within
            :data:`MAX_PAYLOAD_ARM` of its origin.
    """

    mass: float
    com: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        com = tuple(float(v) for v in np.asarray(self.com, dtype=float).reshape(-1))
        if len(com) != 3 or not all(np.isfinite(com)):
            raise ParameterError(f"payload centre of mass must be 3 finite numbers [m], got {com}")
        if not np.isfinite(self.mass) or self.mass < 0:
            raise ParameterError(f"payload mass must be finite and ≥ 0 [kg], got {self.mass}")
        if self.mass > MAX_PAYLOAD_KG:
            raise ParameterError(
                f"payload mass {self.mass:g} kg is beyond the bound: at most {MAX_PAYLOAD_KG:g} "
                f"kg; give the mass in kg (e.g. 20 for 20 kg)"
            )
        arm = float(np.linalg.norm(com))
        if arm > MAX_PAYLOAD_ARM:
            raise ParameterError(
                f"payload centre of mass ({', '.join(f'{v:g}' for v in com)}) m is {arm:g} m "
                f"from the tool frame: at most {MAX_PAYLOAD_ARM:g} m; give X,Y,Z in metres "
                f"(e.g. 0,0,0.1 for 100 mm along the tool z)"
            )
        object.__setattr__(self, "mass", float(self.mass))
        object.__setattr__(self, "com", com)

    @classmethod
    def parse(cls, text: str) -> Payload:
        """``"MASS"`` or ``"MASS,X,Y,Z"`` (kg; m in the tool frame), e.g. ``"5,0,0,0.08"``.

        Raises:
            ParameterError: not 1 or 4 numbers, or a bad value.
        """
        try:
            vals = [float(v) for v in str(text).split(",")]
        except ValueError:
            vals = []
        if len(vals) not in (1, 4):
            raise ParameterError(
                f"payload {text!r} must read MASS or MASS,X,Y,Z (kg; centre of mass in m "
                f"in the tool frame), e.g. 5,0,0,0.08"
            )
        return cls(vals[0], tuple(vals[1:]) if len(vals) == 4 else (0.0, 0.0, 0.0))  # type: ignore[arg-type]

    def describe(self) -> str:
        """One line: mass [kg] and centre of mass [mm]."""
        x, y, z = (1e3 * v for v in self.com)
        return f"payload {self.mass:g} kg at ({x:.1f}, {y:.1f}, {z:.1f}) mm in the tool frame"


def with_payload(mech: Mechanism, payload: Payload, *, replace: bool = False) -> Mechanism:
    """A new mechanism carrying ``payload`` on its measured frame (the input unchanged).

    Args:
        mech: the mechanism.
        payload: the payload.
        replace: take off a payload this function added before (a calibration's), so
            that the new one is the only one.

    Raises:
        ParameterError: the model already has a link named ``payload`` (and not
            ``replace``).
    """
    root = ET.fromstring(mech.urdf_xml)
    if PAYLOAD_LINK in mech.tree.links:
        if not replace:
            raise ParameterError(
                f"{mech.name!r} already has a link {PAYLOAD_LINK!r}; give the payload once "
                f"(in the URDF or as an option, not both)"
            )
        for e in list(root):
            child = e.find("child")
            if (e.tag == "link" and e.get("name") == PAYLOAD_LINK) or (
                e.tag == "joint" and child is not None and child.get("link") == PAYLOAD_LINK
            ):
                root.remove(e)
    link = ET.SubElement(root, "link", name=PAYLOAD_LINK)
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", xyz=" ".join(repr(v) for v in payload.com), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=repr(payload.mass))
    zero = {k: "0" for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    ET.SubElement(inertial, "inertia", zero)
    joint = ET.SubElement(root, "joint", name=f"{PAYLOAD_LINK}_joint", type="fixed")
    ET.SubElement(joint, "parent", link=mech.frame_link(mech.measured_frame))
    ET.SubElement(joint, "child", link=PAYLOAD_LINK)
    ET.SubElement(joint, "origin", xyz="0 0 0", rpy="0 0 0")
    return Mechanism(
        ET.tostring(root, encoding="unicode"),
        mech.sidecar,
        name=mech.name,
        source=mech.source,
        measured_frame=mech.measured_frame,
        q_guess=mech.q_home,
        options=mech.options,
    )
