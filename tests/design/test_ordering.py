"""Measurement order: a short joint-space tour through the designed poses."""

from __future__ import annotations

import itertools

import numpy as np

from pincal.design import travel_order


def _length(q: np.ndarray, home: np.ndarray, order) -> float:
    path = np.vstack([home, q[list(order)]])
    return float(np.abs(np.diff(path, axis=0)).max(axis=1).sum())


def test_poses_on_a_line_are_visited_in_order():
    rng = np.random.default_rng(0)
    x = rng.permutation(np.linspace(0.1, 2.0, 12))
    q = np.column_stack([x, 0.5 * x])
    tour = travel_order(q, np.zeros(2))
    assert np.all(np.diff(x[tour.order]) > 0)
    assert tour.after == _length(q, np.zeros(2), tour.order) < tour.before


def test_small_cases_match_the_best_tour_and_speeds_count():
    rng = np.random.default_rng(1)
    worse = 0
    for _ in range(20):
        q = rng.uniform(-1, 1, (6, 3))
        tour = travel_order(q, np.zeros(3))
        best = min(_length(q, np.zeros(3), p) for p in itertools.permutations(range(6)))
        assert sorted(tour.order) == list(range(6))
        assert tour.after >= best - 1e-12
        worse += tour.after > best * 1.10
    assert worse <= 2  # a heuristic: within 10 % of the optimum in most cases
    q = np.array([[1.0, 0.0], [0.0, 0.05]])
    slow_second = travel_order(q, np.zeros(2), speeds=[1.0, 0.01])  # joint 2 is slow
    assert slow_second.order.tolist() == [0, 1]
