"""One install for a fleet: ``pip install '.[fleet]'`` into a fresh virtual environment
(no system packages, nothing but what the extra brings) reads a fleet's bags and
calibrates them (it brought Dask alone, and every recording failed with "rosbags is not
installed").

The package is copied out of the checkout first (its ``pyproject.toml``, ``README.md``
and ``src/``), so that building it leaves nothing in the checkout; the environment's
commands run without this checkout on their path. The fleet is simulated by the fresh
environment's own ``umbmark simulate --fleet`` and its truth (``truth.json``) is what the
calibrations are held to.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import ROOT, in_ci

#: Lines of pip's that say the package index could not be reached (a skip outside CI).
UNREACHABLE = ("NewConnectionError", "Max retries exceeded", "Temporary failure in name")
ROBOTS, DAYS = 2, 2


def test_the_fleet_extra_brings_the_engine_and_rosbags_and_the_readme_names_it():
    tomllib = pytest.importorskip("tomllib", reason="Python 3.11's TOML reader")
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"][
        "optional-dependencies"
    ]
    assert "umbmark[ros]" in extras["fleet"]
    assert any(r.startswith("rosbags") for r in extras["ros"])
    assert any(r.startswith("dask[distributed]") for r in extras["fleet"])
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme.split("## Quick start: a fleet\n", 1)[1].split("\n## ", 1)[0]
    assert "`python -m pip install '.[fleet]'`" in section


def _environment() -> dict[str, str]:
    """This process's environment without what would put this checkout or its
    environment on the fresh one's path."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env.pop("UMBMARK_HISTORY", None)
    return env


def _run(args: list[str], cwd: Path, timeout: float) -> subprocess.CompletedProcess[str]:
    return subprocess.run(args, cwd=cwd, env=_environment(), capture_output=True, text=True,
                          check=False, timeout=timeout)  # fmt: skip


@pytest.mark.slow
def test_a_fresh_fleet_install_reads_and_calibrates_a_fleet_of_bags(tmp_path: Path):
    source = tmp_path / "umbmark"
    source.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, source / name)
    shutil.copytree(ROOT / "src", source / "src",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))  # fmt: skip
    venv = tmp_path / "venv"
    made = _run([sys.executable, "-m", "venv", str(venv)], tmp_path, 120)
    assert made.returncode == 0, made.stderr
    python, umbmark = venv / "bin" / "python", venv / "bin" / "umbmark"
    installed = _run([str(python), "-m", "pip", "install", "-q", f"{source}[fleet]"], tmp_path,
                     1200)  # fmt: skip
    if (
        installed.returncode != 0
        and not in_ci()
        and any(s in installed.stderr for s in UNREACHABLE)
    ):
        pytest.skip(f"the package index cannot be reached: {installed.stderr.strip()[-200:]}")
    assert installed.returncode == 0, installed.stderr
    # Nothing of this checkout: the fresh environment's own umbmark, in its site-packages.
    where = _run([str(python), "-c", "import umbmark; print(umbmark.__file__)"], tmp_path, 60)
    assert where.returncode == 0, where.stderr
    assert Path(where.stdout.strip()).is_relative_to(venv), where.stdout

    simulated = _run([str(umbmark), "simulate", "--fleet", str(ROBOTS), "--days", str(DAYS),
                      "--minutes", "0.5", "--out", "fleet"], tmp_path, 600)  # fmt: skip
    assert simulated.returncode == 0, simulated.stderr
    watched = _run([str(umbmark), "fleet", "fleet", "--robot-from", "{robot}/{date}/*",
                    "--history", "h.sqlite3", "--workers", "1", "--json"], tmp_path,
                   900)  # fmt: skip
    assert watched.returncode == 0, watched.stderr
    assert "rosbags" not in watched.stderr
    data = json.loads(watched.stdout)
    assert (data["recordings_found"], data["recordings_done"]) == (ROBOTS * DAYS, ROBOTS * DAYS)
    assert data["failed"] == []
    assert data["warnings"] == []
    truth = json.loads((tmp_path / "fleet" / "truth.json").read_text(encoding="utf-8"))
    by = {r["robot"]: r for r in data["robots"]}
    assert sorted(by) == ["robot01", "robot02"]
    for robot in by.values():
        assert robot["recordings"] == DAYS
        # wheels, laser and IMU recorded: the gyro calibrated with the laser (issue 36)
        assert robot["latest"]["method"] == "gyro"
    # Each recording's E_d and gyro scale are its day's truth (robot02's wheel changed on
    # its second day).
    for row in truth["recordings"]:
        for figure, true in (("E_d", row["E_d"]), ("k_g", row["imu"]["k_g"])):
            track = by[row["robot"]]["figures"][figure]
            k = next(i for i, t in enumerate(track["times"]) if _day(t) == row["day"])
            error = track["standard_errors"][k]
            assert abs(track["values"][k] - true) <= max(5 * error, 3e-4), (figure, row)


def _day(start: float) -> str:
    import datetime as dt

    return dt.datetime.fromtimestamp(start, dt.timezone.utc).date().isoformat()
