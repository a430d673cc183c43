"""The monitor without ROS: :class:`Monitor`, the :class:`~umbmark.monitor.status.MonitorCore`
the nodes and the simulated robot feed.

Each message goes to its chunk as it arrives (:mod:`umbmark.monitor.chunks`: the motion
matched a chunk at a time, bounded memory); each chunk joins the window (the newest
chunks holding ``window_metres`` of driving and ``window_radians`` turned each way, since
the last change; at most :data:`WINDOW_CAP` times that much driving) and the present
stretch. A stretch of ``stretch_metres`` of wheel travel is calibrated on its own
(:mod:`umbmark.monitor.estimate`), recorded in the history and followed by the change
model (:mod:`umbmark.monitor.course`); a stretch in which wheels and laser disagreed for
:data:`OUTLIER_SECONDS` or more (pushed, lifted, slipping) is left out and counted
(:attr:`MonitorStatus.outliers <umbmark.monitor.status.MonitorStatus.outliers>`). The
window's figures are what :meth:`Monitor.status` says, refitted each :data:`REFIT_METRES`.

Faults: the clock going back restarts the window and the stretch; the wheels' counts or
the odometry jumping (a controller restarted) starts a new stretch; either way the chunk
in progress is dropped, its driving kept in the odometer (which never goes back); a
message out of order is dropped and counted; a laser that matches nothing leaves its
intervals out (no estimate from them, no change). With a history the monitor's state (its
odometer as each status says it, its last apply: :mod:`umbmark.store.monitor_state`) is
kept before the status is said, and each apply recorded: a monitor started again, killed
or not, goes on from them.
"""

from __future__ import annotations

import math
import time as wall_clock
from collections import Counter, deque
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from umbmark.estimators.registry import GYRO, SCAN_MATCHING
from umbmark.monitor.arrivals import Arrivals, WheelAngles
from umbmark.monitor.chunks import Chunk, ChunkMaker, Driving
from umbmark.monitor.corrected import Integrator, WheelCalibration
from umbmark.monitor.course import Z95, Course, StretchPoint
from umbmark.monitor.estimate import Estimate, Held, estimate
from umbmark.monitor.setup import Input, MonitorSetup
from umbmark.monitor.status import (
    FIGURES,
    ChangeFound,
    CorrectedOdometry,
    Figure,
    Level,
    MonitorStatus,
)
from umbmark.robot.base import ApplyResult, DriveParams, Pose2D, ScanSweep

if TYPE_CHECKING:
    from umbmark.monitor.apply import Offer

__all__ = [
    "OUTLIER_SECONDS",
    "REFIT_METRES",
    "WINDOW_CAP",
    "Monitor",
    "change_line",
    "make_monitor",
]
__all__ += ["said"]

#: A stretch in which wheels and laser disagreed this long [s] is left out.
OUTLIER_SECONDS = 2.0
#: The window is refitted after this much new wheel travel [m].
REFIT_METRES = 5.0
#: The window holds at most this many times ``window_metres`` of wheel travel.
WINDOW_CAP = 10.0
#: Wheel rotation [rad] between readings under which the wheels stand still.
_STILL = 1e-3
#: A robot clock past this [s] is a clock of days (ROS time); before, it started at 0.
_EPOCH_CLOCK = 1e9
#: The monitor's state is written into the history at most this often [s of wall time]:
#: every status of a node (1 Hz), not every second of a simulation run faster.
_SAVE_EVERY = 0.5


