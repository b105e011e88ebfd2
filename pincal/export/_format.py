"""A controller format, and the projection of a calibration onto it.

An export is a projection: the controller evaluates its own kinematic equations with
the exported numbers, and these can hold less than the calibrated model. Over ``m``
random workspace poses (readings ``q`` drawn by :func:`pincal.model.sample_actuators`
on the calibrated model), with ``T_ref(q)`` the calibrated model's measured-frame pose
(gains applied, :class:`~pincal.export._machine.CalibratedMachine`) and ``T_ctl(q)``
the controller's pose from the numbers as written:

* position difference ``e_p = |p_ctl − p_ref|`` [m];
* orientation difference ``e_r = |log3(R_refᵀ R_ctl)|`` [rad];
* for a parallel machine whose controller solves the inverse in closed form, the joint
  difference ``e_q = |q_ctl(T_ref(q)) − q|`` per joint [m or rad].

RMS and max of each are reported, with what the format cannot express.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
import pinocchio as pin

from pincal.export._machine import CalibratedMachine
from pincal.model import actuator_difference

__all__ = ["Built", "ControllerFormat", "Projection", "fmt_number", "projection"]


def fmt_number(x: float) -> str:
    """A number as written in the exports: 12 decimals, no exponent (pm, prad)."""
    text = f"{float(x):.12f}"
    return "0.000000000000" if text == "-0.000000000000" else text


@dataclass
class Built:
    """A format's output before the header.

    Attributes:
        body: the file content after the header.
        controller: readings (m, n_act) → (m, 4, 4) measured-frame poses by the
            controller's equations with the numbers of ``body``.
        not_expressed: what the format cannot express, one phrase each.
        conventions: the choices the format needed (named in the header).
        inverse: optional poses (m, 4, 4) → (m, n_act) readings by the controller.
    """

    body: str
    controller: Callable[[np.ndarray], np.ndarray]
    not_expressed: list[str] = field(default_factory=list)
    conventions: list[str] = field(default_factory=list)
    inverse: Callable[[np.ndarray], np.ndarray] | None = None


class ControllerFormat(ABC):
    """One controller format: its name, file suffix and the numbers it writes."""

    name: ClassVar[str]
    suffix: ClassVar[str]
    summary: ClassVar[str]

    @abstractmethod
    def build(self, machine: CalibratedMachine, q_fit: np.ndarray) -> Built:
        """The format's numbers for ``machine``.

        ``q_fit`` (m, n_act): workspace readings for what the format fits over the
        workspace (not the ones it is judged on).

        Raises:
            ExportError: the machine is not of the kind the format describes.
        """


@dataclass(frozen=True)
class Projection:
    """How far the controller's kinematics with the exported numbers are from the model.

    Lengths [m], angles [rad]; ``joint_*`` [m or rad, per the joints] or None.
    ``q_act`` (m, n_act): the readings compared.
    """

    format: str
    position_rms: float
    position_max: float
    orientation_rms: float
    orientation_max: float
    joint_rms: float | None
    joint_max: float | None
    not_expressed: tuple[str, ...]
    conventions: tuple[str, ...]
    q_act: np.ndarray

    def lines(self) -> list[str]:
        """The report, one line each (µm, µrad)."""
        out = [
            f"projection onto {self.format} over {len(self.q_act)} random workspace poses "
            f"(controller equations with the numbers below vs the calibrated model):",
            f"  position    RMS {self.position_rms * 1e6:.4g} um, "
            f"max {self.position_max * 1e6:.4g} um",
            f"  orientation RMS {self.orientation_rms * 1e6:.4g} urad, "
            f"max {self.orientation_max * 1e6:.4g} urad",
        ]
        if self.joint_rms is not None and self.joint_max is not None:
            out.append(
                f"  joints (controller inverse at the model's poses) RMS "
                f"{self.joint_rms * 1e6:.4g} um|urad, max {self.joint_max * 1e6:.4g} um|urad"
            )
        out.append(
            "cannot express: "
            + ("; ".join(self.not_expressed) if self.not_expressed else "nothing")
            + (" (all of the calibration is in the numbers)" if not self.not_expressed else "")
        )
        out += [f"convention: {c}" for c in self.conventions]
        return out

    def to_dict(self) -> dict:
        """JSON-ready summary (SI)."""
        return {
            "format": self.format,
            "poses": len(self.q_act),
            "position_rms_m": self.position_rms,
            "position_max_m": self.position_max,
            "orientation_rms_rad": self.orientation_rms,
            "orientation_max_rad": self.orientation_max,
            "joint_rms": self.joint_rms,
            "joint_max": self.joint_max,
            "not_expressed": list(self.not_expressed),
            "conventions": list(self.conventions),
        }


def projection(
    name: str, built: Built, machine: CalibratedMachine, q_act: np.ndarray
) -> Projection:
    """Compare the controller of ``built`` with the calibrated model at readings ``q_act``."""
    ref = machine.reference(q_act)
    ctl = built.controller(q_act)
    e_p = np.linalg.norm(ctl[:, :3, 3] - ref[:, :3, 3], axis=1)
    e_r = np.array(
        [np.linalg.norm(pin.log3(r[:3, :3].T @ c[:3, :3])) for r, c in zip(ref, ctl, strict=True)]
    )
    joint_rms = joint_max = None
    missing = list(built.not_expressed)
    if built.inverse is not None:
        e_q = np.abs(actuator_difference(machine.calibrated, built.inverse(ref), q_act))
        solved = ~np.isnan(e_q).any(axis=1)
        if not solved.all():
            missing.append(
                f"the controller's inverse found no solution at {int((~solved).sum())} of "
                f"{len(q_act)} poses (joint figures over the others)"
            )
        if solved.any():
            e_q = e_q[solved]
            joint_rms, joint_max = float(np.sqrt(np.mean(e_q**2))), float(e_q.max())
    return Projection(
        name,
        float(np.sqrt(np.mean(e_p**2))),
        float(e_p.max()),
        float(np.sqrt(np.mean(e_r**2))),
        float(e_r.max()),
        joint_rms,
        joint_max,
        tuple(missing),
        tuple(built.conventions),
        np.array(q_act, dtype=float),
    )
