"""What a fleet's calibrations say, robot by robot: the latest figures with their
intervals, each figure's course over time (steady, a step since a recording, a trend per
week: :func:`umbmark.calibration.changes.change_of`), what to apply, and the robots with no
usable recording and why.

:func:`summarize` takes every recording's outcome (:class:`~umbmark.fleets.outcome.
RecordingOutcome`, from this run or from the history) and returns a
:class:`FleetSummary`; the page and the JSON of ``umbmark fleet`` render it.
"""

from __future__ import annotations

import datetime as dt
import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from umbmark.calibration.changes import FOLLOWED, Change, change_of, followed_of
from umbmark.fleets.outcome import FIGURES, STANDARD_SIDE, RecordingOutcome
from umbmark.fleets.present import (
    UNCONFIRMED,
    ToApply,
    present_e_max_syst,
    robot_terms,
    to_apply,
)
from umbmark.model.scans import LaserMounting
from umbmark.outputs.mounting import MountingForms

__all__ = ["FIGURE_UNITS", "FigureTrack", "FleetSummary", "RobotSummary", "summarize"]

#: The figures a robot's controller takes (the others are the laser's and the gyro's).
WHEELS = ("E_d", "E_b", "E_s")
#: ``E_b`` where only the gyro gave it: relative to the gyro (``E_b k_g``), taken as the
#: present ``E_b`` only where no laser (or reference) ever gave ``E_b`` itself.
GYRO_E_B = "E_b_gyro"
#: Why ``E_b`` relative to the gyro is left uncorrected.
NOT_CORRECTED = (
    "E_b is not corrected: relative to the gyro (E_b k_g) it lies within the gyro's scale "
    "tolerance of no correction; E_d alone is applied (a laser or motion capture in a "
    "recording gives E_b itself)"
)
#: Why a present ``E_b`` relative to the gyro is applied with care at best.
RELATIVE_TO_GYRO = (
    "E_b is relative to the gyro (E_b k_g, from wheels and gyro alone): its interval is the "
    "gyro's scale tolerance; a laser or motion capture in a recording separates the two"
)

#: How each figure is shown: (label, factor to the shown unit, unit, decimals).
FIGURE_UNITS: dict[str, tuple[str, float, str, int]] = {
    "E_d": ("E_d = D_R / D_L", 1.0, "", 6),
    "E_b": ("E_b = b_actual / b", 1.0, "", 6),
    "E_s": ("E_s = D_avg / D", 1.0, "", 6),
    "laser_x": ("laser forward", 1000.0, "mm", 2),
    "laser_y": ("laser left", 1000.0, "mm", 2),
    "laser_yaw": ("laser yaw", 180.0 / math.pi, "deg", 3),
    "E_b_gyro": ("E_b k_g (relative to the gyro)", 1.0, "", 6),
    "k_g": ("k_g, the gyro's scale", 1.0, "", 5),
    "gyro_bias": ("gyro bias", 180.0 / math.pi, "deg/s", 4),
}
#: z of a 95 % interval.
Z95 = 1.959964


