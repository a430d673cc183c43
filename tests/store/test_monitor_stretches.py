"""The monitor's stretches in the history: a calibration ``umbmark history`` lists, a
recording the fleet's summary reads, and the course a monitor started again takes up."""

from __future__ import annotations

import pytest

from umbmark.fleets.outcome import RecordingOutcome
from umbmark.store.history import History
from umbmark.store.monitor_stretches import StretchRecord, read_stretches, record_stretch

ACTIVE = {"wheelbase": 0.34, "wheel_diameter": 0.15, "c_L": 1.0, "c_R": 1.002,
          "wheel_separation_multiplier": 1.01}  # fmt: skip


def test_a_stretch_is_a_calibration_and_a_fleet_recording(tmp_path) -> None:
    h = History(tmp_path / "h.sqlite3")
    figures = {"E_d": (1.004, 1e-4), "E_b": (1.0201, 5e-4), "laser_yaw": (0.01, 4e-4)}
    stretch = StretchRecord("amr", "scan-matching", 1.7e9, 1.7e9 + 60, 12.0, 100.0, 120.0,
                            figures, ACTIVE)  # fmt: skip
    assert record_stretch(h, stretch) is not None
    (cal,) = h.calibrations("amr")
    # relative to the active parameters as a pass measures; composed back, the robot's
    assert cal.E_d == pytest.approx(1.004 / 1.002)
    assert cal.robot_E_d == pytest.approx(1.004)
    assert cal.robot_E_b == pytest.approx(1.0201)
    with h.transaction() as db:
        (text,) = db.execute("SELECT outcome FROM recordings").fetchone()
    import json

    outcome = RecordingOutcome.of_dict(json.loads(text))
    assert outcome.calibrated
    assert outcome.robot == "amr"
    assert outcome.start == 1.7e9
    assert outcome.figures["laser_yaw"] == (0.01, 4e-4)
    (back,) = read_stretches(h, "amr", 10)
    assert back.figures == figures
    assert back.end_odometer == 120.0
    assert back.time == 12.0


def test_umbmark_history_lists_a_monitors_stretches(tmp_path) -> None:
    """A stretch has no verdict (nothing to apply is judged on it): listed with ``-``."""
    from helpers import run_cli

    path = tmp_path / "h.sqlite3"
    h = History(path)
    figures = {"E_d": (1.004, 1e-4), "E_b": (1.0201, 5e-4)}
    record_stretch(h, StretchRecord("amr", "scan-matching", 1.7e9, 1.7e9 + 60, 12.0, 100.0,
                                    120.0, figures, ACTIVE))  # fmt: skip
    done = run_cli("history", "amr", "--history", str(path))
    assert done.returncode == 0, done.stderr
    assert "scan-matching" in done.stdout
