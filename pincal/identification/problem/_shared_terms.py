"""The shared unknowns of the artefact datasets of :class:`InstrumentProblem`.

Each artefact kind (:class:`pincal.measure.Artefact`, e.g. the ``socket`` plates) groups
its datasets into one :class:`pincal.measure.SharedTerms` (its shared unknowns, their
start values, residuals of their own such as a plate's known distances, and what no
measurement fixes). The shared unknowns of every kind are appended after every dataset's
own unknowns, kind by kind in order of first appearance.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from pincal.errors import MeasurementError
from pincal.measure import Artefact, SharedTerms
from pincal.model import Mechanism

__all__ = ["SharedUnknowns"]


class SharedUnknowns:
    """The shared unknowns and group residuals of the artefact datasets of one problem.

    Args:
        datasets: every dataset of the problem (the :class:`Artefact` ones are used).
        first_column: the column of the first shared unknown (after all own unknowns).
        own_columns: dataset index → column of its first own unknown.

    Raises:
        MeasurementError: a kind's :meth:`Artefact.shared_terms` refuses its datasets
            (e.g. two files give different values for one known distance).
    """

    def __init__(
        self, datasets: Sequence[Any], first_column: int, own_columns: dict[int, int]
    ) -> None:
        self.datasets = list(datasets)
        self.own_columns = dict(own_columns)
        by_kind: dict[type[Artefact], list[int]] = {}
        for i, d in enumerate(self.datasets):
            if isinstance(d, Artefact):
                by_kind.setdefault(type(d), []).append(i)
        #: per kind: (its dataset indices, its terms, the column of its first unknown)
        self.groups: list[tuple[list[int], SharedTerms, int]] = []
        col = first_column
        names: list[str] = []
        units: list[str] = []
        sigma: list[np.ndarray] = []
        for cls, idx in by_kind.items():
            terms = cls.shared_terms([self.datasets[i] for i in idx])
            self.groups.append((idx, terms, col))
            col += len(terms.names)
            names += terms.names
            units += terms.units
            if terms.sigma is not None:
                sigma.append(terms.sigma)
        #: dataset index → (s,) columns of its shared unknowns (in its own order)
        self.columns: dict[int, np.ndarray] = {
            i: first + terms.index(self.datasets[i])
            for idx, terms, first in self.groups
            for i in idx
        }
        self.names, self.units = tuple(names), tuple(units)
        #: (d, 1) 1σ of the groups' own residuals [m], or None without any
        self.sigma = np.concatenate(sigma) if sigma else None

    @property
    def warnings(self) -> tuple[str, ...]:
        """What no measurement fixes, in words (every kind's :meth:`SharedTerms.warnings`)."""
        alone = len(self.groups) == 1 and len(self.groups[0][0]) == len(self.datasets)
        return tuple(w for _, terms, _ in self.groups for w in terms.warnings(alone))

    @property
    def fixes_scale(self) -> bool:
        """False when a kind warns that nothing measured fixes the length scale."""
        return not self.warnings

    def start(self, mech: Mechanism, qs: np.ndarray, x0: np.ndarray) -> None:
        """Write start values of the artefacts' own and shared unknowns into ``x0``.

        Args:
            mech: the nominal mechanism.
            qs: (N, nq) its configurations of every pose of the problem.
            x0: (len(x),) the start vector, written in place.
        """
        starts = np.cumsum([0] + [len(d) for d in self.datasets])
        poses: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        thetas: dict[int, np.ndarray] = {}
        for idx, _, _ in self.groups:
            for i in idx:
                d = self.datasets[i]
                T = [mech.frame_placement(q) for q in qs[starts[i] : starts[i + 1]]]
                P = np.array([t.translation for t in T])
                Rs = np.array([t.rotation for t in T])
                theta = np.asarray(d.start(P, Rs), dtype=float)
                if theta.size:
                    x0[self.own_columns[i] : self.own_columns[i] + theta.size] = theta
                poses[i], thetas[i] = (P, Rs), theta
        for idx, terms, first in self.groups:
            phi = terms.start([poses[i] for i in idx], [thetas[i] for i in idx])
            x0[first : first + len(terms.names)] = phi

    def centres(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Named 3-D points [m] of the shared unknowns at ``x`` (e.g. ``"plate.A"``)."""
        out: dict[str, np.ndarray] = {}
        for _, terms, first in self.groups:
            out.update(terms.points(np.asarray(x, dtype=float)[first : first + len(terms.names)]))
        return out

    def block(self, i: int, x: np.ndarray, col: int, n: int, P: np.ndarray,
              Rs: np.ndarray, Jm: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """Raw residuals (m, k) of artefact dataset ``i`` and their Jacobian (m, k, len(x)).

        Args:
            i: the dataset's index.
            x: all unknowns of the problem.
            col: the column of the dataset's own unknowns.
            n: the number of machine parameters (the first columns).
            P: (m, 3) positions of the measured frame [m].
            Rs: (m, 3, 3) its orientations.
            Jm: (m, 6, n) tool Jacobian w.r.t. the machine parameters (None: no
                Jacobian, zeros returned).
        """
        d = self.datasets[i]
        m, k = len(d), len(d.parameter_names)
        R = np.asarray(Rs)
        cols = self.columns[i]
        raw, dp, dw, dth, dphi = d.residuals(P, R, x[col : col + k], x[cols])
        _check_shapes(d, (raw, dp, dw, dth, dphi), (m, d.dim), (3, 3, k, cols.size))
        J = np.zeros((m, d.dim, len(x)))
        if Jm is not None:
            # a local rotation ω of the frame: ∂/∂x = ∂r/∂p ∂p/∂x + ∂r/∂ω ∂ω/∂x
            J[:, :, :n] = dp @ Jm[:, :3] + dw @ Jm[:, 3:6]
            if k:
                J[:, :, col : col + k] = dth
            J[:, :, cols] = dphi
        return raw, J

    def group_block(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The groups' own residuals (d, 1) [m] and their Jacobian (d, 1, len(x))."""
        raws, rows = [], []
        for _, terms, first in self.groups:
            if terms.sigma is None:
                continue
            s = len(terms.names)
            r, D = terms.residuals(np.asarray(x, dtype=float)[first : first + s])
            J = np.zeros((r.size, len(x)))
            J[:, first : first + s] = D
            raws.append(r)
            rows.append(J)
        return np.concatenate(raws)[:, None], np.vstack(rows)[:, None, :]


def _check_shapes(d: Artefact, arrays: tuple[np.ndarray, ...], head: tuple[int, int],
                  widths: tuple[int, ...]) -> None:  # fmt: skip
    """Refuse residuals of a kind that are not (m, dim) with derivatives (m, dim, ·).

    Raises:
        MeasurementError: naming the kind, the item and the shapes expected and got.
    """
    names = ("r", "∂r/∂p", "∂r/∂ω", "∂r/∂θ", "∂r/∂φ")
    wanted = [head, *((*head, w) for w in widths)]
    for name, a, want in zip(names, arrays, wanted, strict=True):
        if np.shape(a) != tuple(want):
            raise MeasurementError(
                f"artefact kind {d.kind!r}: residuals() returned {name} of shape "
                f"{np.shape(a)}, expected {tuple(want)} (m poses × dim {d.dim} × columns)"
            )
