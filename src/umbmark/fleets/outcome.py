"""One recording of a fleet calibrated by what it holds: a plain function that knows
nothing of the engine it runs on.

:func:`calibrate_recording` looks into the recording (:func:`~umbmark.sources.bag.info.
summary.bag_info`: topics, wheels, a laser, an independent reference, the robot's
description) and calibrates it through the calls ``umbmark calibrate`` makes
(:func:`~umbmark.calibration.sources.calibrate_sources`):

- **scan matching** where it holds wheels (or the controller's odometry) and a laser: the
  wheels' diameters, the wheelbase, ``E_s`` and the laser's mounting from ordinary driving;
  with an IMU too (``sensor_msgs/Imu`` with a gyro and a mounting, as ``umbmark info``
  finds it), **the gyro and the laser together** (``method="gyro"`` with both topics): the
  same figures, and the gyro's scale ``k_g`` and bias;
- **a trajectory fit** where it holds an independent reference (motion capture) and no
  laser, and for a run log or an OptiOdom session (wheels and motion capture by format);
- **the gyro** where it holds wheels and an IMU and neither a laser nor a reference:
  ``E_d``, and ``E_b`` relative to the gyro, followed as its own figure ``E_b_gyro``
  (``E_b k_g``: never compared with a laser's ``E_b`` of the same robot), and the gyro's
  bias;
- else it is **left out**, with the reason.

The reading options the user gave (``--truth-topic``, ``-b``, ...) win over what the look
into the recording suggests: a reference given replaces the suggested one whole
(:data:`REFERENCE`), and a ``truth_topic`` the recording does not hold leaves it out,
whichever way it would be calibrated. What comes back, :class:`RecordingOutcome`, is a small value
(picklable: the engine's workers send it back), with each figure and its standard error,
E_max,syst projected on the standard 4 m square, the multipliers to configure, and the
recording's robot, start, length and digest. A recording that cannot be read comes back
failed with its one-line reason, never as an exception.
"""

from __future__ import annotations

import datetime as dt
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from umbmark.core.conventions import Direction
from umbmark.core.errors import InputError, ProblemError
from umbmark.estimators.registry import GYRO, SCAN_MATCHING, TRAJECTORY
from umbmark.fleets.naming import UNNAMED

__all__ = [
    "FIGURES",
    "GYRO_FIGURES",
    "LOGGED",
    "REFERENCE",
    "STANDARD_SIDE",
    "RecordingOutcome",
    "RecordingTask",
    "calibrate_recording",
    "e_max_on_standard_square",
]

#: The figures a fleet follows per robot, in this order: the wheels', the laser's, and the
#: gyro's (``E_b_gyro``: ``E_b k_g``, what wheels and a gyro give without an absolute
#: heading, kept apart from ``E_b``; ``k_g``, the gyro's scale; ``gyro_bias`` [rad/s]).
FIGURES = ("E_d", "E_b", "E_s", "laser_x", "laser_y", "laser_yaw", "E_b_gyro", "k_g", "gyro_bias")
#: The estimate's components the gyro's figures are (figure: component).
GYRO_FIGURES = {"k_g": "gyro_scale", "gyro_bias": "gyro_bias"}
#: The square E_max,syst is projected on [m] (the paper's).
STANDARD_SIDE = 4.0
#: Recordings that are wheels and motion capture by their format (no bag to look into).
LOGGED = ("log", "optiodom")


