"""`pincal fleet`: simulate a production fleet, calibrate every unit, flag the odd ones.

The subcommands: :mod:`pincal.cli.fleet_simulate` and :mod:`pincal.cli.fleet_run`.
"""

from __future__ import annotations

import click

from pincal.cli.fleet_run import run
from pincal.cli.fleet_simulate import simulate


@click.group()
def fleet() -> None:
    """Fleets of units of one model: simulate one, calibrate every unit, compare them.

    Both subcommands take --json: a JSON summary on stdout instead of the text lines.

    \b
    Examples:
      pincal fleet simulate stewart_6ups --units 200 --seed 1 --out fleet/
      pincal fleet run fleet/FLEET.yaml --out fleet-report/ --jobs 2
      pincal fleet run fleet/FLEET.yaml --out fleet-report/ --scheduler local:2
    """


fleet.add_command(simulate)
fleet.add_command(run)
