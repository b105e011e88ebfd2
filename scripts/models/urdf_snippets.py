"""URDF text snippets shared by the model generator scripts (build_*.py)."""

from __future__ import annotations

#: a small placeholder inertia: the models are kinematic, but some URDF tools want one
INERTIAL = (
    '<inertial><mass value="0.1"/>'
    '<inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial>'
)


def sphere_visual(radius: float, colour: str) -> str:
    """A sphere of ``radius`` [m] at the link origin, in a named material."""
    return (
        f'<visual><geometry><sphere radius="{radius}"/></geometry>'
        f'<material name="{colour}"/></visual>'
    )
