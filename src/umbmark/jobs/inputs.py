"""Reading runs for a job: the options that say how to read a source, and the step that
turns a source and those options into runs and the odometry parameters that were active.

Every keyword here is an option of ``umbmark calibrate`` and ``umbmark replay`` with the
same name and meaning (``--current-c-l`` is ``current_c_l``); lengths in metres, times in
seconds. Messages name the options as the command line spells them.

Parameters come from three places, later ones winning: the source itself (a run log's
``metadata.yaml``, an OptiOdom session's metadata, a runs table's ``# umbmark-active:``
line; a bag says nothing), a parameter file (``current_params``: a ros2_control or ROS 1
YAML, or a previous result), and the keywords. The wheel factors and separation
multiplier a source records as active are used only where no ``current_...`` keyword or
file is given (with a note); given ones that differ from them are warned of. Messages
about a parameter name where it came from (an option, or a file's field). A runs table's
end points are judged as a robot driving the square makes them
(:mod:`umbmark.estimators.plausibility`: units, swapped columns, errors beyond the square
test).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Literal, TypeAlias, cast

from umbmark.calibration.compose import ActiveParams, Calibration
from umbmark.core.bounds import (
    MAX_SIDE_LENGTH,
    MAX_WHEELBASE,
    Origin,
    check_int_option,
    check_length,
    check_multiplier,
    check_positive_option,
    option_float,
)
from umbmark.core.errors import InputError
from umbmark.core.messages import info
from umbmark.estimators.plausibility import check_columns, unit_hints
from umbmark.model.kinematics import WheelParams
from umbmark.model.runs import Run
from umbmark.runs.association import Association
from umbmark.runs.load import Format, Loaded, LoadOptions, detect_format, load_runs
from umbmark.runs.logged import SplitMode
from umbmark.runs.options import (
    SAME_ROBOT_TOLERANCE,
    ReadOptions,
    SourceOptions,
)
from umbmark.sources.params.reader import (
    CalibratedParams,
    ControllerParams,
    is_result_file,
    read_calibrated_params,
    read_parameter_file,
    result_nominal,
)
from umbmark.sources.runs_table.reader import RecordedActive, read_table_active

if TYPE_CHECKING:
    from umbmark.jobs.calibrate import CalibrationReport
    from umbmark.sources.bag.options import BagOptions

__all__ = [
    "MAX_SIDE_LENGTH",
    "MAX_WHEELBASE",
    "Calibrated",
    "ReadOptions",
    "RunSource",
    "Runs",
    "SourceOptions",
    "calibrated_name",
    "calibrated_nominal",
    "calibrated_params",
    "check_calibration",
    "check_int_option",
    "check_length",
    "check_multiplier",
    "check_positive_option",
    "check_same_robot",
    "check_square_geometry",
    "option_float",
    "pool_runs",
    "read_runs",
]

#: What can be read: a path to a runs table, run log, OptiOdom session or bag, or runs
#: already in memory (a runs table's worth of end points).
RunSource = str | os.PathLike[str] | Sequence[Run]

PathLike = str | os.PathLike[str]
#: A calibration to replay or simulate with: a result file, or what it holds.
Calibrated: TypeAlias = "PathLike | CalibratedParams | CalibrationReport"


@dataclass(frozen=True)
class Runs:
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
    parts : tuple of Runs
        Pooled from several sources: each source's runs as read (empty for one source).
    nominal : WheelParams or None
        A logged source's own nominal parameters, before any option or file overrides.
    origins : dict of str to Origin
        Where ``wheelbase``, ``separation_multiplier`` and ``side_length`` came from where
        an option did not give them (a file's field), for messages.
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
    parts: tuple[Runs, ...] = field(default=(), repr=False, compare=False)
    nominal: WheelParams | None = field(default=None, repr=False, compare=False)
    origins: Mapping[str, Origin] = field(default_factory=dict, repr=False, compare=False)

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
                "runs of one square; calibrate them separately or with --method trajectory"
            )
        if known and None in self.sides:
            other = self.sources[self.sides.index(None)]
            raise InputError(
                f"{other} is not a square of known side, unlike the other sources; give "
                "--side-length if it is one, or calibrate with --method trajectory"
            )
        if self.side_length is None:
            hint = (
                "; if the runs are not squares, calibrate with --method endpoints or "
                "trajectory (any shape), or auto"
                if self.params is not None
                else ""
            )
            raise InputError(
                f"--side-length is required: the side of the square path, in metres{hint}",
                source=self.sources[0] if len(self.sources) == 1 else None,
            )
        return self.side_length

    @property
    def format(self) -> str:
        """The sources' format (``+``-joined where they differ)."""
        return "+".join(dict.fromkeys(self.formats))


