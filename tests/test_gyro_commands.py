"""A recording's IMU through the commands (issue 36, item 3): ``calibrate``, ``info``'s
suggestion, ``replay``, ``validate`` and ``report`` with ``--imu-topic``, on robots the
simulator drove with known errors and a gyro of known scale and bias
(``umbmark simulate --bag --imu``, with and without ``--scan``).

Every figure is held to the simulation's truth (``simulate --json``) within 3.29 of its
own standard errors (its 99.9 % interval: some ten figures are checked here, each
independent, so that one misses by chance in about 1 % of runs); the IMU read back with
the calibration is held to the closed form of the simulated gyro (``omega_read =
omega_true / k_g + bias``)."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest

pytest.importorskip("rosbags")

import umbmark

from helpers import run_cli

#: The simulated robot: its errors, and its gyro (scale k_g, bias [deg/s]).
E_D, E_B, K_G, BIAS = 1.004, 1.02, 0.98, 0.3
ROBOT = ["--E-d", str(E_D), "--E-b", str(E_B), "--gyro-scale", str(K_G), "--gyro-bias",
         str(BIAS), "--runs", "2", "--seed", "3"]  # fmt: skip
#: 99.9 % of a normal figure's misses, in its standard errors.
Z = 3.29


def _simulated(folder: Path, *extra: str) -> tuple[Path, dict]:  # type: ignore[type-arg]
    bag = folder / "drive.bag"
    proc = run_cli("simulate", *ROBOT, "--bag", str(bag), "--imu", *extra, "--json")
    assert proc.returncode == 0, proc.stderr
    return bag, json.loads(proc.stdout)


@pytest.fixture(scope="module")
def imu_bag(tmp_path_factory) -> tuple[Path, dict]:  # type: ignore[type-arg]
    """Wheels, motion capture and an IMU, no laser."""
    return _simulated(tmp_path_factory.mktemp("imu"))


@pytest.fixture(scope="module")
def laser_bag(tmp_path_factory) -> tuple[Path, dict]:  # type: ignore[type-arg]
    """Wheels, motion capture, a laser and an IMU."""
    return _simulated(tmp_path_factory.mktemp("laser"), "--scan")


def _calibrated(*args: str) -> dict:  # type: ignore[type-arg]
    proc = run_cli("calibrate", *args, "--json")
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)  # type: ignore[no-any-return]


def _within(value: float, truth: float, se: float) -> None:
    assert abs(value - truth) <= Z * se, (value, truth, se, (value - truth) / se)


def _true_bias(sim: dict) -> tuple[float, float]:  # type: ignore[type-arg]
    """The yaw bias's start and end [rad/s]: its mean over the recording lies between."""
    imu = sim["imu"]
    return imu["yaw_bias"], imu["yaw_bias_end"]


@pytest.mark.slow
def test_the_wheels_and_the_imu_alone(imu_bag):
    """E_d within its interval of the truth; E_b relative to the gyro, E_b k_g, within
    its interval of the truth's product; the bias within its interval of the truth's
    (its walk between start and end added); E_b said relative to the gyro in one
    sentence, the verdict care; k_g not determined, and said so."""
    bag, sim = imu_bag
    data = _calibrated(str(bag), "--imu-topic", "/imu")
    assert data["method"] == "gyro"
    se = data["standard_errors"]
    _within(data["E_d"], E_D, se["E_d"])
    gyro = data["gyro_calibration"]
    v, gse = gyro["values"], gyro["standard_errors"]
    E_s = sim["true_E_s"]
    _within(v["E_b_k_g"], E_B * K_G / E_s, gse["E_b_k_g"])
    start, end = _true_bias(sim)
    assert abs(v["bias"] - 0.5 * (start + end)) <= Z * gse["bias"] + 0.5 * abs(end - start)
    assert "k_g" not in v
    assert gyro["relative_to_gyro"] == ["E_b"]
    assert gyro["reference"] == "no reference"
    said = [w for w in data["warnings"] if w.startswith("E_b is relative to the gyro")]
    assert len(said) == 1
    assert data["verdict"]["level"] == "care"
    assert data["new"]["gyro_scale_multiplier"] is None
    assert data["new"]["gyro_bias"] == v["bias"]
    # the terminal: the gyro's section, E_b's row saying what it is
    shown = run_cli("calibrate", str(bag), "--imu-topic", "/imu").stdout
    assert "Gyro (imu_link), against the wheels alone:" in shown
    assert f"bias = {math.degrees(v['bias']):.4f} ± " in shown
    assert "E_b, not corrected" in shown  # E_b k_g = 0.9996 resolves no correction


