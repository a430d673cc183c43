"""Reading runs: a source (a path to a runs table, run log, OptiOdom session or bag, or
runs in memory) and the options that say how to read it (:class:`ReadOptions`) turned
into runs, integrated with the odometry parameters active during them; several sources
pooled into one set of runs.

Which parameters were active (the options, a parameter file, what the source records) is
resolved by :mod:`umbmark.runs.active`, which reads the sources through here.
Messages name the options as the command line spells them.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, cast

from umbmark.core.bounds import Origin
from umbmark.core.errors import InputError, option
from umbmark.core.messages import info
from umbmark.model.active import ActiveParams
from umbmark.model.kinematics import WheelParams
from umbmark.model.run import Run
from umbmark.options.spec import READ
from umbmark.runs.load import Format, Loaded, LoadOptions, detect_format, load_runs
from umbmark.runs.read_options import ReadOptions
from umbmark.sources.params.reader import ControllerParams, named_controller, read_parameter_file
from umbmark.sources.runs_table.reader import RecordedActive, read_table_active

if TYPE_CHECKING:
    from umbmark.runs.association import Association
    from umbmark.sources.bag.bag_options import BagOptions

__all__ = [
    "Chosen",
    "PathLike",
    "RunSource",
    "SourceRuns",
    "bag_options",
    "check_invertible",
    "holds_gyro",
    "is_bag",
    "is_runs",
    "is_table",
    "parameter_file",
    "pool_runs",
    "read_source",
    "recorded_active",
    "source_format",
    "source_name",
]


#: What can be read: a path to a runs table, run log, OptiOdom session or bag, or runs
#: already in memory (a runs table's worth of end points).
RunSource = str | os.PathLike[str] | Sequence[Run]

PathLike = str | os.PathLike[str]


@dataclass(frozen=True)
class SourceRuns:
    """Runs read from one or more sources, and the parameters active while they were driven.

    Attributes
    ----------
    sources : tuple of str
        What was read (paths, or ``"runs"`` for runs given in memory).
    formats : tuple of str
        The format of each source.
    runs : tuple of Run
    active : ActiveParams
        The controller's view of the parameters active during the runs.
    params : WheelParams or None
        What logged runs were integrated with; None for end points only.
    side_length : float or None
        The square's side [m], if given or known to the sources and the same for all.
    controller : ControllerParams
        The controller the parameters are for (from ``current_params``, or a default one
        named by ``controller``).
    associations : tuple of (str, Association)
        Time matching of each recording.
    notes : tuple of str
        What was found and left out, for people.
    sides : tuple of (float or None)
        The side [m] each source knows.
    parts : tuple of SourceRuns
        Pooled from several sources: each source's runs as read (empty for one source).
    nominal : WheelParams or None
        A logged source's own nominal parameters, before any option or file overrides.
    origins : dict of str to Origin
        Where ``wheelbase``, ``separation_multiplier`` and ``side_length`` came from where
        an option did not give them (a file's field), for messages.
    stretches : tuple of Run
        Motion left out of the runs (a square closed several times with no stop between,
        cut short by a reset, broken by a gap) in stretches with a reference, for the
        estimators that fit paths of any shape.
    """

    sources: tuple[str, ...]
    formats: tuple[str, ...]
    runs: tuple[Run, ...]
    active: ActiveParams
    params: WheelParams | None
    side_length: float | None
    controller: ControllerParams
    associations: tuple[tuple[str, Association], ...] = ()
    notes: tuple[str, ...] = field(default=())
    sides: tuple[float | None, ...] = ()
    parts: tuple[SourceRuns, ...] = field(default=(), repr=False, compare=False)
    nominal: WheelParams | None = field(default=None, repr=False, compare=False)
    origins: Mapping[str, Origin] = field(default_factory=dict, repr=False, compare=False)
    stretches: tuple[Run, ...] = field(default=(), repr=False, compare=False)

    def square_side(self) -> float:
        """The side [m] of the square every source drove.

        Raises
        ------
        InputError
            If it is not known, or the sources are not all squares of one side.
        """
        known = {s for s in self.sides if s is not None}
        if len(known) > 1:
            shown = ", ".join(f"{s:g} m" for s in sorted(known))
            raise InputError(
                f"the sources are squares of different sides ({shown}): UMBmark compares "
                "runs of one square; calibrate them separately or with "
                f"{option('method', 'trajectory')}"
            )
        if known and None in self.sides:
            other = self.sources[self.sides.index(None)]
            raise InputError(
                f"{other} is not a square of known side, unlike the other sources; give "
                f"{option('side_length')} if it is one, or calibrate with "
                f"{option('method', 'trajectory')}"
            )
        if self.side_length is None:
            hint = (
                f"; if the runs are not squares, calibrate with {option('method', 'endpoints')} "
                "or trajectory (any shape), or auto"
                if self.params is not None
                else ""
            )
            raise InputError(
                f"{option('side_length')} is required: the side of the square path, in "
                f"metres{hint}",
                source=self.sources[0] if len(self.sources) == 1 else None,
            )
        return self.side_length

    @property
    def format(self) -> str:
        """The sources' format (``+``-joined where they differ)."""
        return "+".join(dict.fromkeys(self.formats))


@dataclass(frozen=True)
class Chosen:
    """The active parameters as given or recorded (None: neither), and notes saying so
    (resolved by :func:`umbmark.runs.active.choose_active`)."""

    c_left: float | None
    c_right: float | None
    separation: float | None
    wheelbase: float | None
    wheel_diameter: float | None
    notes: tuple[str, ...]
    origins: dict[str, Origin] = field(default_factory=dict)


def source_name(source: RunSource) -> str:
    """How a source is named in messages and results."""
    return "runs" if is_runs(source) else os.fspath(cast("PathLike", source))


def is_runs(source: object) -> bool:
    """Whether ``source`` is runs in memory (not a path)."""
    return (
        isinstance(source, Sequence)
        and not isinstance(source, str)
        and all(isinstance(run, Run) for run in source)
    )


def is_table(source: RunSource, options: ReadOptions) -> bool:
    """Whether ``source`` holds end points only (a runs table, or runs in memory)."""
    if is_runs(source):
        return True
    if options.format != "auto":
        return options.format == "table"
    return detect_format(Path(cast("PathLike", source))) == "table"


def is_intervals(source: RunSource, options: ReadOptions) -> bool:
    """Whether ``source`` holds motion intervals (a tuple file), not runs."""
    if is_runs(source):
        return False
    if options.format != "auto":
        return options.format == "tuples"
    path = Path(cast("PathLike", source))
    return path.is_file() and detect_format(path) == "tuples"


def is_bag(source: RunSource, options: ReadOptions) -> bool:
    """Whether ``source`` is a recording in a bag (ROS 1, ROS 2, MCAP)."""
    return not is_runs(source) and source_format(source, options)[1] == "bag"


def holds_gyro(source: RunSource, options: ReadOptions) -> bool:
    """Whether ``source`` is calibrated with its gyro: a bag read with ``imu_topic``."""
    return options.imu_topic is not None and is_bag(source, options)


def source_format(source: RunSource, options: ReadOptions) -> tuple[Path | None, Format]:
    """The path of ``source`` (None for runs in memory) and its format (``"table"`` for
    runs in memory), as ``options.format`` says or detected."""
    if is_runs(source):
        return None, "table"
    path = Path(cast("PathLike", source))
    kind = detect_format(path) if options.format == "auto" else cast("Format", options.format)
    return path, kind


def parameter_file(options: ReadOptions) -> ControllerParams:
    """The parameter file ``current_params`` (read), or the default controller named by
    ``controller``."""
    if options.current_params is None:
        return named_controller(options.controller)
    return read_parameter_file(Path(options.current_params), options.controller)


def recorded_active(path: Path, kind: Format) -> RecordedActive | None:
    """The active parameters a runs table's header or a run log's metadata records."""
    if kind == "table":
        if path.is_dir():
            return None  # reading the table says what is wrong
        return read_table_active(path)
    if kind == "log":
        from umbmark.sources.runlog.reader import METADATA_FILE, read_metadata

        meta_path = (path if path.is_dir() else path.parent) / METADATA_FILE
        if not meta_path.is_file():
            return None  # reading the log says what is wrong
        meta = read_metadata(meta_path)
        if not meta.active_recorded:
            return None
        return RecordedActive(
            c_left=meta.c_left,
            c_right=meta.c_right,
            separation_multiplier=meta.separation_multiplier,
            wheelbase=meta.wheelbase,
            wheel_diameter=meta.wheel_diameter,
            where=f"the run log's {METADATA_FILE}",
            path=str(meta_path),
        )
    return None


def read_source(
    source: RunSource,
    kind: Format,
    options: ReadOptions,
    file: ControllerParams,
    chosen: Chosen,
    side_length: float | None,
    recorded: RecordedActive | None,
    *,
    stretches: bool = False,
) -> SourceRuns:
    """The runs of one source of format ``kind`` (see :func:`source_format`), read with
    the active parameters ``chosen`` for it (what ``recorded`` says the source recorded
    as active; ``file``, the parameter file or the default controller); ``stretches``:
    see :func:`umbmark.runs.active.read_each`.

    Raises
    ------
    InputError
        For a bad source, or parameters it cannot be read with.
    """
    name = source_name(source)
    controller = file
    path = None if is_runs(source) else Path(cast("PathLike", source))
    separation = _first(chosen.separation, 1.0)
    c_left, c_right = _first(chosen.c_left, 1.0), _first(chosen.c_right, 1.0)
    configured, diameter = chosen.wheelbase, chosen.wheel_diameter

    if path is None:
        loaded = Loaded(format="runs", runs=list(cast("Sequence[Run]", source)))
    else:
        given = None
        if kind == "bag":
            if configured is None or diameter is None:
                from umbmark.sources.bag.bag_options import BagOptions
                from umbmark.sources.bag.urdf import described_geometry

                named = BagOptions(
                    left_joint=_joints(options.left_joint) or file.left_joints or None,
                    right_joint=_joints(options.right_joint) or file.right_joints or None,
                )
                configured, diameter, described = described_geometry(
                    path, named.left_joints, named.right_joints, configured, diameter
                )
                chosen = replace(chosen, notes=(*chosen.notes, described))
            given = WheelParams(
                wheelbase=configured * separation,
                wheel_diameter=diameter,
                c_left=c_left,
                c_right=c_right,
            )
            if options.odom_topic is not None or options.odom_tf is not None:
                check_invertible(file, name)
        load = _load_options(options, kind, side_length, given, file, stretches)
        loaded = load_runs(path, kind, load)
        if kind == "table":
            _require_wheelbase(configured)

    if loaded.params is None:  # end points: the options are all there is
        configured = _require_wheelbase(configured)
        active = ActiveParams(
            wheelbase=configured,
            c_left=c_left,
            c_right=c_right,
            separation_multiplier=separation,
            wheel_diameter=diameter,
        )
        return SourceRuns(
            sources=(name,),
            formats=(loaded.format,),
            runs=tuple(loaded.runs),
            active=active,
            params=None,
            side_length=side_length,
            controller=controller,
            notes=(*chosen.notes, *loaded.notes),
            sides=(side_length,),
            origins=_origins(chosen, loaded, side_length),
        )

    # Logged runs: the source's parameters, with whatever the options or files override.
    base = loaded.params
    configured = configured if configured is not None else base.wheelbase
    params = WheelParams(
        wheelbase=configured * separation,
        wheel_diameter=diameter if diameter is not None else base.wheel_diameter,
        encoder_resolution=base.encoder_resolution,
        gear_ratio=base.gear_ratio,
        c_left=_first(chosen.c_left, base.c_left),
        c_right=_first(chosen.c_right, base.c_right),
    )
    runs, kept = loaded.runs, loaded.stretches
    if params != base:
        runs = [run.reintegrated(params) for run in runs]
        kept = [run.reintegrated(params) for run in kept]
    active = ActiveParams(
        wheelbase=configured,
        c_left=params.c_left,
        c_right=params.c_right,
        separation_multiplier=separation,
        wheel_diameter=params.wheel_diameter,
    )
    nominal = base
    if recorded is not None and recorded.wheelbase is not None:
        nominal = replace(base, wheelbase=recorded.wheelbase)
    return SourceRuns(
        sources=(name,),
        formats=(loaded.format,),
        runs=tuple(runs),
        active=active,
        params=params,
        side_length=loaded.side_length,
        controller=controller,
        associations=tuple(loaded.associations),
        notes=(*chosen.notes, *loaded.notes),
        sides=(loaded.side_length,),
        nominal=nominal,
        origins=_origins(chosen, loaded, side_length),
        stretches=tuple(kept),
    )


def _origins(chosen: Chosen, loaded: Loaded, side_length: float | None) -> dict[str, Origin]:
    """Where the parameters came from: the options and files of ``chosen``, else the
    source's own fields (a run log's or OptiOdom session's metadata)."""
    origins = {**loaded.origins, **chosen.origins}
    if side_length is not None:
        origins["side_length"] = Origin(option("side_length"))
    return origins


def _require_wheelbase(configured: float | None) -> float:
    """The wheelbase end points were driven with, which only the options can say."""
    if configured is None:
        raise InputError(
            f"{option('wheelbase')} is required: the wheelbase the odometry used during the "
            "runs, in metres"
        )
    return configured


def check_invertible(file: ControllerParams, name: str) -> None:
    """Refuse odometry that does not come from the wheels."""
    if file.open_loop:
        raise InputError(
            "the controller has open_loop: true, so its odometry integrates the velocity "
            "commands, not the wheels: it cannot be turned back into wheel rotation; record "
            "the wheel joint states, or set open_loop: false for the runs",
            source=name,
        )


def _load_options(
    options: ReadOptions,
    kind: Format,
    side_length: float | None,
    params: WheelParams | None,
    file: ControllerParams,
    stretches: bool = False,
) -> LoadOptions:
    windows = options.time_windows
    split_options = None
    if kind != "table":  # recordings only: kept off a runs table's start-up
        from umbmark.runs.segmentation import SplitOptions

        split_options = SplitOptions(min_rest=float(options.min_rest))
    return LoadOptions(
        unit=options.unit,
        angle_unit=options.angle_unit,
        side_length=side_length,
        params=params,
        split="windows" if windows else options.split,
        windows=windows,
        split_options=split_options,
        max_gap=float(options.max_gap),
        bag=bag_options(options, params, file) if kind == "bag" else None,
        truth_offset=(
            (float(options.truth_offset[0]), float(options.truth_offset[1]))
            if options.truth_offset is not None
            else None
        ),
        keep_stretches=stretches,
    )


def bag_options(
    options: ReadOptions, params: WheelParams | None, file: ControllerParams
) -> BagOptions:
    """How to read a bag's wheels (and ground truth): the reading options as
    :class:`~umbmark.sources.bag.bag_options.BagOptions`, the controller's odometry turned back
    into wheel rotation with ``params`` (the parameters the odometry used)."""
    from umbmark.model.kinematics import OdometryGeometry
    from umbmark.sources.bag.bag_options import BagOptions

    geometry = None
    if params is not None:
        radius = 0.5 * params.wheel_diameter
        geometry = OdometryGeometry(
            left_radius=params.c_left * radius,
            right_radius=params.c_right * radius,
            separation=params.wheelbase,
        )
    computed = BagOptions(
        left_joint=_joints(options.left_joint) or file.left_joints or None,
        right_joint=_joints(options.right_joint) or file.right_joints or None,
        odom_tf=(options.odom_tf[0], options.odom_tf[1]) if options.odom_tf else None,
        odom_geometry=geometry,
        msg_dir=Path(options.msg_dir) if options.msg_dir is not None else None,
    )
    # Every other field is a reading option of the same name (tests/runs/test_read_fields.py).
    shared = {
        f.name: getattr(options, f.name)
        for f in fields(BagOptions)
        if f.name in READ and f.name not in _COMPUTED
    }
    return replace(computed, **shared)


#: The fields of :class:`BagOptions` :func:`bag_options` makes from the reading options of
#: their name rather than copies: joints as tuples (or the controller file's), a path.
_COMPUTED = ("left_joint", "right_joint", "odom_tf", "msg_dir")


def _joints(value: str | Sequence[str] | None) -> str | tuple[str, ...] | None:
    """Joint names as :class:`BagOptions` takes them (it splits and strips them)."""
    return value if value is None or isinstance(value, str) else tuple(value)


def _first(value: float | None, fallback: float) -> float:
    return fallback if value is None else value


def pool_runs(read: Sequence[SourceRuns]) -> SourceRuns:
    """One set of runs from several sources.

    Runs tables must have been driven with the same parameters (their return errors are
    relative to them). Recorded runs may come with different nominal parameters (a
    session recorded with ``Li = 0.205``): their wheel data is integrated anew with the
    first source's, so that one fit sees one odometry.

    Raises
    ------
    InputError
        For tables driven with different parameters.
    """
    first = read[0]
    original = list(read)
    notes: list[str] = []
    for k, other in enumerate(read[1:], start=1):
        if other.active == first.active and other.params == first.params:
            continue
        if first.params is None or other.params is None:
            raise InputError(
                f"{first.sources[0]} and {other.sources[0]} were driven with different "
                "odometry parameters; calibrate them separately",
                source=None,
            )
        notes.append(
            info(
                f"{other.sources[0]}: integrated with the parameters of {first.sources[0]} "
                f"(b = {first.params.wheelbase:g} m, D = {first.params.wheel_diameter:g} m) "
                f"instead of its own (b = {other.params.wheelbase:g} m, "
                f"D = {other.params.wheel_diameter:g} m)"
            )
        )
        read = [
            *read[:k],
            replace(
                other,
                runs=tuple(run.reintegrated(first.params) for run in other.runs),
                stretches=tuple(run.reintegrated(first.params) for run in other.stretches),
            ),
            *read[k + 1 :],
        ]
    sides = tuple(r.side_length for r in read)
    known = set(sides) - {None}
    runs = tuple(
        replace(run, label=f"{Path(r.sources[0]).name} {run.label}".strip())
        for r in read
        for run in r.runs
    )
    return SourceRuns(
        sources=tuple(s for r in read for s in r.sources),
        formats=tuple(f for r in read for f in r.formats),
        runs=runs,
        active=first.active,
        params=first.params,
        side_length=known.pop() if len(known) == 1 and None not in sides else None,
        controller=first.controller,
        associations=tuple(a for r in read for a in r.associations),
        notes=(*(n for r in read for n in r.notes), *notes),
        sides=sides,
        parts=tuple(original),
        origins=first.origins,
        stretches=tuple(
            replace(run, label=f"{Path(r.sources[0]).name} {run.label}".strip())
            for r in read
            for run in r.stretches
        ),
    )