def calibrated_params(params: Calibrated) -> CalibratedParams:
    """The new parameters of a calibration: read from a result file, or taken from a report."""
    from umbmark.jobs.calibrate import CalibrationReport

    if isinstance(params, CalibratedParams):
        return params
    if isinstance(params, CalibrationReport):
        return params.new_params()
    return read_calibrated_params(Path(params))


def calibrated_nominal(params: Calibrated) -> tuple[float | None, float | None]:
    """The nominal wheelbase and wheel diameter [m] a calibration was computed for."""
    from umbmark.jobs.calibrate import CalibrationReport

    if isinstance(params, CalibratedParams):
        return params.configured_wheelbase, params.wheel_diameter
    if isinstance(params, CalibrationReport):
        active = params.calibration.active
        return active.wheelbase, active.wheel_diameter
    return result_nominal(Path(params))


def calibrated_name(params: Calibrated) -> str:
    """How a calibration is named in messages."""
    if isinstance(params, CalibratedParams):
        return params.source or "the calibration"
    if isinstance(params, str | os.PathLike):
        return os.fspath(params)
    return "the calibration"


def check_square_geometry(
    side_length: float | None,
    wheelbase: float,
    origins: Mapping[str, Origin] | None = None,
    multiplier: float = 1.0,
) -> None:
    """Refuse a wheelbase [m] (the odometry's: the configured one times ``multiplier``)
    that is not smaller than the square's side [m].

    A robot whose wheelbase reaches half the side cannot drive the square as UMBmark
    assumes (its wheels would cross the square's centre on the turns): the usual cause is
    swapped or mistyped ``--side-length`` and ``--wheelbase``. ``origins`` says where the
    values came from (``wheelbase``, ``separation_multiplier``, ``side_length``; options
    where not said); the message names those.
    """
    if side_length is None or wheelbase < side_length / 2:
        return
    b_from, side_from, m_from, source = _geometry_origins(origins, multiplier)
    if b_from.file is None and side_from.file is None and m_from is None:
        raise InputError(
            f"--wheelbase {wheelbase:g} m is not smaller than the square: it must be below "
            f"half the side (--side-length {side_length:g} m, so b < {side_length / 2:g} m); "
            "are the two swapped or in other units?"
        )
    named = b_from.named(source)
    if m_from is not None:
        named += f" times {m_from.named(source)} {multiplier:g}"
    raise InputError(
        f"the odometry's wheelbase {wheelbase:g} m ({named}) is not smaller than the square: "
        f"it must be below half the side ({side_from.named(source)} {side_length:g} m, so "
        f"b < {side_length / 2:g} m); are the two swapped or in other units?",
        source=source,
    )


def _geometry_origins(
    origins: Mapping[str, Origin] | None, multiplier: float
) -> tuple[Origin, Origin, Origin | None, str | None]:
    """Where the wheelbase, the side and (unless 1) the multiplier came from, and the one
    file they all come from (None if they come from several, or from options only)."""
    origins = origins or {}
    b_from = origins.get("wheelbase", Origin("--wheelbase"))
    side_from = origins.get("side_length", Origin("--side-length"))
    m_from = origins.get("separation_multiplier") if multiplier != 1.0 else None
    files = {o.file for o in (b_from, side_from, m_from) if o is not None and o.file}
    return b_from, side_from, m_from, files.pop() if len(files) == 1 else None


