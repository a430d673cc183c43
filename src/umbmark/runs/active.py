"""The odometry parameters active while the runs were driven, resolved for each source,
and the runs read with them (:func:`read_each`, :func:`read_runs`).

Parameters come from three places, later ones winning: the source itself (a run log's
``metadata.yaml``, an OptiOdom session's metadata, a runs table's ``# umbmark-active:``
line; a bag says nothing), a parameter file (``current_params``: a ros2_control or ROS 1
YAML, or a previous result), and the keywords. The wheel factors and separation
multiplier a source records as active are used only where no ``current_...`` keyword or
file is given (with a note); given ones that differ from them are warned of. Messages
about a parameter name where it came from (an option, or a file's field).

Every keyword is an option of ``umbmark calibrate`` and ``umbmark replay`` with the same
name and meaning (``--current-c-l`` is ``current_c_l``); lengths in metres. Messages name
the options as the command line spells them.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path

from umbmark.core.bounds import Origin
from umbmark.core.errors import InputError, option
from umbmark.core.messages import info
from umbmark.options.spec import SIDE_LENGTH, WHEELBASE
from umbmark.runs.read import (
    Chosen,
    RunSource,
    SourceRuns,
    parameter_file,
    pool_runs,
    read_source,
    recorded_active,
    source_format,
)
from umbmark.runs.read_options import SAME_ROBOT_TOLERANCE, ReadOptions
from umbmark.sources.params.reader import (
    ControllerParams,
    is_result_file,
    result_nominal,
)
from umbmark.sources.runs_table.reader import RecordedActive

__all__ = [
    "check_same_robot",
    "choose_active",
    "read_each",
    "read_runs",
]


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
                f"or setup; give {option('override_verdict')} to use it anyway"
            )


def read_runs(
    sources: Sequence[RunSource],
    options: ReadOptions,
    *,
    wheelbase: float | None = None,
    side_length: float | None = None,
    override_verdict: bool = False,
) -> SourceRuns:
    """Read the runs of every source, with the odometry parameters the options say.

    Several sources must agree on the square's side and on the parameters that were
    active; their runs are pooled (labels then start with the source's name). A result
    file as ``current_params`` must be for the sources' nominal wheelbase and wheel
    diameter (within 1 %), unless ``override_verdict``.

    Raises
    ------
    InputError
        For bad options, a bad source, or sources that disagree.
    """
    read = read_each(
        sources,
        options,
        wheelbase=wheelbase,
        side_length=side_length,
        override_verdict=override_verdict,
    )
    return read[0] if len(read) == 1 else pool_runs(read)


def read_each(
    sources: Sequence[RunSource],
    options: ReadOptions,
    *,
    wheelbase: float | None = None,
    side_length: float | None = None,
    override_verdict: bool = False,
    stretches: bool = False,
) -> list[SourceRuns]:
    """Each source's runs read on its own, with the odometry parameters the options say
    (:func:`read_runs` before pooling; the held-out validation holds them out one by one).

    Raises
    ------
    InputError
        For bad options, a bad source, or a result file of another robot as
        ``current_params`` (without ``override_verdict``).

    ``stretches``: for an estimator that fits paths of any shape, a recording whose motion
    was all left out of its runs is read as its stretches with a reference
    (:func:`umbmark.runs.logged.runs_from_recordings`) rather than refused.
    """
    if not sources:
        raise InputError("no source given: name a runs table, run log, OptiOdom session or bag")
    if options.scan_topic is not None:
        raise InputError(
            f"{option('scan_topic')} is read by calibrate only (the wheels against the "
            "laser's scan matching), not with runs"
        )
    WHEELBASE.check(wheelbase)
    SIDE_LENGTH.check(side_length)
    file = parameter_file(options)
    read = [
        _read_one(source, options, file, wheelbase, side_length, stretches) for source in sources
    ]
    if options.current_params is not None and not override_verdict:
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
    return read


def _read_one(
    source: RunSource,
    options: ReadOptions,
    file: ControllerParams,
    wheelbase: float | None,
    side_length: float | None,
    stretches: bool = False,
) -> SourceRuns:
    """One source read with the active parameters resolved for it."""
    path, kind = source_format(source, options)
    recorded = None if path is None else recorded_active(path, kind)
    chosen = choose_active(options, file, wheelbase, recorded, note_wheelbase=kind == "table")
    return read_source(
        source, kind, options, file, chosen, side_length, recorded, stretches=stretches
    )


#: Given and recorded active parameters closer than this (relative) agree.
_SAME_ACTIVE = 1e-6


def choose_active(
    options: ReadOptions,
    file: ControllerParams,
    wheelbase: float | None,
    recorded: RecordedActive | None,
    *,
    note_wheelbase: bool = True,
) -> Chosen:
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
        return Chosen(given[0][0], given[1][0], given[2][0], user_b, diameter, (), origins)

    if all(value is None for value, _ in given):
        return _recorded_wins(recorded, user_b, b_flag, diameter, origins, note_wheelbase)
    return _given_wins(recorded, given, user_b, b_flag, diameter, origins)


def _shown(value: float, unit: str = "") -> str:
    return f"{value:.6g}{unit}"


def _recorded_wins(
    recorded: RecordedActive,
    user_b: float | None,
    b_flag: str,
    diameter: float | None,
    origins: dict[str, Origin],
    note_wheelbase: bool,
) -> Chosen:
    """Nothing said what was active: what the source records was (with a note)."""
    where, notes = recorded.where, list[str]()
    recorded_b = recorded.wheelbase
    used = [
        f"{label} = {_shown(value)}"
        for label, value in (
            ("c_L", recorded.c_left),
            ("c_R", recorded.c_right),
            ("wheel_separation_multiplier", recorded.separation_multiplier),
        )
        if value != 1.0
    ]
    if user_b is None and recorded_b is not None and note_wheelbase:
        used.append(f"wheelbase = {_shown(recorded_b, ' m')}")
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
            f"{b_flag} gives wheelbase = {_shown(user_b, ' m')}, but {where} records "
            f"wheelbase = {_shown(recorded_b, ' m')} (times wheel_separation_multiplier "
            f"{_shown(recorded.separation_multiplier)}) as active during the runs; "
            f"using {_shown(user_b, ' m')} times the recorded multiplier"
        )
    if recorded_b is not None:
        origins.setdefault("wheelbase", recorded.origin("wheelbase"))
    origins["separation_multiplier"] = recorded.origin("wheel_separation_multiplier")
    return Chosen(
        recorded.c_left,
        recorded.c_right,
        recorded.separation_multiplier,
        user_b if user_b is not None else recorded_b,
        diameter,
        tuple(notes),
        origins,
    )


def _given_wins(
    recorded: RecordedActive,
    given: Sequence[tuple[float | None, str]],
    user_b: float | None,
    b_flag: str,
    diameter: float | None,
    origins: dict[str, Origin],
) -> Chosen:
    """Something was given: it wins; the notes say where it contradicts the record."""
    where, notes = recorded.where, list[str]()
    recorded_b = recorded.wheelbase
    for (value, flag), label, record in zip(
        given[:2], ("c_L", "c_R"), (recorded.c_left, recorded.c_right), strict=True
    ):
        if value is not None and not math.isclose(value, record, rel_tol=_SAME_ACTIVE):
            notes.append(
                f"{flag} gives {label} = {_shown(value)}, but {where} records {label} = "
                f"{_shown(record)} as active during the runs; using {_shown(value)}"
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
                f"{_shown(used_b, ' m')}, but {where} records {_shown(record_b, ' m')} "
                f"(wheelbase {_shown(recorded_b, ' m')} times wheel_separation_multiplier "
                f"{_shown(recorded.separation_multiplier)}) as active during the runs; "
                f"using {_shown(used_b, ' m')}"
            )
    if user_b is None and recorded_b is not None:
        origins["wheelbase"] = recorded.origin("wheelbase")
        if separation is None:
            origins["separation_multiplier"] = recorded.origin("wheel_separation_multiplier")
    return Chosen(given[0][0], given[1][0], separation, configured, diameter, tuple(notes), origins)


def _given_origins(
    options: ReadOptions, wheelbase: float | None, file: ControllerParams
) -> dict[str, Origin]:
    """Where the wheelbase, its multiplier and the wheel diameter come from when an option
    or the parameter file gives them."""
    params = os.fspath(options.current_params or "")
    # A previous result gives its active wheelbase and its new multiplier.
    result = bool(params) and is_result_file(params)
    origins = {}
    if wheelbase is not None:
        origins["wheelbase"] = Origin(option("wheelbase"))
    elif file.wheel_separation is not None:
        origins["wheelbase"] = Origin("active.wheelbase" if result else "wheel_separation", params)
    if options.wheel_diameter is not None:
        origins["wheel_diameter"] = Origin(option("wheel_diameter"))
    elif file.wheel_radius is not None:
        origins["wheel_diameter"] = Origin("wheel_radius", params)
    if options.current_separation_multiplier is not None:
        origins["separation_multiplier"] = Origin(option("current_separation_multiplier"))
    elif params:
        field = "new.wheel_separation_multiplier" if result else "wheel_separation_multiplier"
        origins["separation_multiplier"] = Origin(field, params)
    return origins