@dataclass(frozen=True)
class RecordingTask:
    """One recording to calibrate.

    Attributes
    ----------
    path : str
        The recording.
    robot : str or None
        Its robot from the path's pattern; None: from the recording.
    day : datetime.date or None
        Its day from the path's pattern; None: from the recording's clock.
    options : mapping of str to object
        Reading options by keyword (as :func:`umbmark.calibrate` takes them), for every
        recording.
    per_robot : mapping of str to mapping
        Robots' own reading options by robot name, which win over ``options`` for the
        robot the recording turns out to be (:meth:`options_for`): for a robot named by
        the pattern, its own entry; for one named only inside the recording, every entry.
    """

    path: str
    robot: str | None = None
    day: dt.date | None = None
    options: Mapping[str, Any] = field(default_factory=dict)
    per_robot: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)

    def options_for(self, robot: str) -> dict[str, Any]:
        """The reading options of this recording once its robot is known: ``options``,
        and over them the robot's own."""
        return {**self.options, **self.per_robot.get(robot, {})}


@dataclass(frozen=True)
class RecordingOutcome:
    """What one recording gave.

    Attributes
    ----------
    path : str
    robot : str
        The robot (the pattern's, else the recording's namespace or robot description,
        else ``unnamed``; of one that cannot be read, as :mod:`umbmark.fleets.naming`
        says).
    start : float or None
        When the recording started [s since 1970, UTC]: the pattern's day at midnight
        where given, else the recording's first message.
    hours : float
        Its length [h].
    digest : str or None
        SHA-256 of its bytes.
    method : str or None
        ``scan-matching``, ``gyro`` or ``trajectory``; None when left out or failed.
    figures : dict of str to (float, float or None)
        Each of :data:`FIGURES` it measured: value and standard error (metres, radians).
    e_max_syst : float or None
        E_max,syst [m] these errors make on the standard 4 m square driven by the
        odometry (both directions, the worse), from ``E_d``, ``E_b``, ``E_s``; None from
        ``E_b`` relative to the gyro.
    multipliers : tuple of float or None
        ``(wheel_separation_multiplier, left, right)`` to configure.
    verdict : str or None
        ``apply``, ``care`` or ``do-not-apply``.
    reason : str or None
        Why it was left out or failed (one line); None when calibrated.
    failed : bool
        It could not be read (``reason`` says why), as opposed to left out.
    wheelbase : float or None
        The nominal wheelbase [m] of the calibration.
    named_by : str or None
        How its robot was found: ``pattern``, ``namespace``, ``description``, ``path`` (a
        recording that cannot be read, by a robot's name in its path:
        :mod:`umbmark.fleets.naming`); None where nothing named it.
    record : dict
        What the history records of the calibration (``calibrate --json``'s
        ``standard_errors``, ``active``, ``new``, ``verdict`` and the nominal wheel
        diameter), and what to apply: ``overlay``, the controller's parameter overlay
        (YAML text; None where the verdict is do not apply), ``mounting``, the laser's
        (:meth:`umbmark.outputs.mounting.MountingForms.to_dict`; None without a laser), and
        ``controller``, the controller's keys in the user's file (``key_path``) and whether
        anything named it (``named``); empty when not calibrated.
    """

    path: str
    robot: str
    start: float | None
    hours: float
    digest: str | None
    method: str | None = None
    figures: dict[str, tuple[float, float | None]] = field(default_factory=dict)
    e_max_syst: float | None = None
    multipliers: tuple[float, float, float] | None = None
    verdict: str | None = None
    reason: str | None = None
    failed: bool = False
    wheelbase: float | None = None
    record: dict[str, Any] = field(default_factory=dict)
    named_by: str | None = None

    @property
    def calibrated(self) -> bool:
        """Whether the recording gave a calibration."""
        return self.method is not None

    @property
    def status(self) -> str:
        """``calibrated``, ``left out`` or ``failed``."""
        return "calibrated" if self.calibrated else "failed" if self.failed else "left out"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (metres, radians, seconds); :meth:`of_dict` reads it back."""
        return {
            "path": self.path,
            "robot": self.robot,
            "start": self.start,
            "hours": self.hours,
            "digest": self.digest,
            "status": self.status,
            "method": self.method,
            "figures": {k: list(v) for k, v in self.figures.items()},
            "e_max_syst": self.e_max_syst,
            "multipliers": None if self.multipliers is None else list(self.multipliers),
            "verdict": self.verdict,
            "reason": self.reason,
            "wheelbase": self.wheelbase,
            "named_by": self.named_by,
            "record": self.record,
        }

    @classmethod
    def of_dict(cls, data: Mapping[str, Any]) -> RecordingOutcome:
        """The outcome :meth:`to_dict` gave."""
        multipliers = data.get("multipliers")
        return cls(
            str(data["path"]),
            str(data["robot"]),
            data.get("start"),
            float(data.get("hours") or 0.0),
            data.get("digest"),
            method=data.get("method"),
            figures={k: (float(v[0]), v[1]) for k, v in dict(data.get("figures") or {}).items()},
            e_max_syst=data.get("e_max_syst"),
            multipliers=None if multipliers is None else tuple(multipliers),
            verdict=data.get("verdict"),
            reason=data.get("reason"),
            failed=data.get("status") == "failed",
            wheelbase=data.get("wheelbase"),
            record=dict(data.get("record") or {}),
            named_by=data.get("named_by"),
        )


def _keywords(flags: tuple[tuple[str, str], ...]) -> dict[str, str]:
    """Command-line options (``("--truth-topic", "/mocap/pose")``) as keywords."""
    from umbmark.options.spec import READ_OPTIONS

    by_flag = {flag: spec.name for spec in READ_OPTIONS for flag in spec.flags}
    return {by_flag[flag]: value for flag, value in flags if flag in by_flag}


_NAMESPACE = re.compile(r"^/([^/]+)/")


def _given(task: RecordingTask) -> tuple[str, str | None]:
    """The robot the pattern gave a recording, and how it was named; ``unnamed`` and None
    where it gave none."""
    return (task.robot, "pattern") if task.robot else (UNNAMED, None)


def _robot_of(info: Any, given: str | None) -> tuple[str, str | None]:  # noqa: ANN401 (BagInfo)
    """The robot and how it was named: the pattern's, else the namespace most of the bag's
    topics share, else the name in its robot description, else ``unnamed``."""
    if given:
        return given, "pattern"
    names: dict[str, int] = {}
    for topic in info.topics:
        match = _NAMESPACE.match(topic.name)
        if match is not None and match[1] not in ("tf", "tf_static", "rosout", "parameter_events"):
            names[match[1]] = names.get(match[1], 0) + 1
    if names and max(names.values()) * 2 > len(info.topics):
        return max(names, key=lambda n: names[n]), "namespace"
    described = "" if info.robot is None else str(getattr(info.robot, "name", ""))
    return (described, "description") if described else (UNNAMED, None)


def _start(info: Any, day: dt.date | None) -> float | None:  # noqa: ANN401 (BagInfo or None)
    if day is not None:
        return dt.datetime(day.year, day.month, day.day, tzinfo=dt.timezone.utc).timestamp()
    return None if info.start is None else float(info.start)


def e_max_on_standard_square(E_d: float, E_b: float, E_s: float, wheelbase: float) -> float | None:
    """E_max,syst [m] these errors make on the standard 4 m square driven by the odometry
    (:func:`umbmark.model.square.square_run_end`, both directions, the worse)."""
    from umbmark.model.square import square_run_end

    worst = 0.0
    for direction in (Direction.CW, Direction.CCW):
        end = square_run_end(E_d, E_b, E_s, STANDARD_SIDE, wheelbase, direction)
        worst = max(worst, math.hypot(float(end[0]), float(end[1])))
    return worst if math.isfinite(worst) else None


#: The reading options that name a recording's reference (a pose topic, or a TF pair):
#: one given, the reference the look into the recording suggests is not used at all (its
#: options would mix with the user's: a topic beside the user's TF pair).
REFERENCE = ("truth_topic", "tf_parent", "tf_child")


def _plan(info: Any, options: Mapping[str, Any]) -> tuple[str | None, dict[str, Any], str]:  # noqa: ANN401
    """How to calibrate the bag: the method, its reading options, and a reason. The
    user's reading options win over what the look suggests; a reference the user gave is
    a trajectory fit's where the bag holds no laser, whatever the look made of it."""
    inputs = info.wheels[:1] or info.odometry[:1]
    reading: dict[str, Any] = {}
    if inputs:
        reading.update(_keywords(inputs[0].options))
    missing = _missing_truth(info, options.get("truth_topic"))
    if missing is not None:
        return None, {}, missing
    imus = [imu.topic for imu in info.imus if imu.problem is None]
    if imus and options.get("imu_topic") is None:
        reading["imu_topic"] = imus[0]
    gyro = bool(imus) or options.get("imu_topic") is not None
    if info.laser_scans and inputs:
        reading["scan_topic"] = info.laser_scans[0]
        method = GYRO.name if gyro else SCAN_MATCHING.name
        return method, {**_without_imu(reading, gyro), **options}, ""
    given = any(options.get(name) is not None for name in REFERENCE)
    truth = [c for c in info.truth if c.warning is None]
    if inputs and (given or (truth and info.independent)):
        if not given:
            reading.update(_keywords(truth[0].options))
        return TRAJECTORY.name, {**_without_imu(reading, False), **options}, ""
    if inputs and gyro:
        return GYRO.name, {**reading, **options}, ""
    if not inputs:
        return None, {}, "no wheels or controller odometry found"
    if info.imus:  # an IMU, and what makes it no gyro to calibrate by (as calibrate says)
        imu = info.imus[0]
        return (
            None,
            {},
            (
                "neither a laser scan, a usable IMU nor an independent reference (motion "
                f"capture): {info.path}: {imu.topic}: {imu.problem}"
            ),
        )
    return None, {}, "neither a laser scan, an IMU nor an independent reference (motion capture)"


