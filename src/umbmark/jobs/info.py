"""The info job: what is in a source, so that a user can pick the options to read it.

:func:`info` is what ``umbmark info`` does. For a ROS bag: every topic with its type,
count, rate and duration, the joints of the joint-state topics and which of them move,
the transforms and their chains, the candidates for the wheels, the controller's
odometry and the ground truth, the IMUs and their mountings, and the options they suggest
(:mod:`umbmark.sources.bag.info.summary`). For a run log or an OptiOdom session: its files, runs,
duration and wheel parameters. A runs table has nothing to look into and is refused.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from umbmark.core.errors import InputError, option
from umbmark.core.jsontext import JsonText
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import Recording
from umbmark.runs.load import FORMATS, detect_format

if TYPE_CHECKING:
    from umbmark.sources.bag.info.summary import BagInfo

__all__ = ["FileInfo", "InfoReport", "LoggedInfo", "info"]

#: Files of a run log or session listed at most.
MAX_FILES = 50
#: Most messages --max-messages may ask to deserialize per topic (time and memory grow
#: with it; a topic with more is sampled).
MAX_MESSAGES = 1_000_000


@dataclass(frozen=True)
class FileInfo:
    """One recording (file) of a run log or OptiOdom session.

    Attributes
    ----------
    name : str
    wheel_samples, truth_samples : int
        Samples with wheel data and with ground truth.
    start : float
        Time of the first wheel sample on the file's clock [s].
    duration : float
        From the first to the last wheel sample [s].
    """

    name: str
    wheel_samples: int
    truth_samples: int
    start: float
    duration: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the attributes by name (seconds)."""
        return {
            "name": self.name,
            "wheel_samples": self.wheel_samples,
            "truth_samples": self.truth_samples,
            "start": self.start,
            "duration": self.duration,
        }


@dataclass(frozen=True)
class LoggedInfo:
    """A run log or an OptiOdom session, in short.

    Attributes
    ----------
    files : tuple of FileInfo
        At most :data:`MAX_FILES`; ``files_not_listed`` more.
    runs : int or None
        The runs ``calibrate`` finds with its default options; None if it finds none
        (``runs_problem`` says why).
    duration : float
        The files' durations added [s].
    params : WheelParams
        The nominal wheel parameters the source gives.
    side_length : float or None
        The square's side [m], if the source gives it.
    """

    files: tuple[FileInfo, ...]
    files_not_listed: int
    runs: int | None
    runs_problem: str | None
    duration: float
    params: WheelParams
    side_length: float | None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (metres, seconds)."""
        p = self.params
        return {
            "files": [f.to_dict() for f in self.files],
            "files_not_listed": self.files_not_listed,
            "runs": self.runs,
            "runs_problem": self.runs_problem,
            "duration": self.duration,
            "wheel_parameters": {
                "wheelbase": p.wheelbase,
                "wheel_diameter": p.wheel_diameter,
                "wheel_diameter_left": p.diameter_left,
                "wheel_diameter_right": p.diameter_right,
                "encoder_resolution": p.encoder_resolution,
                "gear_ratio": p.gear_ratio,
            },
            "side_length": self.side_length,
        }


@dataclass(frozen=True, repr=False)
class InfoReport(JsonText):
    """What is in a source.

    Attributes
    ----------
    source : str
        The path looked into.
    format : str
        ``bag``, ``log`` or ``optiodom``.
    bag : BagInfo or None
        For a bag: topics, joints, transforms, candidates
        (:class:`umbmark.sources.bag.info.summary.BagInfo`).
    logged : LoggedInfo or None
        For a run log or an OptiOdom session.
    """

    source: str
    format: str
    bag: BagInfo | None = None
    logged: LoggedInfo | None = None

    def __repr__(self) -> str:
        if self.bag is not None:
            bag = self.bag
            return (
                f"InfoReport(source={self.source!r}, format='bag', storage={bag.storage!r}, "
                f"topics={len(bag.topics) + bag.topics_not_listed}, "
                f"duration={bag.duration:.6g} s, suggested={self.suggested_options!r})"
            )
        logged = self.logged
        assert logged is not None
        return (
            f"InfoReport(source={self.source!r}, format={self.format!r}, "
            f"files={len(logged.files) + logged.files_not_listed}, runs={logged.runs}, "
            f"duration={logged.duration:.6g} s)"
        )

    @property
    def suggested_options(self) -> str | None:
        """Bags: the options to read the wheels and the ground truth with
        (``--truth-topic /mocap/pose --left-joint ...``); None when nothing fits or for
        other sources (which need no options)."""
        return None if self.bag is None else self.bag.suggested_options

    @property
    def notes(self) -> tuple[str, ...]:
        """What people should know about the source that is information."""
        return () if self.bag is None else self.bag.notes

    @property
    def warnings(self) -> tuple[str, ...]:
        """What people should know about the source that is doubtful."""
        if self.bag is not None:
            return self.bag.warnings
        if self.logged is not None and self.logged.runs_problem is not None:
            return (f"no runs found: {self.logged.runs_problem}",)
        return ()

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (seconds, hertz, metres, radians): what
        ``umbmark info --json`` prints.

        Keys: ``source``, ``format``; for bags ``storage``, ``start`` [s since 1970],
        ``duration``, ``messages``, ``max_messages``, ``complete``, ``topics`` (``name``,
        ``type``, ``count``, ``rate``, ``duration``, ``scanned``), ``topics_not_listed``,
        ``joint_states`` (``topic``, ``scanned``, ``complete``, ``joints``: ``name``,
        ``samples``, ``position_range``, ``max_speed``, ``moving``, ``speed_from``),
        ``transforms`` (``parent``, ``child``, ``topic``, ``static``, ``count``, ``rate``,
        ``moving``, ``turns_only``), ``chains``, ``candidates`` (``wheels``,
        ``odometry``, ``truth``: ``kind``, ``label``, ``options``, ``moving``, ``rate``,
        ``max_gap``, ``warning``, ``headings``), ``model_states`` (``topic``,
        ``scanned``, ``models``: ``name``, ``samples``, ``position_range``, ``moving``),
        ``robot_description`` (``wheelbase``, ``wheel_diameter``, ``left_joints``,
        ``right_joints``, ``topic``; or None), ``robot_description_problem``, ``needs``
        (the options still needed for the wheel geometry), ``independent_reference``,
        ``suggested_options``, ``laser_scans`` (the ``sensor_msgs/LaserScan`` topics),
        ``scan_options`` (the options of ``calibrate --scan-topic``, or None), ``imus``
        (``topic``, ``rate``, ``frame``, ``gyro``, ``mounting``: ``base``, ``rpy``,
        ``source``; ``problem``), ``notes``,
        ``warnings``; for run logs and OptiOdom sessions
        ``files``, ``runs``, ``duration``, ``wheel_parameters``, ``side_length``, ``notes``,
        ``warnings``.
        """
        out: dict[str, Any] = {"source": self.source, "format": self.format}
        if self.bag is not None:
            out.update(self.bag.to_dict())
        elif self.logged is not None:
            out.update(self.logged.to_dict())
            out["suggested_options"] = None
            out["notes"] = list(self.notes)
            out["warnings"] = list(self.warnings)
        return out