class Monitor:
    """The monitor's core (the module's notes; :class:`MonitorCore
    <umbmark.monitor.status.MonitorCore>`'s methods)."""

    def __init__(self, setup: MonitorSetup) -> None:
        self.setup = setup
        self.params = setup.params
        self.arrivals = Arrivals()
        self.angles = WheelAngles(setup.wheel_radii, self.params.wheelbase)
        self.maker = ChunkMaker(setup.wheel_radii, self.params.wheelbase, setup.scan_period,
                                laser="scan" in setup.inputs)  # fmt: skip
        if setup.laser is not None:
            self.maker.mount = (setup.laser.x, setup.laser.y, setup.laser.theta)
        self._mounted = setup.laser is not None
        self.window: deque[tuple[float, Chunk]] = deque()
        self.stretch: list[Chunk] = []
        self.course = Course()
        self.odometer = 0.0
        self.restarts = 0
        self.outliers = 0
        self.stretches = 0
        self.left_out: Counter[str] = Counter()
        self.confirmed: dict[tuple[str, float], ChangeFound] = {}
        self._since_odometer = 0.0
        self._breaks = 0
        self._wheel_kind: Input | None = None
        self._since: float | None = None
        self._fit: Estimate | None = None
        self._fitted_at = -math.inf
        self._travel = 0.0
        self._epoch: float | None = None
        self._latest = -math.inf  # the latest time arrived (since the clock last went back)
        self._wall_floor = -math.inf  # the wall clock at the end of the history's last stretch
        self._moved_at: float | None = None
        self._last_angles: tuple[float, float] | None = None
        self._applied_line: str | None = None
        self._applied_at_odometer = -math.inf
        self._offered: DriveParams | None = None
        self._offer: Offer | None = None
        self._saved_odometer, self._saved_at = -math.inf, -math.inf
        self.integrator = Integrator(self._calibration(None))
        self._store = None
        if setup.history is not None:
            from umbmark.store.history import History

            self._store = History(setup.history)
            self._take_up()

    # --- what it is fed --------------------------------------------------------------

    def wheels(self, time: float, left: float, right: float) -> None:
        if self._arrived("wheels", time) and self._in_order("wheels", time):
            self._wheel_step("wheels", time, self.angles.from_wheels(time, left, right))

    def odometry(self, time: float, pose: Pose2D) -> None:
        if self._arrived("odometry", time) and self._in_order("odometry", time):
            self._wheel_step("odometry", time, self.angles.from_odometry(time, pose))

    def scan(self, sweep: ScanSweep) -> None:
        if not self._arrived("scan", sweep.time):
            return
        if not self._mounted:
            m = sweep.mount
            self.maker.mount, self._mounted = (m.x, m.y, m.theta), True
        self.maker.scan(sweep)

    def gyro(self, time: float, yaw_rate: float) -> None:
        if self._arrived("imu", time) and math.isfinite(yaw_rate):
            self.maker.gyro(time, yaw_rate)

    def _arrived(self, kind: str, time: float) -> bool:
        said = self.arrivals.arrive(kind, time)  # type: ignore[arg-type]
        if self._epoch is None and said == "ok":
            # a simulation's clock (from 0) on the wall clock from now, after the history's
            self._epoch = 0.0 if time > _EPOCH_CLOCK else max(wall_clock.time(),
                                                              self._wall_floor) - time  # fmt: skip
        if said == "back":
            if self._epoch:  # a simulation's clock: the wall clock of its stretches goes on
                self._epoch = max(wall_clock.time(), self._latest + self._epoch) - time
            self._latest = time
            self._restart()
            return True
        if said == "ok":
            self._latest = max(self._latest, time)
        return said == "ok"

    def _restart(self) -> None:
        """The clock went back (a simulation reset): the window and the stretch restart."""
        self.restarts += 1
        self._drop_chunk()
        self.angles.reset()
        self.window.clear()
        self.stretch = []
        self._fit, self._moved_at, self._last_angles = None, None, None
        self.integrator.time = None
        self._since_odometer = self.odometer

    def _drop_chunk(self) -> None:
        """The chunk in progress forgotten (a restart): its driving kept in the odometer,
        which never goes back."""
        pending = self.maker.pending()
        self.odometer += pending.metres
        self._travel += pending.travel
        self.maker.reset()

    def _in_order(self, kind: Input, time: float) -> bool:
        """Whether a wheel reading comes after the last one taken of either kind (a node
        feeds the odometry until joint states with the wheels come, then those, stamped
        by another clock's cycle): one that does not is dropped and counted, so that the
        wheels' times in a chunk always increase."""
        last = self.angles.time
        if last is not None and time <= last:
            self.arrivals.dropped[f"{kind}: not after the last wheel reading"] += 1
            return False
        return True

    def _wheel_step(self, kind: Input, time: float, continued: bool) -> None:
        switched = self._wheel_kind not in (None, kind)  # the odometry, then joint states
        self._wheel_kind = kind
        if not continued and (switched or self.angles.breaks != self._breaks):
            # a controller restarted, or the wheels from another source: a new chunk
            self._breaks = self.angles.breaks
            self._drop_chunk()
            self.stretch = []
        angles = self.angles.angles
        if (
            self._last_angles is None
            or max(abs(angles[0] - self._last_angles[0]), abs(angles[1] - self._last_angles[1]))
            > _STILL
        ):
            self._moved_at, self._last_angles = time, angles
        self.maker.wheels(time, *angles)
        self.integrator.update(time, angles)
        while (chunk := self.maker.make()) is not None:
            self._take(chunk)

    # --- chunks, stretches, the window -----------------------------------------------

    def _take(self, chunk: Chunk) -> None:
        self.left_out.update(chunk.left_out)
        self.window.append((self.odometer, chunk))
        self.odometer += chunk.driving.metres
        self._travel += chunk.driving.travel
        self._trim_window()
        if chunk.moved:
            self.stretch.append(chunk)
        travel = sum(c.driving.travel for c in self.stretch)
        if travel >= self.setup.stretch_metres:
            self._close_stretch(self.stretch)
            self.stretch = []

    def _trim_window(self) -> None:
        s = self.setup
        while len(self.window) > 1:
            rest = Driving()
            for _, c in list(self.window)[1:]:
                rest = rest + c.driving
            enough = (rest.metres >= s.window_metres and rest.left >= s.window_radians
                      and rest.right >= s.window_radians)  # fmt: skip
            if not (enough or rest.travel > WINDOW_CAP * s.window_metres):
                break
            self.window.popleft()

    def _close_stretch(self, chunks: list[Chunk]) -> None:
        disagreed = sum(c.disagreeing_seconds for c in chunks)
        if disagreed >= OUTLIER_SECONDS:
            self.outliers += 1
            return
        laser, gyro = "scan" in self.setup.inputs, "imu" in self.setup.inputs
        window = self.window_estimate() if laser else None
        held = None if window is None else Held.of(window, self.params.wheel_separation)
        found = estimate(chunks, self.params, laser=laser, gyro=gyro, held=held)
        if not found.values:
            self.left_out["stretch determined nothing"] += 1
            return
        self.stretches += 1
        start = chunks[0].start
        odometer = self.odometer - sum(c.driving.metres for c in chunks)
        wall = start + (self._epoch or 0.0)
        for name, (value, se) in found.values.items():
            self.course.add(name, StretchPoint(value, se, start, odometer, wall))
        self._record(found, start, chunks[-1].end, odometer)
        self._judge()

    def _judge(self) -> None:
        """The changes the course shows; a newly confirmed one restarts the window."""
        b = self.params.wheel_separation
        for name in self.course.points:
            _, found = self.course.found(name, self.setup.tolerance, b)
            if found is None or not found.confirmed:
                continue
            key = (name, round(found.since_metres, 3))
            if key not in self.confirmed and found.since_metres > self._since_odometer:
                self._since_odometer, self._since = found.since_metres, found.since
                kept = [(o, c) for o, c in self.window if o >= found.since_metres - 1e-6]
                self.window = deque(kept)
                self._fit = None
            self.confirmed[key] = found

    def _record(self, found: Estimate, start: float, end: float, odometer: float) -> None:
        if self._store is None:
            return
        from umbmark.store.monitor_stretches import StretchRecord, record_stretch

        active = _active(self.params)
        epoch = self._epoch or 0.0
        method = SCAN_MATCHING.name if found.params is not None or found.held else GYRO.name
        record = StretchRecord(self.setup.robot, method, start + epoch, end + epoch, start,
                               odometer, self.odometer, found.values, active)  # fmt: skip
        record_stretch(self._store, record)

    def _take_up(self) -> None:
        """The course (and the odometer) from the history: a monitor started again."""
        from umbmark.monitor.course import MAX_STRETCHES
        from umbmark.store.monitor_state import read_state
        from umbmark.store.monitor_stretches import read_stretches

        assert self._store is not None
        stretches = read_stretches(self._store, self.setup.robot, MAX_STRETCHES)
        for s in stretches:
            for name, (value, se) in s.figures.items():
                self.course.add(name, StretchPoint(value, se, s.time, s.odometer, s.wall_start))
        if stretches:
            self._wall_floor = stretches[-1].wall_end
            self.odometer = self._since_odometer = stretches[-1].end_odometer
            self.stretches = len(stretches)
            self._judge()
        state = read_state(self._store, self.setup.robot)
        if state is not None:  # as it last said it, the chunk then in progress included
            self.odometer = self._saved_odometer = max(self.odometer, state.odometer)
            if state.applied_odometer is not None:
                self._applied_at_odometer = state.applied_odometer

    # --- what it says ----------------------------------------------------------------

    def window_estimate(self) -> Estimate | None:
        """The window's figures, refitted each :data:`REFIT_METRES` of wheel travel."""
        if self._fit is None or self._travel - self._fitted_at >= REFIT_METRES:
            chunks = [c for _, c in self.window if c.moved]
            if not chunks:
                return self._fit
            self._fit = estimate(chunks, self.params, laser="scan" in self.setup.inputs,
                                 gyro="imu" in self.setup.inputs)  # fmt: skip
            self._fitted_at = self._travel
            if self._fit.params is not None:
                self.maker.params = self._fit.params
                self.integrator.calibration = self._calibration(self._fit)
        return self._fit

    def _calibration(self, fit: Estimate | None) -> WheelCalibration:
        r_left, r_right = self.setup.wheel_radii
        if fit is None or fit.params is None:
            return WheelCalibration(r_left, r_right, self.params.wheelbase)
        p = fit.params
        se = {n: fit.values.get(n, (0.0, 0.0))[1] for n in ("E_d", "E_b", "E_s")}
        return WheelCalibration(float(p[0]), float(p[1]), float(p[2]),
                           se["E_s"] * float(p[0]), se["E_s"] * float(p[1]),
                           se["E_b"] * self.params.wheel_separation)  # fmt: skip

    def changes(self) -> tuple[ChangeFound, ...]:
        """The confirmed changes since the start, oldest first, then those to be confirmed."""
        b = self.params.wheel_separation
        latest = []
        for name in self.course.points:
            _, found = self.course.found(name, self.setup.tolerance, b)
            if found is not None and not found.confirmed:
                latest.append(found)
        done = sorted(self.confirmed.values(), key=lambda c: (c.since_metres, c.figure))
        return (*done, *latest)

    def status(self, now: float) -> MonitorStatus:
        status = said(self, now)
        if (
            self._store is not None
            and status.odometer > self._saved_odometer
            and wall_clock.monotonic() - self._saved_at >= _SAVE_EVERY
        ):
            self._save(status.odometer)  # before it is said: a monitor killed goes on from it
        return status

    def _save(self, odometer: float) -> None:
        """The monitor's state into the history (a history that cannot be written is
        counted, ``left_out``, and the monitor goes on)."""
        from umbmark.core.errors import InputError
        from umbmark.store.monitor_state import MonitorState, save_state

        assert self._store is not None
        applied = None if math.isinf(self._applied_at_odometer) else self._applied_at_odometer
        try:
            save_state(self._store, self.setup.robot, MonitorState(odometer, applied))
        except InputError:
            self.left_out["history not written"] += 1
            return
        self._saved_odometer, self._saved_at = odometer, wall_clock.monotonic()

    def corrected(self) -> CorrectedOdometry | None:
        return self.integrator.odometry()

    def rested(self, now: float) -> float:
        """How long the wheels have stood still at ``now`` [s]."""
        return 0.0 if self._moved_at is None else max(0.0, now - self._moved_at)

    def apply_due(self, now: float) -> DriveParams | None:
        from umbmark.monitor.apply import offer

        if self.setup.apply != "at-rest" or self.rested(now) < self.setup.rest_time:
            return None
        if self.integrator.time is None or now - self.integrator.time > self.setup.stale_after:
            return None  # the wheels are silent: not known to rest
        pending = [c for c in self.confirmed.values() if c.figure in ("E_d", "E_b", "E_s")
                   and c.since_metres > self._applied_at_odometer]  # fmt: skip
        if not pending:
            return None
        present = {n: v for n in ("E_d", "E_b", "E_s") if (v := self.course.present(n))}
        found = offer(present, self.params)
        if found is None or not found.verdict.applies:
            return None
        self._offered, self._offer = found.params, found
        return found.params

    def applied(self, now: float, result: ApplyResult) -> None:
        offered, offer = self._offered, self._offer
        self._offered = self._offer = None
        if offered is None:
            return
        said = f"applied at {now:.1f} s: {offered}" if result.active else "not applied"
        self._applied_line = f"{said} ({result.method}: {result.message})"
        if not result.active:
            return
        before = self.params
        self.params = offered
        self.setup = replace(self.setup, params=offered)
        self.angles.radii, self.angles.separation = self.setup.wheel_radii, offered.wheelbase
        self._applied_at_odometer = self.odometer
        if self._store is not None and offer is not None:
            from umbmark.core.errors import InputError

            try:
                self._record_applied(now, before, offer, result)
            except InputError:
                self.left_out["history not written"] += 1
            self._save(max(self._saved_odometer, self.odometer))

    def _record_applied(
        self, now: float, before: DriveParams, offer: Offer, result: ApplyResult
    ) -> None:
        """The apply into the history: a calibration marked applied."""
        from umbmark.store.monitor_state import AppliedRecord, record_applied

        assert self._store is not None
        present = {n: v for n in ("E_d", "E_b", "E_s") if (v := self.course.present(n))}
        new = offer.params
        record = AppliedRecord(
            self.setup.robot, SCAN_MATCHING.name if "scan" in self.setup.inputs else GYRO.name,
            now + (self._epoch or 0.0), self.odometer, present, _active(before),
            {"c_L": new.left_wheel_radius_multiplier, "c_R": new.right_wheel_radius_multiplier,
             "wheel_separation_multiplier": new.wheel_separation_multiplier},
            offer.verdict.to_dict(), f"{result.method}: {result.message}"[:200],
        )  # fmt: skip
        record_applied(self._store, record)


