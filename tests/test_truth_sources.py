"""Ground truth that is the odometry itself, and what real robots publish, read.

The bags are written the way a Husky, a TurtleBot3 in Gazebo and Nav2 write them
(:mod:`robot_bags`), from a simulated robot with known ``E_d`` and ``E_b`` whose truth
differs from its odometry. Expected values are the simulated robot's errors, the
figures the bags were written with (rates, wheel geometry), or what the same runs give
through another, already trusted input (joint states against wheel transforms).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import umbmark

from helpers import api_error, cli_error, run_cli

pytest.importorskip("rosbags")

from robot_bags import (
    HUSKY,
    TB3,
    TB3_URDF,
    drive,
    husky_bag,
    nav2_bag,
    to_fix,
    turtlebot3_bag,
    wheel_quaternion,
)

#: Every test here writes and reads whole robot bags (seconds each): the full run only.
pytestmark = pytest.mark.slow

E_D, E_B = 1.004, 1.015  # the TurtleBot3's
HUSKY_E_D, HUSKY_E_B = 1.003, 1.012
HUSKY_GEOMETRY = {"wheelbase": 0.555, "wheel_diameter": 0.33, "side_length": 2.0}
CONTROLLER = "/husky_velocity_controller/odom"
TB3_JOINTS = "--left-joint wheel_left_joint --right-joint wheel_right_joint"


def as_options(line: str) -> dict[str, str]:
    """``--truth-topic /x --left-joint a`` as keywords."""
    argv = line.split()
    return {argv[i].lstrip("-").replace("-", "_"): argv[i + 1] for i in range(0, len(argv), 2)}


@pytest.fixture(scope="module")
def tb3_motion():
    return drive(TB3, E_D, E_B)


@pytest.fixture(scope="module")
def husky_motion():
    return drive(HUSKY, HUSKY_E_D, HUSKY_E_B, side=2.0)


@pytest.fixture(scope="module")
def husky(tmp_path_factory, husky_motion):
    """Controller odometry, IMU, fused odometry and its TF: no reference at all."""
    return husky_bag(tmp_path_factory.mktemp("husky") / "husky", "ros1", husky_motion)


@pytest.fixture(scope="module")
def husky_rtk(tmp_path_factory, husky_motion):
    """The controller also publishes odom -> base_link; RTK fixes (10 mm); a map frame
    that never moves."""
    return husky_bag(
        tmp_path_factory.mktemp("husky_rtk") / "husky",
        "sqlite3",
        husky_motion,
        gps_sigma=0.01,
        tf_from="controller",
        static_map=True,
    )


@pytest.fixture(scope="module")
def tb3(tmp_path_factory, tb3_motion):
    return turtlebot3_bag(tmp_path_factory.mktemp("tb3") / "tb3", "mcap", tb3_motion)


# --- 1. a ground truth that is the odometry itself ------------------------------------------


def test_info_never_proposes_the_controller_odometry_as_ground_truth(husky):
    report = umbmark.info(husky)
    data = report.to_dict()
    truth = data["candidates"]["truth"]
    # the controller's odometry is no candidate; the fused one only with a warning
    assert [c["label"] for c in truth] == [
        "/odometry/filtered (nav_msgs/msg/Odometry, odom -> base_link)"
    ]
    assert "contains the wheel odometry" in truth[0]["warning"]
    assert data["candidates"]["odometry"][0]["options"] == {"--odom-topic": CONTROLLER}
    # before: "--truth-topic /husky_velocity_controller/odom --odom-topic ..."
    assert data["suggested_options"] == f"--odom-topic {CONTROLLER}"
    assert data["independent_reference"] is False
    (note,) = [n for n in report.warnings if n.startswith("no ground truth independent")]
    assert CONTROLLER in note
    proc = run_cli("info", str(husky))
    assert proc.returncode == 0, proc.stderr
    assert "not suggested: a fused odometry" in proc.stdout
    assert "No ground truth independent of the odometry" in proc.stdout
    assert "warning: no ground truth independent of the odometry" in proc.stderr
    # asked for a ground truth, calibrate says what the bag holds instead
    err = api_error(umbmark.calibrate, husky, **HUSKY_GEOMETRY, odom_topic=CONTROLLER)
    assert "candidates: /odometry/filtered" in err


def test_the_controller_odometry_as_its_own_ground_truth_is_refused(husky):
    same = {"truth_topic": CONTROLLER, "odom_topic": CONTROLLER}
    geometry = {"wheelbase": 0.555, "wheel_diameter": 0.33}
    for job, options in ((umbmark.calibrate, HUSKY_GEOMETRY), (umbmark.replay, geometry)):
        err = api_error(job, husky, **options, **same)
        assert err.startswith(f"{husky}: the ground truth (truth_topic='{CONTROLLER}') is the ")
        assert "E_d = E_b = 1 whatever the robot" in err
        assert "umbmark info lists the candidates" in err
    line = cli_error(
        "calibrate", str(husky), "-b", "0.555", "--wheel-diameter", "0.33", "-L", "2",
        "--truth-topic", CONTROLLER, "--odom-topic", CONTROLLER,
    )  # fmt: skip
    assert "is the controller's odometry the wheels are read from" in line


def test_the_odometrys_own_transforms_are_refused(husky_rtk):
    # the same pair
    err = api_error(
        umbmark.calibrate, husky_rtk, **HUSKY_GEOMETRY,
        odom_tf=("odom", "base_link"), tf_parent="/odom", tf_child="base_link",
    )  # fmt: skip
    assert "is the odometry's own transform (odom_tf=('odom', 'base_link'))" in err
    # a chain whose only moving transform is the odometry's (map -> odom never moves)
    err = api_error(
        umbmark.calibrate, husky_rtk, **HUSKY_GEOMETRY,
        odom_tf=("odom", "base_link"), tf_parent="map", tf_child="base_link",
    )  # fmt: skip
    assert "moves only through the odometry's own transforms (odom -> base_link;" in err


def test_a_ground_truth_that_reproduces_the_odometry_is_refused(husky_rtk):
    # the controller's topic for the wheels, its own transform as the truth: other names,
    # the same data
    err = api_error(
        umbmark.calibrate, husky_rtk, **HUSKY_GEOMETRY,
        odom_topic=CONTROLLER, tf_parent="odom", tf_child="base_link",
    )  # fmt: skip
    assert f"the ground truth odom -> base_link and odometry {CONTROLLER} agree to" in err
    assert "reproduces the odometry the wheels are read from" in err


def test_a_simulators_ground_truth_against_wheel_joints_stays_valid(tmp_path):
    """Perfect simulated wheels: Gazebo's p3d truth agrees with the wheel odometry, and
    is a valid reference for the joints."""
    perfect = drive(TB3, 1.0, 1.0, directions=("cw", "cw", "ccw", "ccw"))
    bag = turtlebot3_bag(
        tmp_path / "perfect", "sqlite3", perfect, model_states=False, wheel_tf=False,
        robot_description=False, ground_truth=True,
    )  # fmt: skip
    data = umbmark.info(bag).to_dict()
    assert data["candidates"]["truth"][0]["label"].startswith("/ground_truth/odom")
    assert data["independent_reference"] is True
    report = umbmark.calibrate(
        bag, wheelbase=0.16, wheel_diameter=0.066, side_length=1.0,
        truth_topic="/ground_truth/odom",
    )  # fmt: skip
    assert report.estimate.E_d == pytest.approx(1.0, abs=1e-5)
    assert report.estimate.E_b == pytest.approx(1.0, abs=1e-5)


# --- 4. what real robots publish ---------------------------------------------------------------


def test_gazebo_model_states_are_a_ground_truth(tb3):
    report = umbmark.info(tb3)
    data = report.to_dict()
    (states,) = data["model_states"]
    assert states["topic"] == "/gazebo/model_states"
    assert [(m["name"], m["moving"]) for m in states["models"]] == [
        ("ground_plane", False),
        ("unit_box", False),
        ("turtlebot3_burger", True),
    ]
    truth = data["candidates"]["truth"]
    assert truth[0]["kind"] == "model"
    assert truth[0]["rate"] == pytest.approx(100.0, rel=1e-6)
    suggested = (
        "--truth-topic /gazebo/model_states --truth-model turtlebot3_burger "
        f"{TB3_JOINTS} --time-source bag"
    )
    assert data["suggested_options"] == suggested
    # as suggested, with the robot description's wheels: the robot's errors
    calibrated = umbmark.calibrate(tb3, side_length=1.0, **as_options(suggested))
    assert calibrated.estimate.E_d == pytest.approx(E_D, abs=2e-5)
    assert calibrated.estimate.E_b == pytest.approx(E_B, abs=5e-5)
    assert any("model turtlebot3_burger of /gazebo/model_states" in n for n in calibrated.notes)
    # the model by default: the one that moves
    default = umbmark.calibrate(
        tb3, side_length=1.0, truth_topic="/gazebo/model_states", time_source="bag"
    )
    assert default.estimate.E_b == calibrated.estimate.E_b
    err = api_error(
        umbmark.calibrate, tb3, side_length=1.0, truth_topic="/gazebo/model_states",
        truth_model="turtlebot3_waffle",
    )  # fmt: skip
    assert "no model 'turtlebot3_waffle' in /gazebo/model_states" in err
    assert "ground_plane, unit_box, turtlebot3_burger" in err
    err = api_error(umbmark.calibrate, tb3, side_length=1.0, truth_topic="/odom",
                    truth_model="turtlebot3_burger")  # fmt: skip
    assert "truth_model names a model of a gazebo_msgs/msg/ModelStates topic" in err


@pytest.mark.slow
def test_model_states_against_wheels_on_sim_time_are_read_on_the_bag_clock(tmp_path, tb3_motion):
    """Gazebo with use_sim_time: the joint states' header stamps count from 12.5 s of
    simulated time, the model states have no header (the bag's receive times, on the wall
    clock, 1.77e9 s). Before: "do not overlap in time"; now both are read on the bag's
    clock, as ``info`` suggests, and the robot's errors come back."""
    bag = turtlebot3_bag(tmp_path / "sim", "mcap", tb3_motion, wheel_tf=False, sim_time=12.5)
    assert "--time-source bag" in umbmark.info(bag).to_dict()["suggested_options"]
    report = umbmark.calibrate(
        bag, side_length=1.0, truth_topic="/gazebo/model_states",
        left_joint="wheel_left_joint", right_joint="wheel_right_joint",
    )  # fmt: skip
    assert report.estimate.E_d == pytest.approx(E_D, abs=2e-5)
    assert report.estimate.E_b == pytest.approx(E_B, abs=5e-5)
    (note,) = [n for n in report.notes if "receive clock" in n]
    last = 12.5 + float(tb3_motion.time[(tb3_motion.time.size - 1) // 3 * 3])
    assert note == (
        "ground truth /gazebo/model_states has no header stamps (the bag's receive times) and "
        f"the wheels' header stamps (12.500 to {last:.3f} s, a simulation's clock) do not "
        "overlap them: both read on the bag's receive clock (--time-source bag, as umbmark "
        "info suggests)"
    )
    # The diff-drive plugin's /odom, stamped like the joints, integrated from the wheels
    # at 100 Hz while the joint states are recorded at 33 Hz: its heading is still the
    # wheels' to rounding. Refused, read on the stamps' clock.
    err = api_error(
        umbmark.calibrate, bag, side_length=1.0, truth_topic="/odom",
        left_joint="wheel_left_joint", right_joint="wheel_right_joint",
    )  # fmt: skip
    assert err.startswith(f"{bag}: the ground truth /odom reproduces the wheels' own odometry")
    assert "wheel radii 33.000 and 33.000 mm and a wheelbase of 160.00 mm" in err


def test_model_states_in_a_bag_without_definitions(tmp_path, tb3_motion):
    """rosbag2 before Iron kept no definitions, and no typestore knows gazebo_msgs."""
    bag = turtlebot3_bag(
        tmp_path / "humble", "sqlite3", tb3_motion, wheel_tf=False,
        robot_description=False, strip_definitions=True,
    )  # fmt: skip
    models = umbmark.info(bag).to_dict()["model_states"][0]["models"]
    assert [m["name"] for m in models if m["moving"]] == ["turtlebot3_burger"]
    report = umbmark.calibrate(
        bag, wheelbase=0.16, wheel_diameter=0.066, side_length=1.0,
        truth_topic="/gazebo/model_states", time_source="bag",
    )  # fmt: skip
    assert report.estimate.E_b == pytest.approx(E_B, abs=5e-5)


def test_wheel_angles_published_only_as_transforms(tmp_path, tb3, tb3_motion):
    bag = turtlebot3_bag(tmp_path / "tf_only", "ros1", tb3_motion, joint_states=False)
    data = umbmark.info(bag).to_dict()
    wheels = data["candidates"]["wheels"]
    assert [c["kind"] for c in wheels] == ["wheel_tf"]
    frames = {"--left-wheel-frame": "wheel_left_link", "--right-wheel-frame": "wheel_right_link"}
    assert wheels[0]["options"] == frames
    assert (
        "--left-wheel-frame wheel_left_link --right-wheel-frame wheel_right_link"
        in (data["suggested_options"])
    )
    common = {"side_length": 1.0, "truth_topic": "/gazebo/model_states", "time_source": "bag"}
    from_tf = umbmark.calibrate(
        bag, left_wheel_frame="wheel_left_link", right_wheel_frame="wheel_right_link",
        method="trajectory", **common,
    )  # fmt: skip
    from_joints = umbmark.calibrate(tb3, method="trajectory", **common)
    # the same wheel angles, through the transforms robot_state_publisher made of them
    assert from_tf.estimate.E_d == pytest.approx(from_joints.estimate.E_d, abs=1e-9)
    assert from_tf.estimate.E_b == pytest.approx(from_joints.estimate.E_b, abs=1e-9)
    assert from_tf.estimate.E_b == pytest.approx(E_B, abs=2e-5)
    err = api_error(
        umbmark.calibrate, bag, left_wheel_frame="wheel_left_link",
        right_wheel_frame="wheel_rear_link", **common,
    )  # fmt: skip
    assert "no transform to the wheel frame wheel_rear_link on /tf" in err
    line = cli_error("replay", str(bag), "--left-wheel-frame", "wheel_left_link")
    assert "--left-wheel-frame and --right-wheel-frame go together" in line


def test_wheel_geometry_from_the_robot_description(tmp_path, tb3, tb3_motion):
    data = umbmark.info(tb3).to_dict()
    assert data["robot_description"]["wheelbase"] == pytest.approx(0.160, abs=1e-12)
    assert data["robot_description"]["wheel_diameter"] == pytest.approx(0.066, abs=1e-12)
    assert data["needs"] == []
    options = {"side_length": 1.0, "truth_topic": "/gazebo/model_states", "time_source": "bag"}
    described = umbmark.calibrate(tb3, **options)
    given = umbmark.calibrate(tb3, wheelbase=0.16, wheel_diameter=0.066, **options)
    assert described.calibration.active.wheelbase == pytest.approx(0.16, abs=1e-12)
    assert described.calibration.active.wheel_diameter == pytest.approx(0.066, abs=1e-12)
    assert described.estimate.E_b == given.estimate.E_b
    (note,) = [n for n in described.notes if "robot description" in n]
    assert note.startswith("wheelbase and wheel diameter from the bag's robot description")
    # the options win, and only the missing one comes from the description
    half = umbmark.calibrate(tb3, wheelbase=0.17, **options)
    assert half.calibration.active.wheelbase == 0.17
    assert any(n.startswith("wheel diameter from the bag's robot description") for n in half.notes)

    bare = turtlebot3_bag(tmp_path / "bare", "sqlite3", tb3_motion, robot_description=False,
                          wheel_tf=False)  # fmt: skip
    info = umbmark.info(bare)
    assert info.to_dict()["needs"] == ["--wheelbase", "--wheel-diameter"]
    proc = run_cli("info", str(bare))
    assert (
        "Still needed: --wheelbase and --wheel-diameter (the bag holds no robot_description)"
        in (proc.stdout)
    )
    err = api_error(umbmark.calibrate, bare, **options)
    assert "a bag needs the wheel parameters" in err
    assert err.endswith("the bag holds no robot_description")


def test_gnss_fixes_are_a_position_only_ground_truth(husky_rtk):
    data = umbmark.info(husky_rtk).to_dict()
    gps = data["candidates"]["truth"][0]
    assert gps["label"] == "/navsat/fix (sensor_msgs/msg/NavSatFix; positions only, sigma 10 mm)"
    assert gps["headings"] is False
    assert gps["rate"] == pytest.approx(10.0, rel=1e-6)
    assert data["suggested_options"] == f"--truth-topic /navsat/fix --odom-topic {CONTROLLER}"
    read = {**HUSKY_GEOMETRY, "odom_topic": CONTROLLER, "truth_topic": "/navsat/fix"}
    for method in ("exact", "endpose"):
        report = umbmark.calibrate(husky_rtk, method=method, **read)
        assert report.estimate.E_d == pytest.approx(HUSKY_E_D, abs=2e-5), method
        assert report.estimate.E_b == pytest.approx(HUSKY_E_B, abs=5e-5), method
    assert any("median horizontal standard deviation of 10 mm" in n for n in report.notes)
    for method in ("heading", "endpoints", "trajectory"):
        err = api_error(umbmark.calibrate, husky_rtk, method=method, **read)
        assert "has positions only" in err, method
        assert f"the {method} method needs headings; use method paper, exact or endpose" in err
    replay = umbmark.replay(husky_rtk, **{k: v for k, v in read.items() if k != "side_length"})
    assert all(e is None for e in replay.heading_errors["nominal"])
    err = api_error(umbmark.calibrate, husky_rtk, truth_offset=(0.2, 0.0), **read)
    assert "truth_offset moves the ground truth along its heading" in err


def test_coarse_gnss_is_listed_but_not_suggested(tmp_path, husky_motion):
    bag = husky_bag(tmp_path / "plain_gps", "mcap", husky_motion, gps_sigma=2.5)
    report = umbmark.info(bag)
    gps = report.to_dict()["candidates"]["truth"][0]
    assert "sigma 2500 mm" in gps["label"]
    assert "an RTK fix is needed" in gps["warning"]
    assert report.suggested_options == f"--odom-topic {CONTROLLER}"
    assert report.to_dict()["independent_reference"] is False


def test_nav2_localization_with_the_max_gap_it_needs(tmp_path, tb3_motion):
    bag = nav2_bag(tmp_path / "nav2", "sqlite3", tb3_motion)
    data = umbmark.info(bag).to_dict()
    truth = data["candidates"]["truth"]
    assert [c["label"] for c in truth] == [
        "TF chain map -> odom -> base_footprint",
        "/amcl_pose (geometry_msgs/msg/PoseWithCovarianceStamped)",
    ]
    # the chain at the odometry's rate (every third 100 Hz sample); AMCL at 2 Hz: 1.1
    # times 0.5 s
    assert truth[0]["rate"] == pytest.approx(100 / 3, rel=1e-3)
    assert truth[1]["rate"] == pytest.approx(2.0, rel=1e-3)
    assert truth[1]["max_gap"] == pytest.approx(0.55)
    common = {"wheelbase": 0.16, "wheel_diameter": 0.066, "side_length": 1.0}
    # map -> odom interpolated between AMCL's updates
    chained = umbmark.calibrate(bag, tf_parent="map", tf_child="base_footprint", **common)
    assert chained.estimate.E_d == pytest.approx(E_D, abs=2e-5)
    assert chained.estimate.E_b == pytest.approx(E_B, abs=5e-5)

    amcl_only = nav2_bag(tmp_path / "amcl", "sqlite3", tb3_motion, map_tf=False)
    report = umbmark.info(amcl_only)
    suggested = f"--truth-topic /amcl_pose {TB3_JOINTS} --max-gap 0.55"
    assert report.suggested_options == suggested
    proc = run_cli("info", str(amcl_only))
    assert "2.0 Hz, needs --max-gap 0.55 s" in proc.stdout
    err = api_error(umbmark.calibrate, amcl_only, truth_topic="/amcl_pose", **common)
    assert "no wheel sample has ground truth within 0.25 s" in err
    calibrated = umbmark.calibrate(amcl_only, **common, **as_options(suggested))
    # poses 0.5 s apart, interpolated where the runs start and stop: E_b to 1e-3
    assert calibrated.estimate.E_b == pytest.approx(E_B, abs=2e-3)


# --- the readers' pieces, against closed forms ------------------------------------------------


def test_gnss_fixes_to_east_north():
    from umbmark.sources.bag.truth.references import enu

    points = np.array([(0.0, 0.0), (3.0, 4.0), (-12.0, 7.5), (20.0, -15.0)])
    fixes = np.array([to_fix(e, n) for e, n in points])
    got = enu(fixes[:, 0], fixes[:, 1], fixes[:, 2])
    # to_fix is first order: it errs by about east * tan(latitude) * north / R, 1.8e-6 m
    # at (3, 4) and 4.5e-5 m at (20, -15)
    assert np.max(np.abs(got - points)) < 1e-4
    assert np.abs(got[1] - points[1]).max() < 3e-6


def test_robot_descriptions_are_read_within_bounds():
    from umbmark.sources.bag.urdf import MAX_URDF_CHARS, parse_robot_description

    described = parse_robot_description(TB3_URDF)
    assert described.name == "turtlebot3_burger"  # its <robot name>
    assert (described.left_joints, described.right_joints) == (
        ("wheel_left_joint",),
        ("wheel_right_joint",),
    )
    # wheels hung from a deck turned by -90 degrees, shifted and raised: their origins
    # composed down from the root, deck x = -0.2 and 0.2 are base y = 0.02 + 0.2 and
    # 0.02 - 0.2, 0.4 m apart; radius 0.05 m from a visual cylinder and a sphere
    nested = """<robot name="r"><link name="base"/><link name="deck"/>
      <joint name="deck_joint" type="fixed"><parent link="base"/><child link="deck"/>
        <origin xyz="0.1 0.02 0.3" rpy="0 0 YAW"/></joint>
      <joint name="left_wheel_joint" type="continuous"><parent link="deck"/>
        <child link="lw"/><origin xyz="-0.2 0 0"/></joint>
      <joint name="right_wheel_joint" type="continuous"><parent link="deck"/>
        <child link="rw"/><origin xyz="0.2 0 0"/></joint>
      <link name="lw"><visual><geometry><cylinder radius="0.05" length="0.02"/></geometry>
      </visual></link>
      <link name="rw"><collision><geometry><sphere radius="0.05"/></geometry></collision>
      </link></robot>"""
    wheels = parse_robot_description(nested.replace("YAW", str(-math.pi / 2)))
    assert wheels.wheelbase == pytest.approx(0.4, abs=1e-12)
    assert wheels.wheel_diameter == pytest.approx(0.1, abs=1e-12)
    with pytest.raises(ValueError, match="not left of the right ones"):
        parse_robot_description(nested.replace("YAW", str(math.pi / 2)))
    for hostile, why in (
        ('<!DOCTYPE r [<!ENTITY a "aaaa">]><robot/>', "declares a document type"),
        ("<robot><link name='x'>", "is not valid XML"),
        ("<sdf version='1.7'/>", "is not a URDF"),
        ("<robot>" + " " * MAX_URDF_CHARS + "</robot>", "is longer than"),
    ):
        with pytest.raises(ValueError, match=why):
            parse_robot_description(hostile)


def test_wheel_turns_from_rotations():
    from umbmark.sources.bag.wheels.wheel_tf import turns_about_y

    angles = np.concatenate([np.linspace(0.0, 30.0, 400), np.linspace(30.0, -4.0, 300)])
    quaternions = np.array([wheel_quaternion(a) for a in angles])
    assert np.max(np.abs(turns_about_y(quaternions) - angles)) < 1e-12
    assert math.isclose(float(turns_about_y(-quaternions)[-1]), -4.0, abs_tol=1e-12)
