"""The validation job: which estimator and model predict the robot best, on its own data.

Calibrating and checking on the same runs says little. :func:`validate` holds each source
out in turn (leave one source out; with a single source, leave one run out), calibrates on
the rest with every estimator that can use them, replays the held-out runs with each
calibration, and compares their mean end-position errors: the held-out error is what a
user will see on runs the calibration never saw. The estimator with the lowest mean
held-out error is recommended; ``umbmark calibrate --method auto`` calibrates with it.

The figures say how well each calibration predicts the kinds of motion held out, and
nothing of others: :attr:`umbmark.calibration.validation.ValidationReport.coverage`
states which (straight legs, arcs, turns on the spot; :mod:`umbmark.estimators.motions`).
An estimator of a turn-rate term (``trajectory-scrub``) is credited only where the rest of
the runs identify it (they hold arcs and turns on the spot, and the fit pins the term),
so that it is never credited with runs it extrapolates to, nor with the single
wheelbase it falls back to. A bag read with ``imu_topic`` adds the ``gyro`` estimator
(the wheels against the gyro, its reference the ground truth's heading), holding out each
run's stretch of the recording.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from umbmark.calibration.heldout import CANDIDATES, validate_read
from umbmark.calibration.validation import ValidationReport
from umbmark.core.errors import InputError, option
from umbmark.estimators.registry import GYROS
from umbmark.runs.active import read_each
from umbmark.runs.read import is_table, source_name
from umbmark.runs.read_options import ReadOptions, SourceOptions

if TYPE_CHECKING:
    from typing_extensions import Unpack

__all__ = ["CANDIDATES", "validate"]


def validate(
    source: str | os.PathLike[str],
    *more_sources: str | os.PathLike[str],
    methods: Sequence[str] | None = None,
    side_length: float | None = None,
    wheelbase: float | None = None,
    override_verdict: bool = False,
    progress: Callable[[float], None] | None = None,
    **options: Unpack[SourceOptions],
) -> ValidationReport:
    """Hold out each source (or, from one source, each run), calibrate on the rest with
    every estimator, replay what was held out, and compare the end errors.

    Parameters
    ----------
    source, *more_sources : path
        Recorded runs (run logs, OptiOdom sessions, bags): replaying needs their wheel
        data.
    methods : sequence of str, optional
        The estimators to compare (default: all of :data:`CANDIDATES`, and ``gyro`` with
        ``imu_topic``).
    side_length, wheelbase : float, optional
        As for :func:`umbmark.calibrate`.
    override_verdict : bool
        Take ``current_params`` even when it is a result for another robot's nominal
        wheelbase or wheel diameter (as for :func:`umbmark.calibrate`).
    progress : callable, optional
        Called with the fraction done.
    **options
        How to read the sources (:class:`umbmark.runs.read_options.ReadOptions`).

    Raises
    ------
    InputError
        For sources without recorded wheel data, or too little to hold anything out.
    """
    read_options = ReadOptions.of(options)
    known = (*CANDIDATES, *GYROS) if read_options.imu_topic is not None else CANDIDATES
    chosen = tuple(known if methods is None else ("nominal", *methods))
    for name in chosen:
        if name in GYROS and name not in known:
            raise InputError(
                f"{option('methods', name)} needs {option('imu_topic')}: the bag's IMU"
            )
        if name not in known:
            raise InputError(f"{option('methods', repr(name))}: use some of {', '.join(known[1:])}")
    paths = (source, *more_sources)
    for path in paths:
        if is_table(path, read_options):
            raise InputError(
                "validation replays recorded runs: give run logs, OptiOdom sessions or bags, "
                "not a runs table",
                source=source_name(path),
            )
    read = read_each(
        paths,
        read_options,
        wheelbase=wheelbase,
        side_length=side_length,
        override_verdict=override_verdict,
    )
    gyro = None
    if len(paths) == 1 and any(name in GYROS for name in chosen):
        from umbmark.calibration.gyro_bag import read_gyro_recording

        gyro = read_gyro_recording(paths[0], read_options, wheelbase)
        gyro.refuse_saturated()
    return validate_read(read, chosen, progress, gyro)
