"""How closely each estimator recovers a robot's errors from controller odometry alone.

The bags of ``tests/test_controller_odometry.py`` (a simulated robot with E_d = 1.003,
E_b = 1.012 driving 5 cw + 5 ccw squares; its wheel angles run through forward
implementations of ROS 1's / ros2_controllers' ``diff_drive_controller`` odometry, published
at 50 Hz, with an AMCL-style ground truth) are calibrated with every square-test estimator
and the trajectory fit; prints the errors of E_d and E_b. Run from the repository root:
python tools/odometry_inversion.py
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import umbmark

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import test_controller_odometry as bags


def main() -> None:
    session = bags.simulated_session(bags.ROBOT, ["cw"] * 5 + ["ccw"] * 5, side=bags.SIDE, rest=2.0)
    folder = Path(tempfile.mkdtemp())
    cases = [("ros1", bags.Humble, "topic"), ("sqlite3", bags.Jazzy, "tf")]
    print("bag      controller  odometry  method       E_d error   E_b error")
    for fmt, kind, how in cases:
        bag = bags.write_odometry_bag(
            folder / fmt, fmt, session, kind(0.34, 0.075, 0.075), odom_as=how
        )
        odom = {"odom_topic": "/odom"} if how == "topic" else {"odom_tf": ("odom", "base_link")}
        for method in ("exact", "endpose", "paper", "trajectory"):
            report = umbmark.calibrate(
                bag, side_length=bags.SIDE, wheelbase=0.34, wheel_diameter=0.15,
                truth_topic="/amcl_pose", method=method, **odom,
            )  # fmt: skip
            est = report.estimate
            print(
                f"{fmt:8} {kind.__name__:11} {how:9} {method:11} "
                f"{est.E_d - bags.E_D:+10.2e} {est.E_b - bags.E_B:+10.2e}"
            )


if __name__ == "__main__":
    main()
