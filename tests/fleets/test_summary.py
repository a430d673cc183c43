"""A fleet's outcomes summed up robot by robot: the drifted ones flagged at the recording
where they changed, the steady ones not, the ones with no usable recording named with why,
and the worst E_max,syst. Outcomes made by hand with a known truth."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from umbmark.core.conventions import Direction
from umbmark.fleets.outcome import RecordingOutcome
from umbmark.fleets.summary import summarize
from umbmark.model.square import square_run_end

from fleet_tasks import T0, daily_outcomes


def test_the_changed_robots_are_flagged_at_their_day_and_the_steady_ones_are_not():
    rng = np.random.default_rng(4)
    outcomes = [
        *daily_outcomes("steady", 20, rng),
        *daily_outcomes("wheel", 20, rng, step_day=12, figure="E_d", jump=20 * 1e-4),
        *daily_outcomes("laser", 20, rng, step_day=7, figure="laser_yaw", jump=0.03),
        RecordingOutcome("blind/day00.mcap", "blind", T0, 8.0, None,
                         reason="neither a laser scan nor an independent reference"),
        RecordingOutcome("blind/day01.mcap", "blind", None, 0.0, None,
                         reason="broken.mcap: cannot be read", failed=True),
    ]  # fmt: skip
    fleet = summarize(outcomes)
    assert [r.robot for r in fleet.robots] == ["blind", "laser", "steady", "wheel"]
    assert set(fleet.drifted) == {"laser", "wheel"}
    assert fleet.unusable == ("blind",)
    by = {r.robot: r for r in fleet.robots}
    wheel, laser = by["wheel"].tracks["E_d"].change, by["laser"].tracks["laser_yaw"].change
    assert (wheel.kind, wheel.since) == ("step", 12)
    assert (laser.kind, laser.since) == ("step", 7)
    assert by["wheel"].flags == (by["wheel"].tracks["E_d"].flag(),)
    assert "since wheel/day12.mcap" in by["wheel"].flags[0]
    assert all(t.change.kind == "steady" for t in by["steady"].tracks.values())
    assert by["blind"].left_out[0][1] == "neither a laser scan nor an independent reference"
    # The worst E_max,syst is the present state's: the wheel's E_d since its step (1.005)
    # with E_b 0.98, on the 4 m square (its end in closed form, model.square).
    assert fleet.worst is not None
    truth = max(
        math.hypot(*square_run_end(1.003 + 20e-4, 0.98, 1.0, 4.0, 0.34, d)[:2])
        for d in (Direction.CW, Direction.CCW)
    )
    assert fleet.worst[0] == "wheel"
    assert fleet.worst[1] == pytest.approx(truth, rel=0.02)
    assert by["wheel"].e_max_syst == fleet.worst[1]
    assert fleet.line().startswith("4 robots: 2 changed beyond their intervals, 1 with no")
    data = json.loads(json.dumps(fleet.to_dict()))
    assert data["drifted"] == ["laser", "wheel"]
    assert data["robots"][3]["figures"]["E_d"]["since"] == "wheel/day12.mcap"


def test_a_changed_nominal_is_compared_on_the_latest_and_said():
    """The same robot (actual wheelbase 0.2016 m, mean diameter 0.0836 m) calibrated
    against a nominal of 0.2 m, then 0.205 m and 0.085 m: E_b and E_s on the latest
    nominal are the same actual geometry over it, and the change is said."""
    b, d = 0.2016, 0.0836

    def made(day: int, wheelbase: float, diameter: float) -> RecordingOutcome:
        figures = {"E_d": (1.001, 1e-4), "E_b": (b / wheelbase, 2e-4), "E_s": (d / diameter, 3e-4)}
        return RecordingOutcome(f"r/day{day}", "amr", T0 + day * 86400.0, 1.0, None,
                                method="trajectory", figures=figures, wheelbase=wheelbase,
                                record={"wheel_diameter": diameter})  # fmt: skip

    outcomes = [made(k, 0.2, 0.084) for k in range(4)] + [made(k, 0.205, 0.085) for k in (4, 5, 6)]
    (robot,) = summarize(outcomes).robots
    e_b, e_s = robot.tracks["E_b"], robot.tracks["E_s"]
    np.testing.assert_allclose(e_b.values, [b / 0.205] * 7, rtol=1e-12)
    np.testing.assert_allclose(e_s.values, [d / 0.085] * 7, rtol=1e-12)
    np.testing.assert_allclose(e_b.errors[:4], [2e-4 * 0.2 / 0.205] * 4, rtol=1e-12)
    assert robot.flags == ()  # the robot did not change; its configuration did
    assert robot.notes == (
        "nominal wheelbase 0.2 m, then 0.205 m from r/day4 (2026-09-25): E_b and E_s are "
        "shown against the latest",
        "nominal wheel diameter 0.084 m, then 0.085 m from r/day4 (2026-09-25): E_b and E_s "
        "are shown against the latest",
    )
    assert robot.to_dict()["notes"] == list(robot.notes)


def _outcome(robot, day, E_d, E_b=0.99, *, active=None, path=None, verdict="apply"):  # type: ignore[no-untyped-def]
    figures = {"E_d": (E_d, 1e-4), "E_b": (E_b, 3e-4), "E_s": (1.0, 2e-4)}
    record = {"active": active or {}, "verdict": {"level": verdict, "reasons": []}}
    return RecordingOutcome(path or f"{robot}/day{day}.mcap", robot, T0 + day * 86400.0, 8.0,
                            None, method="scan-matching", figures=figures, verdict=verdict,
                            wheelbase=0.34, record=record)  # fmt: skip


def test_a_change_in_the_latest_recording_tells_one_story_that_morning():
    """The issue's robot (E_d 1.002, 1.002, then 1.008 after its wheel was changed): the
    flag, the figures, the E_max,syst, what to apply and the summary line all say the
    newest recording alone, not a value pooled across the change."""
    (robot,) = summarize(
        [_outcome("amr", d, e) for d, e in enumerate((1.002, 1.002, 1.008))]
    ).robots
    fleet = summarize([_outcome("amr", d, e) for d, e in enumerate((1.002, 1.002, 1.008))])
    track = robot.tracks["E_d"]
    assert track.change.kind == "latest"
    assert robot.flags == (
        "E_d changed by +0.006000 ± 0.000240 in the latest recording, amr/day2.mcap "
        "(2026-09-23), against 2 recordings before it: to be confirmed by the next",
    )  # 1.96 x hypot(1e-4, 1e-4 / sqrt(2)) = 0.000240: the two before agree exactly
    assert track.latest == (1.008, pytest.approx(1e-4))
    truth = max(
        math.hypot(*square_run_end(1.008, 0.99, 1.0, 4.0, 0.34, d)[:2])
        for d in (Direction.CW, Direction.CCW)
    )
    assert robot.e_max_syst == pytest.approx(truth, rel=1e-9)
    apply = robot.apply
    assert apply is not None
    sep, left, right = apply.multipliers
    assert (sep, right / left) == (pytest.approx(0.99), pytest.approx(1.008))
    assert (left + right) / 2 == pytest.approx(1.0)  # E_s 1: the mean diameter is right
    assert apply.verdict == "care"
    assert "the latest recording alone (2026-09-23)" in apply.basis
    assert "confirm it with the next recording" in apply.overlay  # type: ignore[operator]
    assert fleet.line().startswith(
        "1 robot: 1 changed beyond their intervals (1 of them in its latest recording, to "
        "be confirmed), 0 with no usable recording; 3 recordings: 3 calibrated; worst "
        "E_max,syst"
    )
    assert fleet.to_dict()["unconfirmed"] == ["amr"]


def test_the_next_recording_confirms_the_step_or_makes_it_a_one_off():
    stepped = summarize([_outcome("amr", d, e) for d, e in enumerate((1.002, 1.002, 1.008, 1.008))])
    (robot,) = stepped.robots
    assert robot.flags[0].startswith("E_d stepped by +0.006000")
    assert "confirmed by 2 recordings" in robot.flags[0]
    assert robot.tracks["E_d"].latest[0] == pytest.approx(1.008)
    assert robot.apply is not None
    assert robot.apply.verdict == "apply"
    back = summarize([_outcome("amr", d, e) for d, e in enumerate((1.002, 1.002, 1.008, 1.002))])
    (robot,) = back.robots
    assert robot.flags == ()
    assert robot.tracks["E_d"].latest[0] == pytest.approx(1.002)
    assert any(n.startswith("one-off: amr/day2.mcap (2026-09-23)") for n in robot.notes)
    assert back.line().startswith("1 robot: 0 changed beyond their intervals, 0 with no")


def test_a_correction_applied_between_recordings_is_no_change():
    """After its second recording the robot's controller got the correction (c_R / c_L =
    1.004, as the fleet offered): what the later recordings measure is near 1, what the
    robot is stays 1.004."""
    c_l, c_r = 2 / (1.004 + 1), 2 * 1.004 / (1.004 + 1)
    corrected = {"c_L": c_l, "c_R": c_r, "wheel_separation_multiplier": 0.99}
    outcomes = [_outcome("amr", d, 1.004) for d in range(2)]
    outcomes += [_outcome("amr", d, 1.0, 1.0, active=corrected) for d in range(2, 5)]
    (robot,) = summarize(outcomes).robots
    assert robot.flags == ()
    assert robot.tracks["E_d"].values == pytest.approx([1.004] * 5)
    assert robot.tracks["E_b"].values == pytest.approx([0.99] * 5)
    assert robot.e_max_syst == pytest.approx(0.0, abs=1e-9)  # nothing left to correct
    assert robot.apply is not None
    assert robot.apply.multipliers == pytest.approx((0.99, c_l, c_r))


def test_a_recording_tried_again_counts_once():
    failed = RecordingOutcome("amr/day1.mcap", "amr", None, 0.0, None, reason="cut", failed=True)
    outcomes = [_outcome("amr", 0, 1.002), failed, _outcome("amr", 1, 1.002)]
    (robot,) = summarize(outcomes).robots
    assert robot.recordings == 2
    assert robot.left_out == ()


def test_a_recording_is_counted_once_however_often_it_was_tried():
    """Seven recordings of one robot, as the history gives them back: day04 failed, then
    calibrated; day05 failed twice; day06 left out; day01 calibrated again with other
    reading options (E_d 1.004 instead of 1.003). The robot has seven recordings, five
    calibrated (day01 once, as read last), one left out, one failed; 7 x 8 h."""
    rng = np.random.default_rng(5)
    days = daily_outcomes("amr", 7, rng)
    day01 = days[1]
    again = replace(day01, figures={**day01.figures, "E_d": (1.004, 1e-4)})
    failed = [
        RecordingOutcome(days[4].path, "amr", None, 0.0, None, reason="cannot be read",
                         failed=True),
        RecordingOutcome(days[5].path, "amr", None, 0.0, None, reason="cannot be read",
                         failed=True),
    ]  # fmt: skip
    left = replace(days[6], method=None, figures={}, reason="no laser and no reference")
    outcomes = [*failed, days[0], day01, days[2], days[3], days[4], failed[1], left, again]
    fleet = summarize(outcomes)
    (robot,) = fleet.robots
    assert robot.recordings == 7
    assert robot.hours == 5 * 8.0 + 0.0 + 8.0  # day05 failed before its length was known
    assert robot.failed == ((days[5].path, "cannot be read"),)
    assert [p for p, _ in robot.left_out] == [days[5].path, days[6].path]
    e_d = robot.tracks["E_d"]
    assert e_d.paths == tuple(d.path for d in days[:5])  # each calibrated recording once
    assert e_d.values[1] == 1.004  # day01 as read last
    assert fleet.recordings == (5, 1, 1)
    assert fleet.line().startswith(
        "1 robot: 0 changed beyond their intervals, 0 with no usable recording; 7 "
        "recordings: 5 calibrated, 1 left out, 1 failed; worst E_max,syst"
    )
    assert robot.to_dict()["failed"] == [{"path": days[5].path, "reason": "cannot be read"}]


def _gyro_outcomes(robot: str, days: range, figures: dict[str, tuple[float, float]]):  # type: ignore[no-untyped-def]
    """A robot's outcomes calibrated by the gyro on ``days`` with these figures."""
    return [
        RecordingOutcome(
            f"{robot}/day{day:02d}.mcap", robot, T0 + day * 86400.0, 1.0, "0" * 64,
            method="gyro", figures=dict(figures), e_max_syst=None if "E_b" not in figures
            else 0.1, multipliers=(1.0, 1.0, 1.0), verdict="care", wheelbase=0.34,
        )
        for day in days
    ]  # fmt: skip


