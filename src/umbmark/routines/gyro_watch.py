"""Whether a robot's IMU kept reading while a routine drove: a gyro that fell silent (its
driver stopped, the topic's publisher went away, its stamps stopped advancing) or froze
(the same three rates in every reading, as a driver that lost its sensor and repeats the
last value) measures nothing over that stretch, and a calibration against it would be
wrong without saying so.

:func:`gyro_trouble` says what went wrong over a stretch of the robot's clock, in one
line naming the IMU's topic, or None where the gyro read throughout: silent for
:data:`SILENT` or longer (within the stretch, at its start or at its end), frozen as the
bag reader finds it (:func:`umbmark.model.gyro_series.frozen_stretches`: the same rates
for :data:`umbmark.model.gyro_series.FROZEN` s). Shorter gaps are the calibration's
business (:func:`umbmark.scans.gyro_intervals.gyro_intervals` leaves the intervals
across them out, counted).

The routines then go on without the gyro where something else measures (the anywhere
routine's laser, the coarse check's corner fixes), saying so, and refuse otherwise:
nothing from such a gyro is applied.
"""

from __future__ import annotations

import math

import numpy as np

from umbmark.model.gyro_series import GyroSeries, frozen_stretches

__all__ = ["SILENT", "gyro_trouble"]

#: No reading for this long [s of the robot's clock] is an IMU fallen silent. Longer than
#: a ROS subscriber's delay (the readings of the last moments may not have come yet),
#: shorter than the rests over which the gyro reads its bias (2 s).
SILENT = 1.0


def gyro_trouble(gyro: GyroSeries | None, start: float, end: float, topic: str) -> str | None:
    """Why the gyro's readings cannot measure ``start`` to ``end`` [s, the robot's clock]
    (None: they can): no reading at all, silent for :data:`SILENT` or longer, or frozen.

    Parameters
    ----------
    gyro : GyroSeries or None
        The readings recorded over the stretch (None: none came).
    start, end : float
        The stretch the routine drove [s].
    topic : str
        The IMU's topic, named in the line.

    Returns
    -------
    str or None
        One line, times counted from ``start``.
    """
    span = end - start
    head = f"the IMU on {topic}"
    if gyro is None or len(gyro) < 2:
        return f"{head} gave no readings over the {span:.1f} s the robot drove"
    time = gyro.time
    if time[0] > start + SILENT:
        return f"{head} gave no readings for the first {time[0] - start:.1f} s of {span:.1f} s"
    if time[-1] < end - SILENT:
        return (
            f"{head} fell silent {time[-1] - start:.1f} s into the {span:.1f} s the robot "
            "drove (no reading after that)"
        )
    dt = np.diff(time)
    gap = int(np.argmax(dt))
    if dt[gap] >= SILENT:
        a, b = time[gap] - start, time[gap + 1] - start
        return f"{head} was silent from {a:.1f} to {b:.1f} s of the {span:.1f} s the robot drove"
    frozen = frozen_stretches(time, gyro.rate)
    if frozen.shape[0]:
        a, b = float(frozen[0, 0]), float(frozen[0, 1])
        k = int(np.searchsorted(time, a))
        rates = ", ".join(f"{math.degrees(float(v)):.4g}" for v in gyro.rate[k])
        return (
            f"{head} froze from {a - start:.1f} to {b - start:.1f} s of the {span:.1f} s the "
            f"robot drove (the same rates, {rates} deg/s, in every reading: no gyro reads "
            "that, its noise changes every reading)"
        )
    return None
