"""A planar five-bar linkage closed by a ``6d`` (weld) closure: an over-constrained loop.

Two actuated revolutes about z at (∓0.1, 0, 0) drive proximal links (0.2 m) and
distal links (0.25 m); the left distal link carries a revolute ``tip_joint`` whose
child frame ``tip_a`` is welded to the end ``tip_b`` of the right distal link. All
five joint axes are parallel (z), so the weld's closure Jacobian has 6 rows of rank
3 over the passive joints: the out-of-plane rows can never be changed by them. The
measured frame ``effector`` sits on the left distal link; x, y and rz are measured.
Lengths in m, angles in rad.
"""

from __future__ import annotations

_INERTIAL = (
    '<inertial><mass value="0.1"/><origin xyz="0 0 0"/>'
    '<inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial>'
)


def _link(name: str) -> str:
    return f'  <link name="{name}">{_INERTIAL}</link>\n'


def _joint(name: str, kind: str, parent: str, child: str, xyz: str, lim: float = 3.1) -> str:
    body = (
        f'  <joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="0 0 0"/>'
    )
    if kind == "revolute":
        body += f'<axis xyz="0 0 1"/><limit lower="{-lim}" upper="{lim}" effort="1" velocity="1"/>'
    return body + "</joint>\n"


FIVE_BAR_URDF = (
    '<?xml version="1.0"?>\n<robot name="five_bar">\n'
    + _link("base")
    + _joint("act_a", "revolute", "base", "la1", "-0.1 0 0")
    + _link("la1")
    + _joint("pas_a", "revolute", "la1", "la2", "0.2 0 0")
    + _link("la2")
    + _joint("tip_joint", "revolute", "la2", "tip_a", "0.25 0 0")
    + _link("tip_a")
    + _joint("effector_joint", "fixed", "la2", "effector", "0.25 0.03 0")
    + _link("effector")
    + _joint("act_b", "revolute", "base", "lb1", "0.1 0 0")
    + _link("lb1")
    + _joint("pas_b", "revolute", "lb1", "lb2", "0.2 0 0")
    + _link("lb2")
    + _joint("tip_b_joint", "fixed", "lb2", "tip_b", "0.25 0 0")
    + _link("tip_b")
    + "</robot>\n"
)

FIVE_BAR_SIDECAR: dict = {
    "closed_loop": [["tip_a", "tip_b"]],
    "type": ["6d"],
    "name_mot": ["act_a", "act_b"],
    "measured_frame": "effector",
    "measured": ["x", "y", "rz"],
    # the tip at (0, 0.3), elbows out
    "home": {
        "act_a": 2.160380669573563,
        "pas_a": -1.5957989316942576,
        "act_b": 0.9812119840162302,
        "pas_b": 1.595798931694258,
        "tip_joint": 2.012429177831183,
    },
    "workspace": {"joints": {"act_a": [2.0, 2.3], "act_b": [0.85, 1.1]}},
}
