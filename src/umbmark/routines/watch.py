"""What a person watching a self-calibration is told, as it happens.

- :class:`Watch` carries the routine's three callbacks: the live status (what the robot is
  doing now), lines said once (a check's result, a run's return error, a pass's result),
  and the runs done out of those planned with an estimate of the time left
  (:class:`RunsLeft`). The library reports; a command renders.
- :class:`Stopped` is what an interrupted or stopped routine leaves: what the controller
  holds, which passes are on disk. It rides on the exception that stopped the routine
  (:func:`stopped`), raised after the zero velocity was sent.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from umbmark.core.conventions import Direction
from umbmark.core.messages import duration_words
from umbmark.routines.record import return_error_words

__all__ = ["Progress", "RunsLeft", "Stopped", "Watch", "stopped"]

#: Live status: (pass label, run number, direction, what), shown and replaced.
Progress = Callable[[str, int, Direction | None, str], None]


@dataclass(frozen=True)
class RunsLeft:
    """How far the routine is: runs driven out of those planned, and the time left.

    Attributes
    ----------
    done, planned : int
        Runs driven and measured so far; runs planned in all (every pass the routine may
        still drive, the verification included; fewer once the 3 x SEM rule says no
        further pass is worth it).
    seconds_left : float or None
        The wall time left [s], estimated from the mean time of the runs so far (each run
        with its return to the start and its fixes); None before the first run ends.
    """

    done: int
    planned: int
    seconds_left: float | None

    def text(self) -> str:
        """``3 of 30 runs, about 12 min left``."""
        seconds = self.seconds_left
        left = "" if seconds is None else f", about {duration_words(seconds)} left"
        return f"{self.done} of {self.planned} runs{left}"


def _wall() -> float:
    """The wall clock the time left is estimated on [s]."""
    return time.monotonic()


@dataclass
class Watch:
    """The routine's callbacks and its count of runs.

    Parameters
    ----------
    progress : callable, optional
        The live status (:data:`Progress`).
    notify : callable, optional
        Lines said once, as they happen.
    runs_left : callable, optional
        Called with a :class:`RunsLeft` as each pass begins and each run ends.
    runs : int
        Runs per direction in a pass.
    clock : callable, optional
        Wall time [s] [default: :func:`time.monotonic`]: a person's minutes, not the
        robot's clock.
    """

    progress: Progress | None = None
    notify: Callable[[str], None] | None = None
    runs_left: Callable[[RunsLeft], None] | None = None
    runs: int = 5
    clock: Callable[[], float] | None = None
    done: int = 0
    planned: int = 0
    _began: float | None = field(default=None, repr=False)

    def status(self, label: str, k: int, direction: Direction | None, what: str) -> None:
        if self.progress is not None:
            self.progress(label, k, direction, what)

    def say(self, line: str) -> None:
        if self.notify is not None:
            self.notify(line)

    def begin_pass(self, passes_left: int) -> None:
        """A pass begins; ``passes_left``: it and those that may follow it."""
        if self._began is None:
            self._began = self._now()
        self.planned = self.done + 2 * self.runs * max(passes_left, 0)
        self._report()

    def run_measured(
        self, label: str, k: int, direction: Direction, error: tuple[float, float, float]
    ) -> None:
        """A run ended and was measured: its return error (Eq. 3.1, ``eps_x``, ``eps_y``
        [m], ``eps_theta`` [rad]: the corner fixes against the odometry,
        :func:`umbmark.routines.record.return_error`), and the runs left."""
        self.done += 1
        self.planned = max(self.planned, self.done)
        number = (k - 1) % self.runs + 1
        self.say(
            f"{label}, run {k} of {2 * self.runs} ({direction.value} {number} of {self.runs}): "
            f"return error {return_error_words(error)} (the corner fixes against the odometry)"
        )
        self._report()

    def left(self) -> RunsLeft:
        seconds = None
        if self._began is not None and self.done > 0:
            per_run = (self._now() - self._began) / self.done
            seconds = per_run * (self.planned - self.done)
        return RunsLeft(self.done, self.planned, seconds)

    def _now(self) -> float:
        return _wall() if self.clock is None else self.clock()

    def _report(self) -> None:
        if self.runs_left is not None:
            self.runs_left(self.left())


@dataclass(frozen=True)
class Stopped:
    """What a routine stopped mid-way leaves (after the zero velocity was sent).

    Attributes
    ----------
    holds : str
        What the controller holds now: the last pass applied or the parameters it started
        with, with the multipliers (one sentence).
    passes : tuple of str
        The labels of the passes recorded on disk.
    folder : Path or None
        Where they are (None: the routine was given no folder, nothing was kept).
    unfinished : tuple of (Path, int)
        The run-log folders of passes driven but not finished (their runs recorded, the
        calibration not done), with the number of runs each holds.
    """

    holds: str
    passes: tuple[str, ...]
    folder: Path | None
    unfinished: tuple[tuple[Path, int], ...] = ()

    def text(self) -> str:
        """``the controller holds ...; on disk: pass 1 in DIR``, without the command."""
        holds = self.holds.rstrip(".")
        holds = holds[:1].lower() + holds[1:]
        if self.folder is None:
            disk = "no pass kept (no folder was given)"
        elif not self.passes and not self.unfinished:
            disk = f"no pass finished, nothing in {self.folder}"
        else:
            disk = f"{', '.join(self.passes)} in {self.folder}" if self.passes else ""
            driven = [
                f"{n} run{'s' if n != 1 else ''} of a pass not calibrated in {where} (umbmark "
                f"calibrate {where} reads them)"
                for where, n in self.unfinished
            ]
            disk = "; ".join(([disk] if disk else ["no pass finished"]) + driven)
        return f"{holds}; on disk: {disk}"


def stopped(exc: BaseException) -> Stopped | None:
    """The :class:`Stopped` a self-calibration left on the exception that stopped it."""
    found = getattr(exc, "umbmark_stopped", None)
    return found if isinstance(found, Stopped) else None


def mark_stopped(exc: BaseException, stop: Stopped) -> None:
    """Leave ``stop`` on ``exc`` for :func:`stopped` (the first one stays)."""
    if stopped(exc) is None:
        exc.umbmark_stopped = stop  # type: ignore[attr-defined]