def _without_imu(reading: dict[str, Any], gyro: bool) -> dict[str, Any]:
    """The reading options, the IMU's left out where the gyro is not used."""
    return reading if gyro else {k: v for k, v in reading.items() if k != "imu_topic"}


def _missing_truth(info: Any, topic: str | None) -> str | None:  # noqa: ANN401 (BagInfo)
    """The reason to leave the bag out where the user's truth topic is not in it (as the
    reader says it: the topics there), whichever way it is calibrated; None where it is,
    none was given, or the look listed only some of the bag's topics."""
    names = {t.name: t.msgtype for t in info.topics}
    if topic is None or topic in names or info.topics_not_listed:
        return None
    from umbmark.sources.bag.reader import missing_topic

    return _line(missing_topic(topic, "ground truth", names, info.path))


def _figures(result: Any) -> dict[str, tuple[float, float | None]]:  # noqa: ANN401
    est = result.estimate
    se = dict(est.standard_errors)
    comp = est.components
    out: dict[str, tuple[float, float | None]] = {"E_d": (float(est.E_d), se.get("E_d"))}
    if "E_b_gyro" in comp and "gyro_scale" not in comp:  # E_b k_g: the gyro's, kept apart
        out["E_b_gyro"] = (float(comp["E_b_gyro"]), se.get("E_b_gyro"))
    else:
        out["E_b"] = (float(est.E_b), se.get("E_b"))
    for name, key in GYRO_FIGURES.items():
        if key in comp:
            out[name] = (float(comp[key]), se.get(key))
    if est.E_s is not None:
        out["E_s"] = (float(est.E_s), se.get("E_s"))
    sensor = result.sensor
    if sensor is not None:
        sse = sensor.standard_errors
        for k, name in enumerate(("laser_x", "laser_y", "laser_yaw")):
            out[name] = (float(sensor.laser_pose[k]), float(sse[name]))
    return out


