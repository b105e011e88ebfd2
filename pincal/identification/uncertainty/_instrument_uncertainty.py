"""The covariance of an instrument fit: linear plus its measured second-order term.

:func:`instrument_uncertainty` adds to the linear covariance of a ballbar / probe /
socket fit the second moment of its second-order error over its own confidence region
(:func:`pincal.identification.uncertainty._linearity.check_curvature`, 64 seeded draws; its
coverage is measured in ``docs/quality_gate.md``). That term is a computed moment of the
model's curvature, not a sample covariance of refits; a parametric bootstrap of the
joint fit runs only on request (``draws=N``) and is reported beside it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from pincal.errors import PincalError
from pincal.identification._instrument_identify import InstrumentIdentification
from pincal.identification._verdict import QualityIssue
from pincal.identification.problem import InstrumentRecipe, mechanism_blob
from pincal.identification.uncertainty._bootstrap import bootstrap_covariance
from pincal.identification.uncertainty._inflation import widest_combination
from pincal.identification.uncertainty._intervals import interval_quantiles
from pincal.identification.uncertainty._linearity import check_curvature
from pincal.identification.uncertainty._uncertainty import (
    CURVATURE_DRAWS,
    CURVATURE_LIMIT,
    UncertaintyCheck,
)
from pincal.model import Mechanism

__all__ = ["instrument_uncertainty"]


def instrument_uncertainty(
    fit: InstrumentIdentification,
    mech: Mechanism,
    datasets: Sequence[Any],
    labels: Sequence[str] | None = None,
    *,
    draws: int = 0,
    seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
    n_jobs: int = 1,
) -> UncertaintyCheck:
    """Check an instrument fit's second-order error and add it to the covariance.

    The linear σ of a ballbar or probe fit on random poses are several times too small
    in their well-determined combinations (the model bends over the confidence region
    of its weakly seen directions), while the cost-ratio check of
    :func:`check_uncertainty` fires on designed poses too, whose linear σ are right.
    Here the measure is what matters for the intervals (:func:`check_curvature`): the
    second-order error ``J⁺q`` over draws from the confidence region. Its second moment
    is added to the linear covariance — what that error adds to the mean squared
    error of the fit about its target (see :class:`Curvature` for the term it leaves
    out), larger only in the directions the curvature moves — and its d²/k
    (``excess``) beyond :data:`CURVATURE_LIMIT` is a warning. With ``draws`` > 0 a
    parametric bootstrap of the joint fit (machine and instrument unknowns; each refit
    solves every pose again: minutes on a few hundred readings) is run and reported
    beside the σ (``to_dict()["bootstrap"]``); it never replaces them.

    Args:
        fit: the outcome of :func:`pincal.identification.identify_instruments`.
        mech: the nominal mechanism.
        datasets: the fit's datasets.
        labels: their labels, as given to the fit.
        draws: bootstrap refits to report (0: none; e.g. 100).
        seed: the seed of the draws (curvature and bootstrap).
        progress: ``progress(done, total)`` per bootstrap refit.
        n_jobs: bootstrap worker processes (joblib; -1 = every CPU).
    """
    from pincal.identification.problem import InstrumentProblem

    result, free = fit.result, np.asarray(fit.fitted, dtype=int)
    if free.size == 0 or result.parameter_set is None:
        return UncertaintyCheck(result, None)
    try:
        problem = InstrumentProblem(mech, result.parameter_set, datasets, labels)
    except PincalError:
        return UncertaintyCheck(result, None)
    machine = free < len(result.names)
    base = UncertaintyCheck(result, None, linear_std=result.std,
                            intervals=interval_quantiles(int(np.sum(result.identified))))
    if draws:
        try:
            recipe = InstrumentRecipe(mechanism_blob(mech), result.parameter_set,
                                      tuple(datasets), labels)  # fmt: skip
        except (AttributeError, TypeError):
            recipe = None
        boot = bootstrap_covariance(problem, fit.values, free, draws=draws, seed=seed,
                                    progress=progress, n_jobs=n_jobs, factory=recipe)  # fmt: skip
        base = replace(base, bootstrap=replace(boot, covariance=boot.covariance[
            np.ix_(machine, machine)]))  # fmt: skip
    cu = check_curvature(problem, fit.values, free, draws=CURVATURE_DRAWS, seed=seed)
    base = replace(base, curvature=cu)
    linear = cu.checked and cu.excess <= CURVATURE_LIMIT
    drawn = cu.draws + cu.failed
    beyond = (f"{cu.failed} of {drawn} points drawn from its confidence region do not "
              "assemble (the machine does not close there)")  # fmt: skip
    if not cu.checked:
        text = (f"the curvature of the fit could not be checked: {beyond}; the σ reported "
                "are the linear ones and may be too small")  # fmt: skip
        return replace(base, issue=QualityIssue("linearity", False, text))
    assert cu.second_moment is not None
    cov = (np.asarray(fit.covariance) + cu.second_moment)[np.ix_(machine, machine)]
    if cov.shape != np.shape(result.covariance):
        return base
    new = replace(result, covariance=cov, std=np.sqrt(np.clip(np.diag(cov), 0.0, None)))
    worst = widest_combination(np.asarray(fit.covariance), cu.second_moment)
    base = replace(base, result=new, method="second-order", widened=worst,
                   linear_covariance=np.asarray(result.covariance, dtype=float))
    lower = f"; {beyond}: the σ may still be too small" if cu.failed else ""
    if linear and not cu.failed:
        return base
    if linear:
        text = ("the σ reported include the fit's second-order error (it adds "
                f"{cu.excess:.3g} to d²/k, below the limit){lower}")  # fmt: skip
        return replace(base, issue=QualityIssue("linearity", False, text))
    each = float(np.max(new.std / np.maximum(result.std, 1e-300), initial=1.0))
    text = ("the fit is not linear over its own confidence region: its second-order error "
            f"adds {cu.excess:.3g} to the d²/k of the linear σ (0 when they are right; "
            f"limit {CURVATURE_LIMIT:g}); the σ reported add that second-order error (its "
            f"second moment over {cu.draws} draws from the confidence region): the σ of the "
            f"combination it moves most is {worst:.3g}× the linear one, the parameters' own "
            f"σ up to {each:.2f}×{lower}; a parametric bootstrap, reported beside them: "
            "pincal calibrate --bootstrap 100")  # fmt: skip
    return replace(base, issue=QualityIssue("linearity", False, text))