def _active(p: DriveParams) -> dict[str, float]:
    """The controller's parameters as the history records them."""
    return {"wheelbase": p.wheel_separation, "wheel_diameter": 2.0 * p.wheel_radius,
            "c_L": p.left_wheel_radius_multiplier, "c_R": p.right_wheel_radius_multiplier,
            "wheel_separation_multiplier": p.wheel_separation_multiplier}  # fmt: skip


def make_monitor(found: Any) -> Monitor:  # noqa: ANN401 (umbmark.monitor.ros2_node.Found)
    """The core a ROS node makes from what it found (``Found``: the options' values by
    keyword, its :class:`~umbmark.monitor.ros_node.NodeOptions`, the controller's
    parameters, whether sim time runs): the monitor's options of
    :data:`umbmark.options.monitor.MONITOR` from the values, the inputs from the topics;
    the topics' silence the node's to judge (``judge_silence`` off).

    Raises
    ------
    InputError
        Without the controller's parameters (the wheels' geometry is needed).
    """
    from umbmark.core.errors import InputError, option
    from umbmark.options.monitor import MONITOR

    options, values = found.options, dict(found.values)
    if found.params is None:
        raise InputError("the controller's parameters did not come: the monitor needs its "
                         f"wheel radius and separation (give {option('params_file')})")  # fmt: skip
    kept = {k: values[k] for k in MONITOR if k in values and values[k] is not None}
    kept.pop("robot", None)
    wheels: Input = "wheels" if getattr(options, "wheel_topic", "") else "odometry"
    inputs: tuple[Input, ...] = (wheels,)
    inputs += ("scan",) if getattr(options, "scan_topic", None) else ()
    inputs += ("imu",) if getattr(options, "imu_topic", None) else ()
    history = values.get("history")  # the history given (none without it)
    setup = MonitorSetup(
        str(getattr(options, "robot", "") or values.get("robot") or "robot"), found.params,
        getattr(options, "laser_mount", None), inputs=inputs, judge_silence=False,
        history=None if history is None else str(history), **kept,
    )  # fmt: skip
    return Monitor(setup)


