"""The reach of a mechanism.

Where a mechanism can go: joint ranges and pose sampling of the declared
workspace, the floor a pose must stay above, range exploration and the search for a
well-conditioned home.
"""

from __future__ import annotations

from pincal.model.reach._floor import DEFAULT_FLOOR, above_floor
from pincal.model.reach._home_search import by_name_defaults, conditioning, regular_home
from pincal.model.reach._workspace import joint_ranges, sample_actuators, sample_pose

__all__ = [
    "DEFAULT_FLOOR",
    "above_floor",
    "by_name_defaults",
    "conditioning",
    "joint_ranges",
    "regular_home",
    "sample_actuators",
    "sample_pose",
]
