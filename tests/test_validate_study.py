"""Choosing an estimator by evidence: held-out validation on recorded runs, Monte Carlo on
virtual robots, and calibrate --method auto."""

from __future__ import annotations

import math

import pytest

import umbmark
from umbmark.jobs import study as study_module

from helpers import api_error, cli_error


@pytest.fixture(scope="module")
def sessions(tmp_path_factory):
    """Two recorded sessions of one virtual robot (E_d 1.004, E_b 1.02), 2 + 2 runs each."""
    folder = tmp_path_factory.mktemp("sessions")
    paths = []
    for seed in (1, 2):
        path = folder / f"session-{seed}"
        umbmark.simulate(E_d=1.004, E_b=1.02, runs=2, side_length=2, seed=seed, logs=path)
        paths.append(path)
    return paths


def test_leave_one_source_out_prefers_a_calibration_to_the_nominal(sessions):
    report = umbmark.validate(*sessions, methods=["exact", "endpose"])
    assert report.scheme == "leave one source out"
    assert [f.held_out for f in report.folds] == [str(p) for p in sessions]
    nominal = report.mean_error("nominal")
    exact = report.mean_error("exact")
    assert nominal is not None
    assert exact is not None
    # The robot's errors are far above the slip: any calibration predicts far better.
    assert exact < nominal / 3
    assert report.recommended in ("exact", "endpose")
    data = report.to_dict()
    assert set(data["mean_end_error"]) == {"nominal", "exact", "endpose"}
    assert data["recommended"] == report.recommended


def test_leave_one_run_out_on_one_source(sessions):
    report = umbmark.validate(sessions[0], methods=["paper"])
    assert report.scheme == "leave one run out"
    assert len(report.folds) == 4
    # Two runs per direction: holding one out leaves a direction with one run, which no
    # square estimator can use.
    assert all(f.errors["paper"] is None for f in report.folds)
    assert report.mean_error("paper") is None
    assert report.recommended is None


def test_validation_needs_recorded_runs(table):
    path = table([("cw", 0.1, 0.1, 0, 0)] * 2 + [("ccw", 0.1, -0.1, 0, 0)] * 2)
    assert "validation replays recorded runs" in api_error(umbmark.validate, path)
    assert "methods='median'" in api_error(umbmark.validate, path, methods=["median"])


@pytest.mark.slow
def test_method_auto_takes_the_recommendation(sessions):
    report = umbmark.calibrate(*sessions, method="auto")
    checked = umbmark.validate(*sessions)
    assert report.estimate.method == checked.recommended
    assert report.notes[-1].startswith(f"method auto: {checked.recommended}, by held-out")


@pytest.mark.slow
def test_validate_command_names_a_missing_source_plainly():
    """(That ``--json`` is the library's dictionary: tests/cli/test_main.py, for every command.)"""
    assert "needs" not in cli_error("validate", "nothing.csv")


@pytest.mark.slow
def test_study_reports_what_each_estimator_reaches(monkeypatch):
    monkeypatch.setattr(study_module, "CHUNK", 3)  # several chunks, one worker
    report = umbmark.study(trials=6, methods=["truth", "exact"], workers=1, seed=4)
    truth, exact = report.results
    assert (truth.method, exact.method) == ("truth", "exact")
    assert truth.trials == exact.trials == 6
    assert truth.bias_E_d_ppm == 0.0
    assert exact.refused == 0.0
    # The exact geometry inverts the noise-free closed loop to a few ppm.
    assert abs(exact.worst_bias_E_d_ppm) < 10
    assert abs(exact.worst_bias_E_b_ppm) < 10
    assert 0.0 <= exact.floor_after_one <= 1.0
    assert math.isnan(truth.coverage_E_d)  # the truth has no interval
    assert report.to_dict()["results"][0]["coverage_95_E_d"] is None
    # Chunks carry their own seeds: the result does not depend on the workers.
    again = umbmark.study(trials=6, methods=["truth", "exact"], workers=2, seed=4)
    assert again.results == report.results


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"methods": ["median"]}, "methods='median'"),
        ({"trials": 0}, "trials must be 1 to 100000, got 0"),
        ({"runs": [1]}, "runs must be 2 to 100, got 1"),
        ({"E_d_spread": 0.5}, "E_d_spread must be 0 to 0.2, got 0.5"),
    ],
)
def test_study_refuses_bad_options(options, message):
    assert message in api_error(umbmark.study, **options)
