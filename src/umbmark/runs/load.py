"""One entry point for every source: find the format, read it, produce runs.

Formats
-------
``table``
    A runs table (CSV of end points, see :mod:`umbmark.sources.runs_table.reader`).
``log``
    An umbmark run log (folder with ``metadata.yaml`` and CSV time series, see
    :mod:`umbmark.sources.runlog.reader`), or one CSV of it.
``optiodom``
    An OptiOdom session folder (:mod:`umbmark.sources.optiodom`).
``bag``
    A ROS 1 bag (``.bag``) or ROS 2 bag (folder with ``metadata.yaml``, or its ``.db3`` /
    ``.mcap`` file or that ``metadata.yaml``) (:mod:`umbmark.sources.bag`).
``tuples``
    Motion intervals of the wheels against a laser's scan matching (a ``.tuple`` file,
    :mod:`umbmark.sources.tuples`): not runs, calibrated by the estimators of intervals
    (:func:`umbmark.calibration.scan.calibrate_intervals`); :func:`load_runs` refuses it.
``auto``
    Decide from the path: a ``.tuple`` file is tuples; a ``.bag``, ``.db3`` or ``.mcap``
    file, a folder with a ROS 2 ``metadata.yaml`` or that file is a bag; a folder with
    ``*_metadata.csv`` and ``*_run-NN.csv`` is OptiOdom; a folder (or a CSV beside) with
    umbmark's ``metadata.yaml`` is a run log (its ``metadata.yaml`` is refused: give the
    folder); any other file a runs table.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Literal, cast

from umbmark.core.bounds import Origin
from umbmark.core.conventions import axle_poses
from umbmark.core.errors import InputError, option
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import DEFAULT_MAX_GAP, PoseSeries, Recording
from umbmark.model.run import Run
from umbmark.options.spec import READ

if TYPE_CHECKING:
    from umbmark.runs.association import Association
    from umbmark.runs.logged import SplitMode
    from umbmark.runs.segmentation import SplitOptions
    from umbmark.sources.bag.bag_options import BagOptions

__all__ = ["FORMATS", "Format", "LoadOptions", "Loaded", "detect_format", "load_runs"]

Format = Literal["auto", "table", "log", "optiodom", "bag", "tuples"]
#: The formats ``--format`` takes (:data:`umbmark.options.spec.READ`; a test holds
#: :data:`Format` equal).
FORMATS = cast("tuple[Format, ...]", READ["format"].choices)


@dataclass(frozen=True)
class LoadOptions:
    """How to read a source.

    Attributes
    ----------
    unit, angle_unit : str
        Units of a runs table.
    side_length : float or None
        The square's side [m]; overrides what the source says.
    params : WheelParams or None
        Odometry parameters to integrate logged wheel data with; overrides what the
        source says.
    split : {"rests", "none", "windows", "file"}
        How to find runs in a recording; OptiOdom files are one run each whatever this
        says.
    windows : sequence of (float, float)
        Time windows [s from a recording's start] for ``split="windows"``.
    max_gap : float
        Longest ground-truth gap [s] to interpolate across.
    bag : BagOptions or None
        Topics and joints of a bag.
    truth_offset : (float, float) or None
        Where the ground truth's tracked point sits in the robot frame [m] (forward,
        left of the axle centre); the ground truth is moved to the axle centre.
    keep_stretches : bool
        A recording whose motion was all left out of its runs is read as its stretches
        with a reference, for an estimator of paths of any shape, rather than refused.
    """

    unit: str = "m"
    angle_unit: str = "rad"
    side_length: float | None = None
    params: WheelParams | None = None
    split: SplitMode = "rests"
    windows: Sequence[tuple[float, float]] = ()
    split_options: SplitOptions | None = None
    max_gap: float = DEFAULT_MAX_GAP
    bag: BagOptions | None = None
    truth_offset: tuple[float, float] | None = None
    keep_stretches: bool = False


@dataclass(frozen=True)
class Loaded:
    """Runs from a source and what is known about them.

    Attributes
    ----------
    format : str
        The format that was read.
    runs : list of Run
    params : WheelParams or None
        The parameters logged runs were integrated with (None for a runs table).
    side_length : float or None
        The square's side, from the options or the source.
    associations : list of (str, Association)
    notes : list of str
    origins : dict of str to Origin
        Where the source's own parameters are written (``wheelbase``,
        ``wheel_diameter``, ``side_length``, ``separation_multiplier``), for messages.
    stretches : list of Run
        Motion left out of the runs, in stretches with a reference
        (:func:`umbmark.runs.logged.runs_from_recordings`).
    """

    format: str
    runs: list[Run]
    params: WheelParams | None = None
    side_length: float | None = None
    associations: list[tuple[str, Association]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    origins: dict[str, Origin] = field(default_factory=dict)
    stretches: list[Run] = field(default_factory=list)


#: Bytes of a folder's ``metadata.yaml`` looked into to tell a ROS 2 bag.
_METADATA_PEEK = 1 << 16
_ROS2_KEY = re.compile(rb"^rosbag2_bagfile_information[ \t]*:", re.MULTILINE)


def _is_ros2_bag_folder(path: Path) -> bool:
    """Whether ``path/metadata.yaml`` starts a ROS 2 bag's metadata (its top-level key).

    Only the first 64 KiB are read and not parsed: a hostile file (nested thousands deep,
    an alias bomb, endless) is left to the bag reader, which turns it into one line.
    """
    meta = path / "metadata.yaml"
    if not meta.is_file():
        return False
    try:
        with meta.open("rb") as file:
            head = file.read(_METADATA_PEEK)
    except OSError:
        return False
    return _ROS2_KEY.search(head) is not None


def _regular_or_folder(path: Path) -> None:
    """Refuse a source that is neither a regular file nor a folder: a pipe, a device, a
    socket (``/dev/zero``, a FIFO) would be read forever or block."""
    if path.is_dir() or path.is_file():
        return
    raise InputError(
        "is not a regular file or folder (a device, pipe or socket): give a file", source=path
    )


def detect_format(path: str | Path) -> Format:
    """The format of ``path`` (see the module's documentation).

    Raises
    ------
    InputError
        If ``path`` does not exist or is a folder of no known layout.
    """
    # The readers' modules only where the path needs them (start-up of a runs table).
    path = Path(path)
    if not path.exists():
        raise InputError("no such file or folder", source=path)
    _regular_or_folder(path)
    if path.suffix.lower() in (".bag", ".db3", ".mcap"):
        return "bag"
    if path.suffix.lower() == ".tuple" and path.is_file():
        return "tuples"
    if path.is_dir():
        from umbmark.sources.optiodom import is_optiodom_session
        from umbmark.sources.runlog.reader import is_runlog

        if _is_ros2_bag_folder(path):
            return "bag"
        if is_optiodom_session(path):
            return "optiodom"
        if is_runlog(path):
            return "log"
        raise InputError(
            "is a folder of no known layout (a ROS 2 bag, an OptiOdom session or an umbmark "
            "run log with metadata.yaml)",
            source=path,
        )
    if path.name == "metadata.yaml":
        if _is_ros2_bag_folder(path.parent):
            return "bag"  # the bag reader takes it for its folder, as a .db3 or .mcap file
        _refuse_runlog_metadata(path)
    if path.suffix.lower() == ".csv" and not _looks_like_table(path):
        from umbmark.sources.runlog.reader import is_runlog

        if is_runlog(path):
            return "log"
    return "table"


def _refuse_runlog_metadata(path: Path) -> None:
    """Refuse the ``metadata.yaml`` of a run log given for its folder.

    Raises
    ------
    InputError
        Naming what it is and the folder to give.
    """
    from umbmark.sources.runlog.reader import is_runlog

    if is_runlog(path.parent):
        raise InputError(
            f"is an umbmark run log's metadata, not its runs: give the folder, {path.parent}",
            source=path,
        )


def _looks_like_table(path: Path) -> bool:
    from umbmark.sources.text import first_content_line

    first = first_content_line(path)  # the header only: the file may be long
    return first is not None and "direction" in first[1].lower()


def load_runs(source: str | Path, fmt: Format, options: LoadOptions) -> Loaded:
    """Read ``source`` and return its runs.

    Raises
    ------
    InputError
        Naming the file and the problem.
    """
    source = Path(source)
    if fmt != "auto" and source.exists():
        _regular_or_folder(source)
    kind = detect_format(source) if fmt == "auto" else fmt
    if kind == "tuples":
        raise InputError(
            "holds motion intervals (a tuple file), not runs: calibrate it with "
            f"{option('method', 'scan-matching')}",
            source=source,
        )
    if kind == "table":
        from umbmark.sources.runs_table.reader import read_runs_table

        if options.truth_offset is not None:
            raise InputError(
                f"{option('truth_offset')} moves recorded ground truth to the axle centre; a "
                "runs table "
                "holds end points already: measure them at the axle centre",
                source=source,
            )

        runs = read_runs_table(
            source,
            unit=options.unit,
            angle_unit=options.angle_unit,
        )
        return Loaded(format="table", runs=runs, side_length=options.side_length)

    split = options.split
    params: WheelParams | None
    read_notes: list[str] = []
    origins: dict[str, Origin] = {}
    if kind == "log":
        from umbmark.sources.runlog.reader import METADATA_FILE, read_runlog

        recordings, metadata = read_runlog(source)
        params, side = metadata.params, metadata.side_length
        if metadata.one_run_per_file:
            split = "file"
        meta = str((source if source.is_dir() else source.parent) / METADATA_FILE)
        origins = {key: Origin(key, meta) for key in ("wheelbase", "wheel_diameter", "side_length")}
        origins["separation_multiplier"] = Origin("wheel_separation_multiplier", meta)
    elif kind == "optiodom":
        from umbmark.sources.optiodom import read_optiodom

        recordings, session = read_optiodom(source)
        params, side = session.params, session.side_length
        split = "file"  # each OptiOdom file is one run
        fields = {"wheelbase": "Li", "wheel_diameter": "Di", "side_length": "L"}
        origins = {key: Origin(name, str(session.path)) for key, name in fields.items()}
    else:
        recordings, params, side = _read_bag(source, options, read_notes)
    if options.params is not None:
        params = options.params
    if params is None:
        raise InputError(
            f"needs the wheel parameters: give {option('wheelbase')} and "
            f"{option('wheel_diameter')} (or {option('current_params')} with wheel_separation "
            "and wheel_radius)",
            source=source,
        )
    if options.side_length is not None:
        side = options.side_length
    if options.truth_offset is not None:
        recordings = [_at_axle(recording, options.truth_offset) for recording in recordings]
    from umbmark.runs.logged import runs_from_recordings  # recordings only: kept off start-up

    found = runs_from_recordings(
        recordings,
        params,
        split=split,
        windows=options.windows,
        split_options=options.split_options,
        max_gap=options.max_gap,
        keep_stretches=options.keep_stretches,
    )
    if side is not None:
        from umbmark.runs.legs import check_side

        named = (
            option("side_length")
            if options.side_length is not None or "side_length" not in origins
            else origins["side_length"].named(str(source))
        )
        check_side(found.runs, side, named, params, str(source))
    return Loaded(
        format=kind,
        runs=found.runs,
        params=params,
        side_length=side,
        associations=found.associations,
        notes=[*read_notes, *found.notes],
        origins=origins,
        stretches=found.stretches,
    )


def _read_bag(
    source: Path, options: LoadOptions, notes: list[str]
) -> tuple[list[Recording], WheelParams | None, float | None]:
    """The bag's one recording; what people should know goes to ``notes``."""
    from umbmark.sources.bag.bag_options import BagOptions
    from umbmark.sources.bag.recording import read_recording

    bag = options.bag or BagOptions()
    if bag.truth_topic is None and bag.tf_parent is None and bag.tf_child is None:
        from umbmark.sources.bag.info.summary import truth_candidates
        from umbmark.sources.bag.reader import listing

        candidates, independent = truth_candidates(source)
        found = [c.label for c in candidates]
        named = (
            f"candidates: {listing(found)}"
            if found
            else f"the bag holds no reference independent of the odometry ({independent})"
            if independent
            else "the bag has no pose, odometry or TF topics"
        )
        raise InputError(
            f"no ground truth given ({option('truth_topic')} or "
            f"{option('tf_parent')}/{option('tf_child')}); {named}",
            source=source,
        )
    read = read_recording(source, bag)
    notes += read.notes
    recording = Recording(
        name=source.name,
        wheels=read.wheels,
        truth=read.truth,
        path=str(source),
        wheel_sample=_wheel_sample(bag),
        truth_name=_truth_name(bag),
    )
    return [recording], None, None


def _truth_name(bag: BagOptions) -> str:
    """The ground truth of ``bag``, for messages: ``the ground truth /odom``."""
    if bag.truth_topic is not None:
        return f"the ground truth {bag.truth_topic}"
    return f"the ground truth {bag.tf_parent} -> {bag.tf_child}"


def _wheel_sample(bag: BagOptions) -> str:
    """What one wheel sample of ``bag`` is, for messages: ``/odom message``."""
    if bag.odom_topic is not None:
        return f"{bag.odom_topic} message"
    if bag.odom_tf is not None:
        return f"{bag.odom_tf[0]}->{bag.odom_tf[1]} transform"
    if bag.left_ticks_topic is not None:
        return f"{bag.left_ticks_topic} message"
    return f"{bag.wheel_topic} message"


def _at_axle(recording: Recording, offset: tuple[float, float]) -> Recording:
    """``recording`` with its ground truth moved from the tracked point to the axle."""
    if recording.truth is None:
        return recording
    if not recording.truth.headings:
        raise InputError(
            f"{option('truth_offset')} moves the ground truth along its heading, which a "
            "position-only reference (a GNSS fix, a tracked point) does not measure: mount it "
            f"over the axle centre, or leave {option('truth_offset')} out",
            source=recording.name,
        )
    truth = PoseSeries(time=recording.truth.time, poses=axle_poses(recording.truth.poses, offset))
    return replace(recording, truth=truth)