# --- what it says ----------------------------------------------------------------------


def change_line(change: ChangeFound, odometer: float) -> str:
    """One change for people: ``E_d changed by -0.0060 +- 0.0004 since 482.0 s, 41 m
    ago``."""
    sure = "" if change.confirmed else " (to be confirmed by the next stretch)"
    beyond = " beyond the tolerance" if change.beyond_tolerance else ""
    ago = max(0.0, odometer - change.since_metres)
    return (
        f"{change.figure} changed{beyond} by {change.size:+.4g} +- {change.size_half_width:.2g} "
        f"since {change.since:.1f} s, {ago:.0f} m ago{sure}"
    )


def _figures(monitor: Monitor) -> tuple[Figure, ...]:
    fit = monitor.window_estimate()
    out = []
    for name, unit in FIGURES:
        if fit is not None and name in fit.values:
            value, se = fit.values[name]
            out.append(Figure(name, value, Z95 * se, unit, fit.notes.get(name, "")))
            continue
        present = monitor.course.present(name)
        if present is not None and (fit is None or fit.intervals == 0):
            out.append(Figure(name, present[0], Z95 * present[1], unit, "from the course"))
            continue
        note = "no driving yet" if fit is None else fit.notes.get(name, "not determined")
        out.append(Figure(name, None, None, unit, note))
    return tuple(out)


