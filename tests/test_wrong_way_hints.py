"""Hints that name the likely cause and the fix (issue 21, item 6): a wheel radius given as
the diameter (the usual ROS mix-up, a factor 2), infinite or NaN numbers, a ROS 2 bag's
``metadata.yaml`` given for the bag, a scatter given in millimetres, rosbags missing."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest
import tomllib

import umbmark
from umbmark.calibration.verdict import Evidence, judge
from umbmark.core.errors import InputError
from umbmark.estimators.base import ErrorEstimate, SquareTest
from umbmark.options.spec import READ_OPTIONS, SIDE_LENGTH, WHEELBASE

from helpers import ROOT, api_error, cli_error

#: The virtual robot's nominal wheels (umbmark.simulate's default): D = 0.15 m.
DIAMETER = 0.15
RADIUS = DIAMETER / 2
SQUARE = {"side_length": 2.0, "runs": 3, "dt": 0.02, "E_d": 1.004, "E_b": 0.98}


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Run logs of a virtual robot with 0.15 m wheels: 3 + 3 runs on a 2 m square."""
    path = tmp_path_factory.mktemp("hints") / "logs"
    umbmark.simulate(**SQUARE, wheel_diameter=DIAMETER, logs=path)  # type: ignore[arg-type]
    return path


@pytest.fixture(scope="module")
def bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The same robot's runs as a ROS 2 bag, written with rosbags."""
    pytest.importorskip("rosbags")
    path = tmp_path_factory.mktemp("hints") / "square"
    umbmark.simulate(**SQUARE, wheel_diameter=DIAMETER, bag=path)  # type: ignore[arg-type]
    assert (path / "metadata.yaml").is_file()
    return path


# --- a radius given as the diameter -----------------------------------------------------


@pytest.mark.slow
def test_a_radius_given_as_the_diameter_is_named_before_the_turning(logs: Path) -> None:
    # Read with half the diameter the odometry turns 45 deg where the robot turned 90: the
    # square test cannot identify that, and used to answer "calibrate the turning coarsely".
    line = api_error(umbmark.calibrate, logs, wheel_diameter=RADIUS)
    cause = line.index("looks like the wheels' radius")
    assert f"the wheel diameter given, {RADIUS:g} m," in line
    assert f"pass wheel_diameter={DIAMETER:g}" in line  # the library's keyword
    assert cause < line.index("Calibrate the turning coarsely first")
    # the fix works: the diameter it names reads the runs as the squares they were
    assert umbmark.calibrate(logs, wheel_diameter=DIAMETER).verdict.level == "apply"


@pytest.mark.slow
def test_the_command_line_names_it_too(logs: Path) -> None:
    line = cli_error("calibrate", str(logs), "--wheel-diameter", f"{RADIUS:g}")
    assert f"pass --wheel-diameter {DIAMETER:g}, twice it" in line


def test_a_radius_given_as_the_diameter_of_a_bag(bag: Path) -> None:
    given = {"wheelbase": 0.34, "side_length": 2.0, "truth_topic": "/mocap/robot/pose"}
    line = api_error(umbmark.calibrate, bag, wheel_diameter=RADIUS, **given)
    assert "looks like the wheels' radius (read with twice that, the runs are squares" in line
    assert f"pass wheel_diameter={DIAMETER:g}" in line


@pytest.mark.parametrize(
    ("E_s", "said"),
    [(2.0, "looks like the wheels' radius"), (0.5, "looks like twice the wheels' diameter")],
)
def test_a_fitted_scale_of_two_or_a_half_names_the_diameter(E_s: float, said: str) -> None:
    # the trajectory methods fit E_s, the true mean diameter over the given one
    estimate = ErrorEstimate("trajectory", 0.0, 0.0, 1.0, 1.0, E_s=E_s)
    verdict = judge(estimate, SquareTest(2.0, 0.34), Evidence(wheel_diameter=0.1))
    assert verdict.level == "care"
    assert said in verdict.reasons[0]
    assert f"pass --wheel-diameter {0.1 * E_s:g}" in verdict.reasons[0]
    # a scale error of tyres (12 %) is not a radius
    other = judge(
        ErrorEstimate("trajectory", 0.0, 0.0, 1.0, 1.0, E_s=1.12),
        SquareTest(2.0, 0.34),
        Evidence(wheel_diameter=0.1),
    )
    assert "radius" not in other.reasons[0]


