"""``volumetric-map``: a Cartesian error map and corrected commands on a workspace grid (CSV).

For controllers that keep their nominal kinematics and interpolate a compensation table.
The grid spans the declared workspace (the sidecar's ``workspace: pose:`` x, y, z
ranges) or else the bounding box of the measured frame's nominal positions over a
workspace sample, widened by ``MARGIN`` of its size on each side; ``GRID`` nodes along
each measured position axis (an axis that is not measured, or does not move, has one
node at the home position). At each node ``n`` the target is the node's position with
the measured frame's nominal home orientation (imposed only where the orientation is
measured), and the file holds:

* ``u_nom``: the nominal inverse kinematics of the target (the controller's command);
* ``dp = p_cal(u_nom) − n`` [m] and ``dr = log3(R_nomᵀ R_cal(u_nom))`` [rad]: where the
  calibrated machine puts the frame for that command, less the target (the error map);
* ``du = u_cal − u_nom``: the command correction, ``u_cal`` the calibrated machine's
  inverse kinematics of the target [m or rad per actuator].

A controller interpolates trilinearly in the node's cell (the 8 nodes around a point;
fewer axes, fewer nodes) — forward, the pose it predicts for a reading ``u`` whose
nominal pose is ``(p, R)``::

    p_ctl = p + Σ_k w_k dp_k,   R_ctl = R · Exp(Σ_k w_k dr_k)                   (1)

and inverse, the command for a target at ``p``: ``u = IK_nom(p) + Σ_k w_k du_k`` (2),
``w_k`` the trilinear weights of the cell's nodes. A node the nominal or calibrated
machine cannot reach is written ``reachable = 0`` (its columns empty) and left out of
the sum, the other weights divided by their total (a cell at the workspace's edge); a
cell of unreachable nodes only takes the nearest reachable node's values, and a point
outside the grid the values at the grid's nearest point (clamped). What (1)–(2) cannot
hold: the error's dependence on the orientation (the map is at the home orientation) and,
with more actuators than imposed components, on the configuration that reaches a
position; its variation inside a cell; and beyond the grid.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar

import numpy as np
import pinocchio as pin

from pincal.errors import ExportError, PincalError
from pincal.export._format import Built, ControllerFormat, fmt_number
from pincal.export._machine import CalibratedMachine
from pincal.model import Mechanism, actuator_difference

__all__ = ["GRID", "VolumetricMap", "trilinear"]

#: grid nodes along each measured position axis
GRID = 9
#: the grid's box: the workspace sample's bounding box widened by this share of its size
#: on each side (a sample of the fit readings does not reach the workspace's edge)
MARGIN = 0.1


def trilinear(axes: list[np.ndarray], values: np.ndarray, p: np.ndarray) -> np.ndarray | None:
    """Values (d,) interpolated trilinearly at a point, or None where the map has none.

    The weights of a cell's unreachable (NaN) nodes are left out and the others scaled
    to sum to 1; a cell without a reachable node takes the nearest reachable node's
    values; a point outside the grid takes the values of the grid's nearest point. None
    only when no node is reachable.

    Args:
        axes: the node coordinates along x, y, z (one node: that axis is not interpolated).
        values: (n_x, n_y, n_z, d) node values.
        p: (3,) the point [m].
    """
    index: list[list[tuple[int, float]]] = []
    for a, x in zip(axes, p, strict=True):
        if a.size == 1:
            index.append([(0, 1.0)])
            continue
        x = float(np.clip(x, a[0], a[-1]))  # outside the grid: its nearest point
        i = int(np.clip(np.searchsorted(a, x) - 1, 0, a.size - 2))
        t = float(np.clip((x - a[i]) / (a[i + 1] - a[i]), 0.0, 1.0))
        index.append([(i, 1.0 - t), (i + 1, t)])
    out, total = np.zeros(values.shape[-1]), 0.0
    for ix, wx in index[0]:
        for iy, wy in index[1]:
            for iz, wz in index[2]:
                v = values[ix, iy, iz]
                if not np.isnan(v).any():
                    out += wx * wy * wz * v
                    total += wx * wy * wz
    if total > 1e-12:
        return out / total
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)  # (n_x, n_y, n_z, 3)
    ok = ~np.isnan(values).any(axis=-1)
    d = np.where(ok, np.linalg.norm(grid - p, axis=-1), np.inf)
    k = np.unravel_index(int(np.argmin(d)), d.shape)
    return values[k] if ok[k] else None


def _nearest(fit_q: np.ndarray, fit_p: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The configuration (nq,) of ``fit_q`` whose nominal position (``fit_p``) is nearest ``p``."""
    return fit_q[int(np.argmin(np.linalg.norm(fit_p - p, axis=1)))]


