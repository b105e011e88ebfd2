"""Print a pip constraints file pinning every dependency of pyproject.toml to its lower bound.

Used by .ci/run's "oldest" lane: ``pip install -c <(python .ci/lower_bounds.py) -e ".[test]"``
installs the oldest versions the declared ranges allow, so both ends of each range are tested.
A requirement without a lower bound is left free (and named on stderr).
"""

import re
import sys
import tomllib
from pathlib import Path

project = tomllib.loads(Path(__file__).parents[1].joinpath("pyproject.toml").read_text())["project"]
requirements = list(project["dependencies"]) + list(project["optional-dependencies"]["test"])
for req in requirements:
    match = re.fullmatch(r"\s*([A-Za-z0-9_.\-]+)\s*>=\s*([0-9][^,;\s]*)\s*", req)
    if match:
        print(f"{match[1]}=={match[2]}")
    else:
        print(f"lower_bounds: no single lower bound in {req!r}; left free", file=sys.stderr)
