"""The ``pincal`` command: one group, one module per subcommand.

Exit codes: 0 success; 1 a pincal error (bad input, unreachable pose, …) reported
as one line on stderr; 2 wrong command-line usage. ``--debug`` shows tracebacks.
A new subcommand is a module ``pincal/cli/<cmd>.py`` exposing a click command
decorated with :func:`pincal.cli.common.fail_cleanly`, registered below.
"""

from __future__ import annotations

import logging

import click


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--debug", is_flag=True, help="Show tracebacks and debug logging.")
@click.pass_context
def main(ctx: click.Context, debug: bool) -> None:
    """Kinematic calibration of parallel machines and serial chains.

    MODEL arguments are a bundled model name (stewart_6ups, hexaslide_6pus, pkm5,
    wedge3), a model directory or a .urdf file (with its sidecar .yaml beside it).
    Units inside are SI (m, rad); printed errors are in mm / mrad.

    \b
    Examples:
      pincal demo                              full simulated Stewart calibration
      pincal info stewart_6ups                 joints, closures, presets, identifiability
      pincal poses stewart_6ups --count 18 --index O1 --candidates grid:4 --out poses.csv
      pincal simulate hexaslide_6pus --random 30 --out m.csv
      pincal calibrate hexaslide_6pus --data m.csv --out cal/
      pincal compensate cal/ --targets targets.csv --out commands.csv
      pincal view stewart_6ups --html v.html   offline 3-D view of random poses
      pincal view stewart_6ups --calibrated pincal-out --html errors.html
      pincal report pincal-out                 HTML + Markdown report of a calibration
      pincal --debug info my_robot.urdf        full traceback on errors

    \b
    Exit codes:
      0  success
      1  error in the input or the computation (one line on stderr)
      2  wrong command-line usage (unknown option, missing argument)
    """
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug
    logging.basicConfig(level=logging.DEBUG if debug else logging.WARNING)


from pincal.cli import acceptance as _acceptance  # noqa: E402
from pincal.cli import calibrate as _calibrate  # noqa: E402
from pincal.cli import compensate as _compensate  # noqa: E402
from pincal.cli import demo as _demo  # noqa: E402
from pincal.cli import info as _info  # noqa: E402
from pincal.cli import poses as _poses  # noqa: E402
from pincal.cli import report as _report  # noqa: E402
from pincal.cli import simulate as _simulate  # noqa: E402
from pincal.cli import view as _view  # noqa: E402

for _command in (
    _demo.demo,
    _info.info,
    _poses.poses,
    _simulate.simulate,
    _calibrate.calibrate,
    _compensate.compensate,
    _view.view,
    _report.report,
    _acceptance.acceptance,
):
    main.add_command(_command)

if __name__ == "__main__":  # pragma: no cover
    main()
