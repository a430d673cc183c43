"""The monitor's node without ROS: messages in (already values), the status out once a
second (:class:`MonitorLoop`), shared by the ROS 1 and ROS 2 nodes and tested without them.

Every message is handed to the core under one lock (ROS 1 calls back from one thread per
topic); a topic silent for ``stale_after`` wall seconds is said STALE, and the monitor goes
on when it speaks again; the status is published from a wall-clock loop (a ``/clock`` that
stops or jumps back stops no diagnostics); applying happens at rest where asked; a fault in
one message is one line, not a traceback. The monitor publishes no velocity.
"""

from __future__ import annotations

import math
import signal
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from types import FrameType

from umbmark.monitor.diagnostics import PERIOD
from umbmark.monitor.ros_node import NodeOptions
from umbmark.monitor.status import CorrectedOdometry, MonitorCore, MonitorStatus
from umbmark.robot.base import ApplyResult, DriveParams, Pose2D, ScanSweep

__all__ = ["MonitorLoop", "Outputs", "Silence", "run_ticks", "stop_on_signals", "stopped_line"]
__all__ += ["with_stale"]


# --- silence ---------------------------------------------------------------------------------


class Silence:
    """When each topic last spoke (wall clock, ``time.monotonic()``), and which are silent
    longer than ``after`` seconds: a ``required`` topic (the wheels) from the start, the
    others (a laser, an IMU the robot may not have) once they have spoken."""

    def __init__(
        self, topics: Iterable[str], after: float, now: float, required: Iterable[str] = ()
    ) -> None:
        self.after = after
        self._last = dict.fromkeys(topics, now)
        self._spoke: set[str] = set()
        self._required = set(required)

    def heard(self, topic: str, now: float) -> None:
        """``topic`` spoke at ``now``."""
        self._last[topic] = now
        self._spoke.add(topic)

    def silent(self, now: float) -> tuple[str, ...]:
        """The topics silent longer than ``after``, in their order."""
        return tuple(
            t
            for t, last in self._last.items()
            if now - last > self.after and (t in self._spoke or t in self._required)
        )

    def spoke(self, topic: str) -> bool:
        """Whether ``topic`` ever spoke."""
        return topic in self._spoke


def with_stale(status: MonitorStatus, silent: Sequence[str]) -> MonitorStatus:
    """``status`` with the node's silent topics: STALE, naming them, the core's own
    figures kept."""
    if not silent:
        return status
    stale = tuple(dict.fromkeys((*status.stale, *silent)))
    message = f"silent: {', '.join(stale)}; {status.message}" if status.message else ""
    return replace(
        status, level="STALE", stale=stale, message=message or "silent: " + ", ".join(stale)
    )


# --- the loop ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Outputs:
    """Where the loop's results go (the ROS node's publishers, a test's lists)."""

    diagnostics: Callable[[MonitorStatus], None]
    corrected: Callable[[CorrectedOdometry], None] | None
    apply: Callable[[DriveParams], ApplyResult] | None
    say: Callable[[str], None]


