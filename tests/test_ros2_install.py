"""The ROS 2 install (``pip install ".[ros2]"``, no ROS installation) reads bags: the
documented ROS 2 workflow starts with ``umbmark info BAG`` (docs/ros.md), so the extra
brings rosbags along with rclpy.

The bag is written by ``umbmark simulate --bag`` in this environment, then read by the
ROS 2 environment's own Python (``.venv-ros2``, which the README's test command makes with
``".[ros2]"`` alone).
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

from helpers import run_cli

ROOT = Path(__file__).resolve().parents[1]
PYTHON = ROOT / ".venv-ros2" / "bin" / "python"

if not PYTHON.exists():
    if os.environ.get("CI") == "true":
        pytest.fail(f"{PYTHON} is missing: the test command makes it (README)", pytrace=False)
    pytest.skip(
        f"no {PYTHON.relative_to(ROOT)}: see the README's test command", allow_module_level=True
    )


@pytest.mark.slow
def test_the_ros2_install_reads_a_bag(tmp_path: Path) -> None:
    bag = tmp_path / "square"
    made = run_cli("simulate", "-L", "1", "--runs", "2", "--bag", str(bag), "--bag-storage", "mcap")
    assert made.returncode == 0, made.stderr
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.run(
        [str(PYTHON), "-m", "umbmark", "info", str(bag), "--json"],
        capture_output=True, text=True, check=False, env=env, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    info = json.loads(proc.stdout)
    assert "/joint_states" in json.dumps(info)