def check_calibration(
    calibration: Calibration, origins: Mapping[str, Origin] | None = None
) -> None:
    """Refuse a calibration whose new factors are not positive finite numbers.

    Raises
    ------
    InputError
        Naming the first such factor: the runs and the parameters (named as ``origins``
        says where they came from, see :func:`check_square_geometry`) contradict each other.
    """
    active = calibration.active
    b_from, side_from, m_from, _ = _geometry_origins(origins, active.separation_multiplier)
    named = [side_from.named(), b_from.named(), *([m_from.named()] if m_from else [])]
    for name, value in (
        ("E_d", calibration.estimate.E_d),
        ("E_b", calibration.estimate.E_b),
        ("c_L", calibration.new_c_left),
        ("c_R", calibration.new_c_right),
        ("wheel_separation_multiplier", calibration.new_separation_multiplier),
        ("wheelbase", calibration.wheelbase_corrected),
    ):
        if not (math.isfinite(value) and value > 0):
            raise InputError(
                f"the runs give {name} = {value:.6g}, which no robot can have: check "
                f"{', '.join(named)} and the runs' units and directions"
            )


def check_same_robot(
    result: str,
    theirs: tuple[float | None, float | None],
    source: str,
    ours: tuple[float | None, float | None],
) -> None:
    """Refuse a result computed for other nominal parameters than a source's.

    Parameters
    ----------
    result : str
        The result (a file name) as messages name it.
    theirs : (float or None, float or None)
        The result's nominal wheelbase and wheel diameter [m] (its ``active`` block).
    source : str
        The source as messages name it.
    ours : (float or None, float or None)
        The source's own nominal wheelbase and wheel diameter [m].

    Raises
    ------
    InputError
        Naming both values, where one pair differs by more than 1 %.
    """
    for name, their, our in zip(("wheelbase", "wheel diameter"), theirs, ours, strict=True):
        if their is None or our is None:
            continue
        if abs(their - our) > SAME_ROBOT_TOLERANCE * our:
            raise InputError(
                f"{result} is a calibration for a nominal {name} of {their:g} m, but "
                f"{source} has {our:g} m (more than 1 % apart): a result of another robot "
                "or setup; give --force to use it anyway"
            )


def source_name(source: RunSource) -> str:
    """How a source is named in messages and results."""
    return "runs" if _is_runs(source) else os.fspath(cast("PathLike", source))


def _is_runs(source: object) -> bool:
    return (
        isinstance(source, Sequence)
        and not isinstance(source, str)
        and all(isinstance(run, Run) for run in source)
    )


def is_table(source: RunSource, options: ReadOptions) -> bool:
    """Whether ``source`` holds end points only (a runs table, or runs in memory)."""
    if _is_runs(source):
        return True
    if options.format != "auto":
        return options.format == "table"
    return detect_format(Path(cast("PathLike", source))) == "table"


def read_runs(
    sources: Sequence[RunSource],
    options: ReadOptions,
    *,
    wheelbase: float | None = None,
    side_length: float | None = None,
    force: bool = False,
) -> Runs:
    """Read the runs of every source, with the odometry parameters the options say.

    Several sources must agree on the square's side and on the parameters that were
    active; their runs are pooled (labels then start with the source's name). A result
    file as ``current_params`` must be for the sources' nominal wheelbase and wheel
    diameter (within 1 %), unless ``force``.

    Raises
    ------
    InputError
        For bad options, a bad source, or sources that disagree.
    """
    if not sources:
        raise InputError("no source given: name a runs table, run log, OptiOdom session or bag")
    if wheelbase is not None:
        check_length("--wheelbase", wheelbase, MAX_WHEELBASE)
    if side_length is not None:
        check_length("--side-length", side_length, MAX_SIDE_LENGTH)
    file = _parameter_file(options)
    read = [_read_one(source, options, file, wheelbase, side_length) for source in sources]
    if options.current_params is not None and not force:
        path = Path(options.current_params)
        if is_result_file(path):
            theirs = result_nominal(path)
            for one in read:
                if one.nominal is not None:
                    check_same_robot(
                        str(path),
                        theirs,
                        one.sources[0],
                        (one.nominal.wheelbase, one.nominal.wheel_diameter),
                    )
    if len(read) == 1:
        return read[0]
    return pool_runs(read)