@pytest.mark.slow
def test_the_method_and_infos_suggestion_calibrate_as_the_topic_does(imu_bag):
    """``--method gyro`` on a bag with one IMU reads it (said so); ``info``'s suggested
    options (the motion capture and the IMU) calibrate with the gyro, the motion
    capture's heading its reference: k_g too, within its interval of the truth."""
    bag, _ = imu_bag
    by_topic = umbmark.calibrate(bag, imu_topic="/imu")
    proc = run_cli("calibrate", str(bag), "--method", "gyro", "--json")
    assert proc.returncode == 0, proc.stderr
    assert "--imu-topic /imu: the bag's one sensor_msgs/Imu topic" in proc.stderr
    assert json.loads(proc.stdout)["E_d"] == pytest.approx(by_topic.estimate.E_d, rel=1e-12)
    info = run_cli("info", str(bag), "--json")
    suggested = json.loads(info.stdout)["suggested_options"].split()
    assert suggested[-2:] == ["--imu-topic", "/imu"]
    data = _calibrated(str(bag), *suggested)
    gyro = data["gyro_calibration"]
    assert gyro["reference"] == "heading changes"
    _within(gyro["values"]["k_g"], K_G, gyro["standard_errors"]["k_g"])
    _within(data["E_b"], E_B, data["standard_errors"]["E_b"])
    _within(data["E_d"], E_D, data["standard_errors"]["E_d"])


@pytest.mark.slow
def test_the_wheels_the_imu_and_the_laser_together(laser_bag):
    """k_g, the bias, E_d, E_b, E_s all within their intervals of the truth, the
    laser's mounting of the stated one (0.1 m ahead of the axle), the verdict apply."""
    bag, sim = laser_bag
    data = _calibrated(str(bag), "--imu-topic", "/imu", "--scan-topic", "/scan")
    se = data["standard_errors"]
    gyro = data["gyro_calibration"]
    v, gse = gyro["values"], gyro["standard_errors"]
    assert gyro["reference"] == "scan matching"
    _within(v["k_g"], K_G, gse["k_g"])
    start, end = _true_bias(sim)
    assert abs(v["bias"] - 0.5 * (start + end)) <= Z * gse["bias"] + 0.5 * abs(end - start)
    _within(data["E_d"], E_D, se["E_d"])
    _within(data["E_b"], E_B, se["E_b"])
    _within(data["E_s"], sim["true_E_s"], se["E_s"])
    x, y, yaw = data["laser_pose"]
    sx, sy, syaw = data["laser_pose_standard_errors"]
    _within(x, 0.1, sx)
    _within(y, 0.0, sy)
    _within(yaw, 0.0, syaw)
    assert data["verdict"]["level"] == "apply"
    assert data["new"]["gyro_scale_multiplier"] == v["k_g"]


