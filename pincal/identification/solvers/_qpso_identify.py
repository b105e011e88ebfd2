"""QPSO identification (seed 003): swarm search of the whitened residual cost.

The cost of parameter values ``x`` (n,) is ``0.5·‖r_w(x)‖²`` with ``r_w`` the whitened
residual of :class:`pincal.identification.CalibrationProblem` (the same cost Gauss–Newton
minimises). The swarm searches the box ``x0 ± half_width`` (seed 003: ±0.05 mm for the
hinge coordinates) over the free (identifiable) parameters; the others stay at ``x0``.

Two cost models:

* ``"exact"``: every particle is one closed-loop forward-kinematics evaluation of all
  measured poses (``CalibrationProblem.evaluate(values, jacobian=False)``: a new model
  per particle plus a Newton solve per pose). Faithful but slow: about 35 ms per particle
  for pkm5 with 36 poses, i.e. N·t_max = 24 000 evaluations ≈ 14 min for one direct run.
* ``"linear"`` (default): the residual is linearised at a centre ``x_c`` with the analytic
  identification Jacobian, ``r_w(x) ≈ r_w(x_c) + J_w(x_c)(x − x_c)``, and the swarm is
  evaluated as one matrix product per iteration. Over a ±0.05 mm box the neglected
  second-order residual terms are ~δ²/L ≈ 4e-9 m for strut lengths L ≈ 0.7 m, but the
  ill-conditioned Jacobian amplifies them: on pkm5 (``identifiable20``, 90 noise-free
  poses, errors U(±0.03 mm)) the exact minimiser of the cost linearised at the nominal
  is 0.49–5.3 µm from the truth (max over the parameters; median 1.7 µm over 5 error
  draws) and 1e-5 µm after one re-linearisation there, measured by
  ``python scripts/studies/pkm5_qpso.py`` — still below the 35–76 µm QPSO reaches, and on wedge3
  both models give identical swarms (tested). With ``passes > 1`` the model is
  re-linearised at the best particle and the search repeated (each pass a full QPSO
  run); the reported cost is always the exact one.

Both are seeded and reproducible: the same ``QPSOOptions.seed`` gives the same result.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from pincal.errors import SolverOptionError
from pincal.identification._options import check_int, check_real
from pincal.identification.problem import CalibrationProblem
from pincal.identification.results import Progress, QPSOExtras, SolverOutcome
from pincal.identification.solvers._qpso import Objective, qpso
from pincal.identification.solvers._qpso_stepwise import qpso_stepwise

__all__ = ["COST_MODELS", "QPSOOptions", "qpso_search"]

log = logging.getLogger(__name__)
COST_MODELS = ("linear", "exact")


@dataclass(frozen=True)
class QPSOOptions:
    """Settings of QPSO identification (defaults: seed 003).

    Attributes:
        n_particles: swarm size N (80; ≥ 2).
        t_max: iterations per run, and per coarse stage of the step-wise variant (300; ≥ 0).
        alpha: contraction–expansion coefficient, first → last iteration (1.0 → 0.5; > 0).
        half_width_m: half-width of the search box for length parameters [m] (0.05 mm; > 0).
        half_width_rad: half-width for angle parameters [rad] (1 mrad; not in the seed; > 0).
        seed: random seed (same seed → same result; None = fresh entropy).
        cost_model: ``"linear"`` or ``"exact"`` (see the module docstring).
        passes: linearisation passes of the ``"linear"`` model (≥ 1; default 1).
        spread_tol, patience, fine_t_max, fine_spread: step-wise convergence test and
            fine stage, see :func:`pincal.identification.qpso_stepwise` (spread_tol and
            fine_spread > 0, patience ≥ 1, fine_t_max ≥ 0 or None).

    Raises:
        SolverOptionError: an option outside its range (the message gives the range).
    """

    n_particles: int = 80
    t_max: int = 300
    alpha: tuple[float, float] = (1.0, 0.5)
    half_width_m: float = 5e-5
    half_width_rad: float = 1e-3
    seed: int | None = 0
    cost_model: str = "linear"
    passes: int = 1
    spread_tol: float = 1e-3
    patience: int = 10
    fine_t_max: int | None = None
    fine_spread: float = 0.1

    def __post_init__(self) -> None:
        o = type(self).__name__
        if self.cost_model not in COST_MODELS:
            raise SolverOptionError(
                f"unknown QPSO cost model {self.cost_model!r}; choose from {COST_MODELS}"
            )
        check_int(o, "n_particles", self.n_particles, 2)
        check_int(o, "t_max", self.t_max, 0)
        check_int(o, "passes", self.passes, 1)
        check_int(o, "patience", self.patience, 1)
        if self.fine_t_max is not None:
            check_int(o, "fine_t_max", self.fine_t_max, 0)
        check_real(o, "half_width_m", self.half_width_m, 0.0, open_low=True)
        check_real(o, "half_width_rad", self.half_width_rad, 0.0, open_low=True)
        check_real(o, "spread_tol", self.spread_tol, 0.0, open_low=True)
        check_real(o, "fine_spread", self.fine_spread, 0.0, open_low=True)
        a = np.atleast_1d(np.asarray(self.alpha, dtype=float))
        if a.size not in (1, 2) or not np.all(np.isfinite(a)) or np.any(a <= 0):
            raise SolverOptionError(
                f"{o}.alpha must be a positive number or a (start, end) pair of positive "
                f"numbers, got {self.alpha!r}"
            )
        if self.seed is not None:
            check_int(o, "seed", self.seed, 0)


def qpso_search(
    problem: CalibrationProblem,
    x0: np.ndarray,
    free: np.ndarray,
    opts: QPSOOptions,
    progress: Progress = None,
    *,
    stepwise: bool = False,
) -> SolverOutcome:
    """Minimise the whitened residual cost of ``problem`` with (step-wise) QPSO.

    Args:
        problem: the residual model (n parameters).
        x0: (n,) centre of the search box and values of the non-free parameters [SI].
        free: indices of the parameters to search.
        opts: :class:`QPSOOptions`.
        progress: unused (the swarm reports no per-iteration cost); accepted for symmetry.
        stepwise: seed 003's step-wise variant (coarse one-at-a-time + fine stage).

    Returns:
        SolverOutcome with :class:`QPSOExtras`; success when the exact cost did not rise.
    """
    x0 = np.asarray(x0, dtype=float).copy()
    free = np.asarray(free, dtype=int)
    units = np.array(problem.params.units)[free]
    half = np.where(units == "m", opts.half_width_m, opts.half_width_rad)
    lo, hi = x0[free] - half, x0[free] + half
    rng = np.random.default_rng(opts.seed)
    start = time.perf_counter()
    initial_cost = problem.cost(x0)

    def run(
        cost: Objective, vectorized: bool
    ) -> tuple[np.ndarray, np.ndarray, int, int, tuple[int, ...]]:
        if stepwise:
            res = qpso_stepwise(
                cost,
                lo,
                hi,
                opts.n_particles,
                opts.t_max,
                rng,
                opts.alpha,
                vectorized=vectorized,
                spread_tol=opts.spread_tol,
                patience=opts.patience,
                fine_t_max=opts.fine_t_max,
                fine_spread=opts.fine_spread,
            )
            its = sum(s.iterations for s in res.stages) + res.fine.iterations
            order = tuple(int(free[i]) for i in res.order)
            return res.x, res.fine.history, its, res.nfev, order
        single = qpso(
            cost, lo, hi, opts.n_particles, opts.t_max, rng, opts.alpha, vectorized=vectorized
        )
        return single.x, single.history, single.iterations, single.nfev, ()

    iterations = nfev = 0
    if opts.cost_model == "exact":

        def exact(z: np.ndarray) -> float:
            x = x0.copy()
            x[free] = z
            return problem.cost(x)

        z, history, iterations, nfev, order = run(exact, False)
        passes = 1
    else:
        centre = x0.copy()
        for _ in range(int(opts.passes)):
            r_c, J_c, _ = problem.evaluate(centre)
            J_f = J_c[:, free]
            z_c = centre[free]

            def linear(
                Z: np.ndarray,
                r_c: np.ndarray = r_c,
                J_f: np.ndarray = J_f,
                z_c: np.ndarray = z_c,
            ) -> np.ndarray:
                R = r_c[None, :] + (Z - z_c) @ J_f.T
                return 0.5 * np.einsum("ij,ij->i", R, R)

            z, history, its, nf, order = run(linear, True)
            iterations += its
            nfev += nf
            centre = x0.copy()
            centre[free] = z
        passes = int(opts.passes)
    values = x0.copy()
    values[free] = z
    cost = problem.cost(values)
    seconds = time.perf_counter() - start
    variant = "step-wise QPSO" if stepwise else "QPSO"
    message = (
        f"{variant} ({opts.cost_model} cost, {passes} pass(es), N={opts.n_particles}, "
        f"t_max={opts.t_max}): cost {initial_cost:.6g} → {cost:.6g} in {iterations} "
        f"iterations, {nfev} evaluations, {seconds:.2f} s"
    )
    log.info(message)
    swarm = tuple(float(v) for v in np.asarray(history, dtype=float))
    extras = QPSOExtras(cost, initial_cost, nfev, order, seconds, swarm)
    return SolverOutcome(values, iterations, swarm, bool(cost <= initial_cost), message, extras)