def _parameter_file(options: ReadOptions) -> ControllerParams:
    if options.current_params is None:
        name = options.controller or "diff_drive_controller"
        return ControllerParams(controller=name.strip("/").rsplit("/", 1)[-1], key_path=(name,))
    return read_parameter_file(Path(options.current_params), options.controller)


def _read_one(
    source: RunSource,
    options: ReadOptions,
    file: ControllerParams,
    wheelbase: float | None,
    side_length: float | None,
) -> Runs:
    name = source_name(source)
    controller = file
    recorded: RecordedActive | None = None
    path: Path | None = None
    kind: Format = "table"
    if not _is_runs(source):
        path = Path(cast("PathLike", source))
        kind = detect_format(path) if options.format == "auto" else cast("Format", options.format)
        recorded = _recorded_active(path, kind)
    chosen = _choose_active(options, file, wheelbase, recorded, note_wheelbase=kind == "table")
    separation = _first(chosen.separation, 1.0)
    c_left, c_right = _first(chosen.c_left, 1.0), _first(chosen.c_right, 1.0)
    configured, diameter = chosen.wheelbase, chosen.wheel_diameter

    if path is None:
        loaded = Loaded(format="runs", runs=list(cast("Sequence[Run]", source)))
    else:
        given = None
        if kind == "bag":
            if configured is None or diameter is None:
                from umbmark.sources.bag.options import BagOptions
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
                _check_invertible(file, name)
        loaded = load_runs(path, kind, _load_options(options, kind, side_length, given, file))
        if kind == "table":
            b = _require_wheelbase(configured) * separation
            hints = [
                *check_columns(loaded.runs, side_length, name),
                *unit_hints(loaded.runs, options.unit, options.angle_unit, side_length, b, name),
            ]
            loaded = replace(loaded, notes=[*loaded.notes, *hints])

    if loaded.params is None:  # end points: the options are all there is
        configured = _require_wheelbase(configured)
        active = ActiveParams(
            wheelbase=configured,
            c_left=c_left,
            c_right=c_right,
            separation_multiplier=separation,
            wheel_diameter=diameter,
        )
        return Runs(
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
    runs = loaded.runs
    if params != base:
        runs = [run.reintegrated(params) for run in runs]
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
    return Runs(
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
    )


def _origins(chosen: _Chosen, loaded: Loaded, side_length: float | None) -> dict[str, Origin]:
    """Where the parameters came from: the options and files of ``chosen``, else the
    source's own fields (a run log's or OptiOdom session's metadata)."""
    origins = {**loaded.origins, **chosen.origins}
    if side_length is not None:
        origins["side_length"] = Origin("--side-length")
    return origins


def _require_wheelbase(configured: float | None) -> float:
    """The wheelbase end points were driven with, which only the options can say."""
    if configured is None:
        raise InputError(
            "--wheelbase is required: the wheelbase the odometry used during the runs, in metres"
        )
    return configured


def _recorded_active(path: Path, kind: Format) -> RecordedActive | None:
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


@dataclass(frozen=True)
class _Chosen:
    """The active parameters as given or recorded (None: neither), and notes saying so."""

    c_left: float | None
    c_right: float | None
    separation: float | None
    wheelbase: float | None
    wheel_diameter: float | None
    notes: tuple[str, ...]
    origins: dict[str, Origin] = field(default_factory=dict)


#: Given and recorded active parameters closer than this (relative) agree.
_SAME_ACTIVE = 1e-6


def _choose_active(
    options: ReadOptions,
    file: ControllerParams,
    wheelbase: float | None,
    recorded: RecordedActive | None,
    *,
    note_wheelbase: bool = True,
) -> _Chosen:
    """The active parameters: the options' and the parameter file's; where none of the
    ``--current-...`` options is given, what the source records (with a note). Warns where
    the given ones differ from the recorded ones."""
    from_file = options.current_params is not None
    in_file = f"--current-params {os.fspath(options.current_params or '')}"
    diameter = options.wheel_diameter
    if diameter is None and file.wheel_radius is not None:
        diameter = 2.0 * file.wheel_radius
    if diameter is None and recorded is not None:
        diameter = recorded.wheel_diameter
    user_b = wheelbase if wheelbase is not None else file.wheel_separation
    b_flag = "--wheelbase" if wheelbase is not None else in_file
    factors = [
        (options.current_c_l, "--current-c-l", file.left_wheel_radius_multiplier),
        (options.current_c_r, "--current-c-r", file.right_wheel_radius_multiplier),
        (
            options.current_separation_multiplier,
            "--current-separation-multiplier",
            file.wheel_separation_multiplier,
        ),
    ]
    given = [
        (option, flag) if option is not None else (value, in_file) if from_file else (None, "")
        for option, flag, value in factors
    ]
    origins = _given_origins(options, wheelbase, file)
    if recorded is None:
        return _Chosen(given[0][0], given[1][0], given[2][0], user_b, diameter, (), origins)

    def shown(value: float, unit: str = "") -> str:
        return f"{value:.6g}{unit}"

    where, notes = recorded.where, list[str]()
    recorded_b = recorded.wheelbase
    if all(value is None for value, _ in given):
        # Nothing said what was active: what the source records was.
        used = [
            f"{label} = {shown(value)}"
            for label, value in (
                ("c_L", recorded.c_left),
                ("c_R", recorded.c_right),
                ("wheel_separation_multiplier", recorded.separation_multiplier),
            )
            if value != 1.0
        ]
        if user_b is None and recorded_b is not None and note_wheelbase:
            used.append(f"wheelbase = {shown(recorded_b, ' m')}")
        if used:
            notes.append(
                info(
                    f"active parameters from {where}: {', '.join(used)} (the correction is "
                    "composed with them; give --current-params or --current-c-l, --current-c-r, "
                    "--current-separation-multiplier to override)"
                )
            )
        if (
            user_b is not None
            and recorded_b is not None
            and not math.isclose(user_b, recorded_b, rel_tol=_SAME_ACTIVE)
        ):
            notes.append(
                f"{b_flag} gives wheelbase = {shown(user_b, ' m')}, but {where} records "
                f"wheelbase = {shown(recorded_b, ' m')} (times wheel_separation_multiplier "
                f"{shown(recorded.separation_multiplier)}) as active during the runs; "
                f"using {shown(user_b, ' m')} times the recorded multiplier"
            )
        if recorded_b is not None:
            origins.setdefault("wheelbase", recorded.origin("wheelbase"))
        origins["separation_multiplier"] = recorded.origin("wheel_separation_multiplier")
        return _Chosen(
            recorded.c_left,
            recorded.c_right,
            recorded.separation_multiplier,
            user_b if user_b is not None else recorded_b,
            diameter,
            tuple(notes),
            origins,
        )

    # Something was given: it wins; say where it contradicts the record.
    for (value, flag), label, record in zip(
        given[:2], ("c_L", "c_R"), (recorded.c_left, recorded.c_right), strict=True
    ):
        if value is not None and not math.isclose(value, record, rel_tol=_SAME_ACTIVE):
            notes.append(
                f"{flag} gives {label} = {shown(value)}, but {where} records {label} = "
                f"{shown(record)} as active during the runs; using {shown(value)}"
            )
    separation = given[2][0]
    configured = user_b
    if configured is None and recorded_b is not None:
        # The recorded wheelbase, as the odometry used it unless a multiplier is given.
        configured = (
            recorded_b if separation is not None else recorded_b * (recorded.separation_multiplier)
        )
    if configured is not None and recorded_b is not None:
        used_b = configured * (1.0 if separation is None else separation)
        record_b = recorded_b * recorded.separation_multiplier
        if not math.isclose(used_b, record_b, rel_tol=_SAME_ACTIVE):
            flags = " and ".join(
                f for f in (b_flag if user_b is not None else "", given[2][1]) if f
            )
            notes.append(
                f"the odometry's wheelbase from {flags or 'the options'} is "
                f"{shown(used_b, ' m')}, but {where} records {shown(record_b, ' m')} "
                f"(wheelbase {shown(recorded_b, ' m')} times wheel_separation_multiplier "
                f"{shown(recorded.separation_multiplier)}) as active during the runs; "
                f"using {shown(used_b, ' m')}"
            )
    if user_b is None and recorded_b is not None:
        origins["wheelbase"] = recorded.origin("wheelbase")
        if separation is None:
            origins["separation_multiplier"] = recorded.origin("wheel_separation_multiplier")
    return _Chosen(
        given[0][0], given[1][0], separation, configured, diameter, tuple(notes), origins
    )


def _given_origins(
    options: ReadOptions, wheelbase: float | None, file: ControllerParams
) -> dict[str, Origin]:
    """Where the wheelbase and its multiplier come from when an option or the parameter
    file gives them."""
    params = os.fspath(options.current_params or "")
    # A previous result gives its active wheelbase and its new multiplier.
    result = bool(params) and is_result_file(params)
    origins = {}
    if wheelbase is not None:
        origins["wheelbase"] = Origin("--wheelbase")
    elif file.wheel_separation is not None:
        origins["wheelbase"] = Origin("active.wheelbase" if result else "wheel_separation", params)
    if options.current_separation_multiplier is not None:
        origins["separation_multiplier"] = Origin("--current-separation-multiplier")
    elif params:
        field = "new.wheel_separation_multiplier" if result else "wheel_separation_multiplier"
        origins["separation_multiplier"] = Origin(field, params)
    return origins


def _check_invertible(file: ControllerParams, name: str) -> None:
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
) -> LoadOptions:
    from umbmark.runs.segmentation import SplitOptions

    windows = options.time_windows
    return LoadOptions(
        unit=options.unit,
        angle_unit=options.angle_unit,
        side_length=side_length,
        params=params,
        split=cast("SplitMode", "windows" if windows else options.split),
        windows=windows,
        split_options=SplitOptions(min_rest=float(options.min_rest)),
        max_gap=float(options.max_gap),
        bag=_bag_options(options, params, file) if kind == "bag" else None,
        truth_offset=(
            (float(options.truth_offset[0]), float(options.truth_offset[1]))
            if options.truth_offset is not None
            else None
        ),
    )


