"""What recordings hold, and whether they identify the scrub model's turn-rate term.

By hand (coherent turns and the inflation of the wheelbase's uncertainty, worked out
below), on simulated robots with known truth (squares alone against squares and circles,
robots with and without scrub; :mod:`drive_sim`), and on the real OptiOdom sessions:
``trajectory-scrub`` falls back to one wheelbase with a warning where the recordings do
not identify it, ``--method auto`` does not pick it for a pool of squares, and
``umbmark validate`` says what its figures cover.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import drive_sim
import umbmark
from drive_sim import NO_SCRUB, SCRUB
from umbmark.estimators.motions import MAX_INFLATION, motion_coverage
from umbmark.estimators.trajectory import trajectory_estimate
from umbmark.estimators.trajectory_fit import fit_trajectories
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import RunLog

from helpers import OPTIODOM, run_cli

#: Radius 1 m: wheel angles are travel [m]; wheelbase 0.2 m.
UNIT = WheelParams(wheelbase=0.2, wheel_diameter=2.0)
NOMINAL = WheelParams(wheelbase=drive_sim.WHEELBASE, wheel_diameter=2 * drive_sim.RADIUS)


def _log(d_left, d_right) -> RunLog:
    """A run from wheel travel per step (radius 1: angles are travel); no ground truth."""
    steps = np.column_stack([d_left, d_right]).astype(float)
    angles = np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
    n = angles.shape[0]
    return RunLog(np.arange(n, dtype=float), angles, np.full((n, 3), np.nan))


# --- by hand -------------------------------------------------------------------------------

U = 0.001
SPOT = _log(np.full(50, -U), np.full(50, U))  # turning 100 U, travel 100 U: w = 1
ARC = _log(np.full(50, U), np.full(50, 3 * U))  # turning 100 U, travel 200 U: w = 0.5
GENTLE = _log(np.full(250, 0.8 * U), np.full(250, 1.2 * U))  # turning 100 U, travel 500 U: w 0.2


def test_two_turning_shares_far_apart_and_the_inflation_by_hand():
    # Turns on the spot (w = 1) and arcs of w = 0.5, each turning 100 U / b: equal weights.
    cover = motion_coverage([SPOT, ARC], UNIT)
    assert cover.mean_share == pytest.approx(0.75)
    assert cover.share_spread == pytest.approx(0.25)
    # Worst at w = 0: k = sqrt(1 + (0.75 / 0.25)^2) = sqrt(10) = 3.16 > 3.
    assert cover.worst_share == 0.0
    assert cover.inflation == pytest.approx(math.sqrt(10.0))
    assert not cover.identifies_scrub
    assert cover.held == ("arc", "spot")
    assert cover.travel == pytest.approx({"straight": 0.0, "arc": 2 / 3, "spot": 1 / 3})
    assert cover.weight == pytest.approx({"straight": 0.0, "arc": 0.5, "spot": 0.5})
    assert cover.turned["spot"] == pytest.approx(100 * U / 0.2)
    problem = cover.scrub_problem()
    assert problem is not None
    assert "it would extrapolate to arcs (its wheelbase there 3 times less certain" in problem
    # A third turning share, 0.2, with the same weight: mean 0.5667, variance
    # (0.4333^2 + 0.0667^2 + 0.3667^2) / 3 = 0.10889; k(0) = sqrt(1 + 0.5667^2 / 0.10889).
    wider = motion_coverage([SPOT, ARC, GENTLE], UNIT)
    assert wider.mean_share == pytest.approx(1.7 / 3)
    assert wider.share_spread**2 == pytest.approx(0.10889, rel=1e-4)
    assert wider.inflation == pytest.approx(math.sqrt(1 + (1.7 / 3) ** 2 / 0.108889), rel=1e-4)
    assert wider.inflation < MAX_INFLATION
    assert wider.identifies_scrub
    assert wider.scrub_problem() is None


def test_weaving_weighs_little_and_a_pause_does_not_cut_a_turn():
    # A straight leg whose wheels differ by +-0.05 U in turn (w = 0.05): 100 turns of
    # 0.1 U each.
    e = np.where(np.arange(100) % 2 == 0, 0.05 * U, -0.05 * U)
    weave = _log(U - e, U + e)
    cover = motion_coverage([SPOT, weave], UNIT)
    # Weights (turning^2): the spot turn (100 U)^2, the weave 100 (0.1 U)^2 = U^2.
    assert cover.weight["straight"] == pytest.approx(1 / 10_001)
    assert cover.held == ("straight", "spot")  # the leg is 200 U of the 300 U travelled
    assert not cover.identifies_scrub
    problem = cover.scrub_problem()
    assert problem is not None
    assert problem.startswith("the recordings hold only straight legs and turns on the spot")
    assert "it would extrapolate to arcs" in problem
    # Standing still halfway through a turn on the spot leaves it one turn of 100 U,
    # weighing as much as the arc's (cut in two, it would weigh half as much).
    left = np.r_[np.full(25, -U), np.zeros(10), np.full(25, -U)]
    paused = _log(left, -left)
    assert motion_coverage([paused, ARC], UNIT).weight == pytest.approx(
        {"straight": 0.0, "arc": 0.5, "spot": 0.5}
    )


# --- simulated robots with known truth ------------------------------------------------------


@pytest.fixture(scope="module")
def sims():
    """Squares (legs weaving by about 5 degrees) and circles of three radii, of a robot
    with scrub (b_arc 200, b_spot 206 mm) and one without (203 mm), with slip."""
    return {
        (name, kind): make(robot, seed)
        for name, robot in (("scrub", SCRUB), ("no scrub", NO_SCRUB))
        for kind, make, seed in (
            ("squares", drive_sim.squares, 1),
            ("circles", drive_sim.circles, 2),
        )
    }


def _end_error(logs, params: WheelParams) -> float:
    """Mean end-position error [m] of ``logs`` replayed with ``params`` (truth known)."""
    return float(
        np.mean([math.hypot(*(log.odometry(params)[-1, :2] - log.truth[-1, :2])) for log in logs])
    )


@pytest.mark.parametrize("robot", ["scrub", "no scrub"])
def test_squares_alone_do_not_identify_the_turn_rate_term(sims, robot):
    squares = sims[robot, "squares"]
    cover = motion_coverage(squares, NOMINAL)
    assert cover.held == ("straight", "spot")
    assert cover.inflation > MAX_INFLATION
    assert not cover.identifies_scrub
    with pytest.raises(
        ValueError, match="turn-rate term is not identified: it would extrapolate to arcs"
    ):
        fit_trajectories(squares, NOMINAL, model="scrub")
    # The estimator gives the single wheelbase's fit, and says why.
    estimate, fit = trajectory_estimate(squares, NOMINAL, model="scrub")
    single = fit_trajectories(squares, NOMINAL)
    assert estimate.method == "trajectory-scrub"
    assert fit.spot_wheelbase is None
    assert (fit.r_left, fit.r_right, fit.wheelbase) == (
        single.r_left,
        single.r_right,
        single.wheelbase,
    )
    assert "arc_wheelbase" not in estimate.components
    (warning,) = estimate.warnings
    assert warning.startswith("the recordings hold only straight legs and turns on the spot")
    assert "the result is the single-wheelbase fit, as --method trajectory" in warning


@pytest.mark.slow
def test_the_unidentified_term_costs_a_robot_without_scrub_on_circles(sims):
    """Why the fallback: fitted anyway, the squares' turn-rate term rests on the weaving
    of the legs and misses the circles of a robot that has one wheelbase (known truth)
    several times worse than the single wheelbase does."""
    squares, circles = sims["no scrub", "squares"], sims["no scrub", "circles"]
    loose = fit_trajectories(squares, NOMINAL, model="scrub", check_coverage=False)
    single = fit_trajectories(squares, NOMINAL)
    assert _end_error(circles, loose.params(NOMINAL)) > 3 * _end_error(
        circles, single.params(NOMINAL)
    )
    _, fit = trajectory_estimate(squares, NOMINAL, model="scrub")
    assert _end_error(circles, fit.params(NOMINAL)) == _end_error(circles, single.params(NOMINAL))


@pytest.mark.parametrize("robot", ["scrub", "no scrub"])
def test_squares_and_circles_identify_it(sims, robot):
    logs = sims[robot, "squares"] + sims[robot, "circles"]
    cover = motion_coverage(logs, NOMINAL)
    assert cover.held == ("straight", "arc", "spot")
    assert cover.inflation < MAX_INFLATION
    estimate, fit = trajectory_estimate(logs, NOMINAL, model="scrub")
    assert estimate.warnings == ()
    assert fit.spot_wheelbase is not None
    se = fit.standard_errors
    truth = SCRUB if robot == "scrub" else NO_SCRUB
    assert fit.wheelbase == pytest.approx(truth.b_arc, abs=3 * se["wheelbase"])
    assert fit.spot_wheelbase == pytest.approx(truth.b_spot, abs=3 * se["spot_wheelbase"])
    assert se["wheelbase"] < 5e-4
    assert se["spot_wheelbase"] < 5e-4


def test_circles_alone_extrapolate_to_turns_on_the_spot(sims):
    cover = motion_coverage(sims["scrub", "circles"], NOMINAL)
    assert cover.held == ("arc",)
    assert not cover.identifies_scrub
    problem = cover.scrub_problem()
    assert problem is not None
    assert problem.startswith("the recordings hold only arcs")
    assert "it would extrapolate to turns on the spot" in problem


@pytest.fixture(scope="module")
def folders(sims, tmp_path_factory):
    """Run-log folders: two sessions of squares of the robot with scrub, and three of
    squares and circles."""
    root = tmp_path_factory.mktemp("drives")
    squares = [
        drive_sim.write_session(root / f"squares-{seed}", drive_sim.squares(SCRUB, seed))
        for seed in (11, 12)
    ]
    mixed = [
        drive_sim.write_session(
            root / f"mixed-{seed}",
            drive_sim.squares(SCRUB, seed, runs=2) + drive_sim.circles(SCRUB, seed + 1),
        )
        for seed in (21, 23, 25)
    ]
    return {"squares": squares, "mixed": mixed}


@pytest.mark.slow
def test_auto_does_not_pick_the_scrub_model_for_a_pool_of_squares(folders):
    report = umbmark.calibrate(*folders["squares"], method="auto")
    assert report.estimate.method != "trajectory-scrub"
    note = report.notes[-1]
    assert note.startswith(f"method auto: {report.estimate.method}, by held-out end error")
    assert (
        "trajectory-scrub left out: the recordings hold only straight legs and turns on the spot"
        in note
    )
    assert (
        "the held-out runs hold only straight legs and turns on the spot: the figures say "
        "nothing about arcs"
    ) in note


@pytest.mark.slow
def test_auto_picks_the_scrub_model_where_the_recordings_cover_arcs(folders):
    checked = umbmark.validate(*folders["mixed"], methods=["trajectory", "trajectory-scrub"])
    assert all(fold.refused == {} for fold in checked.folds)
    scrub, single = checked.mean_error("trajectory-scrub"), checked.mean_error("trajectory")
    assert scrub is not None
    assert single is not None
    assert scrub < single / 2  # a robot with 3 % scrub
    assert checked.coverage == "the held-out runs hold straight legs, arcs and turns on the spot"
    report = umbmark.calibrate(*folders["mixed"], method="auto")
    assert report.estimate.method == "trajectory-scrub"
    assert report.model_fit is not None
    assert report.model_fit.spot_wheelbase is not None


@pytest.mark.slow
def test_validate_says_what_its_figures_cover(folders):
    report = umbmark.validate(*folders["squares"], methods=["trajectory", "trajectory-scrub"])
    assert report.covered == ("straight", "spot")
    assert report.coverage == (
        "the held-out runs hold only straight legs and turns on the spot: the figures say "
        "nothing about arcs"
    )
    assert [f.errors["trajectory-scrub"] for f in report.folds] == [None, None]
    assert all(
        "which do not identify its turn-rate term" in f.refused["trajectory-scrub"]
        for f in report.folds
    )
    data = report.to_dict()
    assert data["coverage"]["held_out"] == ["straight", "spot"]
    assert data["coverage"]["not_held_out"] == ["arc"]
    assert data["folds"][0]["motions"] == ["straight", "spot"]
    sources = [str(p) for p in folders["squares"]]
    printed = run_cli("validate", *sources, "--methods", "trajectory")
    assert printed.returncode == 0, printed.stderr
    assert (
        "What these figures cover: the held-out runs hold only straight legs and turns on the"
        in " ".join(printed.stdout.split())
    )


# --- the real OptiOdom sessions ---------------------------------------------------------------

SQUARE = OPTIODOM / "square" / "230620202042"
SQUARE2 = OPTIODOM / "square" / "231220200029"
CIRCLE = OPTIODOM / "circular" / "250620202104"
SAME_DAY = sorted((OPTIODOM / "ivanjko").glob("2506*"))
real = pytest.mark.skipif(not SQUARE.is_dir(), reason="../shared/data is not here")


@real
def test_real_squares_fall_back_to_one_wheelbase_and_predict_circles_as_it_does():
    """Calibrated on the 0.75 m squares, the scrub model's arcs wheelbase came from the
    legs' weaving: replayed on circles it ended 74 mm off, the single wheelbase 18 mm."""
    scrub = umbmark.calibrate(SQUARE, method="trajectory-scrub")
    single = umbmark.calibrate(SQUARE, method="trajectory")
    (warning,) = scrub.warnings
    assert warning.startswith("the recordings hold only straight legs and turns on the spot")
    assert (
        "the scrub model's turn-rate term is not identified: it would extrapolate to arcs"
        in warning
    )
    assert "model" not in scrub.to_dict()
    assert scrub.to_dict()["motions"]["identifies_scrub"] is False
    on_circles = umbmark.replay(CIRCLE, scrub).mean_end_error
    assert on_circles == umbmark.replay(CIRCLE, single).mean_end_error
    assert on_circles < 0.025