@pytest.mark.slow
def test_replay_reads_the_gyro_with_the_calibration_found(tmp_path):
    """Each run's true heading change less the gyro's: as read, the closed form of the
    simulated gyro (the turn's share 1 - 1 / k_g, less the bias over the run) to 0.3 deg;
    with the calibration found (k_g, the bias), within 0.3 deg of none. The gyro's bias
    does not walk here (``--gyro-bias-walk 0``): a walk of 2e-4 deg/s/sqrt(s) moves a
    run's integrated bias by some 0.4 deg from the recording's mean, which no closed form
    knows; what is left is the white noise (0.005 deg/s/sqrt(Hz): 0.05 deg over a run) and
    the motion capture's heading."""
    bag, sim = _simulated(tmp_path, "--gyro-bias-walk", "0")
    start, end = _true_bias(sim)
    assert start == end
    result = tmp_path / "result.json"
    mocap = ["--truth-topic", "/mocap/robot/pose"]
    proc = run_cli("calibrate", str(bag), *mocap, "--imu-topic", "/imu", "-o", str(result))
    assert proc.returncode == 0, proc.stderr
    replayed = ["replay", str(bag), *mocap, "--imu-topic", "/imu", "-p", str(result)]
    proc = run_cli(*replayed, "--json")
    assert proc.returncode == 0, proc.stderr
    runs = json.loads(proc.stdout)["runs"]
    report = umbmark.replay(bag, result, truth_topic="/mocap/robot/pose", imu_topic="/imu")
    assert len(runs) == len(report.runs) == 4
    tolerance = math.radians(0.3)
    for k, run in enumerate(runs):
        log = report.runs[k].log
        assert log is not None
        turn = log.truth_turn()
        assert turn is not None
        a, b, true_turn = turn
        read = true_turn / K_G + start * (b - a)
        assert run["gyro_heading_error_as_read"] == pytest.approx(true_turn - read, abs=tolerance)
        assert abs(run["gyro_heading_error_calibrated"]) < tolerance
    assert "gyro calibrated" in run_cli(*replayed).stdout


@pytest.mark.slow
def test_validate_ranks_the_gyro_among_the_estimators(imu_bag):
    """With an IMU and motion capture the gyro is a candidate: each run held out of the
    recording, the rest calibrated with the gyro, the run replayed: below half the
    nominal's end error on every fold, below a tenth of it on the mean (the robot's
    errors, 0.4 % and 2 %, are some 0.9 m at the end of a clockwise run nominally; a
    counter-clockwise one nominally ends some 0.2 m off, its errors partly cancelling)."""
    bag, _ = imu_bag
    proc = run_cli("validate", str(bag), "--truth-topic", "/mocap/robot/pose", "--imu-topic",
                   "/imu", "--json")  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert len(data["folds"]) == 4
    for fold in data["folds"]:
        errors = fold["end_error"]
        assert errors["gyro"] is not None, fold
        assert errors["gyro"] < 0.5 * errors["nominal"], fold
    mean = data["mean_end_error"]
    assert mean["gyro"] < 0.1 * mean["nominal"], mean
    shown = run_cli("validate", str(bag), "--truth-topic", "/mocap/robot/pose", "--imu-topic",
                    "/imu").stdout  # fmt: skip
    assert "gyro [mm]" in shown
    assert run_cli("validate", str(bag), "--methods", "gyro").stderr == (
        "umbmark: error: --methods gyro needs --imu-topic: the bag's IMU\n"
    )


#: The gyro's section as a person sees it: its box, the widest of its children's right
#: edges, the page's sideways scroll, and its text.
_GYRO_SECTION = """
(() => {
  const s = document.getElementById('gyro-calibration');
  s.scrollIntoView({block: 'start'});
  const b = s.getBoundingClientRect();
  const right = Math.max(...[...s.querySelectorAll('*')].map(e => e.getBoundingClientRect().right));
  return {left: b.left, top: b.top, width: b.width, height: b.height, right: right,
          client: document.documentElement.clientWidth,
          scroll: document.documentElement.scrollWidth - document.documentElement.clientWidth,
          visible: getComputedStyle(s).display !== 'none', text: s.innerText};
})()
"""