def _bag_options(
    options: ReadOptions, params: WheelParams | None, file: ControllerParams
) -> BagOptions:
    from umbmark.model.kinematics import OdometryGeometry
    from umbmark.sources.bag.options import BagOptions

    geometry = None
    if params is not None:
        radius = 0.5 * params.wheel_diameter
        geometry = OdometryGeometry(
            left_radius=params.c_left * radius,
            right_radius=params.c_right * radius,
            separation=params.wheelbase,
        )
    return BagOptions(
        wheel_topic=options.wheel_topic,
        left_joint=_joints(options.left_joint) or file.left_joints or None,
        right_joint=_joints(options.right_joint) or file.right_joints or None,
        odom_topic=options.odom_topic,
        odom_tf=(options.odom_tf[0], options.odom_tf[1]) if options.odom_tf else None,
        odom_geometry=geometry,
        left_ticks_topic=options.left_ticks_topic,
        right_ticks_topic=options.right_ticks_topic,
        ticks_per_revolution=options.ticks_per_rev,
        truth_topic=options.truth_topic,
        tf_parent=options.tf_parent,
        tf_child=options.tf_child,
        time_source=cast("Literal['header', 'bag']", options.time_source),
        left_field=options.left_field,
        right_field=options.right_field,
        msg_dir=Path(options.msg_dir) if options.msg_dir is not None else None,
        truth_model=options.truth_model,
        left_wheel_frame=options.left_wheel_frame,
        right_wheel_frame=options.right_wheel_frame,
    )


def _joints(value: str | Sequence[str] | None) -> str | tuple[str, ...] | None:
    """Joint names as :class:`BagOptions` takes them (it splits and strips them)."""
    return value if value is None or isinstance(value, str) else tuple(value)


def _first(value: float | None, fallback: float) -> float:
    return fallback if value is None else value


def pool_runs(read: Sequence[Runs]) -> Runs:
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
            replace(other, runs=tuple(run.reintegrated(first.params) for run in other.runs)),
            *read[k + 1 :],
        ]
    sides = tuple(r.side_length for r in read)
    known = set(sides) - {None}
    runs = tuple(
        replace(run, label=f"{Path(r.sources[0]).name} {run.label}".strip())
        for r in read
        for run in r.runs
    )
    return Runs(
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
    )
