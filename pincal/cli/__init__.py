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
      pincal simulate hexaslide_6pus --random 30 --out m.csv
      pincal calibrate hexaslide_6pus --data m.csv --out cal/
      pincal compensate cal/ --targets poses.csv --out commands.csv
    """
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug
    logging.basicConfig(level=logging.DEBUG if debug else logging.WARNING)


from pincal.cli import calibrate as _calibrate  # noqa: E402
from pincal.cli import compensate as _compensate  # noqa: E402
from pincal.cli import demo as _demo  # noqa: E402
from pincal.cli import info as _info  # noqa: E402
from pincal.cli import simulate as _simulate  # noqa: E402

main.add_command(_demo.demo)
main.add_command(_info.info)
main.add_command(_calibrate.calibrate)
main.add_command(_compensate.compensate)
main.add_command(_simulate.simulate)

if __name__ == "__main__":  # pragma: no cover
    main()