@dataclass(frozen=True)
class FigureTrack:
    """One figure of one robot over its calibrations.

    Attributes
    ----------
    name : str
        One of :data:`~umbmark.fleets.outcome.FIGURES`.
    times : tuple of float
        When each recording started [s since 1970].
    values, errors : tuple of float
        Each calibration's value and standard error.
    paths : tuple of str
        Each calibration's recording.
    change : Change
        Steady, a step or a trend.
    """

    name: str
    times: tuple[float, ...]
    values: tuple[float, ...]
    errors: tuple[float, ...]
    paths: tuple[str, ...]
    change: Change

    @property
    def latest(self) -> tuple[float, float]:
        """The robot's present value and its standard error: since its last change (the
        mean of a steady robot's calibrations, the value since a step, a trend's line
        now), or the latest calibration alone where it stands alone."""
        return self.change.value, self.change.se

    @property
    def present(self) -> tuple[int, ...]:
        """The calibrations (indices) the present value rests on."""
        change, n = self.change, len(self.values)
        start = 0 if change.since is None else change.since
        return tuple(i for i in range(start, n) if i not in change.one_offs)

    def shown(self, unit: bool = True) -> str:
        """The present value and its 95 % interval in the shown unit (``1.002034 ±
        0.000118``, ``100.18 ± 0.30 mm``; ``unit=False`` leaves the unit out, for a
        column that names it)."""
        _, factor, name, decimals = FIGURE_UNITS[self.name]
        value, se = self.latest
        said = f"{value * factor:.{decimals}f} ± {Z95 * se * factor:.{decimals}f}"
        return f"{said} {name}" if unit and name else said

    def _size(self) -> str:
        _, factor, unit, decimals = FIGURE_UNITS[self.name]
        unit = f" {unit}" if unit else ""
        size, se = self.change.size * factor, self.change.size_se * factor
        return f"{size:+.{decimals}f} ± {Z95 * se:.{decimals}f}{unit}"

    def flag(self) -> str | None:
        """The change in words, or None when steady."""
        change = self.change
        if change.kind == "latest" and change.since is not None:
            k = change.since
            return (
                f"{self.name} changed by {self._size()} in the latest recording, "
                f"{self.paths[k]} ({_day(self.times[k])}), against {_count(change.compared)} "
                "before it: to be confirmed by the next"
            )
        if change.kind == "step" and change.since is not None:
            k = change.since
            return (
                f"{self.name} stepped by {self._size()} since {self.paths[k]} "
                f"({_day(self.times[k])}), confirmed by {_count(change.confirmed_by)}"
            )
        if change.kind == "trend":
            return f"{self.name} trends by {self._size()} per week over {_count(change.compared)}"
        return None

    def course(self) -> str:
        """The course in a few words: the flag, or how many calibrations agree."""
        flag = self.flag()
        if flag is not None:
            return flag
        n = self.change.compared
        return f"{self.name} within its intervals ({_count(n)}{' compared' if n > 1 else ''})"


def _count(n: int) -> str:
    return f"{n} recording{'' if n == 1 else 's'}"


