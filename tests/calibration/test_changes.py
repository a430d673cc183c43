"""A robot's figure over time: steady, a change in the latest recording (to be
confirmed), a step (since which recording), a trend (per week) or a one-off, judged
against the calibrations' own intervals. Series simulated with a known truth, or written
by hand: the change found is the one made, and a steady robot is not flagged."""

from __future__ import annotations

import numpy as np
import pytest

from umbmark.calibration.changes import (
    FOLLOWED,
    SECONDS_PER_WEEK,
    Z_CHANGE,
    change_of,
    followed_of,
)
from umbmark.core.errors import InputError

DAY = 86400.0
SE = 1e-4


def _series(rng, n=30, days=60.0, se=SE):  # type: ignore[no-untyped-def]
    times = np.sort(rng.uniform(0.0, days * DAY, n))
    return times, np.full(n, se)


@pytest.mark.slow
def test_a_steady_robot_is_not_flagged():
    rng = np.random.default_rng(1)
    flagged = 0
    for _ in range(400):
        t, s = _series(rng)
        v = 1.002 + rng.normal(0.0, SE, len(t))
        flagged += change_of(t, v, s).kind != "steady"
    assert flagged <= 1  # a 5-sigma threshold over ~30 places: about 1e-5 per series


@pytest.mark.slow
def test_calibrations_that_scatter_more_than_their_intervals_make_no_change():
    # The stated standard errors are a third of the true scatter (a model error): the
    # Birge ratio scales them up rather than reading the scatter as a change.
    rng = np.random.default_rng(2)
    flagged = 0
    for _ in range(200):
        t, s = _series(rng)
        v = 1.0 + rng.normal(0.0, 3 * SE, len(t))
        change = change_of(t, v, s)
        flagged += change.kind != "steady"
        assert change.birge > 1.5
    assert flagged <= 1


@pytest.mark.parametrize("since", [3, 11, 17, 27])
def test_a_step_is_found_at_its_recording_with_its_size(since: int):
    rng = np.random.default_rng(since)
    t, s = _series(rng)
    jump = 12 * SE  # a wheel changed: 12 standard errors of one calibration
    v = 0.97 + rng.normal(0.0, SE, len(t))
    v[since:] += jump
    change = change_of(t, v, s)
    assert change.kind == "step"
    assert change.since == since
    assert abs(change.size - jump) < 4 * change.size_se
    assert change.z > Z_CHANGE
    assert abs(change.value - (0.97 + jump)) < 4 * change.se


def test_a_trend_is_said_per_week():
    rng = np.random.default_rng(5)
    t, s = _series(rng, n=40, days=70.0)
    per_week = 2e-4  # tyres wearing: 2e-4 of E_s a week, 2 standard errors
    v = 1.0 + per_week * t / SECONDS_PER_WEEK + rng.normal(0.0, SE, len(t))
    change = change_of(t, v, s)
    assert change.kind == "trend"
    assert abs(change.size - per_week) < 4 * change.size_se
    expected_last = 1.0 + per_week * t[-1] / SECONDS_PER_WEEK
    assert abs(change.value - expected_last) < 4 * change.se


def test_one_odd_calibration_at_the_end_is_the_latest_change_and_amid_others_a_one_off():
    rng = np.random.default_rng(3)
    t, s = _series(rng)
    v = 1.0 + rng.normal(0.0, SE, len(t))
    v[-1] += 30 * SE  # one recording alone: a change still to be confirmed, not a step
    change = change_of(t, v, s)
    assert change.kind == "latest"
    assert change.since == len(t) - 1
    assert change.value == v[-1]
    assert change.confirmed_by == 1
    assert change.compared == len(t) - 1
    assert abs(change.size - 30 * SE) < 4 * change.size_se
    v[-1] -= 30 * SE
    v[15] += 30 * SE  # one odd recording amid the others
    change = change_of(t, v, s)
    assert change.kind == "steady"
    assert change.one_offs == (15,)
    assert abs(change.value - 1.0) < 4 * SE / np.sqrt(len(t) - 1)


def _days(*values: float, se: float = SE):  # type: ignore[no-untyped-def]
    n = len(values)
    return np.arange(n) * DAY, np.array(values), np.full(n, se)


def test_a_wheel_changed_before_the_third_of_three_recordings_is_flagged_that_morning():
    # The robot: E_d 1.002, 1.002, then 1.008, each to 1e-4.
    change = change_of(*_days(1.002, 1.002, 1.008))
    assert change.kind == "latest"
    assert change.since == 2
    assert change.value == 1.008  # the newest recording alone, never pooled
    assert change.se == pytest.approx(SE)  # the two before agree: no scatter to add
    assert change.size == pytest.approx(0.006)
    assert change.size_se == pytest.approx(np.hypot(SE, SE / np.sqrt(2)))
    assert change.compared == 2
    assert change.steps == ()


