"""Results that say when they are not to be applied: the verdict on a correction.

A verdict comes first (terminal, JSON ``apply``, HTML page, ``umbmark report``): apply;
apply with care, and why; do not apply, why, and what to record instead. "Do not apply"
withholds the overlay (``--yaml``, ``--ros1-yaml``, the terminal's) and the history's
"applied" mark unless ``--override-verdict`` (``--force`` only replaces files).
Recordings made the way robots make them: a TurtleBot3's bag whose ground truth lost the
robot for a while, a tape-measured table of few runs with a large scatter, run logs of a
robot without errors; and the normal good cases, which stay "apply".
"""

from __future__ import annotations

import json
import math
import os
import shlex
import shutil
import sqlite3
import subprocess
from dataclasses import replace
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

import drive_sim
import umbmark
from robot_bags import TB3, drive, turtlebot3_bag
from umbmark.calibration.verdict import (
    MODEL_REFUSE,
    NOTICEABLE_ANGLE,
    Evidence,
    Verdict,
    judge,
    noticeable,
)
from umbmark.estimators.base import ErrorEstimate, ModelCheckFailure, SquareTest
from umbmark.store.history import MIGRATIONS, History

from helpers import OPTIODOM, linear_cgs, run_cli, runs_around, write_table

L, B = 4.0, 0.34
TEST = SquareTest(L, B)
#: The TurtleBot3's true errors.
TB3_E_D, TB3_E_B = 1.004, 1.02


# --- the criteria, on estimates built by hand ------------------------------------------


def _estimate(E_b: float = 1.0, se_b: float | None = None, **kw: float) -> ErrorEstimate:
    errors = {} if se_b is None else {"E_b": se_b}  # no dof: normal intervals, 1.96 se
    return ErrorEstimate("exact", 0.0, 0.0, kw.pop("E_d", 1.0), E_b, standard_errors=errors, **kw)  # type: ignore[arg-type]


def test_what_matters_is_the_papers_scatter_on_the_square():
    # A Type A error alpha moves both centres by 2 L alpha in x and in y (the paper's
    # first-order results): 2 sqrt(2) L alpha from the origin. What matters is an alpha
    # whose E_max,syst is the paper's 25 mm scatter on its 4 m square.
    cw = linear_cgs(NOTICEABLE_ANGLE, 0.0, 4.0)["cw"]
    assert math.hypot(*cw) == pytest.approx(0.025, rel=1e-12)
    # alpha = (pi/2)(1 - 1/E_b) ~ (pi/2)(E_b - 1); beta = (2L/b)(E_d - 1)/(E_d + 1) ~ (L/b)(E_d - 1)
    assert noticeable("E_b", TEST) == pytest.approx(0.0014067, rel=1e-4)
    assert noticeable("E_d", TEST) == pytest.approx(0.0022097 * 0.34 / 4.0, rel=1e-4)


@pytest.mark.parametrize(
    ("E_b", "se", "level"),
    [
        # 95 % interval 1.02 -/+ 1.96 x 0.025 = 0.971 to 1.069: holds 1 and 0.98, where
        # this correction doubles the error: do not apply.
        (1.02, 0.025, "do-not-apply"),
        # 1.02 -/+ 0.0235 = 0.9965 to 1.0435: holds 1, not 0.98: with care.
        (1.02, 0.012, "care"),
        # 1.02 -/+ 0.0147: 1.0053 to 1.0347, clear of 1.
        (1.02, 0.0075, "apply"),
        # A correction of 0.0005 (below the 0.0014 that matters): harmless, but an
        # interval of -/+ 0.0039 (more than twice 0.0014) may hide an error that matters.
        (1.0005, 0.002, "care"),
        (1.0005, 0.0005, "apply"),
    ],
)
def test_the_interval_says_whether_the_correction_means_anything(E_b, se, level):
    assert judge(_estimate(E_b, se), TEST, Evidence()).level == level


