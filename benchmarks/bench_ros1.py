"""The self-calibration routine's wall time against the virtual robot directly and through
ROS 1, side by side in one run.

- Direct: :func:`umbmark.jobs.selfcal.selfcal` on a
  :class:`~umbmark.robot.virtual.VirtualRobot`, which simulates as fast as the computer allows.
- Through ROS 1: a ``rosmaster`` on a free port, ``tests/ros1_robot_node.py`` (the same
  virtual robot behind /cmd_vel, /clock, /odom, /scan, TF and dynamic_reconfigure, its
  simulated time running ``--rate`` times faster than real time) and ``umbmark selfcal
  --ros1`` as a subprocess (its start-up included), one fresh master and node per rate.

The robot's time is the same routine's on both sides (printed for the direct run, about
340 s for ``--runs 2 -L 1``): through ROS the wall time is bounded below by robot time /
rate; at high rates the control loop (a command, a wait of one 20 ms period, a reading,
over TCP) is the limit.

Run: python benchmarks/bench_ros1.py [--runs 2] [--side 1] [--rates 8,20]
(needs python3-rospy, python3-rosmaster, python3-dynamic-reconfigure, python3-tf2-ros)
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from umbmark.jobs.selfcal import selfcal
from umbmark.robot.ros_common import master_problem
from umbmark.robot.virtual import VirtualRobot

NODE = Path(__file__).resolve().parent.parent / "tests" / "ros1_robot_node.py"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def direct(runs: int, side: float, out: Path) -> tuple[float, float, float, float]:
    """Wall time [s], robot time [s], E_max,syst before and after [m]."""
    robot = VirtualRobot(E_d=1.004, E_b=0.97, slip=0.0004, seed=1)
    start = time.perf_counter()
    report = selfcal(robot, runs=runs, side_length=side, max_passes=1, out=out)
    wall = time.perf_counter() - start
    summary = json.loads(report.to_json())
    return wall, robot.now(), summary["e_max_syst_before"], summary["e_max_syst_after"]


def through_ros1(
    runs: int, side: float, rate: float, tmp: Path
) -> tuple[float, float, float, float]:
    """Wall time [s] of ``umbmark selfcal --ros1``, NaN (the robot's time is the node's),
    E_max,syst before and after [m]."""
    rosmaster = shutil.which("rosmaster")
    if rosmaster is None:
        raise SystemExit("rosmaster is not installed (python3-rosmaster)")
    port = _free_port()
    env = {
        **os.environ,
        "ROS_MASTER_URI": f"http://127.0.0.1:{port}",
        "ROS_IP": "127.0.0.1",
        "ROS_HOME": str(tmp / "ros_home"),
    }
    master = subprocess.Popen([rosmaster, "--core", "-p", str(port)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    node = None
    try:
        while master_problem(env["ROS_MASTER_URI"], 1.0) is not None:
            time.sleep(0.1)
        node = subprocess.Popen(
            [sys.executable, str(NODE), "--rate", str(rate)],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        )  # fmt: skip
        assert node.stdout is not None
        assert node.stdout.readline().strip() == "ready"
        out = tmp / f"ros1-{rate:g}"
        start = time.perf_counter()
        done = subprocess.run(
            [sys.executable, "-m", "umbmark", "selfcal", "--ros1", "--runs", str(runs), "-L",
             str(side), "--max-passes", "1", "--out", str(out), "--json"],
            env=env, capture_output=True, text=True, check=False,
        )  # fmt: skip
        wall = time.perf_counter() - start
        if done.returncode != 0:
            raise SystemExit(f"umbmark selfcal --ros1 failed: {done.stderr.strip()}")
        report = json.loads(done.stdout)
        return wall, float("nan"), report["e_max_syst_before"], report["e_max_syst_after"]
    finally:
        for proc in (node, master):
            if proc is not None:
                proc.terminate()
                proc.wait()
        if node is not None and node.stdout is not None:
            node.stdout.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--side", type=float, default=1.0)
    parser.add_argument("--rates", default="8,20", help="the node's rates, comma-separated")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        rows = [("virtual robot, direct", *direct(args.runs, args.side, tmp / "direct"))]
        for rate in (float(r) for r in args.rates.split(",")):
            rows.append(
                (f"ROS 1, node at {rate:g}x", *through_ros1(args.runs, args.side, rate, tmp))
            )
    base = rows[0][1]
    print(f"umbmark selfcal, --runs {args.runs} -L {args.side:g} --max-passes 1 (+ verification)")
    print(f"{'robot':<24} {'wall [s]':>9} {'robot time [s]':>15} {'ratio':>7} "
          f"{'E_max before [mm]':>18} {'after [mm]':>11}")  # fmt: skip
    for name, wall, robot_time, before, after in rows:
        shown = "-" if math.isnan(robot_time) else f"{robot_time:.1f}"
        print(f"{name:<24} {wall:9.2f} {shown:>15} {wall / base:7.1f} "
              f"{before * 1000:18.1f} {after * 1000:11.1f}")  # fmt: skip


if __name__ == "__main__":
    main()
