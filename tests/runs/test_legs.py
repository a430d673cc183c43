"""A side length the reference's legs disagree with is refused (issue 30, item 1).

Run logs written by the simulation (4 m squares by default; here 2 m ones, the truth
known) and the real OptiOdom sessions (0.75 m and 1.7 m squares, their metadata's ``L``).
ROS bags: ``tests/test_simulate_bag.py``.
"""

from __future__ import annotations

import pytest

import umbmark

from helpers import OPTIODOM, api_error, cli_error

SQUARE = OPTIODOM / "square" / "230620202042"
SQUARE2 = OPTIODOM / "square" / "231220200029"


@pytest.fixture(scope="module")
def log(tmp_path_factory):
    folder = tmp_path_factory.mktemp("legs") / "log"
    umbmark.simulate(side_length=2.0, runs=2, dt=0.05, seed=3, E_d=1.01, E_b=1.02, logs=folder)
    return folder


def test_a_run_log_refuses_a_wrong_side_length(log):
    line = cli_error("calibrate", str(log), "--side-length", "2.5")
    assert line == (
        f"umbmark: error: {log}: --side-length 2.5 m, but the reference's legs measure "
        "2.00 m (median of 16 legs in 4 runs): give --side-length 2 m\n"
    )
    message = api_error(umbmark.calibrate, log, side_length=1.6)
    assert "side_length=1.6 m, but the reference's legs measure 2.00 m" in message
    # 5 % off is what a scale error makes: not refused; the log's own side neither.
    assert umbmark.calibrate(log, side_length=2.1).estimate.E_d > 0
    assert umbmark.calibrate(log).estimate.E_d > 0


def test_a_wrong_side_in_the_metadata_is_refused_by_its_field(log, tmp_path):
    meta = log / "metadata.yaml"
    copy = tmp_path / "log"
    copy.mkdir()
    for path in log.iterdir():
        (copy / path.name).write_bytes(path.read_bytes())
    text = meta.read_text()
    assert "side_length: 2.0" in text
    (copy / "metadata.yaml").write_text(text.replace("side_length: 2.0", "side_length: 3.0"))
    message = api_error(umbmark.calibrate, copy)
    assert message.startswith(f"{copy}: side_length in {copy / 'metadata.yaml'} 3 m, but")
    assert "give side_length=2 m" in message


@pytest.mark.skipif(not SQUARE.is_dir(), reason="no OptiOdom data")
def test_real_squares_pass_and_a_wrong_side_is_refused():
    assert umbmark.calibrate(SQUARE).estimate.E_d > 0  # L = 0.75 m in its metadata
    assert umbmark.calibrate(SQUARE, side_length=0.75).estimate.E_d > 0
    message = api_error(umbmark.calibrate, SQUARE, side_length=1.0)
    assert "the reference's legs measure 0.74 m (median of 24 legs in 6 runs)" in message
    if SQUARE2.is_dir():
        assert umbmark.calibrate(SQUARE2).estimate.E_d > 0  # L = 1.7 m
