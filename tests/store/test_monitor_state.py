"""A robot's monitor in the history besides its stretches: its state (the odometer as it
last said it, where it last applied), and what it applied, a calibration marked applied."""

from __future__ import annotations

import pytest

from umbmark.store.history import History
from umbmark.store.monitor_state import (
    AppliedRecord,
    MonitorState,
    read_state,
    record_applied,
    save_state,
)

ACTIVE = {"wheelbase": 0.34, "wheel_diameter": 0.15, "c_L": 1.0, "c_R": 1.002,
          "wheel_separation_multiplier": 1.01}  # fmt: skip


def test_the_state_is_kept_per_robot_and_replaced(tmp_path) -> None:
    h = History(tmp_path / "h.sqlite3")
    assert read_state(h, "amr") is None
    save_state(h, "amr", MonitorState(12.5, None))
    save_state(h, "amr", MonitorState(30.25, 20.0))
    save_state(h, "other", MonitorState(1.0, None))
    assert read_state(h, "amr") == MonitorState(30.25, 20.0)
    assert read_state(History(tmp_path / "h.sqlite3", read_only=True), "other") == MonitorState(
        1.0, None
    )


def test_an_apply_is_a_calibration_marked_applied(tmp_path) -> None:
    """The robot is E_d 1.006, E_b 1.0302 (what it is); with c_L 1, c_R 1.002 and the
    separation multiplier 1.01 active, a pass would have measured E_d 1.006 / 1.002 and E_b
    1.0302 / 1.01 = 1.02; the new multipliers are kept as given, and a later calibration
    composes with them."""
    h = History(tmp_path / "h.sqlite3")
    new = {"c_L": 0.997, "c_R": 1.003, "wheel_separation_multiplier": 1.0302}
    record = AppliedRecord("amr", "scan-matching", 1.7e9, 140.0,
                           {"E_d": (1.006, 1e-4), "E_b": (1.0302, 5e-4)}, ACTIVE, new,
                           {"level": "apply", "reasons": [], "instead": None},
                           "set_parameters: configured")  # fmt: skip
    id = record_applied(h, record)
    (cal,) = h.calibrations("amr")
    assert cal.id == id
    assert cal.applied
    assert cal.E_d == pytest.approx(1.006 / 1.002)
    assert cal.E_b == pytest.approx(1.0302 / 1.01)
    assert cal.robot_E_d == pytest.approx(1.006)
    assert cal.new["left_wheel_radius_multiplier"] == 0.997
    assert cal.new["right_wheel_radius_multiplier"] == 1.003
    assert cal.new["wheel_separation_multiplier"] == 1.0302
    assert cal.verdict == {"level": "apply", "reasons": [], "instead": None}
    assert h.last_applied("amr") == cal
