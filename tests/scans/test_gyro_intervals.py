"""A recording's wheels and gyro cut into rests and driving: against the simulation's truth.

The recordings are the tests' own closed-form simulator's (``tests/gyro_sim.py``): every
expected value (where the robot rests, how far it turned, what the gyro integrates to)
comes from its program and its exact motion, not from the code under test.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from gyro_sim import Truth, program, record, rest, scan_reference, spin, straight
from umbmark.core.errors import InputError
from umbmark.model.gyro_series import GyroSeries
from umbmark.model.recording import WheelSeries
from umbmark.scans.gyro_intervals import (
    HeadingReference,
    gyro_intervals,
    gyro_reference,
)

#: A gyro without noise, bias walk or tilt, its bias constant: its integral is exact.
CLEAN = Truth(noise=0.0, bias_walk=0.0, tilt=(0.0, 0.0), slip=0.0, ticks=0)
#: The same with a real gyro's white noise: without any, its readings repeat exactly
#: wherever the motion is steady, which is what a frozen or a clipped gyro reads
#: (umbmark.model.gyro_series), so where the cut's rests, turns and clipping are tested.
NOISY = replace(CLEAN, noise=Truth().noise)


def _program():
    return program([straight(1.5), spin(math.pi), straight(-1.0), spin(-math.pi / 2)], 2, rests=3.0)


def test_rests_are_where_the_robot_rests_and_driving_covers_every_turn():
    rec = record(_program(), NOISY)
    iv = gyro_intervals(rec.wheels, rec.gyro)
    motion = rec.motion
    # the program's rests: 4 s at the start, then 3 s after each of 8 segments
    starts = np.array(motion.starts[:-1])
    rests = [
        (a, a + seg.duration)
        for a, seg in zip(starts, motion.segments, strict=True)
        if seg.length == 0.0 and seg.turn == 0.0
    ]
    assert len(rests) == 9
    for a, b in zip(iv.start[iv.rest], iv.end[iv.rest], strict=True):
        assert any(r0 <= a and b <= r1 for r0, r1 in rests), (a, b)
    # every rest of the program holds rest intervals, trimmed by 0.2 s at both ends (the
    # first and the last at one end: the recording begins and ends in them)
    end = rec.wheels.time[-1]
    for r0, r1 in rests:
        inside = iv.rest & (iv.start >= r0 - 1e-9) & (iv.end <= r1 + 1e-9)
        last = min(r1, end)
        trim = 0.2 if r0 == 0.0 or last == end else 0.4
        assert iv.duration[inside].sum() == pytest.approx(last - r0 - trim, abs=0.05)
    # the driving intervals together hold the program's whole turning, to a wheel sample
    truth = motion.state(iv.end)["theta"] - motion.state(iv.start)["theta"]
    total = sum(seg.turn for seg in motion.segments)
    assert truth.sum() == pytest.approx(total, abs=1e-9)
    assert np.abs(truth[iv.rest]).max() < 1e-12
    # each interval begins and ends at a wheel sample (50 Hz); driving lasts at most a
    # second, a rest's piece two (each to a sample)
    assert np.isin(iv.start, rec.wheels.time).all()
    assert np.isin(iv.end, rec.wheels.time).all()
    assert iv.duration[~iv.rest].max() <= 1.02 + 1e-9
    assert iv.duration[iv.rest].max() <= 2.02 + 1e-9


def test_the_gyros_integral_is_the_true_turn_over_its_scale_plus_the_bias():
    rec = record(_program(), CLEAN)
    iv = gyro_intervals(rec.wheels, rec.gyro)
    st0, st1 = rec.motion.state(iv.start), rec.motion.state(iv.end)
    expected = (st1["theta"] - st0["theta"]) / CLEAN.k_g + CLEAN.bias * iv.duration
    # 200 Hz samples of a piecewise-linear rate: the trapezoid misses only at its kinks
    assert np.abs(iv.yaw - expected).max() < 2e-5
    # the wheels' rotations are their readings at the interval's ends
    index = np.searchsorted(rec.wheels.time, np.stack([iv.start, iv.end]))
    readings = rec.wheels.angles[index, 0]
    assert np.array_equal(iv.phi_left, readings[1] - readings[0])
    # at rest the accelerometer reads gravity along z
    assert iv.accel is not None
    assert np.abs(iv.accel[iv.rest] - [0.0, 0.0, 9.80665]).max() < 0.05


def test_a_gap_in_the_gyro_and_a_saturated_turn_leave_their_intervals_out():
    rec = record(program([spin(4 * math.pi, rate=math.radians(300))], 1, rests=2.0), NOISY)
    g = rec.gyro
    # the turn at 300 deg/s read by a gyro of 250 deg/s full scale, and a gap of 0.5 s
    clipped = g.rate.copy()
    clipped[:, 2] = np.clip(clipped[:, 2], -math.radians(250), math.radians(250))
    keep = (g.time < 1.0) | (g.time > 1.5)
    gyro = GyroSeries(g.time[keep], clipped[keep], None, source="clipped")
    iv = gyro_intervals(rec.wheels, gyro)
    assert iv.left_out["gyro saturated"] >= 3
    assert iv.left_out["gap in the gyro"] == 1
    # what is kept never holds a saturated sample
    held = np.abs(clipped[keep, 2]) >= math.radians(250)
    for a, b in zip(iv.start, iv.end, strict=True):
        inside = (gyro.time >= a) & (gyro.time <= b)
        assert not (held & inside).any()


def test_a_fast_turn_below_full_scale_is_not_saturation():
    rec = record(program([spin(4 * math.pi, rate=math.radians(200))], 1, rests=2.0), NOISY)
    assert "gyro saturated" not in gyro_intervals(rec.wheels, rec.gyro).left_out


def test_a_noise_free_gyros_steady_turn_is_no_saturation_but_repeats_as_a_frozen_one():
    # 200 deg/s held exactly for 3.6 s: the same three rates, frozen by the rule, so the
    # saturation inside it is not named twice (umbmark.model.gyro_series)
    from umbmark.model.gyro_series import frozen_stretches, saturated_stretches

    rec = record(program([spin(4 * math.pi, rate=math.radians(200))], 1, rests=2.0), CLEAN)
    g = rec.gyro
    assert saturated_stretches(g.time, g.rate).shape == (0, 2)
    frozen = frozen_stretches(g.time, g.rate)
    assert (frozen[:, 1] - frozen[:, 0]).max() > 3.0


def test_a_gyro_and_wheels_that_do_not_overlap_are_one_line():
    rec = record(program([straight(1.0)], 1, rests=2.0), CLEAN)
    later = replace(rec.gyro, time=rec.gyro.time + 1000.0, source="imu.bag /imu")
    with pytest.raises(InputError) as caught:
        gyro_intervals(rec.wheels, later)
    assert str(caught.value).startswith("imu.bag /imu: the gyro's readings (1000.")
    assert "do not overlap in time" in str(caught.value)


def test_a_standing_robot_gives_rests_only():
    rec = record(program([rest(30.0)], 1, rests=0.0), CLEAN)
    iv = gyro_intervals(rec.wheels, rec.gyro)
    assert iv.rest.all()
    assert iv.yaw / iv.duration == pytest.approx(CLEAN.bias, abs=1e-9)


def test_references_are_set_beside_the_gyro():
    rec = record(_program(), CLEAN)
    g = rec.gyro
    start = np.array([2.0, 10.0, g.time[-1] - 0.5])
    end = start + np.array([1.0, 2.0, 1.0])  # the last runs past the gyro's readings
    ref = gyro_reference(g, HeadingReference(start, end, np.zeros(3)))
    assert len(ref) == 2
    assert ref.left_out == {"outside the gyro's readings": 1}
    st0, st1 = rec.motion.state(ref.start), rec.motion.state(ref.end)
    expected = (st1["theta"] - st0["theta"]) / CLEAN.k_g + CLEAN.bias * (ref.end - ref.start)
    assert ref.gyro_yaw == pytest.approx(expected, abs=2e-5)
    assert np.isnan(ref.variance).all()
    scans = scan_reference(rec)
    from_scans = gyro_reference(g, scans)
    assert from_scans.motion is not None
    assert len(from_scans.motion) == len(from_scans)
    assert from_scans.yaw == pytest.approx(scans.sensor_motion[: len(from_scans), 2])
    # a tuple file's intervals have no times: they cannot be set beside a gyro
    untimed = replace(scans, start_time=None, source="drive.tuple")
    with pytest.raises(InputError, match=r"^drive\.tuple: the motion intervals carry no times"):
        gyro_reference(g, untimed)


def test_wheels_that_never_move_between_rests_and_short_rests():
    time = np.arange(0.0, 10.0, 0.02)
    wheels = WheelSeries(time, np.zeros((time.size, 2)))
    gyro = GyroSeries(np.arange(0.0, 10.0, 0.005), np.zeros((2000, 3)))
    iv = gyro_intervals(wheels, gyro)
    assert iv.rest.all()
    assert iv.duration.sum() == pytest.approx(10.0 - 0.02, abs=1e-9)