@pytest.mark.slow  # about 20 s: auto validates 8 estimators on 6 sessions
@pytest.mark.skipif(len(SAME_DAY) != 4, reason="../shared/data is not here")
def test_real_auto_does_not_pick_the_scrub_model_for_straights_and_spot_turns():
    """The squares and the straights with spot turns of the circles' day: held out among
    themselves the scrub model predicted best (5.7 mm against 6.0), and auto took it; on
    the circles it then ended 92 mm off, the single wheelbase 12 mm."""
    report = umbmark.calibrate(SQUARE, SQUARE2, *SAME_DAY, method="auto", force=True)
    assert report.estimate.method == "trajectory"
    note = report.notes[-1]
    assert "trajectory-scrub left out: the recordings hold only straight legs and turns" in note
    assert note.endswith("the figures say nothing about arcs")
    assert umbmark.replay(CIRCLE, report, force=True).mean_end_error < 0.02


@pytest.mark.slow
@real
def test_real_validate_on_squares_says_nothing_about_arcs():
    report = umbmark.validate(SQUARE, SQUARE2, methods=["trajectory", "trajectory-scrub"])
    assert report.coverage.endswith("the figures say nothing about arcs")
    assert report.mean_error("trajectory-scrub") is None
    mixed = umbmark.validate(SQUARE, SQUARE2, CIRCLE, methods=["trajectory"], force=True)
    assert mixed.covered == ("straight", "arc", "spot")
    assert mixed.coverage.endswith(
        "arcs are held out only against calibrations from runs without them "
        "(250620202104): those figures test extrapolation to them"
    )


@pytest.mark.slow
@real
def test_real_squares_with_circles_identify_the_scrub_model():
    report = umbmark.calibrate(SQUARE, CIRCLE, method="trajectory-scrub")
    assert not any("turn-rate term" in w for w in report.warnings)
    assert report.to_dict()["model"]["spot_wheelbase"] > 0


@pytest.mark.slow
@pytest.mark.skipif(len(SAME_DAY) != 4, reason="../shared/data is not here")
def test_real_straights_with_spot_turns_of_the_circles_day_fall_back():
    """Straight legs and spot turns: the scrub fit was refused outright (its arcs
    wheelbase 250 +- 17 mm); it now gives the single wheelbase, with the reason."""
    report = umbmark.calibrate(*SAME_DAY, method="trajectory-scrub", force=True)
    assert report.model_fit is not None
    assert report.model_fit.spot_wheelbase is None
    assert any("it would extrapolate to arcs" in w for w in report.warnings)
