"""The campaign file of ``pincal run``: a typed, frozen, validated description.

Read with :func:`load_campaign`; every key is checked before any work starts. An
unknown key is an error that suggests the nearest valid one; a wrong type or value
names the key path (``measurements.noise``). Relative paths in the file are
relative to the file's directory. See :data:`KEYS_HELP` (shown by ``pincal run
--help``) and ``docs/examples/campaign.yaml``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pincal._yaml import shown
from pincal.cli._campaign_schema import build, choice
from pincal.cli._campaign_sockets import SOCKETS_HELP, Sockets, plain_socket_section
from pincal.errors import CampaignError, PincalError, clip
from pincal.measure import DEFAULT_NOISE

__all__ = ["KEYS_HELP", "Campaign", "load_campaign"]

INDICES = ("O1", "O2", "O3", "O4", "O5", "A")
DESIGN_METHODS = ("exchange", "detmax", "greedy")
SOURCES = ("simulated", "file")
VALIDATION_SOURCES = ("simulated", "file", "none")

KEYS_HELP = """\
\b
Campaign file keys (YAML; relative paths are relative to the file):
  model: NAME|DIR|URDF|YAML  required; the nominal model (YAML: a sidecar with robot: NAME)
  preset: NAME               parameter preset (default: the model's first)
  out: DIR                   output directory (default: campaign-out; --out overrides)
  design:                    optional pose design (pincal poses)
    count: 18                poses to select
    index: O1                O1 O2 O3 O4 O5 A
    candidates: auto         auto | grid:LEVELS | random:COUNT | oa:LEVELS
    method: exchange         exchange | detmax | greedy
    seed: 0
  measurements:
    source: simulated        simulated | file
    file: PATH               source file: a pincal measurement file (pose or targets)
    poses: 30                simulated without a design: random workspace poses
    errors_seed: 0           simulated "actual" machine: seed of its geometric errors
    error_size: [1, 10]      uniform error bounds [mm, mrad]
    noise: [0.01, 0.02]      measurement noise 1 sigma [mm, mrad] (pincal's default)
    seed: 1                  seed of the poses and the noise
  markers:                   optional: measurements.file is a marker table (motion
                             capture, tracker) in an unknown instrument frame
    link: LINK               required; the measured link carrying the marker
    columns: [x, y, z]       the marker's position columns (e.g. [x1, y1, z1])
    more_columns: []         further markers on LINK, fitted together (an unknown
                             offset each), e.g. [[x2, y2, z2]]; copies are used once
    more_links: []           the link of each further marker when not LINK (two arms:
                             [arm_right_7_link]): the chains are calibrated together
    root: null               the link the chains start from (a humanoid's sole), if
                             not the URDF's root
    length_unit: m           m | mm | um (marker columns)
    orientation_columns: []  a 6-D marker body's orientation columns, e.g.
                             [roll, pitch, yaw]: its pose on LINK is fitted
    orientation: null        their convention: rpy-deg | rpy-rad (R = Rz(yaw)·Ry(pitch)·
                             Rx(roll)) | xyz-deg | xyz-rad | rotvec-deg | rotvec-rad |
                             quat-wxyz | quat-xyzw
    instrument_frame: unknown  unknown (registered, then identified) | known
    marker: unknown          unknown, or [x, y, z] in LINK's frame [mm]
    marker_std: null         1σ of a given marker [mm] (none: held)
    lock: {}                 {JOINT: VALUE} [rad, m]: joints on the chain without a
                             column (off the chain: locked at 0). Columns named otherwise,
                             degrees, a reference pose: a sidecar as model (docs/examples)
{sockets}  identification:
    method: gauss-newton     gauss-newton | lm | qpso | qpso-stepwise | step-planned
    model: geometric         geometric[+compliance][+gain][+harmonics][+temperature]
                             [+strut-compliance] (terms)
    loss: null               linear | huber | soft_l1 | cauchy; marker campaigns also auto
                             (their default: huber when the outlier test names poses)
    prior: null              marker campaigns: auto (default: σ by CV) | none |
                             "LEN_MM,ANG_MRAD"
    instrument: NAME         optional profile judging an estimated noise: laser-tracker |
                             motion-capture | ballbar | touch-probe | cmm
    bootstrap: 0             N > 0: N parametric-bootstrap refits, their σ reported beside
                             the linear σ (never written as the covariance)
  validation:                held-out poses, measured on the same actual machine
    source: simulated        simulated | file | none
    file: PATH               source file: a pincal measurement file
    poses: 20                simulated: random workspace poses
    seed: 2
    cv: null                 K: K-fold cross-validation of the fit (pincal validate --cv)
    cv_seed: 0               seed of the folds
  report: true               write report.html / report.md into the output directory
""".replace("{sockets}", SOCKETS_HELP)


@dataclass(frozen=True)
class Design:
    """Pose design (``pincal poses``)."""

    count: int = 18
    index: str = "O1"
    candidates: str = "auto"
    method: str = "exchange"
    seed: int = 0

    def check(self, key: str) -> None:
        """Raise CampaignError naming ``key.field`` for the first invalid entry of this section."""
        choice(self.index, INDICES, f"{key}.index")
        choice(self.method, DESIGN_METHODS, f"{key}.method")
        if self.count < 1:
            raise CampaignError(f"{key}.count must be ≥ 1, got {clip(self.count)}")
        from pincal.design import parse_candidate_spec

        try:
            parse_candidate_spec(self.candidates)
        except PincalError as exc:
            raise CampaignError(f"{key}.candidates: {exc}") from exc


@dataclass(frozen=True)
class MeasurementSource:
    """Calibration measurements: simulated on a seeded actual machine, or a file."""

    source: str = "simulated"
    file: str | None = None
    poses: int | None = None
    errors_seed: int = 0
    error_size: tuple[float, float] = (1.0, 10.0)
    noise: tuple[float, float] = (DEFAULT_NOISE.position, DEFAULT_NOISE.orientation)
    seed: int = 1

    def check(self, key: str) -> None:
        """Raise CampaignError naming ``key.field`` for the first invalid entry of this section."""
        choice(self.source, SOURCES, f"{key}.source")
        if (self.source == "file") != (self.file is not None):
            raise CampaignError(f"{key}.file is required with source: file, and only then")
        if self.poses is not None and self.poses < 1:
            raise CampaignError(f"{key}.poses must be ≥ 1, got {self.poses}")
        if min(*self.error_size, *self.noise) < 0:
            raise CampaignError(f"{key}.error_size and {key}.noise must be ≥ 0")


@dataclass(frozen=True)
class Identification:
    """Identification options (``pincal calibrate``)."""

    method: str = "gauss-newton"
    loss: str | None = None
    prior: str | None = None
    instrument: str | None = None
    model: str = "geometric"
    bootstrap: int = 0

    def check(self, key: str) -> None:
        """Raise CampaignError naming ``key.field`` for the first invalid entry of this section."""
        from pincal.identification import INSTRUMENT_PROFILES, METHODS
        from pincal.model import split_model

        try:
            split_model(self.model)
        except PincalError as exc:
            raise CampaignError(f"{key}.model: {exc}") from exc

        choice(self.method, tuple(METHODS), f"{key}.method")
        if self.loss is not None:
            choice(self.loss, ("auto", "linear", "huber", "soft_l1", "cauchy"), f"{key}.loss")
        if self.prior is not None:
            from pincal.workflow import parse_prior

            try:
                parse_prior(self.prior)
            except PincalError as exc:
                raise CampaignError(
                    f"{key}.prior: {shown(self.prior)} is not 'auto', 'none' or "
                    "'LEN_MM,ANG_MRAD'"
                ) from exc
        if self.instrument is not None:
            choice(self.instrument, tuple(INSTRUMENT_PROFILES), f"{key}.instrument")
        if self.bootstrap < 0 or self.bootstrap == 1:
            raise CampaignError(f"{key}.bootstrap must be 0 (none) or a number of refits ≥ 2, "
                                f"e.g. 100; got {self.bootstrap}")  # fmt: skip


@dataclass(frozen=True)
class Markers:
    """A marker table in an unknown instrument frame (``pincal calibrate --link``)."""

    link: str
    columns: tuple[str, str, str] = ("x", "y", "z")
    length_unit: str = "m"
    instrument_frame: str = "unknown"
    marker: tuple[float, float, float] | None = None
    marker_std: float | None = None
    more_columns: tuple[tuple[str, str, str], ...] = ()
    more_links: tuple[str, ...] = ()
    root: str | None = None
    lock: dict[str, float] = field(default_factory=dict)
    orientation_columns: tuple[str, ...] = ()
    orientation: str | None = None

    def check(self, key: str) -> None:
        """Raise CampaignError naming ``key.field`` for the first invalid entry of this section."""
        from pincal.measure import ORIENTATIONS

        choice(self.length_unit, ("m", "mm", "um"), f"{key}.length_unit")
        if bool(self.orientation_columns) != (self.orientation is not None):
            raise CampaignError(f"{key}.orientation_columns and {key}.orientation go together "
                                "(e.g. [roll, pitch, yaw] and rpy-deg)")  # fmt: skip
        if self.orientation is not None:
            choice(self.orientation, tuple(ORIENTATIONS), f"{key}.orientation")
            if len(self.orientation_columns) != ORIENTATIONS[self.orientation]:
                raise CampaignError(f"{key}.orientation {self.orientation} needs "
                                    f"{ORIENTATIONS[self.orientation]} orientation_columns, got "
                                    f"{list(self.orientation_columns)}")  # fmt: skip
            if self.more_columns:
                raise CampaignError(f"{key}.orientation_columns describe one marker body: "
                                    "leave more_columns empty")  # fmt: skip
        choice(self.instrument_frame, ("unknown", "known"), f"{key}.instrument_frame")
        if self.more_links and len(self.more_links) != len(self.more_columns):
            raise CampaignError(f"{key}.more_links names one link per more_columns entry "
                                f"({len(self.more_columns)}), got "
                                f"{list(self.more_links)}")  # fmt: skip
        if self.marker_std is not None and (self.marker is None or self.marker_std <= 0):
            raise CampaignError(f"{key}.marker_std needs a given marker and must be > 0 [mm]")

    def options(self) -> list[str]:
        """The ``pincal calibrate`` options of this section."""
        columns = ";".join(",".join(c) for c in (self.columns, *self.more_columns))
        opts = ["--link", ",".join((self.link, *self.more_links)), "--marker-columns", columns]
        opts += ["--length-unit", self.length_unit, "--instrument-frame", self.instrument_frame]
        opts += [x for j, v in self.lock.items() for x in ("--lock", f"{j}={v!r}")]
        opts += ["--root", self.root] if self.root is not None else []
        if self.marker is not None:
            given = [*self.marker, *([self.marker_std] if self.marker_std else [])]
            opts += ["--marker", ",".join(repr(float(v)) for v in given)]
        if self.orientation is not None:
            opts += ["--orientation-columns", ",".join(self.orientation_columns),
                     "--orientation", self.orientation]  # fmt: skip
        return opts


@dataclass(frozen=True)
class Validation:
    """Held-out validation poses."""

    source: str = "simulated"
    file: str | None = None
    poses: int = 20
    seed: int = 2
    cv: int | None = None
    cv_seed: int = 0

    def check(self, key: str) -> None:
        """Raise CampaignError naming ``key.field`` for the first invalid entry of this section."""
        if self.cv is not None and self.cv < 2:
            raise CampaignError(f"{key}.cv must be ≥ 2 folds, got {self.cv}")
        choice(self.source, VALIDATION_SOURCES, f"{key}.source")
        if (self.source == "file") != (self.file is not None):
            raise CampaignError(f"{key}.file is required with source: file, and only then")
        if self.poses < 1:
            raise CampaignError(f"{key}.poses must be ≥ 1, got {self.poses}")


@dataclass(frozen=True)
class Campaign:
    """A whole calibration campaign (see :data:`KEYS_HELP`)."""

    model: str
    preset: str | None = None
    out: str = "campaign-out"
    design: Design | None = None
    measurements: MeasurementSource = field(default_factory=MeasurementSource)
    markers: Markers | None = None
    sockets: Sockets | None = None
    identification: Identification = field(default_factory=Identification)
    validation: Validation = field(default_factory=Validation)
    report: bool = True

    def check(self, key: str = "") -> None:
        """Check every section, then what the sections must agree on (CampaignError)."""
        for f in dataclasses.fields(self):
            sub: Any = getattr(self, f.name)
            if hasattr(sub, "check"):
                sub.check(f.name)
        m = self.measurements
        if m.source == "simulated" and (self.design is None) == (m.poses is None):
            raise CampaignError(
                "simulated measurements need exactly one of a 'design' section or "
                "'measurements.poses' (random workspace poses)"
            )
        if self.markers is not None and m.source != "file":
            raise CampaignError("markers: needs measurements.source: file (a marker table)")
        if self.sockets is not None and (m.source != "file" or self.markers is not None):
            raise CampaignError(
                "sockets: needs measurements.source: file (the plain CSV of seatings) and "
                "no markers section"
            )
        ident = self.identification
        if self.markers is None and (ident.prior is not None or ident.loss == "auto"):
            raise CampaignError(
                "identification.prior and loss: auto apply to marker campaigns (a 'markers' "
                "section)"
            )
        if m.source == "file" and m.poses is not None:
            raise CampaignError("measurements.poses applies to source: simulated only")
        if self.validation.source == "simulated" and m.source != "simulated":
            raise CampaignError(
                "validation.source: simulated needs simulated measurements (the same actual "
                "machine); use validation source: file or none"
            )

    def to_dict(self) -> dict[str, Any]:
        """Plain data (lists for pairs) for YAML/JSON."""

        def plain(v: Any) -> Any:
            if isinstance(v, tuple):
                return list(v)
            if isinstance(v, dict):
                return {k: plain(x) for k, x in v.items()}
            return v

        return plain(dataclasses.asdict(self))


def _resolve(path: str | None, base: Path) -> str | None:
    if path is None:
        return None
    p = Path(path).expanduser()
    return str(p if p.is_absolute() else base / p)


def load_campaign(path: str | Path) -> Campaign:
    """Read and validate a campaign file; relative paths become relative to its directory.

    Raises:
        CampaignError: unreadable file, not YAML, unknown key (nearest valid key
            suggested), wrong type or value, or a missing data file.
    """
    from pincal._yaml import load_yaml

    path = Path(path)
    data = load_yaml(path, "campaign file", CampaignError)
    mk = data.get("markers") if isinstance(data, dict) else None
    if isinstance(mk, dict) and mk.get("marker") == "unknown":  # the default, spelt out
        data = {**data, "markers": {**mk, "marker": None}}
    if isinstance(data, dict) and "sockets" in data:
        data = {**data, "sockets": plain_socket_section(data["sockets"])}
    try:
        camp = build(Campaign, data, "")
        camp.check()
    except CampaignError as exc:  # the message names the key; say which file holds it
        raise CampaignError(f"{clip(str(path), 200)}: {exc}") from None
    base = path.resolve().parent
    m = dataclasses.replace(camp.measurements, file=_resolve(camp.measurements.file, base))
    v = dataclasses.replace(camp.validation, file=_resolve(camp.validation.file, base))
    model = camp.model
    if "/" in model or model.endswith((".urdf", ".xml", ".yaml", ".yml")):
        model = _resolve(model, base) or model
    for key, f in (("measurements.file", m.file), ("validation.file", v.file)):
        if f is not None and not Path(f).is_file():
            what = ("is not a regular file (device, FIFO or directory); give the path of a "
                    "regular file") if Path(f).exists() else "does not exist"  # fmt: skip
            raise CampaignError(f"{key}: {shown(f, 300)} {what}")
    out = _resolve(camp.out, base) or camp.out
    return dataclasses.replace(camp, model=model, out=out, measurements=m, validation=v)
