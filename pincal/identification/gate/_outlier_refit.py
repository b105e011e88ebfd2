"""Outliers confirmed by a refit without them: a smeared fit never names good poses.

:func:`pincal.identification.gate._outliers.deletion_outliers` linearises at the fitted
solution. When gross outliers pulled that solution far (5 mm among 10 µm noise), the
linearisation is poor there and a good pose can look bad once the outliers are deleted
linearly. Here the poses it named are left out and the model refitted (Gauss–Newton,
the parameters it identified, the noise and the prior as the fit had them: the same
cost less those poses); the deletion test is then run again over *all* poses,
linearised at the refit — a point near the outlier-free solution, where deleting the
true outliers is exact to first order — and the poses it named are judged against the
scale of the poses outside them
(:func:`pincal.identification.gate._outliers.refit_outliers`: outliers that mask each other
there are still confirmed). Only the poses named there are reported.
"""

from __future__ import annotations

import numpy as np

from pincal.errors import PincalError
from pincal.identification._options import GaussNewtonOptions
from pincal.identification.gate._outliers import refit_outliers
from pincal.identification.problem import TRIAL_FAILURES, CalibrationProblem
from pincal.identification.results import IdentificationResult
from pincal.measure import Measurements
from pincal.model import Mechanism

__all__ = ["confirm_outliers"]


def confirm_outliers(
    result: IdentificationResult,
    mech: Mechanism,
    meas: Measurements,
    named: tuple[int, ...],
    risk: float,
    cap: int,
) -> tuple[tuple[int, ...], float, np.ndarray, np.ndarray, np.ndarray] | None:
    """The deletion test over all poses, linearised at a refit without ``named``.

    Args:
        result: the fit that named them (its parameter set and noise are reused).
        mech: the nominal mechanism.
        meas: all m measured poses.
        named: pose indices the first deletion test named (1 ≤ len ≤ cap).
        risk: family-wise false-alarm probability over the poses.
        cap: most poses named (as in :func:`deletion_outliers`).

    Returns:
        (named poses, bound) of the test at the refit and the refit's linearisation over
        all poses — whitened Jacobian (m, k, p), whitened residuals (m, k) and σ (m, k)
        [m, rad] — on which the misspecification probes judge the fit without the
        outliers' smear; or None when the refit fails (too few poses left, a solve that
        does not close…): keep the first answer.
    """
    from pincal.identification._identify import identify

    ps, w = result.parameter_set, result.weighting
    if w is None or not named:
        return None
    keep = np.setdiff1d(np.arange(len(meas)), np.asarray(named, dtype=int))
    declared = None
    if w.source == "declared":
        declared = {"position": w.position_std * 1e3, "orientation": w.orientation_std * 1e3}
        declared = {b: v for b, v in declared.items() if np.isfinite(v)}
    options = None
    if result.prior is not None:  # without it a prior-held direction runs away
        weight, mean = result.prior
        with np.errstate(divide="ignore"):
            sd = np.where(weight > 0, 1.0 / weight, np.inf)
        options = GaussNewtonOptions(prior_std=tuple(sd), prior_mean=tuple(mean))
    try:
        refit = identify(mech, ps, meas.subset(keep), initial=result.full_values,
                         fit=result.identified_names, noise=declared or None,
                         options=options)  # fmt: skip
        rw = refit.weighting
        model = CalibrationProblem(mech, ps, meas, noise=declared or None)
        if rw is not None and rw.source.startswith("estimate"):
            std = {"position": rw.position_std, "orientation": rw.orientation_std}
            model = model.with_block_std({b: std[b] for b in model.blocks})
        r_w, J_w, _ = model.evaluate(refit.full_values)
    except (PincalError, *TRIAL_FAILURES):
        return None
    if J_w is None:
        return None
    m, k = len(meas), len(meas.components)
    A = J_w[:, refit.identified].reshape(m, k, -1)
    z = np.asarray(r_w).reshape(m, k)
    return (*refit_outliers(A, z, named, risk, cap), A, z, np.asarray(model.sigma, dtype=float))