@pytest.mark.slow
def test_the_report_page_shows_the_gyro(imu_bag, tmp_path):
    """``umbmark report BAG --imu-topic``: the square runs' E_max,syst against the motion
    capture, the correction the gyro's, its runs predicted after with it far inside the
    measured (the robot's errors make some 0.87 m of E_max,syst; the gyro's calibration
    takes E_d and E_b to their truth within their intervals, what is left is the runs'
    scatter); the gyro's section in headless chromium at a desk's and a phone's width:
    on the screen, inside the page's width (no sideways scroll), its scale and bias as
    read within their intervals of the truth."""
    from test_report_command import Chromium

    bag, _ = imu_bag
    page = tmp_path / "page.html"
    proc = run_cli("report", str(bag), "--truth-topic", "/mocap/robot/pose", "-L", "4",
                   "--imu-topic", "/imu", "-o", str(page), "--json")  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    measured = data["e_max_syst"][0]
    assert measured > 0.5
    assert data["predicted_after"]["e_max_syst"] < 0.1 * measured
    (one,) = data["passes"]
    gyro = one["gyro_calibration"]
    _within(gyro["values"]["k_g"], K_G, gyro["standard_errors"]["k_g"])
    browser = Chromium(tmp_path / "profile")
    try:
        seen = {}
        for width, mobile in ((1200, False), (390, True)):
            browser.open(page, width, mobile=mobile)
            assert browser.errors() == []
            seen[width] = browser.evaluate(_GYRO_SECTION)
    finally:
        browser.close()
    for width, box in seen.items():
        assert box["visible"], width
        assert box["top"] == pytest.approx(0.0, abs=1.0), box  # scrolled to, on the screen
        assert 100 < box["height"] < 2000, box
        assert box["left"] >= 0, box
        assert box["right"] <= box["client"] + 0.5, box
        assert box["scroll"] <= 0, box
        text = box["text"]
        k_g = re.search(r"scale k_g = (\d\.\d+) ± (\d\.\d+)", text)
        bias = re.search(r"bias = (\d\.\d+) ± (\d\.\d+) deg/s", text)
        assert k_g is not None, text
        assert bias is not None, text
        _within(float(k_g[1]), K_G, float(k_g[2]))
        assert abs(float(bias[1]) - BIAS) < Z * float(bias[2]) + 0.02  # its walk: 0.02 deg/s
        assert "turtlebot_create" in text  # where a driver takes them


@pytest.mark.slow
def test_the_fleet_lists_each_bad_imu_with_its_line(tmp_path):
    """A robot's recordings of wheels and an IMU, no laser, no reference: the good IMU
    calibrated by the gyro (E_b relative to the gyro), each bad one (no messages, frozen,
    its frame unknown, accelerations only, saturating) left out with the line calibrate
    says of it, none offered for applying; the robot's figures from the good one only."""
    pytest.importorskip("distributed", reason="the fleet's extra: pip install '.[fleet]'")
    import corpus_inputs as ci

    session = ci.simulated_session()
    kinds = {"ok": "", "empty": "the topic has no messages", "frozen": "a frozen IMU",
             "no-frame": "the IMU's frame imu_link has no transform",
             "accel-only": "no angular velocity", "saturated": "the gyro saturates"}  # fmt: skip
    assert set(kinds) == set(ci.IMUS)
    paths = {}
    for day, kind in enumerate(kinds, 1):
        folder = tmp_path / "fleet" / "robot01" / f"2026-11-0{day}"
        folder.mkdir(parents=True)
        paths[kind] = str(ci.write_session_bag(folder / "drive", "mcap", session, truth=False,
                                               imu=kind))  # fmt: skip
    proc = run_cli("fleet", str(tmp_path / "fleet"), "--robot-from", "{robot}/{date}/*", "-b",
                   "0.34", "--wheel-diameter", "0.15", "--history", str(tmp_path / "h.sqlite3"),
                   "--workers", "1", "--json", timeout=300)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    (robot,) = data["robots"]
    assert data["failed"] == []
    assert robot["latest"]["method"] == "gyro"
    assert robot["latest"]["path"].endswith("2026-11-01/drive")
    left = {entry["path"]: entry["reason"] for entry in robot["left_out"]}
    assert len(left) == 5
    for kind, said in kinds.items():
        if kind == "ok":
            continue
        reason = left[next(p for p in left if paths[kind].endswith(p))]
        assert said in reason, (kind, reason)
        assert "\n" not in reason
        assert next(p for p in left if paths[kind].endswith(p)) in reason
    assert "E_b_gyro" in robot["figures"]
    assert "E_b" not in robot["figures"]
