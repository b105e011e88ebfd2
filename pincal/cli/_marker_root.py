"""``--root LINK`` of ``pincal calibrate``: a marker chain that starts at another link.

A humanoid standing on one sole, a mobile manipulator whose torso is fixed to the
instrument, a chain measured from a hand back to the body: the tree is re-rooted at
LINK (:func:`pincal.model.reroot_urdf`) and the joints between LINK and ``--link`` are
the calibrated chain (:attr:`pincal.measure.MarkerSetup.root`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import TYPE_CHECKING, TypeVar, overload

import click

if TYPE_CHECKING:  # imported in the calls: the CLI starts without the model stack
    from pincal.measure import MarkerSetup

_F = TypeVar("_F", bound=Callable[..., object])

__all__ = ["root_option", "with_root"]


def root_option(f: _F) -> _F:
    """The ``--root`` option (a marker table's chain starts at LINK)."""
    return click.option(
        "--root", "root", default=None, metavar="LINK",
        help="With --link: the link the measured chain starts from, fixed to the instrument "
        "(a humanoid's sole, a torso), if not the URDF's root; the joints between it and "
        "--link are calibrated, every other joint locked.",
    )(f)  # fmt: skip


@overload
def with_root(setup: MarkerSetup, root: str | None, link: str | None) -> MarkerSetup: ...


@overload
def with_root(setup: None, root: str | None, link: str | None) -> None: ...


def with_root(setup: MarkerSetup | None, root: str | None, link: str | None) -> MarkerSetup | None:
    """``setup`` (a :class:`pincal.measure.MarkerSetup`) starting at ``root``.

    Raises:
        click.BadParameter: ``--root`` without ``--link``, or equal to it.
    """
    if root is None:
        return setup
    if link is None:
        raise click.BadParameter("--root applies to marker tables (--link)", param_hint="--root")
    if root == link:
        raise click.BadParameter(f"--root {root!r} is the measured --link itself: the chain "
                                 "between them is empty", param_hint="--root")  # fmt: skip
    assert setup is not None  # None only checks the options (no --link)
    return dataclasses.replace(setup, root=root)