@dataclass(frozen=True)
class RobotSummary:
    """One robot of the fleet.

    Attributes
    ----------
    robot : str
    recordings : int
        Its recordings (calibrated, left out and failed), each once: a recording
        recorded more than once (tried again after a failure, read again with other
        options) is the one outcome :func:`summarize` keeps of it.
    hours : float
        Their length [h].
    tracks : dict of str to FigureTrack
        Each figure it has calibrations of (what the robot is, on its latest nominal).
    latest : RecordingOutcome or None
        Its latest calibration that is part of its course.
    left_out : tuple of (str, str)
        Recordings not calibrated: path and reason (those that failed too).
    notes : tuple of str
        What else people should know: the robot's configured (nominal) geometry changed
        between its recordings (``E_b`` and ``E_s`` are then shown against the latest),
        one-offs left out, calibrations not used because their verdict is do not apply.
    e_max_syst : float or None
        E_max,syst [m] the robot's present errors make on the standard 4 m square, with
        the parameters active in its latest recording.
    apply : ToApply or None
        What to set in its controller from its present state.
    failed : tuple of (str, str)
        Those of ``left_out`` that could not be read: path and reason.
    """

    robot: str
    recordings: int
    hours: float
    tracks: dict[str, FigureTrack] = field(default_factory=dict)
    latest: RecordingOutcome | None = None
    left_out: tuple[tuple[str, str], ...] = ()
    notes: tuple[str, ...] = ()
    e_max_syst: float | None = None
    apply: ToApply | None = None
    failed: tuple[tuple[str, str], ...] = ()

    @property
    def flags(self) -> tuple[str, ...]:
        """Every figure that changed beyond its intervals, in words."""
        return tuple(f for f in (t.flag() for t in self.tracks.values()) if f is not None)

    @property
    def changed(self) -> bool:
        return bool(self.flags)

    @property
    def unconfirmed(self) -> bool:
        """Whether a figure changed in the latest recording alone (to be confirmed)."""
        return any(t.change.kind == "latest" for t in self.tracks.values())

    @property
    def usable(self) -> bool:
        """Whether any recording gave a calibration that is part of its course."""
        return self.latest is not None

    @property
    def mounting(self) -> MountingForms | None:
        """The laser's mounting to declare: the fleet's present estimate of it (since its
        last change, :attr:`FigureTrack.latest`) in the forms a user applies (a URDF
        origin, static transforms), against the mounting the latest recording states;
        None without a laser."""
        tracks = [self.tracks.get(name) for name in ("laser_x", "laser_y", "laser_yaw")]
        if self.latest is None or any(t is None for t in tracks):
            return None
        return _mounting_forms(
            [t.latest for t in tracks if t is not None], self.latest.record.get("mounting")
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (metres, radians, seconds)."""
        latest = self.latest
        return {
            "robot": self.robot,
            "recordings": self.recordings,
            "hours": self.hours,
            "usable": self.usable,
            "figures": {name: _track_dict(track) for name, track in self.tracks.items()},
            "flags": list(self.flags),
            "e_max_syst": self.e_max_syst,
            "apply": None if self.apply is None else self.apply.to_dict(),
            "latest": None
            if latest is None
            else {  # the recording; what it says of the robot is in figures and apply
                "path": latest.path,
                "start": latest.start,
                "method": latest.method,
                "verdict": latest.verdict,
            },
            "mounting": None if self.mounting is None else self.mounting.to_dict(),
            "left_out": [{"path": p, "reason": r} for p, r in self.left_out],
            "failed": [{"path": p, "reason": r} for p, r in self.failed],
            "notes": list(self.notes),
        }


def _track_dict(track: FigureTrack) -> dict[str, Any]:
    value, se = track.latest
    change = track.change
    return {
        "value": value,
        "standard_error": se,
        "interval_95": [value - Z95 * se, value + Z95 * se],
        "change": change.kind,
        "since": None if change.since is None else track.paths[change.since],
        "size": change.size,
        "size_standard_error": change.size_se,
        "birge": change.birge,
        "compared": change.compared,
        "confirmed_by": change.confirmed_by,
        "steps": [track.paths[k] for k in change.steps],
        "one_offs": [track.paths[k] for k in change.one_offs],
        "times": list(track.times),
        "values": list(track.values),
        "standard_errors": list(track.errors),
        "paths": list(track.paths),
    }


@dataclass(frozen=True)
class FleetSummary:
    """The fleet, robot by robot.

    Attributes
    ----------
    robots : tuple of RobotSummary
        By name.
    """

    robots: tuple[RobotSummary, ...]

    @property
    def drifted(self) -> tuple[str, ...]:
        """The robots with a figure that changed (in the latest recording too)."""
        return tuple(r.robot for r in self.robots if r.changed)

    @property
    def unconfirmed(self) -> tuple[str, ...]:
        """The robots with a figure that changed in their latest recording alone."""
        return tuple(r.robot for r in self.robots if r.unconfirmed)

    @property
    def unusable(self) -> tuple[str, ...]:
        """The robots with no recording that gave a calibration."""
        return tuple(r.robot for r in self.robots if not r.usable)

    @property
    def worst(self) -> tuple[str, float] | None:
        """The robot whose present errors make the largest E_max,syst on the standard 4 m
        square, and that E_max,syst [m]."""
        found = [(r.robot, r.e_max_syst) for r in self.robots if r.e_max_syst is not None]
        return max(found, key=lambda f: f[1]) if found else None

    @property
    def recordings(self) -> tuple[int, int, int]:
        """The robots' recordings (each once): calibrated, left out, failed."""
        failed = sum(len(r.failed) for r in self.robots)
        left_out = sum(len(r.left_out) for r in self.robots) - failed
        return sum(r.recordings for r in self.robots) - left_out - failed, left_out, failed

    def line(self) -> str:
        """One line for people: the robots that changed and that have no usable
        recording, the recordings calibrated, left out and failed, the worst E_max,syst."""
        worst = self.worst
        said = (
            ""
            if worst is None
            else f"; worst E_max,syst on the {STANDARD_SIDE:g} m square: {worst[1] * 1000:.1f} "
            f"mm ({worst[0]})"
        )
        pending = len(self.unconfirmed)
        latest = (
            f" ({pending} of them in {'its' if pending == 1 else 'their'} latest recording, "
            "to be confirmed)"
            if pending
            else ""
        )
        calibrated, left_out, failed = self.recordings
        counts = ", ".join(
            [f"{calibrated} calibrated"]
            + ([f"{left_out} left out"] if left_out else [])
            + ([f"{failed} failed"] if failed else [])
        )
        total = calibrated + left_out + failed
        return (
            f"{len(self.robots)} robot{'' if len(self.robots) == 1 else 's'}: "
            f"{len(self.drifted)} changed beyond their intervals{latest}, "
            f"{len(self.unusable)} with no usable recording; {total} "
            f"recording{'' if total == 1 else 's'}: {counts}{said}"
        )

    def to_dict(self) -> dict[str, Any]:
        worst = self.worst
        return {
            "robots": [r.to_dict() for r in self.robots],
            "drifted": list(self.drifted),
            "unconfirmed": list(self.unconfirmed),
            "unusable": list(self.unusable),
            "worst_e_max_syst": None if worst is None else {"robot": worst[0], "value": worst[1]},
            "standard_side": STANDARD_SIDE,
        }


def _track(name: str, outcomes: Sequence[RecordingOutcome]) -> FigureTrack | None:
    rows = [
        (o.start, o.figures[name][0], o.figures[name][1], o.path)
        for o in outcomes
        if name in o.figures
        and o.figures[name][1] is not None
        and o.start is not None
        and math.isfinite(o.figures[name][0])
        and math.isfinite(o.figures[name][1] or math.nan)
        and (o.figures[name][1] or 0.0) > 0.0
    ]
    if not rows:
        return None
    rows.sort(key=lambda r: (r[0], r[3]))
    times = np.array([r[0] for r in rows], dtype=np.float64)
    values = np.array([r[1] for r in rows], dtype=np.float64)
    errors = np.array([r[2] for r in rows], dtype=np.float64)
    return FigureTrack(
        name,
        tuple(float(t) for t in times),
        tuple(float(v) for v in values),
        tuple(float(e) for e in errors),
        tuple(r[3] for r in rows),
        (followed_of if name in FOLLOWED else change_of)(times, values, errors),
    )


def summarize(outcomes: Sequence[RecordingOutcome]) -> FleetSummary:
    """The fleet's robots from their recordings' outcomes (any order, oldest tries
    first where a recording was tried more than once).

    Parameters
    ----------
    outcomes : sequence of RecordingOutcome

    Returns
    -------
    FleetSummary
    """
    by_robot: dict[str, list[RecordingOutcome]] = {}
    for outcome in outcomes:
        by_robot.setdefault(outcome.robot, []).append(outcome)
    return FleetSummary(
        tuple(_robot(name, _each_once(by_robot[name])) for name in sorted(by_robot))
    )


def _robot(name: str, mine: Sequence[RecordingOutcome]) -> RobotSummary:
    """One robot from its recordings' outcomes (one each)."""
    calibrated = sorted((o for o in mine if o.calibrated), key=lambda o: (o.start or 0.0, o.path))
    used = [o for o in calibrated if o.verdict != "do-not-apply"]
    latest = used[-1] if used else None
    notes = list(_nominal_changes(calibrated))
    notes += [_refused(o) for o in calibrated if o.verdict == "do-not-apply"]
    left_out = tuple((o.path, o.reason or "") for o in mine if not o.calibrated)
    failed = tuple((o.path, o.reason or "") for o in mine if o.failed)
    hours = float(sum(o.hours for o in mine))
    if latest is None:
        return RobotSummary(name, len(mine), hours, {}, None, left_out, tuple(notes), failed=failed)
    on_latest = [robot_terms(o, latest) for o in used]
    tracks = {f: t for f in FIGURES if (t := _track(f, on_latest)) is not None}
    notes += _one_offs(tracks)
    present = {f: tracks[f].latest[0] for f in WHEELS if f in tracks}
    wheel_names = [f for f in WHEELS if f in tracks]
    cautions = []
    if "E_b" not in tracks and GYRO_E_B in tracks:  # E_b relative to the gyro, said so
        present["E_b"] = _relative_e_b(tracks[GYRO_E_B], latest)
        wheel_names.insert(1, GYRO_E_B)
        cautions.append(RELATIVE_TO_GYRO if present["E_b"] != 1.0 else NOT_CORRECTED)
    by_path = {o.path: o for o in used}
    rests_on = sorted(
        {by_path[tracks[f].paths[i]].path for f in wheel_names for i in tracks[f].present}
    )
    wheels = [tracks[f] for f in wheel_names]
    if any(t.change.kind == "latest" for t in wheels):
        cautions.insert(0, UNCONFIRMED)
    if calibrated[-1] is not latest:
        cautions.append(
            f"the newest calibration, {calibrated[-1].path}, failed its checks (do not apply): "
            "these values rest on the recordings before it"
        )
    apply = to_apply(present, [by_path[p] for p in rests_on], latest, basis=_basis(wheels),
                     cautions=cautions)  # fmt: skip
    measured = present if "E_b" in tracks else {k: v for k, v in present.items() if k != "E_b"}
    return RobotSummary(
        name, len(mine), hours, tracks, latest, left_out, tuple(notes),
        present_e_max_syst(measured, latest), apply, failed,
    )  # fmt: skip


def _relative_e_b(track: FigureTrack, latest: RecordingOutcome) -> float:
    """The present ``E_b`` from ``E_b`` relative to the gyro: its value where its
    interval widened by the gyro's scale tolerance says which way to correct
    (:func:`umbmark.estimators.gyro.widened_resolves`, as a calibration applies it), else
    1 (no correction)."""
    from umbmark.estimators.gyro import SCALE_TOLERANCE, widened_resolves

    value, se = track.latest
    gyro = latest.record.get("gyro_calibration") or {}
    tolerance = gyro.get("scale_tolerance") or SCALE_TOLERANCE
    widened = math.hypot(se, value * float(tolerance) / Z95)
    return value if widened_resolves(value, widened) else 1.0


def _basis(wheels: Sequence[FigureTrack]) -> str:
    """What the wheels' present figures rest on, for people."""
    if not wheels:
        return "no wheel figures"
    said: list[tuple[str, str]] = []
    for track in wheels:
        change, present = track.change, track.present
        first, last = _day(track.times[present[0]]), _day(track.times[present[-1]])
        if change.kind == "latest":
            what = f"the latest recording alone ({last}): a change to be confirmed"
        elif change.kind == "step":
            what = f"the {_count(len(present))} since its step on {first}"
        elif change.kind == "trend":
            what = f"its trend over {_count(len(present))}, at {last}"
        elif len(present) == 1:
            what = f"one recording ({last})"
        else:
            what = f"the mean of {_count(len(present))} from {first} to {last}"
        said.append((track.name, what))
    grouped: dict[str, list[str]] = {}
    for name, what in said:  # figures that rest on the same recordings, said once
        grouped.setdefault(what, []).append(name)
    return "; ".join(f"{', '.join(names)}: {what}" for what, names in grouped.items())


def _one_offs(tracks: Mapping[str, FigureTrack]) -> list[str]:
    """A note for each recording left out of some figure's course as a one-off."""
    found: dict[str, list[str]] = {}
    when: dict[str, float] = {}
    for track in tracks.values():
        for k in track.change.one_offs:
            found.setdefault(track.paths[k], []).append(track.name)
            when[track.paths[k]] = track.times[k]
    return [
        f"one-off: {path} ({_day(when[path])}) disagreed with the recordings around it in "
        f"{', '.join(names)}, and later ones returned: left out of the figures"
        for path, names in sorted(found.items(), key=lambda f: when[f[0]])
    ]


def _refused(outcome: RecordingOutcome) -> str:
    """Why a calibrated recording is not part of the course."""
    reasons = (outcome.record.get("verdict") or {}).get("reasons") or ["its checks failed"]
    when = "" if outcome.start is None else f" ({_day(outcome.start)})"
    return (
        f"not used: {outcome.path}{when}: its calibration's verdict is do not apply "
        f"({'; '.join(str(r) for r in reasons)})"
    )


def _each_once(outcomes: Sequence[RecordingOutcome]) -> list[RecordingOutcome]:
    """One outcome of each recording (by path), in the order given: of a recording given
    more than once, the best (calibrated over left out over failed: a recording calibrated
    after a failed try is calibrated), the last given among equals (the latest recorded,
    as :func:`~umbmark.store.fleet_recordings.read_recordings` gives them)."""

    def rank(o: RecordingOutcome) -> int:
        return 2 if o.calibrated else 0 if o.failed else 1

    kept: dict[str, RecordingOutcome] = {}
    for outcome in outcomes:
        before = kept.get(outcome.path)
        if before is None or rank(outcome) >= rank(before):
            kept[outcome.path] = outcome
    return list(kept.values())


def _mounting_forms(
    fitted: Sequence[tuple[float, float]], recorded: Mapping[str, Any] | None
) -> MountingForms:
    """The forms of a fitted ``x, y, yaw`` (value, standard error each [m, m, rad]), with
    the frames, height and tilt, and the stated mounting, of a recording's forms."""
    recorded = recorded or {}
    xyz, rpy = recorded.get("xyz") or (0.0,) * 3, recorded.get("rpy") or (0.0,) * 3
    lift = (float(xyz[2]), float(rpy[0]), float(rpy[1]))
    base = str(recorded.get("base_frame") or "base_link")
    frame = str(recorded.get("laser_frame") or "laser")
    (x, se_x), (y, se_y), (yaw, se_yaw) = fitted
    stated_lift = lift if recorded.get("z_roll_pitch_stated") else None
    return MountingForms(
        fitted=LaserMounting(x, y, yaw, stated_lift, base, frame, "fitted"),
        standard_errors=(se_x, se_y, se_yaw),
        intervals=tuple((v - Z95 * se, v + Z95 * se) for v, se in fitted),
        stated=_stated(recorded.get("stated"), base, frame),
    )


def _stated(stated: Mapping[str, Any] | None, base: str, frame: str) -> LaserMounting | None:
    """The stated mounting of a recording's forms (their ``to_dict``)."""
    if not stated:
        return None
    raw = stated.get("lift")
    lift = None if raw is None else (float(raw[0]), float(raw[1]), float(raw[2]))
    source = str(stated.get("source") or "")
    return LaserMounting(float(stated["x"]), float(stated["y"]), float(stated["yaw"]), lift,
                         base, frame, source)  # fmt: skip


def _nominal(outcome: RecordingOutcome) -> tuple[float | None, float | None]:
    """The nominal wheelbase and wheel diameter [m] a calibration was made against."""
    diameter = outcome.record.get("wheel_diameter")
    return outcome.wheelbase, None if diameter is None else float(diameter)


def _nominal_changes(calibrated: Sequence[RecordingOutcome]) -> tuple[str, ...]:
    """Where the configured geometry changed between calibrations (in time order)."""
    notes: list[str] = []
    for before, now in itertools.pairwise(calibrated):
        pairs = zip(("wheelbase", "wheel diameter"), _nominal(before), _nominal(now), strict=True)
        for what, old, new in pairs:
            if old and new and not math.isclose(old, new, rel_tol=1e-9):
                when = "" if now.start is None else f" ({_day(now.start)})"
                notes.append(
                    f"nominal {what} {old:g} m, then {new:g} m from {now.path}{when}: "
                    "E_b and E_s are shown against the latest"
                )
    return tuple(notes)


def _day(start: float) -> dt.date:
    return dt.datetime.fromtimestamp(start, dt.timezone.utc).date()
