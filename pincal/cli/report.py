"""`pincal report`: the HTML + Markdown + JSON report of a calibration output directory."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pincal.cli._paths import guard_paths
from pincal.cli.common import announce, fail_cleanly
from pincal.errors import PincalError


@click.command()
@click.argument("directory", type=click.Path(path_type=Path))
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Where to write the report (default: DIRECTORY).",
)
@click.option("--name", default="report", show_default=True, help="Report file stem.")
@click.option(
    "--validation",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="JSON of `pincal validate --out`: adds the Validation and Cross-validation sections.",
)
@click.option(
    "--truth",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="<data>.truth.json of `pincal simulate`: true values beside the identified ones.",
)
@click.option(
    "--design",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="<poses>.json of `pincal poses`: the index history of the pose selection.",
)
@click.option("--json", "as_json", is_flag=True, help="Print the written paths as JSON.")
@fail_cleanly
def report(
    directory: Path,
    out: Path | None,
    name: str,
    validation: Path | None,
    truth: Path | None,
    design: Path | None,
    as_json: bool,
) -> None:
    """Assemble the plots and numbers of a calibration in DIRECTORY into one report.

    Reads DIRECTORY/identification.json (written by `pincal demo` and
    `pincal calibrate`) and writes NAME.html (self-contained, plots embedded),
    NAME.md and NAME.json with the same numbers (lengths in µm, angles in µrad,
    uncertainties 2σ): data and noise (declared or estimated), residuals before
    and after, outliers and down-weighted poses, parameters with 2σ (poorly
    determined ones flagged) and their correlations, Cramér–Rao prediction vs
    achievement, validation and convergence when the JSON holds them. Position and
    orientation are reported apart, each over its measured components (named).
    --validation, --truth and --design add what a campaign's other steps wrote
    (`pincal run` passes them), so its report has the sections of `pincal demo`'s.

    \b
    Examples:
      pincal demo --out pincal-out && pincal report pincal-out
      pincal report pincal-out --out /tmp/report --json
    """
    from pincal.cli._progress import counted
    from pincal.report import calibration_report, campaign_notes

    if not name or "/" in name or "\\" in name or name.startswith("."):
        raise click.BadParameter("must be a plain file stem", param_hint="--name")
    target = out or directory
    guard_paths(
        {**_inputs(directory), "--validation": validation, "--truth": truth, "--design": design},
        {f"--name's {x}": target / f"{name}.{x}" for x in ("html", "md", "json")},
    )
    notes = campaign_notes(validation, truth, design)
    with counted("plots", unit="plot") as step:
        files = calibration_report(directory, out, name=name, notes=notes, progress=step)
    if as_json:
        paths = {"html": str(files.html), "markdown": str(files.markdown)}
        click.echo(json.dumps({**paths, "json": str(files.json)}))
    else:
        click.echo(f"wrote {files.html}, {files.markdown} and {files.json}")


def _inputs(directory: Path) -> dict[str, Path]:
    """The files of calibration DIRECTORY that the report must not overwrite."""
    from pincal.io import (
        CALIBRATED_SIDECAR,
        CALIBRATED_URDF,
        IDENTIFICATION_FILE,
        MANIFEST,
        read_calibration,
    )

    names = {MANIFEST, IDENTIFICATION_FILE, CALIBRATED_URDF, CALIBRATED_SIDECAR}
    try:
        cal = read_calibration(directory, verify=False)
    except PincalError:
        pass  # the report names the problem
    else:
        announce(cal)
        names |= set(cal.manifest.get("files") or {}) | {cal.calibrated_urdf.name}
    return {f"DIRECTORY's {n}": directory / n for n in sorted(names) if (directory / n).exists()}
