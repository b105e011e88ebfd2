"""The ``pincal`` command: one group, one module per subcommand.

Exit codes: 0 success; 1 a pincal error (bad input, unreachable pose, …) reported
as one line on stderr; 2 wrong command-line usage. ``--debug`` shows tracebacks.
"""

from __future__ import annotations

import logging

import click


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--debug", is_flag=True, help="Show tracebacks and debug logging.")
@click.pass_context
def main(ctx: click.Context, debug: bool) -> None:
    """Kinematic calibration of parallel machines and serial chains.

    \b
    Examples:
      pincal demo                      full simulated Stewart calibration
      pincal info stewart_6ups         joints, closures, presets, identifiability
      pincal poses stewart_6ups --count 18 --index O1 --candidates grid:4 --out poses.csv
    """
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug
    logging.basicConfig(level=logging.DEBUG if debug else logging.WARNING)


from pincal.cli import demo as _demo  # noqa: E402
from pincal.cli import info as _info  # noqa: E402
from pincal.cli import poses as _poses  # noqa: E402

main.add_command(_demo.demo)
main.add_command(_info.info)
main.add_command(_poses.poses)

if __name__ == "__main__":  # pragma: no cover
    main()