def calibrate_recording(task: RecordingTask) -> RecordingOutcome:
    """Calibrate one recording by what it holds (see the module).

    Parameters
    ----------
    task : RecordingTask

    Returns
    -------
    RecordingOutcome
        Calibrated, left out (``reason``) or failed (``failed``, ``reason``): never an
        exception for a recording that cannot be read. A recording at a URL is copied
        first (:func:`_remote`); its outcome keeps the URL, redacted.
    """
    from umbmark.sources.remote import is_url

    if is_url(task.path):
        return _remote(task)
    return _local(task, Path(task.path), None)


def _remote(task: RecordingTask) -> RecordingOutcome:
    """A recording at a URL streamed into a private temporary folder
    (:func:`umbmark.sources.remote.fetched`: its SHA-256 taken on the way), calibrated
    there, and the copy deleted whatever happens; the outcome (its path, its reason, the
    overlay's provenance) names the URL redacted (:func:`~umbmark.sources.remote.redacted`:
    no user, password or signature), never the copy: the URL as given is only read."""
    from dataclasses import replace

    from umbmark.sources.remote import fetched, redacted

    shown = redacted(task.path)
    try:
        with fetched(task.path) as (local, digest):
            outcome = _local(task, local, digest)
    except InputError as exc:
        robot, how = _given(task)
        return RecordingOutcome(shown, robot, None, 0.0, None, reason=redacted(_line(exc)),
                                failed=True, named_by=how)  # fmt: skip
    url = shown.rstrip("/")
    overlay = outcome.record.get("overlay")
    record = dict(outcome.record)
    if overlay:
        record["overlay"] = redacted(overlay.replace(str(local), url))
    reason = None if outcome.reason is None else redacted(outcome.reason.replace(str(local), url))
    return replace(outcome, path=shown, reason=reason, record=record)