def test_e_b_relative_to_the_gyro_is_a_figure_of_its_own_never_the_lasers_e_b():
    """A robot with a laser three days (E_b 1.02, its gyro's k_g 0.98) and without it
    three more (E_b k_g = 0.9996): two courses, neither changed, the E_b to apply the
    laser's; a robot with a gyro alone: its E_b k_g applied where the gyro's 3 % scale
    tolerance says which way to correct (1.06), with care and said so, not where it
    does not (1.01: left at 1, said so)."""
    from umbmark.fleets.summary import NOT_CORRECTED, RELATIVE_TO_GYRO

    both = {"E_d": (1.003, 1e-4), "E_b": (1.02, 5e-4), "E_s": (1.0, 5e-4), "k_g": (0.98, 2e-4)}
    alone = {"E_d": (1.003, 1e-4), "E_b_gyro": (1.02 * 0.98, 2e-4)}
    fleet = summarize(
        [
            *_gyro_outcomes("mixed", range(3), both),
            *_gyro_outcomes("mixed", range(3, 6), alone),
            *_gyro_outcomes("wide", range(2), {"E_d": (1.0, 1e-4), "E_b_gyro": (1.06, 2e-4)}),
            *_gyro_outcomes("level", range(2), {"E_d": (1.0, 1e-4), "E_b_gyro": (1.01, 2e-4)}),
        ]
    )
    by = {r.robot: r for r in fleet.robots}
    mixed = by["mixed"]
    assert len(mixed.tracks["E_b"].values) == 3
    assert len(mixed.tracks["E_b_gyro"].values) == 3
    assert mixed.flags == ()
    assert mixed.apply is not None
    assert mixed.apply.multipliers[0] == pytest.approx(1.02, abs=1e-12)
    assert mixed.e_max_syst is not None
    wide, level = by["wide"].apply, by["level"].apply
    assert wide is not None
    assert level is not None
    assert wide.multipliers[0] == pytest.approx(1.06, abs=1e-12)
    assert (wide.verdict, RELATIVE_TO_GYRO in wide.reasons) == ("care", True)
    assert level.multipliers[0] == 1.0
    assert NOT_CORRECTED in level.reasons
    assert by["wide"].e_max_syst is None  # not from E_b relative to the gyro
    shown = by["mixed"].tracks["E_b_gyro"].shown()
    assert shown.startswith("0.999600 ± 0.000")