def info(
    source: str | os.PathLike[str],
    *,
    max_messages: int | None = None,
    format: str = "auto",
) -> InfoReport:
    """Look into a ROS bag, a run log or an OptiOdom session.

    What ``umbmark info`` does, with the same options as keywords.

    Parameters
    ----------
    source : path
        A ROS 1 ``.bag`` file, a ROS 2 bag folder (or its ``.db3``/``.mcap`` file), a
        run-log folder (or one CSV of it) or an OptiOdom session folder.
    max_messages : int, optional
        Bags: messages deserialized per topic at most (default
        :data:`umbmark.sources.bag.info.summary.DEFAULT_MAX_MESSAGES`, at most
        :data:`MAX_MESSAGES`); a topic with more is sampled in stretches spread over its
        time span.
    format : {"auto", "bag", "log", "optiodom"}
        The source's format; ``auto`` decides by the path.

    Returns
    -------
    InfoReport

    Raises
    ------
    InputError
        The source cannot be read, or is a runs table (nothing to look into).

    Examples
    --------
    >>> report = umbmark.info("run.bag")
    >>> report.suggested_options
    '--truth-topic /mocap/pose --left-joint wheel_left_joint --right-joint wheel_right_joint'
    """
    name = os.fspath(source)
    if format not in FORMATS:
        raise InputError(f"{option('format', repr(format))}: use one of {', '.join(FORMATS)}")
    if max_messages is not None and (
        isinstance(max_messages, bool)
        or not isinstance(max_messages, int)
        or not 1 <= max_messages <= MAX_MESSAGES
    ):
        raise InputError(
            f"{option('max_messages', str(max_messages)[:24])}: must be at least 1 and at most "
            f"{MAX_MESSAGES}"
        )
    kind = detect_format(name) if format == "auto" else format
    if kind == "table":
        raise InputError(
            "is read as a runs table (end points measured by hand): there is nothing to look"
            " into; umbmark info looks into ROS bags, run logs and OptiOdom sessions",
            source=name,
        )
    if kind == "tuples":
        from umbmark.estimators.registry import INTERVALS

        raise InputError(
            "holds motion intervals (a tuple file): umbmark info looks into ROS bags, run logs "
            "and OptiOdom sessions; calibrate it with "
            f"{option('method', ' or '.join(INTERVALS))}",
            source=name,
        )
    if kind == "bag":
        from umbmark.sources.bag.info.summary import DEFAULT_MAX_MESSAGES, bag_info

        limit = DEFAULT_MAX_MESSAGES if max_messages is None else max_messages
        return InfoReport(source=name, format="bag", bag=bag_info(name, max_messages=limit))
    return InfoReport(source=name, format=kind, logged=_logged_info(Path(name), kind))


def _logged_info(path: Path, kind: str) -> LoggedInfo:
    """A run log (``kind="log"``) or OptiOdom session in short."""
    from umbmark.runs.load import LoadOptions, load_runs

    recordings: list[Recording]
    if kind == "log":
        from umbmark.sources.runlog.reader import read_runlog

        recordings, metadata = read_runlog(path)
        params, side = metadata.params, metadata.side_length
    else:
        from umbmark.sources.optiodom import read_optiodom

        recordings, session = read_optiodom(path)
        params, side = session.params, session.side_length
    files = [
        FileInfo(
            name=r.name,
            wheel_samples=int(r.wheels.time.size),
            truth_samples=0 if r.truth is None else int(r.truth.time.size),
            start=float(r.wheels.time[0]),
            duration=float(r.wheels.time[-1] - r.wheels.time[0]),
        )
        for r in recordings
    ]
    runs: int | None = None
    problem: str | None = None
    try:
        runs = len(load_runs(path, "log" if kind == "log" else "optiodom", LoadOptions()).runs)
    except InputError as err:
        problem = err.problem
    return LoggedInfo(
        files=tuple(files[:MAX_FILES]),
        files_not_listed=max(len(files) - MAX_FILES, 0),
        runs=runs,
        runs_problem=problem,
        duration=float(sum(f.duration for f in files)),
        params=params,
        side_length=side,
    )