def _local(task: RecordingTask, path: Path, digest: str | None) -> RecordingOutcome:
    """``task``'s recording read at ``path`` (itself, or its local copy); ``digest``: its
    SHA-256 where already taken."""
    from umbmark.core.digest import path_sha256
    from umbmark.runs.load import detect_format

    robot, how = _given(task)
    try:
        digest = digest or path_sha256(path)
        kind = detect_format(path)
        if kind in LOGGED:
            return _logged(task, path, digest, kind)
        info = _bag_info(path, kind)
    except (InputError, ProblemError, OSError) as exc:
        return RecordingOutcome(task.path, robot, None, 0.0, None, reason=_line(exc), failed=True,
                                named_by=how)  # fmt: skip
    robot, how = _robot_of(info, task.robot)
    start, hours = _start(info, task.day), info.duration / 3600.0
    method, options, reason = _plan(info, task.options_for(robot))
    if method is None:
        return RecordingOutcome(task.path, robot, start, hours, digest, reason=reason,
                                named_by=how)  # fmt: skip
    try:
        result = _calibrate(path, method, options)
    except (InputError, ProblemError) as exc:
        return RecordingOutcome(task.path, robot, start, hours, digest, reason=_line(exc),
                                named_by=how)  # fmt: skip
    return _calibrated(task.path, robot, start, hours, digest, method, result, how)


def _calibrated(
    path: str,
    robot: str,
    start: float | None,
    hours: float,
    digest: str | None,
    method: str,
    result: Any,  # noqa: ANN401 (CalibrationResult)
    named_by: str | None,
) -> RecordingOutcome:
    """The outcome of a recording that gave a calibration."""
    figures = _figures(result)
    cal = result.calibration
    wheelbase = float(cal.active.wheelbase)
    E_s = figures.get("E_s", (1.0, None))[0]
    e_max = (  # none from E_b relative to the gyro: the gyro's scale tolerance is in it
        None
        if "E_b" not in figures
        else e_max_on_standard_square(figures["E_d"][0], figures["E_b"][0], E_s, wheelbase)
    )
    return RecordingOutcome(
        path,
        robot,
        start,
        hours,
        digest,
        method=method,
        figures=figures,
        e_max_syst=e_max,
        multipliers=(cal.new_separation_multiplier, cal.new_c_left, cal.new_c_right),
        verdict=result.verdict.level,
        wheelbase=wheelbase,
        record=_record(result),
        named_by=named_by,
    )


