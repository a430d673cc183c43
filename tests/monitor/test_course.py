"""The course on the fleet's change model: a steady series found steady, a step found in
the latest stretch, then confirmed, and the navigation tolerance."""

from __future__ import annotations

import numpy as np
import pytest

from umbmark.monitor.course import Z95, Course, StretchPoint, beyond


def _course(values: list[float], se: float = 1e-4) -> Course:
    c = Course()
    for k, v in enumerate(values):
        c.add("E_d", StretchPoint(v, se, 60.0 * k, 20.0 * k, 1e9 + 60.0 * k))
    return c


def test_steady_is_not_a_change() -> None:
    rng = np.random.default_rng(4)
    c = _course(list(1.002 + 1e-4 * rng.standard_normal(30)))
    change, found = c.found("E_d", 0.02, 0.34)
    assert change is not None
    assert change.kind == "steady"
    assert found is None


def test_a_step_is_found_then_confirmed() -> None:
    before, after = [1.002] * 8, [0.996]
    _, found = _course(before + after).found("E_d", 0.02, 0.34)
    assert found is not None
    assert not found.confirmed
    assert found.since == 60.0 * 8
    assert found.since_metres == 20.0 * 8
    _, found = _course(before + after + [0.996]).found("E_d", 0.02, 0.34)
    assert found is not None
    assert found.confirmed
    assert found.size == pytest.approx(-0.006, abs=1e-6)
    # the 95 % half-width of a difference of means of 8 stretches and of the 1 after the
    # one the change fell in (that one holds both states)
    assert found.size_half_width == pytest.approx(Z95 * 1e-4 * np.sqrt(1 / 8 + 1 / 1), rel=1e-6)


def test_the_size_leaves_out_the_stretch_the_change_fell_in() -> None:
    """A wheel changed a tenth into a stretch: that stretch says 1.002 - 0.9 x 0.006,
    within the change model's 5 sigma of the next (so not left out as unsettled); once
    the next confirms it, the size is that next one's against the 8 before: -0.006, where
    the change model's pooled size (-0.0057 +- 0.00023) misses the truth."""
    c = Course()
    for k, v in enumerate([1.002] * 8 + [1.002 - 0.9 * 0.006, 0.996]):
        c.add("E_d", StretchPoint(v, 1e-4, 60.0 * k, 20.0 * k, 1e9 + 60.0 * k))
    change, found = c.found("E_d", 0.02, 0.34)
    assert change is not None
    assert found is not None
    assert found.confirmed
    assert change.size == pytest.approx(-0.0057, abs=1e-6)  # the model's, pooled
    assert abs(change.size + 0.006) > Z95 * change.size_se
    assert found.since == 60.0 * 8  # dated to the stretch it fell in
    assert found.size == pytest.approx(-0.006, abs=1e-9)
    # one stretch against 8, each of 1e-4, scaled by the course's scatter as the model does
    assert found.size_half_width == pytest.approx(
        Z95 * change.birge * 1e-4 * np.sqrt(1 + 1 / 8), rel=1e-6
    )


def test_the_tolerance() -> None:
    # E_d: a change of 0.006 on a 0.34 m wheelbase drifts 0.0176 rad per metre
    assert not beyond("E_d", -0.006, 0.02, 0.34)
    assert beyond("E_d", -0.007, 0.02, 0.34)
    assert beyond("laser_yaw", 0.0524, 0.02, 0.34)
    assert not beyond("laser_x", 0.01, 0.02, 0.34)
    assert not beyond("gyro_bias", 1.0, 0.02, 0.34)


def test_the_course_is_bounded() -> None:
    from umbmark.monitor.course import MAX_STRETCHES

    c = _course([1.0] * (MAX_STRETCHES + 20))
    assert len(c.points["E_d"]) == MAX_STRETCHES


def test_the_gyro_bias_is_followed_not_flagged() -> None:
    c = Course()
    for k, v in enumerate([0.002] * 8 + [0.0025] * 3):  # a bias that wandered: 5e-4 rad/s
        c.add("gyro_bias", StretchPoint(v, 1e-5, 60.0 * k, 20.0 * k, 1e9 + 60.0 * k))
    change, found = c.found("gyro_bias", 0.02, 0.34)
    assert change is not None
    assert change.kind == "steady"  # followed, not judged
    assert found is None  # not flagged
    assert c.present("gyro_bias") == pytest.approx((0.0025, 1e-5), rel=1e-6)  # the latest's