@pytest.mark.parametrize(("E_b", "se"), [(1.02, 0.025), (1.02, 0.012), (1.0005, 0.002)])
def test_a_scan_matching_verdict_speaks_of_driving_not_of_squares(E_b, se):
    """Wheels calibrated against a laser's scan matching drove no square: what narrows
    their interval is more driving with turns, not a larger square."""
    errors = {"E_b": se}
    estimate = ErrorEstimate("scan-matching", 0.0, 0.0, 1.0, E_b, standard_errors=errors)
    verdict = judge(estimate, SquareTest(1.0, B), Evidence())
    said = " ".join((*verdict.reasons, verdict.instead or ""))
    assert verdict.level != "apply"
    assert "square" not in said.replace("square root", ""), said
    assert "record more driving, with turns both ways" in said
    # The same interval of a square test still asks for more runs or a larger square.
    square = judge(_estimate(E_b, se), TEST, Evidence())
    assert "a larger square" in (square.instead or "")


def test_a_fit_that_does_not_hold_is_not_applied():
    def fit(position: float, heading: float = 0.0) -> str:
        comp = {"rms_position": position, "rms_heading": heading, "samples": 1000.0}
        estimate = _estimate(components=comp)  # type: ignore[arg-type]
        return judge(estimate, TEST, Evidence(recorded_runs=6, path_length=4.5)).level

    # 200 mm on 4.5 m of travel: 4.4 %, more than an uncalibrated LabMate's 2 %.
    assert fit(0.2) == "do-not-apply"
    assert fit(0.03) == "care"  # 0.7 %, 30 mm: more than slip leaves
    assert fit(0.01) == "apply"
    assert fit(0.001, math.radians(14)) == "do-not-apply"  # the 14 deg
    assert fit(0.001, math.radians(5)) == "care"


def test_the_other_criteria():
    nominal = judge(_estimate(), TEST, Evidence(nominal_best=True))
    assert nominal.level == "do-not-apply"
    assert "nominal parameters" in nominal.reasons[0]
    assert nominal.instead is not None
    assert nominal.instead.startswith("keep the active")
    assert judge(_estimate(), TEST, Evidence(runs_per_direction=(2, 5))).level == "care"
    assert judge(_estimate(), TEST, Evidence(runs_per_direction=(3, 3))).level == "apply"
    assert judge(_estimate(), TEST, Evidence(warnings=("shaky",))).level == "care"
    skid = judge(_estimate(1.5, 0.001), TEST, Evidence())  # a wheelbase 50 % off
    assert skid.level == "care"
    assert "skid-steer" in skid.reasons[0]


def test_a_strongly_failed_model_check_is_not_applied():
    def check(p: float, misfit: float, swapped: float | None = None) -> Verdict:
        failure = ModelCheckFailure(p, misfit, swapped, swapped is not None and swapped > 0.001)
        warned = ("the runs' positions do not fit one robot of the model",)
        return judge(_estimate(model_failure=failure), TEST, Evidence(warnings=warned))  # type: ignore[arg-type]

    # the paper's scatter on its 4 m square is 25 mm: a miss of 300 mm at p = 1e-6 is no
    # robot's; a marginal p, or a miss within the scatter, stays a warning
    assert check(1e-6, 0.3).level == "do-not-apply"
    assert check(MODEL_REFUSE / 2, 0.3).level == "do-not-apply"
    assert check(MODEL_REFUSE * 2, 0.3).level == "care"
    assert check(1e-6, 0.02).level == "care"
    unlabelled = check(1e-6, 0.3)
    assert "swapped" not in unlabelled.reasons[0]
    assert unlabelled.instead is not None
    assert "direction labels" in unlabelled.instead
    swapped = check(1e-6, 0.3, swapped=0.5)
    assert "the direction labels are likely swapped" in swapped.reasons[0]
    assert swapped.instead == "swap the cw and ccw labels of the runs and calibrate again"


def _swapped(table: Path, out: Path) -> Path:
    lines = table.read_text(encoding="utf-8").splitlines()
    other = {"cw": "ccw", "ccw": "cw"}
    swapped = [
        f"{other[x.split(',', 1)[0]]},{x.split(',', 1)[1]}" if x.split(",")[0] in other else x
        for x in lines
    ]
    out.write_text("\n".join(swapped) + "\n", encoding="utf-8")
    return out