def said(monitor: Monitor, now: float) -> MonitorStatus:
    """The monitor's status at ``now`` [s]."""
    s = monitor.setup
    figures = _figures(monitor)
    changes = monitor.changes()
    pending = [c for c in changes if c.confirmed and c.since_metres > monitor._applied_at_odometer]
    stale: tuple[str, ...] = ()
    if s.judge_silence and monitor.arrivals.last:
        stale = monitor.arrivals.silent(now, s.inputs, s.stale_after)
    level: Level = "OK"
    if pending:
        level = "ERROR" if any(c.beyond_tolerance for c in pending) else "WARN"
    if stale:
        level = "STALE"
    odometer = monitor.odometer + monitor.maker.pending().metres  # the chunk in progress too
    lines = [change_line(c, odometer) for c in changes if c in pending or not c.confirmed]
    if stale:
        lines.insert(0, f"silent for more than {s.stale_after:g} s: {', '.join(stale)}")
    if not lines:
        lines.append(f"no change over {monitor.stretches} stretches of driving "
                     f"({odometer:.0f} m)")  # fmt: skip
    window = monitor.window_estimate()
    driving = window.driving if window is not None else None
    return MonitorStatus(
        time=now,
        robot=s.robot,
        level=level,
        message="; ".join(lines),
        figures=figures,
        metres=0.0 if driving is None else driving.metres,
        radians_left=0.0 if driving is None else driving.left,
        radians_right=0.0 if driving is None else driving.right,
        odometer=odometer,
        since=monitor._since,
        changes=changes,
        stale=stale,
        outliers=monitor.outliers,
        applied=monitor._applied_line,
    )
