"""A robot's figure over time: steady, a step (since which recording) or a trend (per
week), judged against the calibrations' own intervals. Series simulated with a known
truth: the change found is the one made, and a steady robot is not flagged."""

from __future__ import annotations

import numpy as np
import pytest

from umbmark.core.errors import InputError
from umbmark.fleets.changes import SECONDS_PER_WEEK, Z_CHANGE, change_of

DAY = 86400.0
SE = 1e-4


def _series(rng, n=30, days=60.0, se=SE):  # type: ignore[no-untyped-def]
    times = np.sort(rng.uniform(0.0, days * DAY, n))
    return times, np.full(n, se)


def test_a_steady_robot_is_not_flagged():
    rng = np.random.default_rng(1)
    flagged = 0
    for _ in range(400):
        t, s = _series(rng)
        v = 1.002 + rng.normal(0.0, SE, len(t))
        flagged += change_of(t, v, s).kind != "steady"
    assert flagged <= 1  # a 5-sigma threshold over ~30 places: about 1e-5 per series


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


def test_one_odd_calibration_at_the_end_is_no_step():
    rng = np.random.default_rng(3)
    t, s = _series(rng)
    v = 1.0 + rng.normal(0.0, SE, len(t))
    v[-1] += 30 * SE  # one recording alone: an outlier, not a change (yet)
    assert change_of(t, v, s).kind != "step"
    v[-1] -= 30 * SE
    v[15] += 30 * SE  # one odd recording amid the others
    assert change_of(t, v, s).kind == "steady"


def test_few_calibrations_are_steady_and_bad_series_are_refused():
    assert change_of(np.array([0.0]), np.array([1.0]), np.array([SE])).kind == "steady"
    assert change_of(np.arange(3.0), np.array([1.0, 1.1, 1.2]), np.full(3, SE)).kind == "steady"
    with pytest.raises(InputError, match="positive and finite"):
        change_of(np.arange(2.0), np.ones(2), np.array([SE, 0.0]))
    with pytest.raises(InputError, match="in order"):
        change_of(np.array([1.0, 0.0]), np.ones(2), np.full(2, SE))
    with pytest.raises(InputError, match="finite"):
        change_of(np.arange(2.0), np.array([1.0, np.nan]), np.full(2, SE))
