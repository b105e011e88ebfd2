"""The simulated calibration of ``pincal demo``, without the CLI.

A seeded "actual" machine is drawn around the nominal model, measurement poses
are chosen from a candidate set by maximising O1 on the noise-whitened Jacobian
(D-optimal design), the Cramér–Rao bound predicts the achievable accuracy before
measuring, a laser-tracker campaign is simulated, the parameters are identified and
the result is validated on fresh poses (predicted vs achieved). :func:`simulate_demo`
returns all of it as one :class:`DemoResult`; nothing is written (the command writes
the calibration directory from :meth:`DemoResult.annotations`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from pincal.design import (
    MAX_CANDIDATE_BYTES,
    MAX_CANDIDATES,
    CramerRaoReport,
    DesignScaling,
    PoseDesign,
    candidate_set,
    cramer_rao_from_jacobian,
    select_poses,
)
from pincal.errors import QualityGateError
from pincal.identification import (
    IdentificationResult,
    QualityVerdict,
    check_quality,
    identify,
)
from pincal.measure import DEFAULT_NOISE, NoiseModel, simulate_measurements
from pincal.model import COMPONENTS, Mechanism, ParameterSet, load_mechanism, sample_actuators
from pincal.sensitivity import identification_jacobian, parameters
from pincal.validation import PoseErrors, pose_errors

__all__ = ["DemoAccuracy", "DemoResult", "DemoSettings", "draw_errors", "simulate_demo"]


@dataclass(frozen=True)
class DemoSettings:
    """Settings of the simulated campaign.

    Attributes:
        model: bundled model name; preset: parameter preset.
        seed: random seed.
        n_poses: measurement poses; n_validation: fresh validation poses.
        error_std: std of the drawn geometric errors [mm].
        noise: instrument noise (mm, mrad).
        method: identification method.
        report: the command writes report.html too (not used by :func:`simulate_demo`).
        candidates: candidate spec for pose selection (``auto``, ``grid:4``, ``random:300``,
            ``oa:5``) or ``"none"`` for random measurement poses.
        index: observability index maximised on the noise-whitened Jacobian.
        bounded: refuse a candidate set past the default bounds of
            :func:`pincal.design.candidate_set` (False: ``--yes``).
        force: write the calibration even when the quality gate refuses it (recorded).
    """

    model: str = "stewart_6ups"
    preset: str = "stewart42"
    seed: int = 7
    n_poses: int = 30
    n_validation: int = 60
    error_std: float = 0.5
    noise: NoiseModel = DEFAULT_NOISE
    method: str = "gauss-newton"
    report: bool = True
    candidates: str = "auto"
    index: str = "O1"
    bounded: bool = True
    force: bool = False


@dataclass(frozen=True)
class DemoAccuracy:
    """The identified parameters against the simulated truth, in plain floats.

    Attributes:
        names, units: the identified parameters (k,) and their units ("m" or "rad").
        true, identified, error, std: per parameter (k,) [m or rad]: the true value,
            the identified one, their difference, the identification's 1σ.
        z_rms: RMS of error/σ (≈ 1 when the σ are right).
        within_2sigma: share of |error| < 2σ [%].
        achieved_rms: RMS parameter error [m and rad mixed, as the report states µm].
        predicted_std: RMS Cramér–Rao σ of the same parameters, predicted before
            measuring [m and rad mixed], None without a design.
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    true: tuple[float, ...]
    identified: tuple[float, ...]
    error: tuple[float, ...]
    std: tuple[float, ...]
    z_rms: float
    within_2sigma: float
    achieved_rms: float
    predicted_std: float | None


@dataclass(frozen=True)
class DemoResult:
    """Everything the demo computed (SI inside).

    Attributes:
        settings: the settings run.
        nominal: the nominal mechanism; params: the parameter set identified.
        true_values: the drawn parameter errors (n,) [m, rad] (the truth).
        result: the identification.
        before, after: validation errors of the nominal and calibrated models on the
            fresh poses, against the actual machine.
        verdict: the quality gate's verdict.
        design: the pose design (None: random poses).
        crb: the Cramér–Rao prediction made before measuring (None: random poses).
    """

    settings: DemoSettings
    nominal: Mechanism
    params: ParameterSet
    true_values: np.ndarray
    result: IdentificationResult
    before: PoseErrors
    after: PoseErrors
    verdict: QualityVerdict
    design: PoseDesign | None = None
    crb: CramerRaoReport | None = None

    def accuracy(self) -> DemoAccuracy:
        """The identified parameters against the truth (:class:`DemoAccuracy`)."""
        r = self.result
        names = tuple(r.params.names)
        true = self.true_values[[self.params.index(n) for n in names]]
        err = r.values - true
        z = err / r.std
        predicted = None
        if self.crb is not None:
            std = self.crb.std[[self.crb.names.index(n) for n in names]]
            predicted = float(np.sqrt(np.mean(std**2)))
        return DemoAccuracy(
            names, tuple(r.params.units), tuple(float(v) for v in true),
            tuple(float(v) for v in r.values), tuple(float(v) for v in err),
            tuple(float(v) for v in r.std), float(np.sqrt(np.mean(z**2))),
            float(np.mean(np.abs(z) < 2) * 100), float(np.sqrt(np.mean(err**2))), predicted,
        )  # fmt: skip

    def annotations(self) -> dict[str, object]:
        """The notes the calibration directory records: gate, truth, validation, design."""
        s, before, after, truth = self.settings, self.before, self.after, self.true_values
        notes: dict[str, object] = {
            "quality": self.verdict.to_dict(overridden=s.force),
            "truth": dict(zip(self.params.names, (float(t) for t in truth), strict=True)),
            "validation_before": before.summary(),
            "validation_after": after.summary(),
            "validation_components": list(before.components),
            "validation_source": f"{s.n_validation} fresh poses of the simulated actual "
            "machine (truth)",
            "validation_errors": {
                "before": {
                    "position": before.position.tolist(),
                    "orientation": before.orientation.tolist(),
                },
                "after": {
                    "position": after.position.tolist(),
                    "orientation": after.orientation.tolist(),
                },
            },
        }
        if self.design is not None:
            notes["index_history"] = {s.index: list(self.design.selection.history)}
        return notes


