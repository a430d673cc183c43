"""/diagnostics without ROS running: laid out as diagnostic_updater writes it, and a real
DiagnosticArray filled (ROS 1's Debian message classes, where installed: plain Python)."""

from __future__ import annotations

import pytest

from umbmark.monitor.diagnostics import STATUS_NAME, compose, fill_array, level_value
from umbmark.monitor.status import FIGURES, Figure, MonitorStatus


def _status(level: str = "WARN") -> MonitorStatus:
    figures = tuple(
        Figure(name, 1.0021 if name == "E_d" else None, 0.0004 if name == "E_d" else None,
               unit, "" if name == "E_d" else "turned one way only")
        for name, unit in FIGURES
    )  # fmt: skip
    return MonitorStatus(2000.0, "r7", level, "E_d changed", figures,  # type: ignore[arg-type]
                         123.4, 5.0, 6.0, 789.0, 1500.0, applied="yaml: wrote x")  # fmt: skip


def test_the_status_is_named_and_levelled_as_diagnostic_updater_writes_it() -> None:
    """diagnostic_updater names a task's status ``<node name>: <task>`` and levels it OK 0,
    WARN 1, ERROR 2, STALE 3 (diagnostic_msgs/DiagnosticStatus); ROS 2's level field is
    one byte (``b'\\x00'``), ROS 1's an integer."""
    for index, level in enumerate(("OK", "WARN", "ERROR", "STALE")):
        d = compose(_status(level))
        assert (d.name, d.level, d.hardware_id, d.message) == (
            "umbmark_monitor: odometry", index, "r7", "E_d changed",
        )  # fmt: skip
    assert STATUS_NAME == "umbmark_monitor: odometry"
    assert compose(_status(), "/ns/renamed").name == "ns/renamed: odometry"
    assert [level_value(k, ros2=True) for k in range(4)] == [b"\x00", b"\x01", b"\x02", b"\x03"]
    assert level_value(2, ros2=False) == 2
    with pytest.raises(ValueError, match="0 to 3"):
        level_value(4, ros2=True)


def test_the_key_values_are_strings_in_order() -> None:
    values = dict(compose(_status()).values)
    assert compose(_status()).values[0] == ("E_d", "1.0021 +- 0.0004")
    assert values["laser_x [m]"] == "not determined: turned one way only"
    assert values["metres observed [m]"] == "123.4"
    assert values["applied"] == "yaml: wrote x"
    assert all(isinstance(k, str) and isinstance(v, str) for k, v in compose(_status()).values)


def test_a_real_diagnostic_array_is_filled() -> None:
    msg = pytest.importorskip("diagnostic_msgs.msg", reason="python3-diagnostic-msgs (Debian)")
    array = fill_array(compose(_status("ERROR")), msg.DiagnosticArray, msg.DiagnosticStatus,
                       msg.KeyValue, "STAMP", ros2=False)  # fmt: skip
    assert array.header.stamp == "STAMP"
    (status,) = array.status
    assert (status.name, status.level, status.hardware_id) == (STATUS_NAME, 2, "r7")
    assert (status.values[0].key, status.values[0].value) == ("E_d", "1.0021 +- 0.0004")
    assert status.level == msg.DiagnosticStatus.ERROR