def test_the_next_recording_confirms_a_step_or_makes_it_a_one_off():
    step = change_of(*_days(1.002, 1.002, 1.008, 1.008))
    assert step.kind == "step"
    assert step.since == 2
    assert step.steps == (2,)
    assert step.value == pytest.approx(1.008)
    assert step.se == pytest.approx(SE / np.sqrt(2))
    assert step.size == pytest.approx(0.006)
    assert (step.compared, step.confirmed_by) == (2, 2)
    back = change_of(*_days(1.002, 1.002, 1.008, 1.002))
    assert back.kind == "steady"
    assert back.one_offs == (2,)
    assert back.value == pytest.approx(1.002)
    assert back.compared == 3
    # Neither: the newest the change to be confirmed, against the course before both (the
    # odd one not settled: neither returned to nor agreed with).
    neither = change_of(*_days(1.002, 1.002, 1.008, 0.996))
    assert neither.kind == "latest"
    assert neither.one_offs == ()
    assert neither.compared == 2
    assert neither.value == 0.996
    assert neither.size == pytest.approx(-0.006)


def test_two_recordings_are_compared_on_their_stated_intervals():
    changed = change_of(*_days(1.002, 1.008))
    assert (changed.kind, changed.compared, changed.value) == ("latest", 1, 1.008)
    same = change_of(*_days(1.002, 1.0021))
    assert (same.kind, same.compared) == ("steady", 2)
    # Within the threshold but apart by 2.8 standard errors: the pooled value's interval
    # carries the scatter (chi^2 = 8 on 1 degree of freedom: Birge ratio sqrt(8)).
    apart = change_of(*_days(1.0020, 1.0024))
    assert apart.kind == "steady"
    assert apart.value == pytest.approx(1.0022)
    assert apart.birge == pytest.approx(np.sqrt(8.0))
    assert apart.se == pytest.approx(SE / np.sqrt(2) * np.sqrt(8.0))


def test_a_change_after_a_step_is_judged_against_the_state_since_the_step():
    values = [1.0] * 8 + [1.01] * 5 + [1.004]
    change = change_of(*_days(*values))
    assert change.kind == "latest"
    assert change.steps == (8,)
    assert change.compared == 5  # the five since the step, not all thirteen
    assert change.size == pytest.approx(-0.006)
    assert change_of(*_days(*values[:-1])).kind == "step"


def test_a_latest_recording_within_the_courses_own_scatter_is_no_change():
    # Calibrations that scatter three times their intervals (alternating +-3 se): the
    # newest, 6 se off, is 2 of the course's own standard errors.
    values = [1.0 + (3 * SE if k % 2 else -3 * SE) for k in range(12)] + [1.0 + 6 * SE]
    change = change_of(*_days(*values))
    assert change.kind == "steady"
    assert change.birge > 2.5


def test_few_calibrations_and_bad_series_are_refused():
    one = change_of(np.array([0.0]), np.array([1.0]), np.array([SE]))
    assert (one.kind, one.compared) == ("steady", 1)
    with pytest.raises(InputError, match="positive and finite"):
        change_of(np.arange(2.0), np.ones(2), np.array([SE, 0.0]))
    with pytest.raises(InputError, match="in order"):
        change_of(np.array([1.0, 0.0]), np.ones(2), np.full(2, SE))
    with pytest.raises(InputError, match="finite"):
        change_of(np.arange(2.0), np.array([1.0, np.nan]), np.full(2, SE))


@pytest.mark.slow
def test_two_or_three_recordings_as_stated_are_rarely_flagged():
    # Compared on their stated intervals, calibrations that scatter as stated: a change
    # beyond 5 of its standard errors is a 6e-7 tail (one test per recording).
    rng = np.random.default_rng(11)
    flagged = 0
    for n in (2, 3) * 1000:
        t = np.arange(n) * DAY
        flagged += change_of(t, 1.0 + rng.normal(0.0, SE, n), np.full(n, SE)).changed
    assert flagged == 0


def test_each_morning_tells_the_day_befores_story_and_one_more_recording():
    """A robot's series with a one-off and a step, read one morning at a time: a change
    in the latest recording is confirmed as a step, or made a one-off, by the next; a
    step stays where it was found."""
    rng = np.random.default_rng(12)
    values = 1.0 + rng.normal(0.0, SE, 24)
    values[7] += 40 * SE  # a bad recording
    values[15:] += 30 * SE  # a wheel changed
    told = [change_of(*_days(*values[: n + 1])) for n in range(len(values))]
    assert [c.kind for c in told[:7]] == ["steady"] * 7
    assert (told[7].kind, told[7].since) == ("latest", 7)
    assert all(c.kind == "steady" and 7 in c.one_offs for c in told[8:15])
    assert (told[15].kind, told[15].since) == ("latest", 15)
    assert all((c.kind, c.since) == ("step", 15) for c in told[16:])
    assert all(c.one_offs == (7,) for c in told[16:])
    assert told[-1].confirmed_by == 9
    assert abs(told[-1].size - 30 * SE) < 4 * told[-1].size_se


def test_a_gyro_bias_that_wanders_is_followed_not_judged():
    # A MEMS gyro's bias as a random walk over a week of daily recordings, each stating
    # a standard error far below the walk: the followed course is steady and its present
    # value is the newest recording's own, never a mean over the wandering.
    rng = np.random.default_rng(5)
    t = np.arange(8) * DAY
    v = np.radians(0.3 + np.cumsum(rng.normal(0.0, 0.01, 8)))
    s = np.full(8, np.radians(0.0005))
    assert "gyro_bias" in FOLLOWED
    followed = followed_of(t, v, s)
    assert (followed.kind, followed.value, followed.se) == ("steady", v[-1], s[-1])
    assert (followed.steps, followed.since, followed.size) == ((), None, 0.0)
    with pytest.raises(InputError, match="standard errors"):
        followed_of(t, v, np.zeros(8))