def draw_errors(params: ParameterSet, std_mm: float, rng: np.random.Generator) -> np.ndarray:
    """Random errors (n,) [m, rad]: N(0, std) on lengths [mm → m]; angles std/100 mm per rad."""
    scale = np.array([std_mm * 1e-3 if u == "m" else std_mm * 1e-3 / 0.1 for u in params.units])
    return rng.normal(0.0, 1.0, len(params)) * scale


def simulate_demo(
    settings: DemoSettings = DemoSettings(),
    progress: Callable[[str], None] | None = None,
    gate: bool = True,
) -> DemoResult:
    """Run the simulated calibration (see the module docstring); nothing is written.

    BLAS runs single-threaded throughout: every dense solve here is small, and a
    threaded BLAS on a busy machine made them several times slower.

    Args:
        settings: the campaign (:class:`DemoSettings`).
        progress: called with a line before each long step.
        gate: refuse a fit the quality gate refuses (unless ``settings.force``).

    Raises:
        QualityGateError: ``gate`` and the gate refused the fit without ``force``.
        PincalError subclasses of the design (candidate set) and of the fit.
    """
    with threadpool_limits(1):
        return _simulate(settings, progress or (lambda _msg: None), gate)


def _simulate(settings: DemoSettings, say: Callable[[str], None], gate: bool) -> DemoResult:
    rng = np.random.default_rng(settings.seed)
    nominal = load_mechanism(settings.model)
    params = parameters(nominal, settings.preset)
    true = draw_errors(params, settings.error_std, rng)
    actual = params.apply(nominal, true)
    q_val = sample_actuators(nominal, settings.n_validation, rng)
    design = None
    if settings.candidates == "none":
        say(f"sampling {settings.n_poses} random measurement poses")
        q_meas = sample_actuators(nominal, settings.n_poses, rng)
    else:
        say(f"candidate poses {settings.candidates}")
        cands = candidate_set(
            nominal, params, settings.candidates, rng,
            max_candidates=MAX_CANDIDATES if settings.bounded else None,
            max_bytes=MAX_CANDIDATE_BYTES if settings.bounded else None,
        )  # fmt: skip
        sig = settings.noise.std(("x", "rx"))
        scaling = DesignScaling("noise", position_std=sig[0], orientation_std=sig[1])
        say(f"selecting {settings.n_poses} of {len(cands)} poses by {settings.index}")
        design = select_poses(cands, settings.n_poses, settings.index, scaling, rng=rng)
        q_meas = design.q_act
    comps = nominal.measured_components
    if design is not None:  # the selected candidates' Jacobian blocks, already computed
        J_meas = design.candidates.jacobians
    else:
        J_meas = identification_jacobian(nominal, params, q_meas).reshape(
            len(q_meas), len(comps), len(params)
        )
    J_val = identification_jacobian(nominal, params, q_val, components=COMPONENTS).reshape(
        len(q_val), 6, len(params)
    )
    # the prediction, like the validation, is over the measured components only
    J_val[:, [k for k, c in enumerate(COMPONENTS) if c not in comps], :] = 0.0
    crb = cramer_rao_from_jacobian(J_meas, comps, settings.noise, J_val, params.names, params.units)
    meas = simulate_measurements(actual, q_meas, settings.noise, rng)
    say(f"identifying {len(params)} parameters ({settings.method})")
    result = identify(nominal, params, meas, settings.method)
    verdict = check_quality(result, meas, mech=nominal)
    if not verdict.passed and not settings.force and gate:
        raise QualityGateError(verdict.reason(), verdict)
    say(f"validating on {settings.n_validation} fresh poses")
    before = pose_errors(nominal, actual, q_val, comps)
    after = pose_errors(result.calibrated, actual, q_val, comps)
    return DemoResult(settings, nominal, params, true, result, before, after, verdict,
                      design, crb)  # fmt: skip
