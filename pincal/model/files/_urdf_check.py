"""Checks of an untrusted URDF before Pinocchio parses it: size limits and attribute values.

Pinocchio's URDF parser (urdfdom) reports a malformed file only on the process's
standard error and then fails with "does not contain a valid URDF model"; a very deep
chain overflows its recursion (the interpreter dies), and ``createData`` allocates
four nv × nv × nv tensors (second-order derivatives: 6.9 GB at nv = 600). So every URDF
is checked here first, in pure Python, naming the element and attribute at fault:

* size limits (:class:`pincal.model.Limits`, the ones in force by default): links,
  degrees of freedom and tree depth (on the command line ``PINCAL_MAX_LINKS``,
  ``PINCAL_MAX_DOF``, ``PINCAL_MAX_TREE_DEPTH``);
* the attributes urdfdom requires (robot/link/joint names, joint type, parent/child,
  ``<limit>`` of revolute and prismatic joints with ``effort`` and ``velocity``, the
  ``joint`` of ``<mimic>``) and the numbers of origins, axes, limits, dynamics and
  calibration: finite, joint origins within ±:data:`MAX_COORDINATE`, limits within
  ±:data:`MAX_LIMIT` with ``lower <= upper``.

:func:`captured_stderr` runs a Pinocchio call with the process's file descriptor 2
redirected, so what urdfdom prints can go into the error message (clipped) or the log.
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import tempfile
import threading
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterator
from typing import TypeVar

from pincal.errors import ModelFileError, clip

__all__ = [
    "JOINT_TYPES",
    "MAX_COORDINATE",
    "MAX_LIMIT",
    "captured_stderr",
    "check_joint_element",
    "check_robot_element",
]

#: URDF joint types and their degrees of freedom (velocity dimension)
JOINT_TYPES = {
    "revolute": 1,
    "continuous": 1,
    "prismatic": 1,
    "fixed": 0,
    "floating": 6,
    "planar": 3,
}
#: largest accepted joint origin coordinate [m] or angle [rad]
MAX_COORDINATE = 1e6
#: largest accepted joint limit magnitude [m or rad]; Gazebo models write ±1e16 for "none"
MAX_LIMIT = 1e16

_FLOAT_MAX = sys.float_info.max

T = TypeVar("T")


def _name(e: ET.Element, what: str) -> str:
    name = e.get("name")
    if not name:
        raise ModelFileError(f"URDF <{what}> without a name attribute; every {what} needs one")
    return name


def check_robot_element(root: ET.Element) -> None:
    """Check the ``<robot>`` root element and its name.

    Raises:
        ModelFileError: the root is not ``<robot>`` or has no name.
    """
    if root.tag != "robot":
        raise ModelFileError(f"URDF root element is <{clip(root.tag)}>, expected <robot>")
    if not root.get("name"):
        raise ModelFileError('URDF <robot> has no name attribute; give one: <robot name="...">')


def _numbers(
    e: ET.Element | None, attr: str, n: int, where: str, bound: float
) -> list[float] | None:
    """The ``n`` numbers of attribute ``attr`` of ``e`` (None when absent), checked finite."""
    if e is None or e.get(attr) is None:
        return None
    text = str(e.get(attr))
    try:
        values = [float(s) for s in text.split()]
    except ValueError:
        raise ModelFileError(
            f"{where} <{e.tag} {attr}>: cannot read {n} number{'s' if n > 1 else ''} "
            f"from '{clip(text)}'"
        ) from None
    if len(values) != n:
        raise ModelFileError(
            f"{where} <{e.tag} {attr}>: expected {n} numbers, got {len(values)} in '{clip(text)}'"
        )
    if not all(math.isfinite(v) and abs(v) <= bound for v in values):
        raise ModelFileError(
            f"{where} <{e.tag} {attr}>: '{clip(text)}' must hold finite numbers within "
            f"±{bound:g} (SI units: m, rad)"
        )
    return values


def _scalar(
    e: ET.Element, attr: str, where: str, bound: float = math.inf, required: bool = False
) -> float | None:
    if e.get(attr) is None:
        if required:
            raise ModelFileError(
                f'{where} <{e.tag}> has no {attr} attribute; urdfdom requires it (e.g. {attr}="1")'
            )
        return None
    values = _numbers(e, attr, 1, where, min(bound, _FLOAT_MAX))
    return None if values is None else float(values[0])


def check_joint_element(e: ET.Element) -> tuple[str, str, str, str]:
    """Check one ``<joint>`` the way urdfdom reads it, naming the attribute at fault.

    Returns:
        (name, type, parent link, child link).

    Raises:
        ModelFileError: a missing or unreadable attribute, an absurd origin, limits that
            are not finite, beyond ±:data:`MAX_LIMIT` or inverted (lower > upper).
    """
    name = _name(e, "joint")
    where = f"URDF joint '{clip(name)}'"
    jtype = e.get("type")
    if jtype not in JOINT_TYPES:
        raise ModelFileError(
            f"{where} has type {clip(jtype)!r}; valid types are {', '.join(JOINT_TYPES)}"
        )
    ends = []
    for tag in ("parent", "child"):
        sub = e.find(tag)
        link = sub.get("link") if sub is not None else None
        if not link:
            raise ModelFileError(f'{where} lacks <{tag} link="..."/>')
        ends.append(link)
    origin = e.find("origin")
    _numbers(origin, "xyz", 3, where, MAX_COORDINATE)
    _numbers(origin, "rpy", 3, where, MAX_COORDINATE)
    _numbers(e.find("axis"), "xyz", 3, where, _FLOAT_MAX)  # normalised: any finite size
    _check_limit(e, jtype, where)
    for tag, attrs in (
        ("dynamics", ("damping", "friction")),
        ("calibration", ("rising", "falling", "reference_position")),
        ("safety_controller", ("soft_lower_limit", "soft_upper_limit", "k_position")),
    ):
        sub = e.find(tag)
        if sub is not None:
            for attr in attrs:
                _scalar(sub, attr, where)
            if tag == "safety_controller":
                _scalar(sub, "k_velocity", where, required=True)
    mimic = e.find("mimic")
    if mimic is not None:
        if not mimic.get("joint"):
            raise ModelFileError(f'{where} <mimic> has no joint attribute (<mimic joint="..."/>)')
        _scalar(mimic, "multiplier", where)
        _scalar(mimic, "offset", where)
    return name, jtype, ends[0], ends[1]


def _check_limit(e: ET.Element, jtype: str, where: str) -> None:
    limit = e.find("limit")
    if limit is None:
        if jtype in ("revolute", "prismatic"):
            raise ModelFileError(
                f"{where} is {jtype} but has no <limit>; add "
                '<limit lower="..." upper="..." effort="..." velocity="..."/> (SI units)'
            )
        return
    bounded = jtype in ("revolute", "prismatic")
    bound = MAX_LIMIT if bounded else math.inf
    lower = _scalar(limit, "lower", where, bound)
    upper = _scalar(limit, "upper", where, bound)
    _scalar(limit, "effort", where, required=True)
    _scalar(limit, "velocity", where, required=True)
    lo = 0.0 if lower is None else lower
    hi = 0.0 if upper is None else upper
    if bounded and lo > hi:
        raise ModelFileError(
            f"{where} <limit>: lower {lo:.6g} > upper {hi:.6g}; the range must "
            f"have lower <= upper (equal values, or none, mean no range)"
        )


_STDERR_LOCK = threading.Lock()


def captured_stderr(call: Callable[[], T]) -> tuple[T | None, str, BaseException | None]:
    """Run ``call`` with file descriptor 2 redirected to a temporary file.

    urdfdom and hpp-fcl print their diagnostics to the process's standard error (not
    Python's ``sys.stderr``); this collects them for the message or the log. The
    redirection is process-wide, so calls are serialised by a lock.

    Returns:
        (result or None, captured text, exception raised by ``call`` or None).
    """
    with _STDERR_LOCK, tempfile.TemporaryFile() as tmp:
        with _fd2_to(tmp.fileno()):
            try:
                result: T | None = call()
                error: BaseException | None = None
            except Exception as exc:  # handed back to the caller
                result, error = None, exc
        tmp.seek(0)
        text = tmp.read(1 << 16).decode("utf-8", "replace")
    return result, text, error


def _flush_c_stderr() -> None:
    with contextlib.suppress(Exception):
        import ctypes

        ctypes.CDLL(None).fflush(None)


@contextlib.contextmanager
def _fd2_to(fd: int) -> Iterator[None]:
    saved = os.dup(2)
    try:
        os.dup2(fd, 2)
        yield
    finally:
        _flush_c_stderr()
        os.dup2(saved, 2)
        os.close(saved)
