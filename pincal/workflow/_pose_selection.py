"""Measurement poses chosen as ``pincal poses`` chooses them, without the CLI.

Three steps, so that the command can show the candidates' progress and name the option
of a bad candidate spec: :func:`pose_basis` settles the preset and reduces a
rank-deficient one to its identifiable base set; :func:`pose_candidates` makes the
candidate set; :func:`select_pose_design` screens the candidates (limits,
singularities, collisions, reach on a displaced model: :func:`compensation_test`),
selects the poses maximising an observability index on the scaling asked, orders them
for travel and predicts the parameters' standard deviations (Cramér–Rao). Nothing is
written: :class:`PoseSelection` holds what ``pincal.io.write_pose_design`` writes.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from pincal.design import (
    MAX_CANDIDATE_BYTES,
    MAX_CANDIDATES,
    CandidateSet,
    CramerRaoReport,
    DesignScaling,
    PoseDesign,
    ScreenReport,
    ScreenSettings,
    candidate_set,
    characteristic_length,
    cramer_rao_from_jacobian,
    screen_candidates,
    select_poses,
    travel_order,
)
from pincal.errors import OptionValueError, PincalError
from pincal.measure import NoiseModel
from pincal.model import Mechanism, ParameterSet
from pincal.sensitivity import base_parameters, parameters
from pincal.workflow._model_description import reduction_line
from pincal.workflow._reach_screen import compensation_test

__all__ = [
    "PoseBasis",
    "PoseRequest",
    "PoseSelection",
    "pose_basis",
    "pose_candidates",
    "select_pose_design",
]

Say = Callable[[str], None]


@dataclass(frozen=True)
class PoseBasis:
    """The parameters poses are chosen for.

    Attributes:
        preset: the preset's name.
        preset_params: the preset's parameters (the reach screen's errors are drawn on
            them).
        params: the parameters the design identifies: the preset's, or its identifiable
            base set when the preset is rank-deficient.
    """

    preset: str
    preset_params: ParameterSet
    params: ParameterSet

    def lines(self, model: str) -> list[str]:
        """What the command says on stderr: the reduction (if any) and the count."""
        reduced = len(self.params) < len(self.preset_params)
        n = len(self.preset_params)
        return [
            *([reduction_line(self.preset, len(self.params), n)] if reduced else []),
            f"{model}: {len(self.params)} parameters (preset {self.preset!r})",
        ]


def pose_basis(mech: Mechanism, preset: str | None) -> PoseBasis:
    """The preset (None: the model's first, else ``full``) and the parameters to identify."""
    preset = preset or (next(iter(mech.presets)) if mech.presets else "full")
    params = parameters(mech, preset)
    reduced = base_parameters(mech, params)
    return PoseBasis(preset, params, reduced if len(reduced) < len(params) else params)


def pose_candidates(
    mech: Mechanism,
    basis: PoseBasis,
    spec: str,
    seed: int,
    *,
    max_candidates: int | None = MAX_CANDIDATES,
    max_bytes: int | None = MAX_CANDIDATE_BYTES,
    n_jobs: int = 1,
    progress: Callable[[int, int], None] | None = None,
    scheduler: str | None = None,
    screens: ScreenSettings | None = None,
) -> CandidateSet:
    """The candidate poses of ``spec`` (``auto``, ``grid:LEVELS``, ``random:COUNT``, ``oa:LEVELS``).

    Refused past ``max_candidates`` poses or ``max_bytes`` of memory (None: no bound;
    :func:`pincal.design.candidate_set`); ``progress(done, total)`` over the poses;
    evaluated on ``n_jobs`` local processes or a Dask ``scheduler``. With the
    ``screens`` the design will apply, a grid's default ranges leave the joint-limit
    margin out and ``auto`` judges the grid by the poses those screens keep (all but the
    compensation screen, which runs on the design's candidates only).
    """

    def usable(cands: CandidateSet) -> CandidateSet:
        assert screens is not None
        return screen_candidates(mech, cands, screens)[0]

    return candidate_set(
        mech, basis.params, spec, rng=seed, progress=progress,
        max_candidates=max_candidates, max_bytes=max_bytes, n_jobs=n_jobs,
        scheduler=scheduler, joint_margin=screens.joint_margin if screens else 0.0,
        usable=usable if screens else None,
    )  # fmt: skip


#: the option that relaxes each screen (named when the screens leave too few poses)
RELAX = {
    "joint-limit margin": "--joint-margin",
    "singularity margin": "--singular-margin",
    "self-collision": "--no-collisions",
    "obstacle collision": "--no-collisions or fewer --obstacle",
    "compensation": "--reach-errors smaller or none",
}


@dataclass(frozen=True)
class PoseRequest:
    """What ``pincal poses`` asks for.

    Attributes:
        count: number of poses to select.
        index: observability index maximised (``O1``…``O5``, ``A``).
        scaling: row scaling: ``noise`` (whitening), ``K`` (characteristic length) or
            ``none`` (unscaled SI).
        K_mm: the characteristic length [mm] of ``K`` (None: from the candidates).
        noise: noise 1σ (position [mm], orientation [mrad]).
        method: ``exchange``, ``detmax`` or ``greedy``.
        order: ``travel`` (a short joint-space tour from home) or ``selection``.
        restarts: random starts (the best kept).
        seed: random seed of the starts and of the reach screen's errors.
        reach_errors: error bounds (mm, mrad) of the reach screen, None: not screened.
        spec: the candidate spec (named in the messages).
    """

    count: int
    index: str
    scaling: str
    K_mm: float | None
    noise: tuple[float, float]
    method: str
    order: str
    restarts: int
    seed: int
    reach_errors: tuple[float, float] | None
    spec: str


@dataclass(frozen=True)
class PoseSelection:
    """The poses chosen, as :func:`select_pose_design` returns them.

    Attributes:
        design: the selected poses (in travel order when asked).
        crb: the Cramér–Rao prediction of the parameters' standard deviations [m, rad].
        screens: what each screen removed.
        extra: the further entries of ``<stem>.json`` (noise, predicted σ, screens).
        request: what was asked.
    """

    design: PoseDesign
    crb: CramerRaoReport
    screens: ScreenReport
    extra: dict[str, Any]
    request: PoseRequest

    def lines(self) -> list[str]:
        """The command's summary: the index's history, the condition number, the CRB."""
        sel, req = self.design.selection, self.request
        hist = " → ".join(f"{v:.5g}" for v in (sel.history[0], sel.history[-1]))
        return [
            f"{req.method}: {req.index} {hist} in {sel.iterations} iterations "
            f"({'converged' if sel.converged else 'iteration limit'}); "
            f"condition number {self.design.indices_all.condition_number:.4g}",
            self.crb.summary(),
        ]

    def record(self) -> dict[str, Any]:
        """The design's entries of the ``--json`` summary."""
        sel = self.design.selection
        return {
            "count": len(self.design.candidates),
            "index": self.request.index,
            "value": float(sel.value),
            "converged": bool(sel.converged),
            "predicted_std_by_unit": self.crb.std_by_unit(),  # [mm], [mrad]: never mixed
            "screens_removed": self.screens.removed,
        }


def select_pose_design(
    mech: Mechanism,
    basis: PoseBasis,
    cands: CandidateSet,
    request: PoseRequest,
    settings: ScreenSettings,
    say: Say | None = None,
) -> PoseSelection:
    """Screen ``cands``, select ``request.count`` poses, order them, predict the σ.

    ``say``: given the screens' and scaling's summaries (stderr on the command line).

    Raises:
        OptionValueError: fewer feasible candidates than ``request.count``.
        PincalError: a characteristic length with a scaling other than ``K``.
    """
    tell = say or (lambda _line: None)
    req = request
    errors = req.reach_errors
    compensable = (
        None if errors is None
        else compensation_test(mech, basis.preset_params, errors, req.seed, say=tell)
    )  # fmt: skip
    cands, screens = screen_candidates(mech, cands, settings, compensable=compensable)
    tell(cands.summary())
    tell(f"  {screens.summary()}")
    for note in screens.notes:
        tell(f"  {note}")
    if req.count > len(cands):
        busiest = sorted(screens.removed, key=lambda n: -screens.removed[n])
        relax = "; ".join(dict.fromkeys(RELAX[n] for n in busiest if screens.removed[n]))
        raise OptionValueError(
            f"--count {req.count} is more than the {len(cands)} feasible candidate poses of "
            f"--candidates {req.spec} ({screens.summary()}); ask for at most {len(cands)} "
            "poses, generate more candidates (e.g. --candidates random:2000 or a finer "
            f"grid:LEVELS) or relax the screens that removed them ({relax or 'none did'})"
        )
    noise_model = NoiseModel(*req.noise)
    design_scaling = _scaling(req, cands, noise_model)
    tell(f"scaling: {design_scaling.describe()}")
    design = select_poses(
        cands, req.count, req.index, design_scaling, req.method,
        rng=np.random.default_rng(req.seed), restarts=req.restarts,
    )  # fmt: skip
    if req.order == "travel":
        speeds = [0.1 if mech.tree.joints[j].type == "prismatic" else 1.0 for j in mech.actuated]
        tour = travel_order(design.q_act, mech.actuators_of(mech.q_home), speeds)
        design = dataclasses.replace(
            design,
            candidates=design.candidates.subset(tour.order),
            indices=design.indices[tour.order],
        )
        tell(tour.summary())
    params = basis.params
    crb = cramer_rao_from_jacobian(
        design.candidates.jacobians, cands.components, noise_model, None,
        params.names, params.units,
    )  # fmt: skip
    extra = {
        "noise": {"position_mm": req.noise[0], "orientation_mrad": req.noise[1]},
        "predicted_std": dict(zip(params.names, map(float, crb.std), strict=True)),
        "screens": {"removed": screens.removed, "notes": list(screens.notes),
                    "reach_errors_mm_mrad": None if errors is None else list(errors)},
    }  # fmt: skip
    return PoseSelection(design, crb, screens, extra, req)


def _scaling(req: PoseRequest, cands: CandidateSet, noise: NoiseModel) -> DesignScaling:
    """The row scaling of ``req.scaling``."""
    if req.scaling == "K":
        K = (
            req.K_mm * 1e-3
            if req.K_mm is not None
            else characteristic_length(cands.jacobians, cands.components)
        )
        return DesignScaling(rows="K", K=K)
    if req.scaling == "noise":
        if req.K_mm is not None:
            raise PincalError("--K applies to --scaling K only")
        sig = noise.std(("x", "rx"))
        return DesignScaling(
            rows="noise", position_std=float(sig[0]), orientation_std=float(sig[1])
        )
    return DesignScaling(rows="none")
