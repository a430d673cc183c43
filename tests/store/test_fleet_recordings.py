"""The fleet's recordings in the history: recorded with what they gave, known again by
identity or digest under the same reading options (a failed one tried again), read back
latest first per recording; a calibrated one is a calibration of its robot too."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

from umbmark.store.fleet_recordings import (
    RecordingRow,
    done_recordings,
    identity,
    options_key,
    read_recordings,
    record_recording,
)
from umbmark.store.history import History
from umbmark.store.records import NewCalibration


def _row(path: str, status: str, digest: str | None, key: str, start: float = 0.0) -> RecordingRow:
    return RecordingRow("amr1", path, digest, f"{path}|1|2", key, start, 8.0, status,  # type: ignore[arg-type]
                        None if status == "calibrated" else "why", {"path": path})  # fmt: skip


def _calibration() -> NewCalibration:
    return NewCalibration(
        dt.datetime(2026, 11, 2, tzinfo=dt.timezone.utc), "scan-matching", 1.003, 0.98, 1.001,
        0.12, {"E_d": 1e-4}, {"wheelbase": 0.34}, {"wheel_separation_multiplier": 0.98},
        {"level": "apply", "reasons": [], "instead": None}, 0.34, 0.15,
    )  # fmt: skip


def test_recordings_are_known_again_by_identity_or_digest(tmp_path: Path):
    store = History(tmp_path / "h.sqlite3")
    key = options_key({"scan_topic": "/scan", "wheelbase": 0.34})
    assert key == options_key({"wheelbase": 0.34, "scan_topic": "/scan"})  # order aside
    assert key != options_key({"scan_topic": "/scan2", "wheelbase": 0.34})
    id = record_recording(store, _row("a.mcap", "calibrated", "d1", key, 2.0), _calibration())
    assert id == 1
    (cal,) = store.calibrations("amr1")
    assert cal.inputs == [{"name": "a.mcap", "sha256": "d1"}]  # the digest, not read again
    record_recording(store, _row("b.mcap", "left out", "d2", key, 1.0), None)
    record_recording(store, _row("c.mcap", "failed", None, key, 3.0), None)
    # The failed one is tried again; the others are known with their key and robot.
    assert done_recordings(store) == {"a.mcap|1|2": {key: "amr1"}, "b.mcap|1|2": {key: "amr1"}}
    record_recording(store, _row("b.mcap", "left out", "d2", options_key({}), 2.0), None)
    assert done_recordings(store)["b.mcap|1|2"] == {key: "amr1", options_key({}): "amr1"}
    rows = read_recordings(History(tmp_path / "h.sqlite3", read_only=True))
    assert [r.path for r in rows] == ["b.mcap", "a.mcap", "b.mcap", "c.mcap"]  # oldest first
    assert rows[1].calibration == 1
    # Tried again and calibrated: the latest row is the one read.
    record_recording(store, _row("c.mcap", "calibrated", "d3", key, 3.0), _calibration())
    assert [r.status for r in read_recordings(store, ["amr1"])][-1] == "calibrated"
    assert read_recordings(store, ["other"]) == []


def test_identity_is_path_size_and_time(tmp_path: Path):
    one = tmp_path / "a.mcap"
    one.write_bytes(b"x" * 10)
    first = identity(str(one))
    assert first.endswith(f"|10|{one.stat().st_mtime_ns}")
    one.write_bytes(b"x" * 11)
    assert identity(str(one)) != first
    folder = tmp_path / "bag"
    folder.mkdir()
    (folder / "metadata.yaml").write_text("x")
    (folder / "bag_0.db3").write_bytes(b"yy")
    assert "|3|" in identity(str(folder))


def test_a_urls_identity_is_url_size_and_version_and_an_unreadable_one_matches_nothing(
    tmp_path: Path,
):
    """``file://`` and ``memory://`` through fsspec: the URL and size, and a version that
    follows the modification time; a URL that cannot be read: empty, which no recording
    done has (it is done again)."""
    import os

    import pytest

    pytest.importorskip("fsspec", reason="the remote extra: pip install '.[remote]'")
    one = tmp_path / "a.mcap"
    one.write_bytes(b"x" * 10)
    url = f"file://{one}"
    first = identity(url)
    assert first.startswith(f"{url}|10|")
    assert identity(url) == first
    os.utime(one, ns=(one.stat().st_atime_ns, one.stat().st_mtime_ns + 10**9))
    assert identity(url).startswith(f"{url}|10|")
    assert identity(url) != first
    folder = tmp_path / "bag"
    folder.mkdir()
    (folder / "metadata.yaml").write_text("x")
    (folder / "bag_0.db3").write_bytes(b"yy")
    assert identity(f"file://{folder}").startswith(f"file://{folder}|3|")
    gone = f"memory:///umbmark-{os.getpid()}/gone.mcap"
    assert identity(gone) == ""
    store = History(tmp_path / "h.sqlite3")
    key = options_key({})
    record_recording(store, _row(gone, "calibrated", "d1", key), None)  # identity gone|1|2
    unreadable = RecordingRow("amr1", gone, "d2", identity(gone), key, 0.0, 1.0, "left out",
                              "why", {})  # fmt: skip
    record_recording(store, unreadable, None)
    assert set(done_recordings(store)) == {f"{gone}|1|2"}  # the empty identity: none


def test_a_recording_read_again_with_other_options_comes_in_the_order_last_recorded(
    tmp_path: Path,
):
    """One recording read with options A, then B, then A again (a robot's entry changed
    and changed back): both rows are read back, the one recorded last (A's) after the
    other, so that a summary keeping the last of a recording keeps the latest."""
    store = History(tmp_path / "h.sqlite3")
    a, b = options_key({"scan_topic": "/scan"}), options_key({"scan_topic": "/front/scan"})
    for key in (a, b, a):
        record_recording(store, _row("r.mcap", "left out", "d1", key, 5.0), None)
    assert [r.options_key for r in read_recordings(store)] == [b, a]