class VolumetricMap(ControllerFormat):
    """``volumetric-map``: error map and command corrections on a workspace grid."""

    name: ClassVar[str] = "volumetric-map"
    suffix: ClassVar[str] = ".csv"
    summary: ClassVar[str] = "Cartesian error map and command corrections on a workspace grid"

    def build(self, machine: CalibratedMachine, q_fit: np.ndarray) -> Built:
        nom, cal = machine.nominal, machine.calibrated
        comps = nom.measured_components
        moved = [i for i, c in enumerate("xyz") if c in comps]
        if not moved:
            raise ExportError(
                f"a volumetric map is over positions; {nom.name!r} measures {list(comps)} "
                "(use --format generic-table)"
            )
        home = nom.frame_placement(nom.q_home)
        conf_nom = nom.configurations(q_fit)
        conf_cal = cal.configurations(machine.actual(q_fit))
        fit_p = np.array([nom.frame_placement(q).translation for q in conf_nom])
        axes = []
        box = (
            "the declared workspace"
            if nom.workspace.pose
            else (f"the workspace sample's bounding box widened by {MARGIN:.0%} each side")
        )
        for i in range(3):
            declared = nom.workspace.pose.get("xyz"[i])
            if declared is not None:
                lo, hi = (float(v) for v in declared)
            else:
                lo, hi = fit_p[:, i].min(), fit_p[:, i].max()
                lo, hi = lo - MARGIN * (hi - lo), hi + MARGIN * (hi - lo)
            one = i not in moved or hi - lo < 1e-9
            axes.append(np.array([home.translation[i]]) if one else np.linspace(lo, hi, GRID))
        n_act = len(nom.actuated)
        scale = 1.0 + np.array([machine.gains().get(j, 0.0) for j in nom.actuated])
        values = np.full((*(a.size for a in axes), 6 + n_act), np.nan)
        u_nom_all = np.full((*values.shape[:3], n_act), np.nan)
        for idx in np.ndindex(*values.shape[:3]):
            p = np.array([axes[i][idx[i]] for i in range(3)])
            target = pin.SE3(home.rotation, p)
            try:
                qn = nom.inverse_configuration(target, _nearest(conf_nom, fit_p, p))
                qc = cal.inverse_configuration(target, _nearest(conf_cal, fit_p, p))
                u_nom, u_cal = nom.actuators_of(qn), cal.actuators_of(qc) / scale
                T = cal.frame_placement(cal.configuration(machine.actual(u_nom[None])[0]))
            except PincalError:
                continue
            if not (_within(nom, u_nom) and _within(cal, u_cal)):
                continue
            R_nom = nom.frame_placement(qn).rotation
            du = actuator_difference(nom, u_cal, u_nom)  # a continuous joint's within π
            values[idx] = np.concatenate([T.translation - p, pin.log3(R_nom.T @ T.rotation), du])
            u_nom_all[idx] = u_nom
        reachable = ~np.isnan(values[..., 0])
        if not reachable.any():
            raise ExportError(
                f"no node of the {values.shape[:3]} workspace grid is reachable by both the "
                "nominal and the calibrated machine"
            )
        body = _csv(axes, values, u_nom_all, nom.actuated)
        written = np.array(
            [[float(fmt_number(v)) if np.isfinite(v) else np.nan for v in row]
             for row in values.reshape(-1, values.shape[-1])]
        ).reshape(values.shape)  # fmt: skip
        forward, inverse = _controller(nom, axes, written, (conf_nom, fit_p))
        turned = any(c.startswith("r") for c in comps)
        held = "the error's dependence on orientation (the map is at the nominal home orientation)"
        redundant = (
            f"the error's dependence on the configuration reaching a position ({n_act} "
            f"actuators for {len(comps)} imposed components: one configuration per node)"
        )
        missing = [
            *([held] if turned else []),
            *([redundant] if n_act > len(comps) else []),
            "its variation inside a grid cell (trilinear)",
            "the error beyond the grid (clamped to its edge)",
        ]
        missing += [f"joint term {t}" for t in machine.terms_not_held(("gain",))]
        if not reachable.all():
            missing.append(
                f"{int((~reachable).sum())} of {reachable.size} nodes unreachable (reachable = 0; "
                "left out of their cells' weights, the nearest reachable node's values where "
                "a cell has none)"
            )
        worse = _worse_than_none(machine, forward, q_fit, fit_p)
        if worse:
            missing.append(worse)
        conventions = [
            f"{'x'.join(str(a.size) for a in axes)} nodes over {box}; trilinear in each cell",
            "du = calibrated command − nominal command for the same target",
        ]
        return Built(body, forward, missing, conventions, inverse)


