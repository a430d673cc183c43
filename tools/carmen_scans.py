"""Scan matching and the scan-matching calibration on a real CARMEN log.

A CARMEN log (``FLASER`` or ``ROBOTLASER1`` sweeps, ``ODOM`` lines or the odometry the
laser lines carry) holds no wheel rotation: its odometry is turned back into it through
the nominal geometry given (``umbmark.sources.carmen.odometry_wheels``), so what the
calibration finds is against that geometry (the odometry's scale of distance ``E_s``, of
turning ``E_b``, the laser's mounting). This prints how many intervals were matched and
why the others were left out, how far each match lies from the odometry's own motion of
the laser (median and 95th percentile), and the calibration or its refusal.

The real log it was written for: the MIT Killian Court log (a B21 robot, a SICK laser,
180 beams, 3873 sweeps) as ``killian.g2o`` in the PyPI package ``rtb-data`` (MIT licence,
the Robotics Toolbox for Python's data)::

    python -m pip download --no-deps rtb-data==2.0.0 -d /tmp/rtb
    python -c "import zipfile; z = zipfile.ZipFile('/tmp/rtb/rtb_data-2.0.0-py3-none-any.whl'); \\
        zipfile.ZipFile(z.open('rtbdata/data/killian.g2o.zip')).extract('killian.g2o', '/tmp/rtb')"
    python tools/carmen_scans.py /tmp/rtb/killian.g2o --max-interval 4

Its sweeps are a pose graph's key frames, 1.8 s (median) and about 0.5 m apart, hence
``--max-interval 4``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from umbmark.calibration.scan import calibrate_intervals
from umbmark.core.errors import InputError
from umbmark.model.kinematics import OdometryGeometry
from umbmark.runs.read_options import ReadOptions
from umbmark.scans.intervals import IntervalOptions, OdometryGuess, match_intervals
from umbmark.sources.carmen import odometry_wheels, read_carmen


def odometry_motion(times: np.ndarray, poses: np.ndarray, t0: float, t1: float) -> np.ndarray:
    """The odometry's motion ``[x, y, yaw]`` from ``t0`` to ``t1`` in its frame at ``t0``."""
    unwrapped = np.column_stack([poses[:, :2], np.unwrap(poses[:, 2])])
    a = np.array([np.interp(t0, times, unwrapped[:, k]) for k in range(3)])
    b = np.array([np.interp(t1, times, unwrapped[:, k]) for k in range(3)])
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return np.array([c * dx + s * dy, -s * dx + c * dy, b[2] - a[2]])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", type=Path, help="a CARMEN log (.clf, .log, or g2o with ROBOTLASER1)")
    parser.add_argument("--wheelbase", type=float, default=0.5, help="nominal [m] (0.5)")
    parser.add_argument("--wheel-diameter", type=float, default=0.1, help="nominal [m] (0.1)")
    parser.add_argument("--min-interval", type=float, default=0.5, help="[s] (0.5)")
    parser.add_argument("--max-interval", type=float, default=1.5, help="[s] (1.5)")
    args = parser.parse_args()
    try:
        log = read_carmen(args.log)
    except InputError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    scans, odo = log.scans, log.odometry
    print(
        f"{len(scans)} sweeps of {scans.beams} beams over {scans.times[-1] - scans.times[0]:.0f} s "
        f"(median {np.median(np.diff(scans.times)):.2f} s apart), {len(odo.time)} odometry poses; "
        f"stated mounting: {log.stated_mounting}"
    )
    radius = args.wheel_diameter / 2
    wheels = odometry_wheels(odo, OdometryGeometry(radius, radius, args.wheelbase))
    mounting = log.stated_mounting or (0.0, 0.0, 0.0)
    options = IntervalOptions(
        min_interval=args.min_interval,
        max_interval=args.max_interval,
        guess=OdometryGuess(radius, radius, args.wheelbase, mounting),
    )
    start = time.process_time()
    report = match_intervals(scans, wheels, options)
    cpu = time.process_time() - start
    iv = report.intervals
    print(f"{len(iv)} intervals matched in {cpu:.1f} s of CPU; left out: {report.left_out}")
    if len(iv) == 0:
        return 1
    if log.stated_mounting is None:
        odometry = np.array(
            [
                odometry_motion(odo.time, odo.poses, s, s + d)
                for s, d in zip(iv.start_time, iv.duration, strict=True)
            ]
        )
        err = iv.sensor_motion - odometry
        shift = 1000.0 * np.hypot(err[:, 0], err[:, 1])
        yaw = np.degrees(np.abs(err[:, 2]))
        print(
            "match - odometry: "
            f"position median {np.median(shift):.1f} mm, 95 % {np.percentile(shift, 95):.1f} mm; "
            f"yaw median {np.median(yaw):.2f} deg, 95 % {np.percentile(yaw, 95):.2f} deg"
        )
    try:
        result = calibrate_intervals(
            [iv], ReadOptions(wheel_diameter=args.wheel_diameter), "scan-matching",
            wheelbase=args.wheelbase,
        )  # fmt: skip
    except InputError as err:
        print(f"calibration refused: {err}")
        return 0
    data = result.to_dict()
    se = data["standard_errors"]
    print(
        f"E_s {data['E_s']:.4f} ± {se['E_s']:.4f}, E_b {data['E_b']:.4f} ± {se['E_b']:.4f}, "
        f"E_d {data['E_d']:.5f} ± {se['E_d']:.5f}; laser x {data['laser_pose'][0]:.4f} m, "
        f"y {data['laser_pose'][1]:.4f} m, yaw {math.degrees(data['laser_pose'][2]):.2f} deg"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