def _linear_misfit(table: Path) -> float:
    """How far [m] the clusters' centres lie from the nearest robot of the paper's
    first-order model (least squares in alpha and beta; ``helpers.linear_cgs``)."""
    rows = [line.split(",") for line in table.read_text().splitlines() if line[:2] in ("cw", "cc")]
    errors = {
        d: [[float(r[1]) - float(r[3]), float(r[2]) - float(r[4])] for r in rows if r[0] == d]
        for d in ("cw", "ccw")
    }
    centres = {d: np.mean(e, axis=0) / 1000 for d, e in errors.items()}  # mm to m
    basis = [
        np.concatenate([linear_cgs(*unit, L)[d] for d in ("cw", "ccw")])
        for unit in ((1, 0), (0, 1))
    ]
    design = np.column_stack(basis)
    observed = np.concatenate([centres["cw"], centres["ccw"]])
    fitted, *_ = np.linalg.lstsq(design, observed, rcond=None)
    return float(np.max(np.hypot(*(observed - design @ fitted).reshape(2, 2).T)))


@pytest.mark.slow
def test_the_example_with_cw_and_ccw_swapped_is_not_applied(tmp_path: Path):
    table = tmp_path / "runs.csv"
    umbmark.example(str(table))
    swapped = _swapped(table, tmp_path / "swapped.csv")
    # the paper's first-order model, independently: the example fits one robot within the
    # scatter, the swapped table misses every robot by far more than the 25 mm scatter
    assert _linear_misfit(table) < 0.025
    assert _linear_misfit(swapped) > 0.1
    p = umbmark.calibrate(swapped, side_length=L, wheelbase=B, unit="mm", method="endpose")
    p_value = p.estimate.components["model_check_p"]
    assert p_value < MODEL_REFUSE
    yaml = tmp_path / "o.yaml"
    args = ("calibrate", str(swapped), "-L", "4", "-b", "0.34", "--unit", "mm")
    proc = run_cli(*args, "--yaml", str(yaml))
    assert proc.returncode == 4, proc.stderr  # do not apply
    first = proc.stdout.splitlines()[0]
    assert first.startswith(
        f"Verdict: do not apply: the model check fails strongly (p = {p_value:.2g}"
    )
    assert "the direction labels are likely swapped" in first
    assert "Instead: swap the cw and ccw labels" in first
    assert "ros__parameters" not in proc.stdout  # no overlay printed
    assert "No ros2_control overlay: the verdict is do not apply" in proc.stdout
    assert not yaml.exists()
    data = json.loads(run_cli(*args, "--json").stdout)
    assert data["verdict"]["level"] == "do-not-apply"
    # swapped back, the same runs apply
    back = _swapped(swapped, tmp_path / "back.csv")
    assert umbmark.calibrate(back, side_length=L, wheelbase=B, unit="mm").verdict.level == "apply"


# --- recordings that give each case ----------------------------------------------------


