"""Validation of a calibration on held-out measurements.

It reports the before/after errors, an ISO 9283 style pose-accuracy table and the
Cramér–Rao prediction.

Errors are measured minus predicted on the components the file measures: position
error = norm of the measured position components [m]; orientation error = norm of the
measured components of log3(R_predictedᵀ R_measured) [rad] (measured frame).

ISO 9283 (pose accuracy and repeatability) per commanded pose j (rows with the same
actuator values are repeats of one command):

- AP_p = ‖P̄ − P_c‖ over the measured position axes: distance between the mean attained
  position and the commanded one (the pose the model predicts for the command);
- AP_a, AP_b, AP_c: ā − a_c etc., ISO 9283's angles a, b, c about the base x, y, z axes
  (R = Rz(c)·Ry(b)·Rx(a)) [rad], for the measured rotation components
  (``ORIENTATION_CONVENTION``, the same as ``pincal acceptance``: both use
  :func:`~pincal.validation.point_accuracy`);
- RP_l = l̄ + 3 S_l with l_i = ‖P_i − P̄‖ and S_l their sample std (n ≥ 2 repeats).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pincal.design import predicted_validation_rms
from pincal.errors import ShapeError
from pincal.measure import Measurements, NoiseModel
from pincal.model import COMPONENTS, Mechanism, ParameterSet
from pincal.sensitivity import (
    PLACEMENT_BOUND,
    beyond_placement,
    identification_jacobian,
    placement_words,
)
from pincal.validation._iso9283 import ORIENTATION_CONVENTION, point_accuracy

__all__ = [
    "PREDICTION_COND_BOUND",
    "HeldOutValidation",
    "prediction_caveat",
    "validate_held_out",
]

#: largest condition number of the parameters' correlation matrix for which it is printed
PREDICTION_COND_BOUND = 1e10


def prediction_caveat(
    names: tuple[str, ...],
    units: tuple[str, ...],
    covariance: np.ndarray,
    bounds: tuple[float, float] = PLACEMENT_BOUND,
    cond_bound: float | None = None,
) -> str | None:
    """Why the Cramér–Rao prediction of a covariance would be meaningless, or None.

    The prediction is first-order in the parameters' errors: it means nothing when the
    covariance is not a covariance (non-finite, not positive semi-definite), when it is
    ill-conditioned (condition number of the correlation matrix above ``cond_bound``:
    some combination of parameters is barely determined) or when an identified
    parameter's σ exceeds ``bounds`` (length [m], angle
    [rad]; outside the small-error regime where the linearisation holds). The bound and
    the rule are the fit's own (:data:`pincal.sensitivity.PLACEMENT_BOUND`, one
    definition for both): the fit holds a direction placed beyond it at 1σ, so the
    prediction is withheld exactly where the fit would hold (a 2σ rule withheld the
    prediction on the RUSR with a universal joint, 1σ 12 mm, where it holds: predicted /
    achieved 1.14 ± 0.08 over 10 campaigns, scripts/studies/prediction_honesty.py).

    Args:
        names: the k identified parameters, in ``covariance``'s order.
        units: their units (``"m"`` or ``"rad"``).
        covariance: (k, k) [SI].
        bounds: default :data:`pincal.sensitivity.PLACEMENT_BOUND`.
        cond_bound: default :data:`PREDICTION_COND_BOUND`.
    """
    cond_bound = PREDICTION_COND_BOUND if cond_bound is None else cond_bound
    cov = np.asarray(covariance, dtype=float)
    k = len(names)
    if cov.shape != (k, k) or not np.all(np.isfinite(cov)):
        return "the calibration's covariance is not finite"
    if k == 0:
        return None
    var = np.diag(cov)
    eig = np.linalg.eigvalsh((cov + cov.T) / 2)
    if np.any(var <= 0) or eig.min() < -1e-9 * max(eig.max(), 0.0):
        return "the calibration's covariance is not positive definite"
    d = 1 / np.sqrt(var)
    corr_eig = np.linalg.eigvalsh(cov * np.outer(d, d))
    cond = corr_eig.max() / corr_eig.min() if corr_eig.min() > 0 else np.inf
    if not cond <= cond_bound:
        return (
            f"the calibration's covariance is ill-conditioned (condition number of its "
            f"correlation matrix {cond:.2g} > {cond_bound:.0e}: some combination of "
            "parameters is barely determined by the poses)"
        )
    std = np.sqrt(var)
    big = [
        f"{names[i]} (σ {std[i] * 1e3:.3g} {'mrad' if units[i] == 'rad' else 'mm'})"
        for i in np.flatnonzero(beyond_placement(std, units, bounds))
    ]
    if big:
        return (
            f"{len(big)} identified parameter{'s are' if len(big) > 1 else ' is'} beyond "
            f"{placement_words(bounds)}, "
            "outside the small-error range where the first-order prediction holds: "
            + ", ".join(big[:5]) + (" …" if len(big) > 5 else "")
        )
    return None


@dataclass(frozen=True)
class ModelErrors:
    """Per-pose errors (m,) of one model's predictions [m, rad] and ISO 9283 rows."""

    position: np.ndarray
    orientation: np.ndarray
    ap: list[dict[str, Any]]

    def summary(self, has_pos: bool, has_rot: bool) -> dict[str, float | None]:
        """RMS and max position [mm] and orientation [mrad] errors (None: not measured)."""
        p, o = self.position * 1e3, self.orientation * 1e3
        return {
            "rms_position_mm": float(np.sqrt(np.mean(p**2))) if has_pos else None,
            "max_position_mm": float(p.max()) if has_pos else None,
            "rms_orientation_mrad": float(np.sqrt(np.mean(o**2))) if has_rot else None,
            "max_orientation_mrad": float(o.max()) if has_rot else None,
        }