class MonitorLoop:
    """The node without ROS: messages in (already values), the status out at 1 Hz.

    Parameters
    ----------
    core : MonitorCore
    options : NodeOptions
    outputs : Outputs
    now : callable
        The robot's clock [s] (ROS time: sim time where ``/clock`` runs).
    wheels_topic : str
        The topic the wheels come on (joint states or the odometry), for its silence.
    """

    def __init__(
        self,
        core: MonitorCore,
        options: NodeOptions,
        outputs: Outputs,
        now: Callable[[], float],
        wheels_topic: str,
    ) -> None:
        self.core = core
        self.options = options
        self.outputs = outputs
        self.now = now
        self.wheels_topic = wheels_topic
        self._lock = threading.Lock()
        self._silence = Silence(
            (wheels_topic, *options.topics()),
            options.stale_after,
            time.monotonic(),
            required=(wheels_topic,),
        )
        self._faults: dict[str, float] = {}
        self.faults = 0
        self._level: str | None = None
        self._stale: tuple[str, ...] = ()
        self._applied: str | None = None
        self._last_corrected: float | None = None
        self.published = 0
        self._stopped = False

    def stop(self) -> None:
        """The node stops: messages still queued in its subscriptions (ROS goes on calling
        back while it shuts down) are not taken, nor said, after its last line."""
        self._stopped = True

    # --- messages in (from any thread) ----------------------------------------------

    def _fault(self, what: str, exc: BaseException) -> None:
        """One line per kind of fault a minute at most; counted."""
        if self._stopped:  # a publisher closed under a callback as the node stops
            return
        self.faults += 1
        wall = time.monotonic()
        if wall - self._faults.get(what, -math.inf) >= 60.0:
            self._faults[what] = wall
            detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            self.outputs.say(f"umbmark_monitor: a {what} left out ({detail[:200]})")

    def wheels(self, stamp: float, left: float, right: float) -> None:
        """The wheels' angles at ``stamp``."""
        self._feed("wheels", self.wheels_topic, lambda: self.core.wheels(stamp, left, right))
        self._corrected()

    def odometry(self, stamp: float, pose: Pose2D) -> None:
        """The controller's odometry pose (where no joint states come)."""
        self._feed("odometry", self.wheels_topic, lambda: self.core.odometry(stamp, pose))
        self._corrected()

    def heard(self, topic: str) -> None:
        """``topic`` spoke (the odometry while joint states feed the wheels)."""
        self._silence.heard(topic, time.monotonic())

    def scan(self, make: Callable[[], ScanSweep]) -> None:
        """A laser sweep (made inside, so that a bad one is a fault, not a traceback)."""
        topic = self.options.scan_topic or "scan"
        self._feed("scan", topic, lambda: self.core.scan(make()))

    def gyro(self, make: Callable[[], tuple[float, float]]) -> None:
        """A gyro reading ``(stamp, yaw rate in the base frame)``."""

        def feed() -> None:
            stamp, rate = make()
            self.core.gyro(stamp, rate)

        self._feed("IMU message", self.options.imu_topic or "imu", feed)

    def _feed(self, what: str, topic: str, call: Callable[[], None]) -> None:
        if self._stopped:
            return
        self._silence.heard(topic, time.monotonic())
        try:
            with self._lock:
                call()
        except Exception as exc:  # a message the core cannot take: said, not raised
            self._fault(what, exc)

    def _corrected(self) -> None:
        publish = self.outputs.corrected
        if publish is None or self._stopped:
            return
        try:
            with self._lock:
                corrected = self.core.corrected()
            if corrected is None or corrected.time == self._last_corrected:
                return
            self._last_corrected = corrected.time
            publish(corrected)
        except Exception as exc:
            self._fault("corrected odometry", exc)

    # --- once a second ---------------------------------------------------------------

    def tick(self) -> MonitorStatus | None:
        """The status published (and the apply made, where due); None on a fault."""
        try:
            now = self.now()
            with self._lock:
                status = self.core.status(now)
            status = with_stale(status, self._silence.silent(time.monotonic()))
            if status.applied is None and self._applied is not None:
                status = replace(status, applied=self._applied)
            self.outputs.diagnostics(status)
            self.published += 1
            self._say_changes(status)
            if self.options.apply == "at-rest" and self.outputs.apply is not None:
                self._apply(now)
            return status
        except Exception as exc:
            self._fault("status", exc)
            return None

    def _say_changes(self, status: MonitorStatus) -> None:
        """A line on the terminal where the level or the silent topics change."""
        if status.level != self._level or status.stale != self._stale:
            if self._stale and not status.stale:
                self.outputs.say(f"umbmark_monitor: {', '.join(self._stale)} back: going on")
            self.outputs.say(f"umbmark_monitor: {status.level}: {status.message}")
            self._level, self._stale = status.level, status.stale

    def _apply(self, now: float) -> None:
        with self._lock:
            params = self.core.apply_due(now)
        if params is None or self.outputs.apply is None:
            return
        values = ", ".join(
            f"{k} {getattr(params, k):.6g}"
            for k in ("wheel_separation_multiplier", "left_wheel_radius_multiplier",
                      "right_wheel_radius_multiplier")
        )  # fmt: skip
        self.outputs.say(f"umbmark_monitor: the robot is at rest: applying {values}")
        try:
            result = self.outputs.apply(params)
        except Exception as exc:  # InputError, SafetyError: not applied, said
            detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            result = ApplyResult("none", False, f"not applied: {detail}")
        self._applied = f"{result.method}: {result.message}"[:400]
        self.outputs.say(f"umbmark_monitor: applied ({self._applied})")
        with self._lock:
            self.core.applied(self.now(), result)


def stop_on_signals() -> threading.Event:
    """An event set by SIGINT or SIGTERM (Ctrl-C, ``kill``, a launch file's shutdown),
    with the signal's name kept as its ``signal_name`` attribute; the main thread waits on
    it."""
    stop = threading.Event()

    def handler(signum: int, _frame: FrameType | None) -> None:
        stop.signal_name = signal.Signals(signum).name  # type: ignore[attr-defined]
        stop.set()

    signal.signal(signal.SIGINT, handler)
    signal.signal(signal.SIGTERM, handler)
    return stop


def run_ticks(loop: MonitorLoop, stop: threading.Event, period: float = PERIOD) -> None:
    """Call ``loop.tick()`` every ``period`` wall seconds until ``stop`` is set (in the
    calling thread)."""
    next_tick = time.monotonic()
    while not stop.is_set():
        loop.tick()
        next_tick += period
        delay = next_tick - time.monotonic()
        if delay < 0.0:  # behind (a slow apply): go on from now
            next_tick, delay = time.monotonic(), 0.0
        stop.wait(delay)


def stopped_line(stop: threading.Event, loop: MonitorLoop, started: float) -> str:
    """The one line said when the node stops."""
    why = getattr(stop, "signal_name", "stopped")
    minutes = (time.monotonic() - started) / 60.0
    return (
        f"umbmark_monitor stopped ({why}) after {minutes:.1f} min: {loop.published} statuses "
        f"published, {loop.faults} messages left out"
    )