def _worse_than_none(
    machine: CalibratedMachine,
    forward: Callable[[np.ndarray], np.ndarray],
    q: np.ndarray,
    plain: np.ndarray,
) -> str:
    """A phrase when the map's positions miss the model by more than no map does at ``q``.

    ``plain`` (m, 3): the nominal positions at ``q`` [m] (no map).
    """
    ref = machine.reference(q)[:, :3, 3]
    rms = [
        float(np.sqrt(np.mean(np.sum((p - ref) ** 2, axis=1))))
        for p in (forward(q)[:, :3, 3], plain)
    ]
    if rms[0] < rms[1]:
        return ""
    return (
        f"over the fit readings the map is no better than no map (position RMS "
        f"{rms[0] * 1e6:.4g} um against {rms[1] * 1e6:.4g} um uncorrected): this machine's error "
        "depends on more than the position (orientation, configuration); a map does not "
        "describe it (see generic-table or dh-standard)"
    )


def _within(mech: Mechanism, u: np.ndarray) -> bool:
    lo, hi = mech.actuator_limits.T
    return bool(np.all((u >= lo - 1e-12) & (u <= hi + 1e-12)))


def _csv(
    axes: list[np.ndarray], values: np.ndarray, u_nom: np.ndarray, actuated: tuple[str, ...]
) -> str:
    cols = [
        "x_m",
        "y_m",
        "z_m",
        "reachable",
        "dx_m",
        "dy_m",
        "dz_m",
        "drx_rad",
        "dry_rad",
        "drz_rad",
        *(f"u_nom_{j}" for j in actuated),
        *(f"du_{j}" for j in actuated),
    ]
    lines = [",".join(cols)]
    for idx in np.ndindex(*values.shape[:3]):
        p = [fmt_number(float(axes[i][idx[i]])) for i in range(3)]
        v = values[idx]
        if np.isnan(v[0]):
            lines.append(",".join([*p, "0"] + [""] * (len(cols) - 4)))
            continue
        n = len(actuated)
        row = [float(x) for x in (*v[:6], *u_nom[idx], *v[6 : 6 + n])]
        lines.append(",".join([*p, "1", *(fmt_number(x) for x in row)]))
    return "\n".join(lines) + "\n"


def _controller(
    nom: Mechanism,
    axes: list[np.ndarray],
    values: np.ndarray,
    starts: tuple[np.ndarray, np.ndarray],
) -> tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], np.ndarray]]:
    """Equations (1) and (2) of the module with the numbers as written.

    ``starts``: nominal configurations and their positions; the controller's inverse
    starts from the nearest (a row of NaN where it finds no solution).
    """

    def forward(q_act: np.ndarray) -> np.ndarray:
        out = []
        for q in nom.configurations(q_act):
            T = nom.frame_placement(q)
            v = trilinear(axes, values[..., :6], T.translation)
            if v is not None:
                T = pin.SE3(T.rotation @ pin.exp3(v[3:]), T.translation + v[:3])
            out.append(T.homogeneous)
        return np.array(out)

    def inverse(poses: np.ndarray) -> np.ndarray:
        out = []
        for M in poses:
            guess = _nearest(*starts, M[:3, 3])
            try:
                u = nom.actuators_of(nom.inverse_configuration(pin.SE3(M[:3, :3], M[:3, 3]), guess))
            except PincalError:
                out.append(np.full(len(nom.actuated), np.nan))
                continue
            v = trilinear(axes, values[..., 6:], M[:3, 3])
            out.append(u if v is None else u + v)
        return np.array(out)

    return forward, inverse