@dataclass(frozen=True)
class HeldOutValidation:
    """Validation of a calibration on held-out data (SI inside; ``to_dict`` in mm/mrad)."""

    components: tuple[str, ...]
    groups: list[np.ndarray]
    before: ModelErrors
    after: ModelErrors
    repeatability_mm: list[float | None]
    predicted: dict[str, float | str | None]

    @property
    def has_position(self) -> bool:
        """True when the held-out data measure a position component."""
        return any(c in ("x", "y", "z") for c in self.components)

    @property
    def has_orientation(self) -> bool:
        """True when the held-out data measure an orientation component."""
        return any(c in ("rx", "ry", "rz") for c in self.components)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: summaries, per-pose errors and the ISO 9283 table (mm, mrad)."""
        hp, hr = self.has_position, self.has_orientation
        iso = []
        for j, rows in enumerate(self.groups):
            iso.append(
                {
                    "pose": j,
                    "rows": [int(r) for r in rows],
                    "repeats": len(rows),
                    "before": self.before.ap[j],
                    "after": self.after.ap[j],
                    "RP_l_mm": self.repeatability_mm[j],
                }
            )
        return {
            "components": list(self.components),
            "orientation_convention": ORIENTATION_CONVENTION if hr else None,
            "poses": int(sum(len(g) for g in self.groups)),
            "commanded_poses": len(self.groups),
            "before": self.before.summary(hp, hr),
            "after": self.after.summary(hp, hr),
            "per_pose": {
                "before_position_mm": (self.before.position * 1e3).tolist(),
                "after_position_mm": (self.after.position * 1e3).tolist(),
                "before_orientation_mrad": (self.before.orientation * 1e3).tolist(),
                "after_orientation_mrad": (self.after.orientation * 1e3).tolist(),
            },
            "iso9283": iso,
            "predicted": self.predicted,
        }


def _groups(q_act: np.ndarray) -> list[np.ndarray]:
    """Row indices of each distinct command, in order of first appearance."""
    keys = np.round(q_act, 12)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = np.asarray(inverse).ravel()
    order = np.argsort(first)
    return [np.nonzero(inverse == g)[0] for g in order]


def _model_errors(
    model: Mechanism,
    meas: Measurements,
    groups: list[np.ndarray],
    pos: list[int],
    rot: list[int],
    joints: np.ndarray | None = None,
    shift: np.ndarray | None = None,
) -> ModelErrors:
    """Errors of ``model`` at ``joints`` (m, n_act) (None: the commands).

    The measured frame is moved by ``shift`` (m, 3) [m] (None: not moved). Each row is
    predicted at its own joints and shift (the repeats of one command may differ, e.g.
    measured at other temperatures); the ISO 9283 AP of a command compares the attained
    poses, each moved by its own prediction's difference to the first row's, with the
    first row's prediction, so AP is the mean of the rows' errors.
    """
    joints = meas.q_act if joints is None else joints
    m = len(meas)
    ep = np.zeros((m, 3))
    er = np.zeros((m, 3))
    ap: list[dict[str, Any]] = []
    comps = tuple(COMPONENTS[k] for k in pos) + tuple(COMPONENTS[3 + k] for k in rot)
    for rows in groups:
        T0 = model.forward(joints[rows[0]])
        P = np.empty((len(rows), 3))
        R = None if meas.rotations is None else np.empty((len(rows), 3, 3))
        for j, i in enumerate(rows):
            same = j == 0 or np.array_equal(joints[i], joints[rows[0]])
            T = T0 if same else model.forward(joints[i])
            at = T.translation + (0.0 if shift is None else shift[i])  # predicted [m]
            ep[i] = meas.positions[i] - at
            P[j] = meas.positions[i] - (at - T0.translation)  # referred to T0
            if meas.rotations is not None and R is not None:
                er[i] = pin.log3(T.rotation.T @ meas.rotations[i])
                R[j] = T0.rotation @ T.rotation.T @ meas.rotations[i]
        pa = point_accuracy(T0, P, R, comps)
        entry: dict[str, Any] = {"AP_p_mm": pa.ap_p * 1e3 if pos else None}
        for k, label in enumerate(("AP_a_mrad", "AP_b_mrad", "AP_c_mrad")):
            entry[label] = float(pa.ap_abc[k] * 1e3) if k in rot else None
        ap.append(entry)
    position = np.linalg.norm(ep[:, pos], axis=1) if pos else np.zeros(m)
    orientation = np.linalg.norm(er[:, rot], axis=1) if rot else np.zeros(m)
    return ModelErrors(position, orientation, ap)


def _repeatability(meas: Measurements, rows: np.ndarray, pos: list[int]) -> float | None:
    if len(rows) < 2 or not pos:
        return None
    comps = tuple(COMPONENTS[k] for k in pos)
    T = pin.SE3.Identity()  # RP does not depend on the command
    return float(point_accuracy(T, meas.positions[rows], None, comps).rp_l * 1e3)


def _prediction(
    nominal: Mechanism,
    params: ParameterSet,
    names: tuple[str, ...],
    covariance: np.ndarray,
    q_rows: np.ndarray,
    pos: list[int],
    rot: list[int],
    noise: NoiseModel | None,
    conditions: dict[str, np.ndarray | None] | None = None,
    values: np.ndarray | None = None,
    propagated: np.ndarray | None = None,
) -> dict[str, float | str | None]:
    """Cramér–Rao prediction of the calibrated model's validation RMS (mm, mrad).

    ``propagated`` (default ``covariance``) is propagated through the Jacobian at
    ``values`` (the full parameter vector it was evaluated at; None: nominal), the
    caveat judges ``covariance``. ``withheld`` is None, or why the prediction is not
    given (:func:`prediction_caveat`; the RMS entries are then None).
    """
    cols = [params.index(n) for n in names]
    units = tuple(params.units[c] for c in cols)
    caveat = prediction_caveat(names, units, covariance)
    if caveat is not None:
        none = {f"{w}_rms_{k}": None for w in ("model", "observed")
                for k in ("position_mm", "orientation_mrad")}  # fmt: skip
        return {**none, "withheld": caveat}
    cov = covariance if propagated is None else propagated
    J = identification_jacobian(nominal, params, q_rows, values, components=COMPONENTS,
                                conditions=conditions)  # fmt: skip
    J = J.reshape(len(q_rows), 6, len(params))[:, :, cols]
    out: dict[str, float | str | None] = {"withheld": None}
    for key, idx, sigma in (
        ("position_mm", pos, None if noise is None else noise.position * 1e-3),
        ("orientation_mrad", rot, None if noise is None else noise.orientation * 1e-3),
    ):
        if not idx:
            out[f"model_rms_{key}"] = out[f"observed_rms_{key}"] = None
            continue
        model = predicted_validation_rms(J[:, idx, :], cov) * np.sqrt(len(idx))
        out[f"model_rms_{key}"] = float(model * 1e3)
        out[f"observed_rms_{key}"] = (
            None if sigma is None else float(np.sqrt(model**2 + len(idx) * sigma**2) * 1e3)
        )
    return out


def validate_held_out(
    nominal: Mechanism,
    calibrated: Mechanism,
    meas: Measurements,
    params: ParameterSet,
    names: tuple[str, ...],
    covariance: np.ndarray,
    noise: NoiseModel | None = None,
    held_weak: tuple[str, ...] = (),
    joints: np.ndarray | None = None,
    covariance_kind: str = "cramer-rao",
    shift: np.ndarray | None = None,
    values: np.ndarray | None = None,
    propagated: np.ndarray | None = None,
) -> HeldOutValidation:
    """Before (nominal) / after (calibrated) errors on held-out measurements.

    The calibrated model predicts at ``joints`` when given: the joint values the
    calibration's joint terms (compliance under load, gain, harmonics, struts'
    compliance) say the commands move the joints to (``u + B(u) θ``,
    :class:`pincal.compensation.JointTermCorrection`); the nominal predicts at the
    commands.

    Args:
        nominal: the nominal mechanism (the one ``params`` was built for).
        calibrated: the calibrated mechanism.
        meas: held-out measurements (not used for fitting).
        params: the calibration's parameter set (preset) on ``nominal``.
        names: identified parameter names (k,) in the order of ``covariance``.
        covariance: (k, k) covariance of the identified parameters [SI].
        noise: instrument noise of ``meas`` for the observed-RMS prediction, if known.
        held_weak: parameters the fit held at nominal because the poses barely
            determined them; their error is not in ``covariance``, so the prediction is
            withheld (it would be optimistic).
        joints: (m, n_act) joint values of the calibrated model's predictions [rad, m]
            (None: the commands ``meas.q_act``; a geometric calibration).
        shift: (m, 3) world position change of the measured frame the joint terms add
            to the calibrated predictions [m] (a thermal expansion of the links), or None.
        covariance_kind: which covariance the prediction propagates (``propagated``,
            else ``covariance``; a key of :data:`pincal.identification.COVARIANCE_KINDS`:
            ``cramer-rao`` only for the linear one at a declared noise); recorded as the
            prediction's ``covariance``.
        values: (n,) the full parameter vector of ``params`` at which the covariance
            was evaluated [SI] (the fit's solution); the prediction's Jacobian is taken
            there, since a covariance only cancels the directions the data do not see
            against the Jacobian of its own point (None: the nominal; on a machine whose
            Jacobian changes over the fit's move, the 2-RSU ankle, J at the nominal
            against the covariance at the solution predicted 0.24 mm for 0.018 mm).
        propagated: (k, k) the covariance propagated to the prediction [SI] (None:
            ``covariance``): the linear one when ``covariance`` was widened for the
            parameters' curvature (:func:`pincal.identification.prediction_covariance`);
            ``covariance`` still decides whether the prediction is withheld.

    Returns:
        The :class:`HeldOutValidation`.

    Raises:
        ConvergenceError: a command whose closure a model cannot solve.
    """
    comps = tuple(meas.components)
    pos = [k for k in range(3) if COMPONENTS[k] in comps]
    rot = [k for k in range(3) if COMPONENTS[3 + k] in comps]
    if meas.rotations is None:
        rot = []
    groups = _groups(meas.q_act)
    before = _model_errors(nominal, meas, groups, pos, rot)
    if joints is not None:
        joints = np.asarray(joints, dtype=float)
        if joints.shape != meas.q_act.shape:
            raise ShapeError(
                f"joints must have the shape of the commands {meas.q_act.shape}, got {joints.shape}"
            )
    if shift is not None and np.shape(shift) != (len(meas), 3):
        raise ShapeError(f"shift must have shape ({len(meas)}, 3), got {np.shape(shift)}")
    after = _model_errors(calibrated, meas, groups, pos, rot, joints, shift)
    rp = [_repeatability(meas, rows, pos) for rows in groups]
    first = [g[0] for g in groups]
    q_rows = meas.q_act[first]
    conditions = {k: None if v is None else np.asarray(v)[first]
                  for k, v in (meas.conditions or {}).items()}  # fmt: skip
    cov = np.asarray(covariance, dtype=float)
    predicted = _prediction(nominal, params, names, cov, q_rows, pos, [3 + k for k in rot], noise,
                            conditions, values, propagated)  # fmt: skip
    if held_weak and predicted["withheld"] is None:
        more = " …" if len(held_weak) > 5 else ""
        predicted = {k: None for k in predicted}
        predicted |= {
            "withheld": f"{len(held_weak)} parameters were held at nominal because the poses "
            f"barely determine them ({', '.join(held_weak[:5])}{more}); their error is not "
            "in the covariance, so the prediction would be optimistic"
        }
    predicted = {**predicted, "covariance": covariance_kind}
    return HeldOutValidation(comps, groups, before, after, rp, predicted)