def _logged(task: RecordingTask, path: Path, digest: str | None, kind: str) -> RecordingOutcome:
    """A run log or an OptiOdom session at ``path`` (itself, or its local copy): wheels and
    motion capture, so a trajectory fit."""
    robot, how = _given(task)
    try:
        result = _calibrate(path, TRAJECTORY.name, task.options_for(robot))
    except (InputError, ProblemError) as exc:
        start = _start(None, task.day) if task.day else _logged_start(path, kind, ())
        return RecordingOutcome(task.path, robot, start, 0.0, digest, reason=_line(exc),
                                named_by=how)  # fmt: skip
    logs = [r.log for r in result.runs if r.log is not None]
    start = _start(None, task.day) if task.day else _logged_start(path, kind, logs)
    hours = sum(float(log.time[-1] - log.time[0]) for log in logs) / 3600.0
    return _calibrated(task.path, robot, start, hours, digest, TRAJECTORY.name, result, how)


#: A run log's clock that reads after this [s since 1970] is a clock of days (ROS time).
_EPOCH_CLOCK = 1e9


def _logged_start(path: Path, kind: str, logs: Sequence[Any]) -> float:
    """When a run log or an OptiOdom session was recorded [s since 1970]: an OptiOdom
    session's id, a run log's time column where it is a clock of days (ROS time), else
    the time its files were last written."""
    from umbmark.sources.optiodom import session_start

    found = session_start(path) if kind == "optiodom" else None
    first = min((float(log.start) for log in logs), default=0.0)
    if found is None and first > _EPOCH_CLOCK:
        found = first
    if found is not None:
        return found
    files = [p for p in path.rglob("*") if p.is_file()] if path.is_dir() else [path]
    return max((p.stat().st_mtime for p in files), default=path.stat().st_mtime)


def _record(result: Any) -> dict[str, Any]:  # noqa: ANN401 (CalibrationResult)
    """What the history keeps of a calibration: its figures' record, and what to apply in
    the forms a user applies it (the controller's overlay, keyed as its controller is,
    only where the verdict lets it be applied; the laser's mounting as a URDF origin and
    static transforms)."""
    from umbmark.outputs.mounting import mounting_forms

    data = result.to_dict()
    forms = mounting_forms(result)
    return {
        "standard_errors": data.get("standard_errors") or {},
        "active": data.get("active") or {},
        "new": data.get("new") or {},
        "verdict": data.get("verdict") or {},
        "wheel_diameter": result.calibration.active.wheel_diameter,
        "overlay": None if result.overlay_withheld else result.overlay_yaml(),
        "mounting": None if forms is None else forms.to_dict(),
        "gyro_calibration": None if result.gyro is None else result.gyro.to_apply(),
        "controller": {
            "key_path": list(result.controller.key_path),
            "named": bool(result.controller.named),
        },
    }


def _bag_info(path: Path, kind: str) -> Any:  # noqa: ANN401 (BagInfo)
    from umbmark.sources.bag.info.summary import bag_info

    if kind != "bag":
        raise InputError("is not a recording (a ROS bag, MCAP, run log or OptiOdom session)",
                         source=path)  # fmt: skip
    return bag_info(path)


def _calibrate(path: Path, method: str, options: Mapping[str, Any]) -> Any:  # noqa: ANN401
    from umbmark.calibration.sources import calibrate_sources
    from umbmark.runs.read_options import ReadOptions

    wheelbase = options.get("wheelbase")
    reading = {k: v for k, v in options.items() if k != "wheelbase"}
    fit = None if method in (SCAN_MATCHING.name, GYRO.name) else method
    return calibrate_sources([str(path)], ReadOptions.of(reading), method=fit, wheelbase=wheelbase)


def _line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__
