"""The self-calibration routine's wall time against the virtual robot directly and through
ROS 2, side by side in one run, and the drive loop's achieved rate over ROS 2.

- Direct: :func:`umbmark.jobs.selfcal.selfcal` on a
  :class:`~umbmark.robot.virtual.VirtualRobot`, as fast as the computer allows.
- Through ROS 2: ``tests/ros2_robot_node.py`` (the same virtual robot behind
  diff_drive_controller's interfaces, ``/clock`` ``--rate`` times faster than real time) and
  ``umbmark selfcal --ros2`` as subprocesses with ``.venv-ros2/bin/python`` (rclpy from the
  package index) on a private ``ROS_DOMAIN_ID``: pass 1, the stop for a controller restart,
  the node restarted on the overlay, ``--resume`` and the verification. The wall time is
  the two ``umbmark`` runs (start-up included), not the node's restart.
- The drive loop: ``tests/ros2_probe.py drive``, one velocity per 20 ms of sim time for 10 s
  of sim time: loops per sim second (50 is every period) and per wall second.

Run: python benchmarks/bench_ros2.py [--runs 2] [--side 1] [--rates 8,20]
(needs .venv-ros2: the README's test command makes it)
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile
import time
from pathlib import Path

from umbmark.jobs.selfcal import selfcal
from umbmark.robot.virtual import VirtualRobot

ROOT = Path(__file__).resolve().parent.parent
PYTHON = ROOT / ".venv-ros2" / "bin" / "python"
NODE = ROOT / "tests" / "ros2_robot_node.py"
PROBE = ROOT / "tests" / "ros2_probe.py"


def direct(runs: int, side: float, out: Path) -> tuple[float, float, float]:
    """Wall time [s], E_max,syst before and after [m]."""
    robot = VirtualRobot(E_d=1.004, E_b=0.97, slip=0.0004, seed=1)
    start = time.perf_counter()
    report = selfcal(robot, runs=runs, side_length=side, max_passes=1, out=out)
    wall = time.perf_counter() - start
    summary = json.loads(report.to_json())
    return wall, summary["e_max_syst_before"], summary["e_max_syst_after"]


def _env(tmp: Path, domain: int) -> dict[str, str]:
    return {
        **os.environ,
        "ROS_DOMAIN_ID": str(domain),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
        "ROS_LOG_DIR": str(tmp / "ros_log"),
        "PYTHONPATH": str(ROOT / "src"),
    }


class Node:
    def __init__(self, env: dict[str, str], rate: float, *args: str) -> None:
        self.proc = subprocess.Popen(
            [str(PYTHON), str(NODE), "--rate", str(rate), *args],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        )  # fmt: skip
        assert self.proc.stdout is not None
        assert self.proc.stdout.readline().strip() == "ready"

    def close(self) -> None:
        self.proc.terminate()
        self.proc.wait()
        if self.proc.stdout is not None:
            self.proc.stdout.close()


def _umbmark(env: dict[str, str], *args: str) -> tuple[float, dict[str, object]]:
    start = time.perf_counter()
    done = subprocess.run(
        [str(PYTHON), "-m", "umbmark", "selfcal", "--ros2", *args, "--json"],
        env=env, capture_output=True, text=True, check=False,
    )  # fmt: skip
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"umbmark selfcal --ros2 failed: {done.stderr.strip()[-2000:]}")
    report: dict[str, object] = json.loads(done.stdout)
    return wall, report


def through_ros2(
    runs: int, side: float, rate: float, tmp: Path, domain: int
) -> tuple[float, float, float, float, float]:
    """Wall time [s] of pass 1 and of the resumed verification, E_max,syst before and
    after [m], the drive loop's loops per sim second and per wall second."""
    env = _env(tmp, domain)
    out = tmp / f"ros2-{rate:g}"
    node = Node(env, rate)
    try:
        done = subprocess.run(
            [str(PYTHON), str(PROBE), "drive", "10"],
            env=env, capture_output=True, text=True, check=True,
        )  # fmt: skip
        loop = json.loads(done.stdout.strip().splitlines()[-1])
        wall_1, _ = _umbmark(env, "--runs", str(runs), "-L", str(side), "--max-passes", "1",
                             "--out", str(out))  # fmt: skip
    finally:
        node.close()
    node = Node(env, rate, "--params-file", str(out / "restart-overlay.yaml"))
    try:
        wall_2, report = _umbmark(env, "--resume", str(out))
    finally:
        node.close()
    before, after = report["e_max_syst_before"], report["e_max_syst_after"]
    return (wall_1 + wall_2, float(before), float(after),  # type: ignore[arg-type]
            loop["loops_per_sim_second"], loop["loops_per_wall_second"])  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--side", type=float, default=1.0)
    parser.add_argument("--rates", default="8,20", help="the node's rates, comma-separated")
    args = parser.parse_args()
    if not PYTHON.exists():
        raise SystemExit(f"no {PYTHON}: make it with the README's test command")
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        base, before0, after0 = direct(args.runs, args.side, tmp / "direct")
        rows = []
        for k, rate in enumerate(float(r) for r in args.rates.split(",")):
            rows.append((rate, *through_ros2(args.runs, args.side, rate, tmp,
                                             1 + (os.getpid() + k) % 100)))  # fmt: skip
    print(f"umbmark selfcal, --runs {args.runs} -L {args.side:g} --max-passes 1 (+ verification)")
    print(f"{'robot':<24} {'wall [s]':>9} {'ratio':>7} {'E_max before [mm]':>18} "
          f"{'after [mm]':>11} {'loop [1/sim s]':>15} {'loop [1/wall s]':>16}")  # fmt: skip
    print(f"{'virtual robot, direct':<24} {base:9.2f} {1.0:7.1f} {before0 * 1000:18.1f} "
          f"{after0 * 1000:11.1f} {'-':>15} {'-':>16}")  # fmt: skip
    for rate, wall, before, after, per_sim, per_wall in rows:
        name = f"ROS 2, node at {rate:g}x"
        print(f"{name:<24} {wall:9.2f} {wall / base:7.1f} {before * 1000:18.1f} "
              f"{after * 1000:11.1f} {per_sim:15.1f} {per_wall:16.1f}")  # fmt: skip


if __name__ == "__main__":
    main()
