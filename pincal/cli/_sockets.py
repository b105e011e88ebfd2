"""``pincal simulate --instrument socket``: a ball seated in two sockets 50 mm apart."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from pincal.model import Mechanism

__all__ = ["SOCKET_SPACING", "simulate_socket_file"]

#: the known distance between the two simulated sockets [m]
SOCKET_SPACING = 0.05


def default_sockets(mech: Mechanism) -> dict[str, np.ndarray]:
    """Two socket centres [m], 50 mm apart, inside the reach of ``mech``.

    Socket A lies at 60 % of the home tool point's horizontal reach (its height kept),
    B 50 mm from A, horizontal and across the reach.
    """
    p = mech.frame_placement(mech.q_home).translation
    a = np.array([0.6 * p[0], 0.6 * p[1], p[2]])
    across = np.array([-p[1], p[0], 0.0])
    norm = float(np.linalg.norm(across))
    across = across / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])
    return {"A": a, "B": a + SOCKET_SPACING * across}


def simulate_socket_file(
    nominal: Mechanism, actual: Mechanism, n_poses: int, std: float, rng: np.random.Generator,
    out: str, length_unit: str,
) -> tuple[Path, int, dict[str, float]]:  # fmt: skip
    """Write a socket file of ``actual`` seating its ball in two sockets, half the poses each.

    The file declares the sockets' known distance (50 mm, 1σ = ``std``).

    Returns:
        (written path, number of poses, true socket centres ``"plate.A_x"`` … [m]).
    """
    from pincal.io import write_socket_data
    from pincal.measure import KnownDistance, SocketPlate, simulate_sockets

    centres = default_sockets(nominal)
    plate = SocketPlate("plate", std, (KnownDistance("A", "B", SOCKET_SPACING, std),))
    per = max(n_poses // 2, 1)
    click.echo(f"… seating the ball {per} times in each of 2 sockets 50 mm apart", err=True)
    data = simulate_sockets(actual, plate, centres, per, rng)
    path = write_socket_data(out, data, length_unit=length_unit)
    truth = {f"plate.{s}_{a}": float(c[i]) for s, c in centres.items() for i, a in enumerate("xyz")}
    return path, len(data), truth
