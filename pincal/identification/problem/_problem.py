"""The whitened residual model of one pose file, batched over its poses.

:class:`CalibrationProblem` is the residual model of an
:class:`pincal.identification.IdentificationProblem` of one pose file: the residual of pose i is
``measured − model`` in the measured components (``[p_meas − p; log3(Rᵀ R_meas)]``),
whitened by the noise standard deviations, with the analytic identification Jacobian.

The standard deviations are, in this order: the measurements' per-value ``std``, the
declared noise model (the ``noise`` argument, else the file's ``# noise:`` header), or —
when neither is given (the normal case for real data) — estimated per block
(position, orientation) from the residuals by variance-component estimation
(:mod:`pincal.identification.solvers._noise`). A residual model whose noise is still to be
estimated has ``noise_source == "estimate"`` and must be re-weighted
(:meth:`CalibrationProblem.with_block_std`) before it is fitted: it never fits with
silent unit weights.

The poses' closed configurations at trial values, warm-started, are
:class:`pincal.identification.problem._pose_configurations.PoseConfigurations`; this module
assembles the residuals and the Jacobian on them.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from pincal.errors import (
    ClosureError,
    ConvergenceError,
    MeasurementError,
    MobilityError,
    ModelFileError,
)
from pincal.identification.problem._pose_configurations import PoseConfigurations
from pincal.identification.problem._residual_model import Evaluates
from pincal.measure import Measurements, NoiseModel
from pincal.model import BatchKinematics, Linearisation, Mechanism, ParameterSet
from pincal.model.kernels import jlog3_batch, log3_batch
from pincal.sensitivity import sensitivities_batch

__all__ = ["BLOCKS", "TRIAL_FAILURES", "CalibrationProblem"]

#: exceptions that make a trial parameter vector unusable: the model cannot be built
#: (ModelFileError), its mobility changes (MobilityError, e.g. an emulated ball joint
#: whose axes no longer meet), its loops cannot be assembled (ClosureError) or a pose
#: cannot be solved (ConvergenceError, SingularConfigurationError)
TRIAL_FAILURES = (ConvergenceError, ClosureError, MobilityError, ModelFileError)
#: noise blocks: name → measured components of the block
BLOCKS = {"position": ("x", "y", "z"), "orientation": ("rx", "ry", "rz")}


class CalibrationProblem(Evaluates[np.ndarray]):
    """Whitened residuals and Jacobian of a parameter set against measurements.

    Args:
        mech: nominal mechanism; params: parameter set (n); measurements: m poses.
        noise: declared instrument noise (a :class:`NoiseModel` or ``{"position": mm,
            "orientation": mrad}``); overrides the measurements' noise model. A zero σ
            of a measured block counts as not declared.

    Attributes:
        sigma: (m, k) standard deviations of the residuals [m, rad].
        noise_source: ``"per-pose"``, ``"declared"``, ``"estimated"`` (re-weighted by
            :meth:`with_block_std`) or ``"estimate"`` (still to be estimated; ``sigma``
            is a placeholder that must not be fitted with).
        blocks: {block name: column indices into the measured components}.
        poses: the measured poses' closed configurations at trial values.

    Raises:
        MeasurementError: the measurements are of other joints or another frame, or a
            bad noise specification.
    """

    def __init__(
        self,
        mech: Mechanism,
        params: ParameterSet,
        measurements: Measurements,
        noise: NoiseModel | Mapping[str, float] | None = None,
    ):
        if tuple(measurements.actuated) != tuple(mech.actuated):
            raise MeasurementError(
                f"measurement columns {list(measurements.actuated)} do not match the actuated "
                f"joints {list(mech.actuated)}"
            )
        if measurements.frame != mech.measured_frame:
            raise MeasurementError(
                f"measurements are of frame {measurements.frame!r}, the model measures "
                f"{mech.measured_frame!r}"
            )
        self.mech, self.params, self.meas = mech, params, measurements
        self.rows = measurements.component_indices
        declared = NoiseModel.from_spec(noise)
        noise = declared if declared is not None else measurements.noise
        comps = measurements.components
        self.blocks = {
            b: np.array([j for j, c in enumerate(comps) if c in cs], dtype=int)
            for b, cs in BLOCKS.items()
            if any(c in cs for c in comps)
        }
        m, k = len(measurements), len(self.rows)
        if measurements.std is not None and declared is None:
            self.sigma = np.array(measurements.std, dtype=float)
            self.noise_source = "per-pose"
        elif noise is not None and np.all(noise.std(comps) > 0):
            self.sigma = np.tile(noise.std(comps), (m, 1))
            self.noise_source = "declared"
        else:
            self.sigma = np.ones((m, k))
            self.noise_source = "estimate"
        self.poses = PoseConfigurations(mech, params, measurements)
        self._memo: dict[bytes, tuple] = {}  # last evaluations: r_w, J_w, r_raw, qs, kinematics
        #: (values key, (m, k, n) model Jacobian of the measured components) of the last
        #: Jacobian evaluation, for :meth:`structural_jacobian`
        self._structural: tuple[bytes, np.ndarray] | None = None

    @property
    def predict_starts(self) -> bool:
        """Whether each pose's loop solve starts from a first-order prediction.

        Switched on by Gauss–Newton for its run (:attr:`PoseConfigurations.predict_starts`).
        """
        return self.poses.predict_starts

    @predict_starts.setter
    def predict_starts(self, value: bool) -> None:
        self.poses.predict_starts = value

    @property
    def known_noise(self) -> bool:
        """Whether ``sigma`` holds the noise (declared, per-pose or estimated)."""
        return self.noise_source != "estimate"

    @property
    def sigma_floor(self) -> float:
        """Smallest σ an estimate may take [m, rad]: 100× the kinematic solver's tolerance."""
        return 100 * self.mech.options.tol

    def block_std(self) -> dict[str, float]:
        """{block: σ} when each block has one σ for all its poses (NaN otherwise)."""
        out = {}
        for b, cols in self.blocks.items():
            vals = self.sigma[:, cols]
            out[b] = float(vals.flat[0]) if np.all(vals == vals.flat[0]) else float("nan")
        return out

    def with_block_std(self, std: Mapping[str, float]) -> CalibrationProblem:
        """A copy weighted by one σ per block (``{"position": m, "orientation": rad}``).

        The copy has ``noise_source == "estimated"`` and shares the nominal mechanism,
        the last configurations (as start guesses) and the last evaluations (re-weighted:
        a re-fit from the last solution starts without solving the kinematics again)
        with this one.

        Raises:
            MeasurementError: a measured block without a finite σ > 0.
        """
        sigma = np.empty_like(self.sigma)
        for b, cols in self.blocks.items():
            v = std.get(b)
            if v is None or not np.isfinite(v) or v <= 0:
                raise MeasurementError(f"noise σ of the {b} block must be finite and > 0, got {v}")
            sigma[:, cols] = float(v)
        new = CalibrationProblem(self.mech, self.params, self.meas)
        new.sigma, new.noise_source = sigma, "estimated"
        new.poses = self.poses.warm_copy()
        new._structural = self._structural
        scale = (self.sigma / sigma).reshape(-1)
        for key, (r_w, J_w, raw, qs, bk) in self._memo.items():  # warm: re-weighted only
            r_new = r_w * scale
            J_new = None if J_w is None else J_w * scale[:, None]
            for a in (r_new, J_new):
                if a is not None:
                    a.setflags(write=False)
            new._memo[key] = (r_new, J_new, raw, qs, bk)
        return new

    @property
    def solver_floor_cost(self) -> float:
        """Cost of residuals at 100× the FK tolerance: below it, data are fitted exactly."""
        return 0.5 * float(np.sum((100 * self.mech.options.tol / self.sigma) ** 2))

    @property
    def names(self) -> tuple[str, ...]:
        """The unknowns: the machine's parameters (a pose file has no own unknowns)."""
        return self.params.names

    @property
    def units(self) -> tuple[str, ...]:
        """The parameters' units ('m' or 'rad')."""
        return self.params.units

    @property
    def n_machine(self) -> int:
        """Machine parameters: all of the unknowns."""
        return len(self.params)

    @property
    def n_equations(self) -> int:
        """Scalar measurement equations: poses × measured components."""
        return len(self.meas) * len(self.rows)

    def linearisation(self, values: np.ndarray) -> Linearisation:
        """The parameter set linearised at values (n,) [SI] (kept for the last one)."""
        return self.poses.linearisation(values)

    def mechanism(self, values: np.ndarray) -> Mechanism:
        """The mechanism with parameter values (n,) [SI] applied (cached for the last one)."""
        return self.poses.mechanism(values)

    def cost(self, values: np.ndarray) -> float:
        """0.5·‖whitened residual‖² at ``values``.

        Returns +inf when the model cannot be assembled or a pose cannot be solved.
        """
        try:
            r, _, _ = self.evaluate(values, jacobian=False)
        except TRIAL_FAILURES:
            return float("inf")
        return 0.5 * float(r @ r)

    def residuals(
        self, values: np.ndarray, jacobian: bool
    ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """Whitened residual (N,), its Jacobian (N, n) or None, and raw residuals (m, k).

        Evaluations are memoised per parameter vector (the returned arrays are
        read-only); a Jacobian asked for after a residual-only evaluation reuses that
        evaluation's closed configurations and kinematics.
        """
        values = np.asarray(values, dtype=float)
        key = values.tobytes()
        hit = self._memo.get(key)
        if hit is not None and (hit[1] is not None or not jacobian):
            return hit[0], (hit[1] if jacobian else None), hit[2]
        mech = self.mechanism(values)
        qs, bk = (hit[3], hit[4]) if hit is not None else self.poses.solve(mech, values)
        out = self._assemble(mech, values, qs, bk, jacobian)
        for a in out:
            if a is not None:
                a.setflags(write=False)
        if len(self._memo) >= 2:
            self._memo.pop(next(iter(self._memo)))
        self._memo[key] = (*out, qs, bk)
        return out

    def structural_jacobian(self, values: np.ndarray) -> np.ndarray:
        """Whitened Jacobian (N, n) of the model's measured components alone.

        The residual Jacobian of :meth:`evaluate` maps the model's rotation through
        ``Jlog3`` of the measured deviation; far from the solution (a tilted actual
        machine measured in rz only) that mixes unmeasured rotations into the measured
        rows and makes second-order effects look identifiable. Which parameters are
        identifiable is decided on this Jacobian instead: the same rows and weights,
        the deviation taken as zero. Kept from the last Jacobian evaluation at
        ``values`` (no new solve); evaluated otherwise.
        """
        values = np.asarray(values, dtype=float)
        key = values.tobytes()
        if self._structural is None or self._structural[0] != key:
            hit = self._memo.get(key)
            qs, bk = (hit[3], hit[4]) if hit is not None else self.poses.solve(
                self.mechanism(values), values
            )
            self._assemble(self.mechanism(values), values, qs, bk, True)
        assert self._structural is not None
        return (self._structural[1] / self.sigma[:, :, None]).reshape(-1, len(self.params))

    def _assemble(
        self,
        mech: Mechanism,
        values: np.ndarray,
        qs: np.ndarray,
        bk: BatchKinematics | None,
        jacobian: bool,
    ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        meas = self.meas
        if jacobian:
            lin = self.linearisation(values)
            basis = self.poses.term_basis(mech, values)
            sens = sensitivities_batch(mech, self.params, qs, bk, lin, basis)
            p, R = sens.positions, sens.rotations
        elif bk is not None:
            R, p = mech.batch_model.frame_placement(bk, mech.frame_id(mech.measured_frame))
        else:
            T = [mech.frame_placement(q) for q in qs]
            p, R = np.array([t.translation for t in T]), np.array([t.rotation for t in T])
        shift = self.poses.shift
        if shift is not None:
            p = p + shift @ values
        r = np.zeros((len(meas), 6))
        r[:, :3] = meas.positions - p
        D_rot = None
        if meas.rotations is not None:
            E = np.swapaxes(R, 1, 2) @ np.asarray(meas.rotations, dtype=float)
            r[:, 3:] = log3_batch(E)
            if jacobian:
                D_rot = jlog3_batch(r[:, 3:]) @ np.swapaxes(E, 1, 2)
        r_raw = r[:, self.rows]
        w = 1.0 / self.sigma
        r_w = (r_raw * w).ravel()
        if not jacobian:
            return r_w, None, r_raw
        Js = sens.jacobian
        if shift is not None:  # terms moving the frame: their position columns
            Js = np.concatenate([Js[:, :3] + shift, Js[:, 3:]], axis=1)
        self._structural = (values.tobytes(), -np.asarray(Js)[:, self.rows])
        J = -np.concatenate([Js[:, :3], Js[:, 3:] if D_rot is None else D_rot @ Js[:, 3:]], 1)
        J_w = (J[:, self.rows] * w[:, :, None]).reshape(-1, len(self.params))
        return r_w, J_w, r_raw
