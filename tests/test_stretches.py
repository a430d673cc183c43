"""Motion left out of the runs is not thrown away (issue 30, item 6).

Squares driven back to back, the recorder dropping ``/joint_states`` for 1.5 s across each
return to the start (the stop there is lost): no stop near the start tells the squares
apart, so they are left out ("closes its square 3 times"). The estimators that fit paths
of any shape (``trajectory``, ``endpoints``) fit them anyway, as their stretches between
the gaps; the square estimators still refuse. The squares are the package's simulator's
(a TurtleBot3-like robot, E_d = 1.005, E_b = 1.03), written as real bags.
"""

from __future__ import annotations

import pytest

import umbmark
from driven import TB3, squares, write_session_bag
from umbmark.sim.robot import SimRobot

from helpers import api_error

pytest.importorskip("rosbags")

from test_bag import LEFT, RIGHT

E_D, E_B = 1.005, 1.03
ROBOT = SimRobot.with_errors(TB3, E_d=E_D, E_b=E_B)
KEYWORDS = {
    "wheelbase": TB3.wheelbase, "wheel_diameter": TB3.wheel_diameter, "side_length": 1.0,
    "truth_topic": "/ground_truth", "left_joint": LEFT, "right_joint": RIGHT,
}  # fmt: skip


def _bag(tmp_path, pauses, chained):
    """Four ccw squares with ``pauses`` [s]; wheel messages lost across the returns after
    the squares ``chained``."""
    session = squares(ROBOT, ["ccw"] * 4, side=1.0, pauses=pauses)
    drops = [(session.stops[k] - 0.6, session.starts[k + 1] + 0.6) for k in chained]
    return write_session_bag(tmp_path / "tb3", "sqlite3", session, wheels="joints", drop=drops)


def _close(estimate) -> None:
    se = estimate.standard_errors
    assert abs(estimate.E_d - E_D) <= 3 * se["E_d"] + 1e-4, (estimate.E_d, se)
    assert abs(estimate.E_b - E_B) <= 3 * se["E_b"] + 1e-4, (estimate.E_b, se)


@pytest.mark.slow
def test_the_trajectory_fit_uses_the_motion_left_out_of_the_runs(tmp_path):
    # Squares 1 to 3 chained by the lost messages, square 4 after a rest: one run.
    bag = _bag(tmp_path, [2.0, 0.3, 0.3, 2.0, 2.0], chained=(0, 1))
    report = umbmark.calibrate(bag, **KEYWORDS, method="trajectory")
    assert len(report.runs) == 1
    (left,) = [w for w in report.warnings if "left out the motion" in w]
    assert "it closes its square 3 times" in left
    # the run and the three stretches between the gaps: the squares 1 to 3, cut twice
    assert report.model_fit is not None
    assert report.model_fit.runs == 4
    (used,) = [n for n in report.notes if "stretch(es)" in n]
    assert used.startswith("the trajectory fit used the 1 run(s) and 3 stretch(es) of motion")
    _close(report.estimate)


@pytest.mark.slow
def test_with_no_run_left_the_stretches_are_the_runs_of_a_trajectory_fit(tmp_path):
    bag = _bag(tmp_path, [2.0, 0.3, 0.3, 0.3, 2.0], chained=(0, 1, 2))
    message = api_error(umbmark.calibrate, bag, **KEYWORDS, method="exact")
    assert "it closes its square 4 times" in message
    assert message.endswith("; no run is left")
    for method in ("trajectory", "endpoints"):
        report = umbmark.calibrate(bag, **KEYWORDS, method=method)
        assert [run.label for run in report.runs] == [f"tb3 stretch {k}" for k in (1, 2, 3, 4)]
        assert any(n.startswith("no run is left: the 4 stretch(es)") for n in report.notes)
        if method == "trajectory":
            _close(report.estimate)
