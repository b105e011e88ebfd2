"""QPSO identification (seed 003): swarm search of the whitened residual cost.

The cost of parameter values ``x`` (n,) is ``0.5·‖r_w(x)‖²`` with ``r_w`` the whitened
residual of :class:`pincal.identification._identify.CalibrationProblem` (the same cost Gauss–Newton
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
  ``python scripts/pkm5_qpso.py`` — still below the 35–76 µm QPSO reaches, and on wedge3
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

from pincal.errors import ConvergenceError, ParameterError
from pincal.identification._qpso import qpso, qpso_stepwise

__all__ = ["QPSOIdentification", "QPSOOptions", "qpso_identify"]

log = logging.getLogger(__name__)
COST_MODELS = ("linear", "exact")


@dataclass(frozen=True)
class QPSOOptions:
    """Settings of QPSO identification (defaults: seed 003).

    Attributes:
        n_particles: swarm size N (80).
        t_max: iterations per run, and per coarse stage of the step-wise variant (300).
        alpha: contraction–expansion coefficient, first → last iteration (1.0 → 0.5).
        half_width_m: half-width of the search box for length parameters [m] (0.05 mm).
        half_width_rad: half-width for angle parameters [rad] (1 mrad; not in the seed).
        seed: random seed (same seed → same result).
        cost_model: ``"linear"`` or ``"exact"`` (see the module docstring).
        passes: linearisation passes of the ``"linear"`` model (≥ 1; default 1).
        spread_tol, patience, fine_t_max, fine_spread: step-wise convergence test and
            fine stage, see :func:`pincal.identification._qpso.qpso_stepwise`.
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
        if self.cost_model not in COST_MODELS:
            raise ParameterError(
                f"unknown QPSO cost model {self.cost_model!r}; choose from {COST_MODELS}"
            )
        if int(self.passes) < 1:
            raise ParameterError(f"passes must be at least 1, got {self.passes}")
        if not (self.half_width_m > 0 and self.half_width_rad > 0):
            raise ParameterError("search half-widths must be positive")


@dataclass(frozen=True)
class QPSOIdentification:
    """Outcome of :func:`qpso_identify`.

    Attributes:
        values: (n,) identified values [SI] (free entries searched, others = x0).
        cost: exact cost 0.5·‖r_w‖² at ``values``.
        initial_cost: exact cost at ``x0``.
        history: best cost per swarm iteration (of the cost model; last pass, or the fine
            stage of the step-wise variant).
        iterations: swarm iterations over all passes and stages.
        nfev: cost evaluations (particles) over all passes and stages.
        order: step-wise only: free-parameter indices (into the full vector) in the order
            the coarse stage fixed them; empty for the direct variant.
        seconds: wall time of the search.
        message: summary.
    """

    values: np.ndarray
    cost: float
    initial_cost: float
    history: np.ndarray
    iterations: int
    nfev: int
    order: tuple[int, ...]
    seconds: float
    message: str


def _exact_cost(problem, x: np.ndarray) -> float:
    try:
        r, _, _ = problem.evaluate(x, jacobian=False)
    except ConvergenceError:
        return float("inf")
    return 0.5 * float(r @ r)


def qpso_identify(
    problem,
    x0: np.ndarray | None = None,
    free: np.ndarray | None = None,
    *,
    stepwise: bool = False,
    options: QPSOOptions | None = None,
) -> QPSOIdentification:
    """Minimise the whitened residual cost of ``problem`` with (step-wise) QPSO.

    Args:
        problem: a :class:`pincal.identification._identify.CalibrationProblem` (n parameters).
        x0: (n,) centre of the search box and values of the non-free parameters [SI]
            (default zeros = nominal).
        free: indices of the parameters to search (default all).
        stepwise: seed 003's step-wise variant (coarse one-at-a-time + fine stage).
        options: :class:`QPSOOptions` (default: the seed's settings).

    Returns:
        QPSOIdentification.
    """
    opts = options or QPSOOptions()
    n = len(problem.params)
    x0 = np.zeros(n) if x0 is None else np.asarray(x0, dtype=float).copy()
    if x0.shape != (n,):
        raise ParameterError(f"x0 must have shape ({n},), got {x0.shape}")
    free = np.arange(n) if free is None else np.asarray(free, dtype=int)
    units = np.array(problem.params.units)[free]
    half = np.where(units == "m", opts.half_width_m, opts.half_width_rad)
    lo, hi = x0[free] - half, x0[free] + half
    rng = np.random.default_rng(opts.seed)
    start = time.perf_counter()
    initial_cost = _exact_cost(problem, x0)

    def run(cost, vectorized: bool):
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
        res = qpso(
            cost, lo, hi, opts.n_particles, opts.t_max, rng, opts.alpha, vectorized=vectorized
        )
        return res.x, res.history, res.iterations, res.nfev, ()

    iterations = nfev = 0
    if opts.cost_model == "exact":

        def exact(z: np.ndarray) -> float:
            x = x0.copy()
            x[free] = z
            return _exact_cost(problem, x)

        z, history, iterations, nfev, order = run(exact, False)
        passes = 1
    else:
        centre = x0.copy()
        for _ in range(int(opts.passes)):
            r_c, J_c, _ = problem.evaluate(centre)
            J_f = J_c[:, free]
            z_c = centre[free]

            def linear(Z: np.ndarray, r_c=r_c, J_f=J_f, z_c=z_c) -> np.ndarray:
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
    cost = _exact_cost(problem, values)
    seconds = time.perf_counter() - start
    variant = "step-wise QPSO" if stepwise else "QPSO"
    message = (
        f"{variant} ({opts.cost_model} cost, {passes} pass(es), N={opts.n_particles}, "
        f"t_max={opts.t_max}): cost {initial_cost:.6g} → {cost:.6g} in {iterations} "
        f"iterations, {nfev} evaluations, {seconds:.2f} s"
    )
    log.info(message)
    return QPSOIdentification(
        values=values,
        cost=cost,
        initial_cost=initial_cost,
        history=np.asarray(history, dtype=float),
        iterations=iterations,
        nfev=nfev,
        order=order,
        seconds=seconds,
        message=message,
    )
