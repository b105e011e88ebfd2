"""Joint machine + instrument identification from files of several measurement kinds.

:class:`InstrumentProblem` is a residual model beside
:class:`pincal.identification.CalibrationProblem`: the unknowns are
``x = [machine parameters (n); θ of instrument 1; θ of instrument 2; …]``. Each dataset
is either :class:`pincal.measure.Measurements` (pose, position, component subset, tracker
poses — residuals exactly as in ``CalibrationProblem``) or
:class:`pincal.measure.InstrumentData` (one scalar per pose) or
:class:`pincal.measure.SocketData` (a ball seated in sockets: three residuals per pose,
socket centres shared by the files of one plate and appended after every file's own
unknowns, one residual per known distance); every block is whitened by its own noise,
so several files of different kinds combine in one fit. Each dataset is one
:class:`pincal.identification.problem._data_blocks.DataBlock` (pose sensor, scalar instrument,
sockets): one ``evaluate(x, jacobian)`` loops over them. The Jacobian is analytic:
``∂v/∂p · ∂p/∂x`` with ``∂p/∂x`` of every pose at once from
:func:`pincal.sensitivity.sensitivities_batch` (the pose route's kernels), and
``∂v/∂θ`` from the instrument. It is the residual model of an
:class:`pincal.identification.IdentificationProblem` of several data sets
(``joint_model``), solved by :func:`pincal.identification.identify`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pincal.errors import ConvergenceError, MeasurementError
from pincal.identification.problem._data_blocks import ArtefactBlock, DataBlock, data_block
from pincal.identification.problem._problem import TRIAL_FAILURES
from pincal.identification.problem._residual_model import Evaluates
from pincal.identification.problem._shared_terms import SharedUnknowns
from pincal.measure import (
    Artefact,
    DeclaredConstant,
    InstrumentData,
    Measurements,
)
from pincal.model import BatchKinematics, Linearisation, Mechanism, ParameterSet
from pincal.sensitivity import Identifiability, analyse_jacobian, sensitivities_batch

__all__ = ["Dataset", "InstrumentProblem"]

Dataset = InstrumentData | Measurements | Artefact


class InstrumentProblem(Evaluates[list[np.ndarray]]):
    """Whitened residuals and Jacobian of machine + instrument parameters.

    Args:
        mech: nominal mechanism; params: its n parameters.
        datasets: one or more :class:`Measurements` / :class:`InstrumentData`.
        labels: a label per dataset (default ``"<kind><i>"``), prefixing θ names.

    Raises:
        MeasurementError: no datasets, or a dataset of other joints / another frame.
    """

    def __init__(
        self,
        mech: Mechanism,
        params: ParameterSet,
        datasets: Sequence[Dataset],
        labels: Sequence[str] | None = None,
    ):
        datasets = list(datasets)
        if not datasets:
            raise MeasurementError("give at least one measurement dataset")
        self.mech, self.params, self.datasets = mech, params, datasets
        self.labels = (
            list(labels)
            if labels is not None
            else [
                f"{'pose' if isinstance(d, Measurements) else d.kind}{i}"
                for i, d in enumerate(datasets)
            ]
        )
        for d, label in zip(datasets, self.labels, strict=True):
            if tuple(d.actuated) != tuple(mech.actuated) or d.frame != mech.measured_frame:
                raise MeasurementError(
                    f"dataset {label!r} is of joints {list(d.actuated)} / frame {d.frame!r}; "
                    f"the model has {list(mech.actuated)} / {mech.measured_frame!r}"
                )
        qs = mech.configurations(np.vstack([d.q_act for d in datasets]))
        starts = np.cumsum([0] + [len(d) for d in datasets])
        self.blocks: list[DataBlock] = []
        names: list[str] = list(params.names)
        units: list[str] = list(params.units)
        own_cols: dict[int, int] = {}  # artefact dataset index → column of its own unknowns
        for i, (d, label) in enumerate(zip(datasets, self.labels, strict=True)):
            P0 = np.array([mech.frame_placement(q).translation
                           for q in qs[starts[i] : starts[i + 1]]])  # fmt: skip
            block = data_block(d, label, mech, params, P0)
            if isinstance(block, ArtefactBlock):
                own_cols[i], block.index = len(names), i
            self.blocks.append(block)
            names += block.own_names
            units += block.own_units
        self.sigma: list[np.ndarray] = [b.sigma for b in self.blocks]
        self.n_machine = len(params)
        self.sockets = SharedUnknowns(datasets, len(names), own_cols)
        for b in self.blocks:
            if isinstance(b, ArtefactBlock):
                b.shared = self.sockets
        names += self.sockets.names
        units += self.sockets.units
        if self.sockets.sigma is not None:
            self.sigma.append(self.sockets.sigma)
        self.names, self.units = tuple(names), tuple(units)
        self.x0 = np.concatenate([np.zeros(self.n_machine), *[b.theta0 for b in self.blocks],
                                  np.zeros(len(self.sockets.names))])  # fmt: skip
        self.sockets.start(mech, qs, self.x0)
        self._qs: np.ndarray | None = None
        self._cache: tuple[bytes, Linearisation, Mechanism] | None = None

    @property
    def fixes_scale(self) -> bool:
        """False when only sockets without a known distance were measured."""
        return self.sockets.fixes_scale

    @property
    def scale_warnings(self) -> tuple[str, ...]:
        """What no measurement fixes, in words (see :class:`SharedUnknowns`)."""
        return self.sockets.warnings

    def socket_centres(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """``"plate.socket"`` → (3,) socket centre at ``x`` [m]."""
        return self.sockets.centres(x)

    @property
    def n_equations(self) -> int:
        """Number of scalar equations over all data blocks."""
        return int(sum(s.size for s in self.sigma))

    @property
    def known_noise(self) -> bool:
        """True: every block is whitened by its file's declared σ (never re-estimated)."""
        return True

    @property
    def solver_floor_cost(self) -> float:
        """Cost of residuals at 100× the FK tolerance: below it, data are fitted exactly."""
        return 0.5 * float(sum(np.sum((100 * self.mech.options.tol / s) ** 2) for s in self.sigma))

    def mechanism(self, x: np.ndarray) -> Mechanism:
        """The mechanism with the machine part of ``x`` applied (cached for the last one)."""
        return self._applied(x)[1]

    def _applied(self, x: np.ndarray) -> tuple[Linearisation, Mechanism]:
        """The parameters linearised at the machine part of ``x`` and their mechanism."""
        values = np.asarray(x, dtype=float)[: self.n_machine]
        key = values.tobytes()
        if self._cache is None or self._cache[0] != key:
            lin = self.params.linearise(values)
            mech = self.mech if not np.any(values) else self.params.apply(self.mech, lin)
            self._cache = (key, lin, mech)
        return self._cache[1], self._cache[2]

    def cost(self, x: np.ndarray) -> float:
        """0.5·‖whitened residual‖²; +inf when the model cannot be assembled."""
        try:
            r, _, _ = self.evaluate(x, jacobian=False)
        except TRIAL_FAILURES:
            return float("inf")
        return 0.5 * float(r @ r)

    def _configurations(self, mech: Mechanism) -> tuple[np.ndarray, BatchKinematics | None]:
        """Closed configurations (m, nq) of every pose, started from the last ones.

        In batch; the rows the batched Newton does not accept (other branch, no
        convergence) pose by pose. Returns the batched kinematics too when every row was
        accepted (else None).
        """
        rows = np.vstack([d.q_act for d in self.datasets])
        qs, accepted, bk = mech.try_configurations_batch(rows, self._qs)
        qs = np.array(qs, dtype=float)
        for i in map(int, np.flatnonzero(~accepted)):
            q_act = rows[i]
            guess = None if self._qs is None else self._qs[i]
            try:
                qs[i] = mech.configuration(q_act, guess, pose_index=i)
            except ConvergenceError:
                if guess is None:
                    raise
                qs[i] = mech.configuration(q_act, None, pose_index=i)
        self._qs = qs
        return qs, (bk if bool(np.all(accepted)) else None)

    def _tool(
        self, x: np.ndarray, jacobian: bool
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Tool positions (m, 3) [m], orientations (m, 3, 3) and Jacobian (m, 6, n) or None.

        The batched sensitivities of :func:`pincal.sensitivity.sensitivities_batch`
        (the kernels of the pose route) over every pose of every dataset.
        """
        lin, mech = self._applied(x)
        qs, bk = self._configurations(mech)
        if jacobian:
            sens = sensitivities_batch(mech, self.params, qs, bk, lin)
            return sens.positions, sens.rotations, sens.jacobian
        if bk is not None and mech.batch_model.supported:
            R, P = mech.batch_model.frame_placement(bk, mech.frame_id(mech.measured_frame))
            return P, R, None
        placements = [mech.frame_placement(q) for q in qs]
        P = np.array([T.translation for T in placements]).reshape(-1, 3)
        return P, np.array([T.rotation for T in placements]).reshape(-1, 3, 3), None

    def residuals(
        self, x: np.ndarray, jacobian: bool
    ) -> tuple[np.ndarray, np.ndarray | None, list[np.ndarray]]:
        """Whitened residual (N,), its Jacobian (N, n + Σk) or None, raw residuals per dataset.

        Residuals are ``measured − model`` [m, rad]; the third item is a list of
        (m_i, k_i) arrays, one per dataset.
        """
        x = np.asarray(x, dtype=float)
        n = self.n_machine
        P_all, R_all, J_all6 = self._tool(x, jacobian)
        r_all, J_all, raws = [], [], []
        start, col = 0, n
        for block in self.blocks:
            rows = slice(start, start + len(block))
            start = rows.stop
            Jm = None if J_all6 is None else J_all6[rows]
            raw, J = block.residuals(x, col, n, P_all[rows], R_all[rows], Jm)
            col += len(block.own_names)
            sig = block.sigma
            raws.append(raw)
            r_all.append((raw / sig).ravel())
            J_all.append((J / sig[:, :, None]).reshape(-1, len(x)))
        if len(self.sigma) > len(self.datasets):  # the known distances of the plates
            raw, J = self.sockets.group_block(x)
            sig = self.sigma[-1]
            raws.append(raw)
            r_all.append((raw / sig).ravel())
            J_all.append((J / sig[:, :, None]).reshape(-1, len(x)))
        r_w = np.concatenate(r_all)
        return r_w, (np.vstack(J_all) if jacobian else None), raws

    def declared_constants(self, x: np.ndarray) -> list[tuple[str, DeclaredConstant, np.ndarray]]:
        """Every constant the datasets declare and the fit trusts, at ``x``.

        Returns:
            Per constant (its dataset's label, the constant, its (N,) whitened Jacobian
            column: ∂(readings)/∂constant / σ on its dataset's rows, 0 elsewhere).
        """
        P = self._tool(np.asarray(x, dtype=float), False)[0]
        out, row, pose, col = [], 0, 0, self.n_machine
        for b in self.blocks:
            m, k = len(b), len(b.own_names)
            for c in b.declared_constants(np.asarray(x[col : col + k], dtype=float),
                                          P[pose : pose + m]):  # fmt: skip
                column = np.zeros(self.n_equations)
                column[row : row + b.sigma.size] = (np.asarray(c.derivative, dtype=float)[:, None]
                                                    / b.sigma).ravel()  # fmt: skip
                out.append((b.label, c, column))
            row, pose, col = row + b.sigma.size, pose + m, col + k
        return out

    @property
    def order(self) -> np.ndarray:
        """The column order of :meth:`analyse`: instrument parameters first."""
        return np.r_[np.arange(self.n_machine, len(self.names)), np.arange(self.n_machine)]

    def analyse(self, x: np.ndarray | None = None, J: np.ndarray | None = None) -> Identifiability:
        """Identifiability of the joint parameters at ``x`` (default the start values).

        The instrument parameters are listed first so they enter the base first.
        ``J``: the whitened Jacobian at ``x`` when already evaluated.
        """
        if J is None:
            _, J, _ = self.evaluate(self.x0 if x is None else x)
        return analyse_jacobian(J[:, self.order], tuple(self.names[i] for i in self.order))

    def tool_points(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tool points (m, 3) [m] of every pose at ``x`` and their sensitivities (m, 3, n)."""
        P, _, Jm = self._tool(np.asarray(x, dtype=float), True)
        assert Jm is not None
        return P, Jm[:, :3]
