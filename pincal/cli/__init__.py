"""The ``pincal`` command: one group, one module per subcommand.

Exit codes: 0 success; 1 a pincal error (bad input, unreachable pose, …) reported
as one line on stderr; 2 wrong command-line usage. ``--debug`` shows tracebacks.
A new subcommand is a module ``pincal/cli/<cmd>.py`` exposing a click command
decorated with :func:`pincal.cli.common.fail_cleanly`, registered below.
"""

from __future__ import annotations

import json
import logging
import sys

import click


class _Group(click.Group):
    """The pincal group: a usage error of a subcommand given ``--json`` is JSON too."""

    def invoke(self, ctx: click.Context) -> object:
        args = [*getattr(ctx, "_protected_args", []), *ctx.args]
        try:
            return super().invoke(ctx)
        except click.ClickException as exc:
            if "--json" not in args[1:] or (ctx.obj or {}).get("debug"):
                raise
            message = " ".join(exc.format_message().split())
            click.echo(json.dumps({"error": {"type": type(exc).__name__, "message": message}}))
            sys.exit(exc.exit_code)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--debug", is_flag=True, help="Show tracebacks and debug logging.")
@click.pass_context
def main(ctx: click.Context, debug: bool) -> None:
    """Kinematic calibration of parallel machines and serial chains.

    MODEL arguments are a bundled model name ({models}), a model directory, a .urdf
    file (with its sidecar .yaml beside it) or an MJCF .xml file. Units inside are SI
    (m, rad); printed errors are in mm / mrad; every CSV states its units in its header.

    A campaign: poses → simulate (or measure) → calibrate → view → compensate →
    validate → report. `calibrate` writes one calibration directory (calibration.json,
    calibrated.urdf + calibrated.yaml, identification.json) that view --calibrated,
    compensate, validate and report read as it is.

    \b
    Examples:
      pincal demo                              full simulated Stewart calibration
      pincal info stewart_6ups                 joints, closures, presets, identifiability
      pincal poses hexaslide_6pus --count 40 --candidates random:300 --out poses.csv
      pincal simulate hexaslide_6pus --poses poses.csv --out m.csv
      pincal calibrate hexaslide_6pus --data m.csv --out cal/
      pincal view hexaslide_6pus --poses poses.csv --calibrated cal/ --html errors.html
      pincal compensate cal/ --targets poses.csv --out commands.csv
      pincal validate cal/ --data held_out.csv  errors on data not used for fitting
      pincal report cal/                       HTML + Markdown report of a calibration
      pincal export cal/ --format generic-table --out machine.yaml   controller parameters
      pincal --debug info my_robot.urdf        full traceback on errors

    \b
    Exit codes:
      0  success
      1  error in the input or the computation (one line on stderr)
      2  wrong command-line usage (unknown option, missing argument)
    """
    from threadpoolctl import threadpool_limits

    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug
    # a library warning reads like pincal's other warning lines; --debug names the logger
    fmt = "%(levelname)s:%(name)s:%(message)s" if debug else "pincal: warning: %(message)s"
    logging.basicConfig(level=logging.DEBUG if debug else logging.WARNING, format=fmt)
    # pincal's dense solves are small (≤ a few thousand rows × ~100 columns): one BLAS
    # thread is fastest, and threaded BLAS on a busy machine was 12–48× slower.
    ctx.with_resource(threadpool_limits(1))


from pincal.cli import acceptance as _acceptance  # noqa: E402
from pincal.cli import calibrate as _calibrate  # noqa: E402
from pincal.cli import compensate as _compensate  # noqa: E402
from pincal.cli import demo as _demo  # noqa: E402
from pincal.cli import export as _export  # noqa: E402
from pincal.cli import fleet as _fleet  # noqa: E402
from pincal.cli import import_cmd as _import_cmd  # noqa: E402
from pincal.cli import import_sockets as _import_sockets  # noqa: E402
from pincal.cli import info as _info  # noqa: E402
from pincal.cli import poses as _poses  # noqa: E402
from pincal.cli import report as _report  # noqa: E402
from pincal.cli import run as _run  # noqa: E402
from pincal.cli import select_model as _select_model  # noqa: E402
from pincal.cli import simulate as _simulate  # noqa: E402
from pincal.cli import validate as _validate  # noqa: E402
from pincal.cli import view as _view  # noqa: E402
from pincal.model import bundled_models as _bundled_models  # noqa: E402

main.help = (main.help or "").replace("{models}", ", ".join(_bundled_models()))

for _command in (
    _demo.demo,
    _info.info,
    _poses.poses,
    _simulate.simulate,
    _calibrate.calibrate,
    _compensate.compensate,
    _validate.validate,
    _view.view,
    _report.report,
    _export.export,
    _import_cmd.import_tracker,
    _import_sockets.import_sockets,
    _run.run,
    _acceptance.acceptance,
    _select_model.select_model_cmd,
    _fleet.fleet,
):
    main.add_command(_command)

if __name__ == "__main__":  # pragma: no cover
    main()