# --- numbers that are no numbers ---------------------------------------------------------

NUMBERS = [s for s in (*READ_OPTIONS, WHEELBASE, SIDE_LENGTH) if s.kind == "number"]


@pytest.mark.parametrize("value", [math.inf, -math.inf, math.nan])
@pytest.mark.parametrize("spec", NUMBERS, ids=lambda s: s.flag)
def test_every_number_option_refuses_infinity_and_nan_as_such(spec, value: float) -> None:  # type: ignore[no-untyped-def]
    given = (value, 0.0) if spec.nargs == 2 else value
    with pytest.raises(InputError) as caught:
        spec.check(given)
    assert str(caught.value) == f"{spec.flag} must be a finite number, got {value}"


def test_wheelbase_inf_on_the_command_line_and_in_python(tmp_path: Path) -> None:
    table = tmp_path / "runs.csv"
    umbmark.example(str(table))
    line = cli_error("calibrate", str(table), "-L", "4", "--wheelbase", "inf", "--unit", "mm")
    assert line.strip() == "umbmark: error: --wheelbase must be a finite number, got inf"
    line = api_error(umbmark.calibrate, table, side_length=4, wheelbase=math.nan, unit="mm")
    assert "wheelbase must be a finite number, got nan" in line
    assert "> 0" not in line


# --- a ROS 2 bag's metadata.yaml --------------------------------------------------------


@pytest.mark.slow
def test_a_ros2_bags_metadata_is_read_as_the_bag(bag: Path) -> None:
    given = {
        "wheelbase": 0.34,
        "wheel_diameter": DIAMETER,
        "side_length": 2.0,
        "truth_topic": "/mocap/robot/pose",
    }
    folder = umbmark.calibrate(bag, **given)  # type: ignore[arg-type]
    meta = umbmark.calibrate(bag / "metadata.yaml", **given)  # type: ignore[arg-type]
    assert meta.format == "bag"
    assert meta.estimate.E_d == folder.estimate.E_d
    assert meta.estimate.E_b == folder.estimate.E_b
    assert len(meta.runs) == 6
    # umbmark info looks into it as into the folder
    assert umbmark.info(bag / "metadata.yaml").format == umbmark.info(bag).format == "bag"


def test_a_run_logs_metadata_says_to_give_the_folder(logs: Path) -> None:
    line = api_error(umbmark.calibrate, logs / "metadata.yaml")
    assert line == (
        f"{logs / 'metadata.yaml'}: is an umbmark run log's metadata, not its runs: give the "
        f"folder, {logs}"
    )


# --- a scatter in millimetres -----------------------------------------------------------


def test_a_scatter_in_millimetres_is_told_in_metres() -> None:
    line = cli_error("plan", "--scatter", "10", "-L", "4")
    assert line.startswith("umbmark: error: --scatter 10 m is implausibly large: lengths are")
    assert "10 mm is --scatter 0.01, 10 cm is --scatter 0.1" in line
    # what it suggests is taken
    assert umbmark.plan(scatter=0.01, side_length=4).scatter == 0.01
    assert "finite" in api_error(umbmark.plan, scatter=math.inf, side_length=4)


# --- rosbags missing --------------------------------------------------------------------


def test_missing_rosbags_names_an_install_that_works(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # umbmark is installed from its checkout, not from an index: the line names rosbags
    # as pyproject.toml's ros extra requires it, and the extra for a checkout
    extra = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    (required,) = extra["optional-dependencies"]["ros"]
    monkeypatch.setitem(sys.modules, "rosbags.rosbag2", None)
    line = api_error(umbmark.simulate, **SQUARE, bag=tmp_path / "square")
    assert line == (
        f"{tmp_path / 'square'}: writing bags needs rosbags, which is not installed: python -m "
        f"pip install '{required}' (or, in umbmark's checkout, python -m pip install '.[ros]')"
    )
    assert "umbmark[ros]" not in line