@pytest.fixture(scope="module")
def lost_truth(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A TurtleBot3 in Gazebo (E_d 1.004, E_b 1.02) driving six 1 m squares, its ground
    truth a tracker that locked onto a reflection 0.6 m to its left for 5 s in five of
    them (jumps of less than 1 m: not refused as a lost tracker)."""
    motion = drive(TB3, TB3_E_D, TB3_E_B)
    truth = motion.truth.copy()
    for start in (10, 40, 70, 100, 130):  # [s], while the robot drives
        truth[(motion.time >= start) & (motion.time < start + 5), 1] += 0.6
    path = tmp_path_factory.mktemp("lost") / "tb3"
    return turtlebot3_bag(
        path, "mcap", replace(motion, truth=truth), model_states=False, wheel_tf=False,
        ground_truth=True,
    )  # fmt: skip


BAG = ("--truth-topic", "/ground_truth/odom", "-L", "1")


@pytest.mark.slow
def test_a_trajectory_fit_to_a_lost_truth_is_not_applied(lost_truth: Path, tmp_path: Path):
    outputs = {"--yaml": tmp_path / "o.yaml", "--ros1-yaml": tmp_path / "p.yaml"}
    files = [a for flag, path in outputs.items() for a in (flag, str(path))]
    json_out, page = tmp_path / "r.json", tmp_path / "r.html"
    args = ["calibrate", str(lost_truth), *BAG, "--method", "trajectory", *files]
    proc = run_cli(*args, "-o", str(json_out), "--report", str(page))
    assert proc.returncode == 4, proc.stderr  # do not apply
    # The verdict first, and no overlay to paste.
    first = proc.stdout.splitlines()[0]
    assert first.startswith("Verdict: do not apply: ")
    assert "misses the ground truth by" in first
    assert "ros__parameters" not in proc.stdout
    assert "No ros2_control overlay: the verdict is do not apply" in proc.stdout
    for path in outputs.values():
        assert not path.exists()
        assert f"wrote {path}" not in proc.stderr
    assert (
        "umbmark: warning: --yaml, --ros1-yaml not written: the verdict is do not apply "
        "(--override-verdict writes them; --force only replaces files that exist)\n"
    ) in proc.stderr
    data = json.loads(json_out.read_text())
    assert next(iter(data)) == "verdict"
    assert data["verdict"]["level"] == "do-not-apply"
    assert "ground truth" in data["verdict"]["instead"]
    # Why it matters: the fit's E_b lies on the other side of 1 than the robot's (1.02):
    # the correction would make the robot worse. The end points are unaffected (the
    # reflection came and went mid-run): the square's own estimate is right and applies.
    assert abs(data["E_b"] - TB3_E_B) > abs(1.0 - TB3_E_B)
    exact = umbmark.calibrate(lost_truth, truth_topic="/ground_truth/odom", side_length=1.0)
    assert exact.estimate.E_b == pytest.approx(TB3_E_B, abs=1e-3)
    assert exact.verdict.level == "apply"
    # The page, as a browser builds it: the verdict heads it, the overlay is withheld.
    html = _Ids()
    html.feed(_dom(page, tmp_path))
    assert html.sections[0] == "apply"
    assert html.levels == ["do-not-apply"]
    assert "overlay-withheld" in html.ids
    assert "overlay-yaml" not in html.ids
    # --override-verdict writes the overlay, which says it is not to be applied.
    forced = run_cli(*args, "--override-verdict")
    assert forced.returncode == 0, forced.stderr
    assert "ros__parameters" in forced.stdout
    text = outputs["--yaml"].read_text()
    assert "# Verdict: do not apply: " in text
    assert "wheel_separation_multiplier" in text


def _dom(page: Path, tmp_path: Path) -> str:
    """The page's DOM as headless chromium builds it (its text where chromium is missing,
    outside CI)."""
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        if os.environ.get("CI"):
            pytest.fail("chromium is missing on CI (apt-get install chromium)")
        return page.read_text()
    argv = [chromium, "--headless", "--disable-gpu", "--no-sandbox", "--dump-dom"]
    argv += [f"--user-data-dir={tmp_path / 'profile'}", page.resolve().as_uri()]
    done = subprocess.run(argv, check=True, capture_output=True, text=True, timeout=60)
    return done.stdout


class _Ids(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.ids: list[str] = []
        self.sections: list[str] = []
        self.levels: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        if a.get("id"):
            self.ids.append(a["id"] or "")
            if tag == "section":
                self.sections.append(a["id"] or "")
        if a.get("data-level"):
            self.levels.append(a["data-level"] or "")


@pytest.mark.slow
def test_the_history_records_it_but_does_not_mark_it_applied(lost_truth: Path, tmp_path: Path):
    db = tmp_path / "h.sqlite3"
    where = ("--robot", "tb3", "--history", str(db))
    proc = run_cli("calibrate", str(lost_truth), *BAG, "--method", "trajectory", *where)
    assert proc.returncode == 4, proc.stderr  # do not apply
    (line,) = [x for x in proc.stderr.splitlines() if "recorded" in x]
    assert line == (
        f"umbmark: recorded as calibration 1 of robot tb3 in {db}; its verdict is do not "
        "apply: not to be configured on the robot"
    )
    assert "--applied" not in proc.stderr
    (record,) = History(db).calibrations("tb3")
    assert record.verdict is not None
    assert record.verdict["level"] == "do-not-apply"
    marked = run_cli("history", "tb3", "--history", str(db), "--applied", "1")
    assert marked.returncode == 2, marked.stderr
    assert "calibration 1 of tb3 was judged do not apply" in marked.stderr
    assert "--override-verdict marks it applied all the same" in marked.stderr
    assert not History(db).calibrations("tb3")[0].applied
    # --force replaces files; it does not mark a do-not-apply calibration applied.
    marked = run_cli("history", "tb3", "--history", str(db), "--applied", "1", "--force")
    assert marked.returncode == 2, marked.stderr
    assert not History(db).calibrations("tb3")[0].applied
    forced = run_cli("history", "tb3", "--history", str(db), "--applied", "1", "--override-verdict")
    assert forced.returncode == 0, forced.stderr
    assert History(db).calibrations("tb3")[0].applied
    table = run_cli("history", "tb3", "--history", str(db))
    assert "do not apply" in table.stdout


def test_a_history_of_schema_1_keeps_its_calibrations(tmp_path: Path):
    """Calibrations recorded before the verdict have none, and may be marked applied."""
    db = tmp_path / "old.sqlite3"
    raw = sqlite3.connect(db)
    MIGRATIONS[0](raw)
    raw.execute("PRAGMA user_version = 1")
    raw.execute("INSERT INTO robots VALUES ('old', 0.34, NULL, '2026-01-01T00:00:00Z')")
    raw.execute(
        "INSERT INTO calibrations (robot, time, method, inputs, E_d, E_b, E_s, e_max_syst, "
        "standard_errors, active, new, applied) VALUES ('old', '2026-01-01T00:00:00Z', "
        "'exact', '[]', 1.001, 0.99, NULL, 0.1, '{}', ?, '{}', 0)",
        (json.dumps({"wheelbase": 0.34, "wheel_separation_multiplier": 1.0, "c_L": 1.0,
                     "c_R": 1.0, "wheel_diameter": None}),),
    )  # fmt: skip
    raw.commit()
    raw.close()
    store = History(db)
    assert store.schema_version == len(MIGRATIONS)  # brought up to date
    (old,) = store.calibrations("old")
    assert old.verdict is None
    store.mark_applied("old", 1)
    assert store.calibrations("old")[0].applied


@pytest.fixture
def wide(tmp_path: Path) -> Path:
    """A tape-measured table: 3 runs each way on a 4 m square scattering 150 mm (the
    paper's: 25 mm) about a robot with alpha = 0.006 rad (E_b about 1.004)."""
    rows = runs_around(linear_cgs(0.006, 0.0, L), spread=0.15, n=3)
    return write_table(tmp_path / "wide.csv", rows, "direction,x_abs,y_abs,x_odo,y_odo")


def test_an_interval_that_holds_no_correction_and_its_double_is_not_applied(
    wide: Path, tmp_path: Path
):
    yaml = tmp_path / "o.yaml"
    proc = run_cli("calibrate", str(wide), "-L", "4", "-b", "0.34", "--yaml", str(yaml), "--json")
    assert proc.returncode == 4, proc.stderr  # do not apply
    data = json.loads(proc.stdout)
    low, high = data["intervals_95"]["E_b"]
    E_b = data["E_b"]
    assert E_b - 1.0 > 0.0014  # a correction that matters on the square, and robots
    assert low <= 2.0 - E_b < 1.0 <= high  # it would make twice as wrong, or none at all
    assert data["verdict"]["level"] == "do-not-apply"
    assert data["verdict"]["reasons"][0].startswith("E_b's 95 % interval")
    assert data["verdict"]["instead"].startswith("record more runs")
    assert not yaml.exists()
    assert "--yaml not written: the verdict is do not apply" in proc.stderr
    # The Python API refuses to write it, even with force, unless overridden.
    report = umbmark.calibrate(wide, side_length=L, wheelbase=B)
    assert report.withheld == ()
    with pytest.raises(umbmark.InputError, match="Verdict: do not apply"):
        report.write(yaml=yaml)
    with pytest.raises(umbmark.InputError, match="override_verdict=True writes it"):
        report.write(yaml=yaml, force=True)
    assert not yaml.exists()
    assert report.write(yaml=yaml, override_verdict=True) == [yaml]


@pytest.mark.slow
def test_umbmark_report_shows_the_verdict(wide: Path, tmp_path: Path):
    page = tmp_path / "p.html"
    proc = run_cli("report", str(wide), "-L", "4", "-b", "0.34", "-o", str(page))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("Verdict: do not apply: E_b's 95 % interval")
    assert "correction" in proc.stdout  # the passes' column
    assert "do not apply" in proc.stdout.split("UMBmark passes", 1)[1]
    html = _Ids()
    html.feed(page.read_text())
    assert html.sections[0] == "apply"
    assert "overlay-withheld" in html.ids


@pytest.mark.slow
def test_auto_finding_the_nominal_parameters_best_is_not_applied(tmp_path: Path):
    """Run logs of a robot with no error at all (true radii and wheelbase the nominal
    ones), with random slip: no estimator predicts held-out sessions better than the
    nominal parameters, and the verdict says to keep them."""
    perfect = drive_sim.Robot(
        r_left=drive_sim.RADIUS, r_right=drive_sim.RADIUS,
        b_arc=drive_sim.WHEELBASE, b_spot=drive_sim.WHEELBASE,
    )  # fmt: skip
    folders = []
    for seed in (1, 2, 3):
        rng = np.random.default_rng(seed)
        logs = [
            drive_sim.drive(
                drive_sim.square_rates(1.5, 1 if k % 2 else -1, 0.3, rng.uniform(0, 6.3)),
                perfect,
                1e-3,
                rng,
            )
            for k in range(4)
        ]
        folders.append(str(drive_sim.write_session(tmp_path / f"session-{seed}", logs)))
    yaml = tmp_path / "o.yaml"
    proc = run_cli("calibrate", *folders, "-L", "1.5", "--method", "auto", "--yaml", str(yaml))
    assert proc.returncode == 4, proc.stderr  # do not apply
    assert proc.stdout.startswith(
        "Verdict: do not apply: no estimator predicted held-out runs better than the nominal "
        "parameters"
    )
    assert "Instead: keep the active parameters" in proc.stdout.splitlines()[0]
    assert not yaml.exists()
    # The note saying what auto did is information, not a warning.
    assert "umbmark: method auto: no estimator predicted" in proc.stderr
    assert "warning: method auto" not in proc.stderr


@pytest.mark.slow
def test_a_fit_that_diverges_says_why_and_what_to_try(tmp_path: Path):
    """A robot on a stand: its wheels turn, the motion capture sees it stay put."""
    logs = drive_sim.squares(drive_sim.NO_SCRUB, 5, runs=4)
    rng = np.random.default_rng(5)
    still = [replace(log, truth=1e-4 * rng.normal(size=log.truth.shape)) for log in logs]
    folder = drive_sim.write_session(tmp_path / "stand", still)
    proc = run_cli("calibrate", str(folder), "--method", "endpoints")
    assert proc.returncode == 2
    line = proc.stderr
    assert line.startswith("umbmark: error: ")
    assert line.count("\n") == 1
    assert "the fit diverged" in line
    assert "Check that the ground truth follows the robot (not a robot on a stand" in line
    assert "try --method trajectory" in line
    assert "must be > 0" not in line  # before: "wheelbase must be > 0, got -1.1"


# --- the good cases stay "apply" -----------------------------------------------------


def test_the_example_and_the_demo_apply(tmp_path: Path, demo: umbmark.DemoReport):
    table = tmp_path / "runs.csv"
    umbmark.example(str(table))
    assert umbmark.calibrate(table, side_length=4, wheelbase=0.34, unit="mm").verdict.level == (
        "apply"
    )
    assert demo.report.verdict.level == "apply"
    square, _circles = umbmark.example_sessions(tmp_path / "real")
    assert square.parent.name == "square"
    assert umbmark.calibrate(square).verdict.level == "apply"


@pytest.mark.parametrize("session", ["230620202042", "231220200029"])
def test_real_square_sessions_apply(session: str):
    if not (OPTIODOM / "square" / session).is_dir():
        pytest.skip("../shared/data is not here")  # the package ships the first only
    report = umbmark.calibrate(OPTIODOM / "square" / session)
    assert report.estimate.method == "exact"
    assert report.verdict.level == "apply", report.verdict
    assert report.overlay_withheld is False


@pytest.mark.slow
def test_the_verdict_is_printed_first_and_is_json_s_first_key(tmp_path: Path):
    table = tmp_path / "runs.csv"
    umbmark.example(str(table))
    args = ("calibrate", str(table), "-L", "4", "-b", "0.34", "--unit", "mm")
    proc = run_cli(*args)
    assert proc.stdout.splitlines()[0] == "Verdict: apply."
    assert "ros__parameters" in proc.stdout
    data = json.loads(run_cli(*args, "--json").stdout)
    assert next(iter(data)) == "verdict"
    assert data["verdict"] == {"level": "apply", "reasons": [], "instead": None}
    assert data["second_pass"].startswith("E_max,syst = ")
    assert "apply" not in data
    # One name for each, the same in Python and in the JSON: the verdict on applying, and
    # the 3 x SEM sentence (whether another pass is worth it).
    report = umbmark.calibrate(str(table), side_length=4, wheelbase=0.34, unit="mm")
    assert report.verdict.to_dict() == data["verdict"]
    assert report.second_pass == data["second_pass"]
    # A recorded calibration to apply suggests the command that marks it applied.
    db = tmp_path / "h.sqlite3"
    recorded = run_cli(*args, "--robot", "r", "--history", str(db))
    (line,) = [x for x in recorded.stderr.splitlines() if "recorded" in x]
    suggested = shlex.split(line.split("configured on the robot: umbmark ", 1)[1])
    assert suggested == ["history", "r", "--history", str(db), "--applied", "1"]


@pytest.mark.slow
def test_runs_without_error_and_without_scatter_are_not_applied(tmp_path: Path):
    # Every run came back exactly where its odometry says: E_max,syst = 0.0 mm and
    # 3 x SEM = 0.0 mm, what a ground truth that is the odometry gives (or a noise-free
    # simulation's second pass), never a measured one: not plainly "apply".
    table = write_table(
        tmp_path / "same.csv",
        [(d, 0.0, 0.0, 0.0, 0.0) for d in ("cw",) * 5 + ("ccw",) * 5],
        "direction,x_abs,y_abs,x_odo,y_odo",
    )
    proc = run_cli("calibrate", str(table), "-L", "4", "-b", "0.34")
    assert proc.returncode == 0, proc.stderr
    first = proc.stdout.splitlines()[0]
    assert first.startswith(
        "Verdict: apply with care: E_max,syst = 0.0 mm and 3 x SEM = 0.0 mm: the runs came "
        "back exactly where the odometry says, without any scatter, which no measured "
        "reference shows: a ground truth that reproduces the odometry, or a simulation "
        "without noise."
    )
    assert "Verdict: apply." not in proc.stdout
    assert "E_max,syst = 0.0 mm > 3 x SEM" not in proc.stdout
    assert "nothing was measured (a ground truth that reproduces the odometry)" in proc.stdout
    # a tenth of a millimetre of scatter is a measurement: judged as before
    spread = [(d, 1e-4 * (k % 2), 0.0, 0.0, 0.0) for k, d in enumerate(("cw",) * 5 + ("ccw",) * 5)]
    table = write_table(tmp_path / "tiny.csv", spread, "direction,x_abs,y_abs,x_odo,y_odo")
    report = umbmark.calibrate(table, side_length=4.0, wheelbase=0.34)
    assert not any("without any scatter" in r for r in report.verdict.reasons)
