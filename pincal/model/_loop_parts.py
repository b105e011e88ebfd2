"""The loop parts of a mechanism: assembled home, mobility and loop solvers of a model.

Given the single-pose kinematic queries of a Pinocchio model (:class:`KinematicQueries`),
:func:`close_loops` assembles the home configuration (from the sidecar ``home`` values,
or beside a given configuration when a mechanism is derived with moved joints), checks
the mobility there, and builds the pose-by-pose :class:`LoopSolver` and the batched
:class:`BatchLoopSolver` on home's assembly branch. A :class:`~pincal.model.Mechanism`
takes these parts when it is made and when it is derived
(:meth:`~pincal.model.Mechanism.with_joint_origins`).
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import dataclass

import numpy as np

from pincal.model.batch import BatchLoopSolver, BatchModel, BatchNewton
from pincal.model.loops import Assembly, KinematicQueries, LoopSolver, SolverOptions

__all__ = ["LoopParts", "close_loops"]


@dataclass(frozen=True)
class LoopParts:
    """What :func:`close_loops` builds for a model.

    Attributes:
        q_home: assembled home configuration (nq,), read-only [m, rad].
        notes: remarks made while assembling (for ``pincal info``).
        mobility, closure_rank, idle_joints: see :class:`~pincal.model.loops._assembly.Mobility`.
        loop_solver: pose-by-pose loop closing on home's assembly branch.
        batch_solver: batched loop closing (many poses together) on the same branch.
    """

    q_home: np.ndarray
    notes: tuple[str, ...]
    mobility: int
    closure_rank: int
    idle_joints: tuple[str, ...]
    loop_solver: LoopSolver
    batch_solver: BatchLoopSolver


def close_loops(
    queries: KinematicQueries,
    options: SolverOptions,
    home: Mapping[str, object],
    q_guess: np.ndarray | None = None,
    template: tuple[BatchModel, Collection[int], Collection[int]] | None = None,
) -> LoopParts:
    """Assemble home, check the mobility and build the loop solvers of ``queries``' model.

    Args:
        queries: the single-pose kinematics of the model.
        options: the solver options.
        home: the sidecar ``home`` values per joint [m, rad] (used when ``q_guess`` is None;
            home keeps the actuator values it names).
        q_guess: (nq,) a configuration to assemble beside (a derived mechanism: the home
            of the one it derives from), or None.
        template: the batched model of a mechanism with the same tree, the ids of the
            joints and the indices of the frames that moved (for a derived mechanism).

    Raises:
        ClosureError, MobilityError, SingularConfigurationError: the model does not
            assemble at home, or not with a consistent mobility.
    """
    assembly = Assembly(queries, options)
    if q_guess is None:
        keep = any(n in home for n in queries.actuated)
        q_home = assembly.assemble(assembly.home_guess(home), keep_actuators=keep)
    else:
        q_home = assembly.assemble(np.asarray(q_guess, dtype=float), beside=True)
    q_home.setflags(write=False)  # shared with derived mechanisms: never modified
    mobility = assembly.mobility(q_home)
    loop_solver = LoopSolver(queries, options, q_home, mobility.passive_rank)
    kernels = BatchNewton(queries, options, loop_solver.branch_block, template)
    return LoopParts(
        q_home=q_home,
        notes=tuple(assembly.notes),
        mobility=mobility.mobility,
        closure_rank=mobility.closure_rank,
        idle_joints=tuple(mobility.idle_joints),
        loop_solver=loop_solver,
        batch_solver=BatchLoopSolver(kernels, loop_solver),
    )
