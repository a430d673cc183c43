"""``umbmark calibrate`` end to end: summary, JSON, YAML, plots, composition, bad input."""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest
import yaml
from typer.testing import CliRunner

from umbmark.cli.main import app

from helpers import linear_cgs, runs_around

L, B = 4.0, 0.34
ALPHA, BETA = math.radians(-1.0254), math.radians(0.566)
runner = CliRunner()


def _rows(unit_scale: float = 1.0, spread: float = 0.025):
    return [
        (d, xa * unit_scale, ya * unit_scale, xo, yo)
        for d, xa, ya, xo, yo in runs_around(linear_cgs(ALPHA, BETA, L), spread)
    ]


def _calibrate(*args: str):
    return runner.invoke(app, ["calibrate", *args])


def _json(*args: str) -> dict:
    result = _calibrate(*args, "--json")
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def test_summary_states_every_figure_with_its_unit(table):
    result = _calibrate(str(table(_rows())), "--side-length", "4", "--wheelbase", "0.34")
    assert result.exit_code == 0, result.output
    out = " ".join(result.stdout.split())  # rich wraps lines at the terminal's width
    e_max = math.hypot(*linear_cgs(ALPHA, BETA, L)["ccw"]) * 1000
    assert f"E_max,syst = {e_max:.1f} mm" in out
    assert "centre of gravity x [mm]" in out
    assert "SEM = sigma / sqrt(n) [mm]" in out
    assert "> 3 x SEM" in out
    assert "run UMBmark again" in out
    assert re.search(r"alpha, Type A error per turn -1\.0254 ± \d\.\d+ deg", out)
    assert "wheelbase [mm] (Eq. 4.26)" in out
    assert "ros__parameters:" in out
    assert "wheel_separation_multiplier:" in out


def test_json_has_the_promised_keys_in_metres_and_radians(table):
    data = _json(str(table(_rows())), "--side-length", "4", "--wheelbase", "0.34")
    cg = linear_cgs(ALPHA, BETA, L)
    assert data["cg_cw"] == pytest.approx(list(cg["cw"]), abs=1e-12)
    assert data["cg_ccw"] == pytest.approx(list(cg["ccw"]), abs=1e-12)
    assert data["e_max_syst"] == pytest.approx(math.hypot(*cg["ccw"]))
    assert data["alpha"] == pytest.approx(ALPHA)
    assert data["beta"] == pytest.approx(BETA)
    E_d = data["E_d"]
    assert data["c_L"] == pytest.approx(2 / (E_d + 1))
    assert data["c_R"] == pytest.approx(2 / (1 / E_d + 1))
    assert data["wheelbase_corrected"] == pytest.approx(0.34 * 90 / (90 - (-1.0254)))
    # Five runs on a regular pentagon of radius 25 mm: radial sigma^2 = 5 r^2 / 4.
    assert data["sigma_cw"] == pytest.approx(0.025 * math.sqrt(5 / 4))
    assert data["sem_ccw"] == pytest.approx(0.025 * math.sqrt(5 / 4) / math.sqrt(5))
    assert data["second_pass_recommended"] is True
    assert data["units"] == {"length": "m", "angle": "rad"}
    assert len(data["runs"]) == 10
    assert data["warnings"] == []


def test_lengths_in_mm_give_the_same_result(table):
    in_m = _json(str(table(_rows(), name="m.csv")), "-L", "4", "-b", "0.34")
    in_mm = _json(str(table(_rows(1000.0), name="mm.csv")), "-L", "4", "-b", "0.34", "--unit", "mm")
    for key in ("E_d", "E_b", "alpha", "beta", "e_max_syst", "wheelbase_corrected", "sem"):
        assert in_mm[key] == pytest.approx(in_m[key], rel=1e-12), key


def test_output_file_holds_the_same_object(table, tmp_path):
    out = tmp_path / "result.json"
    data = _json(str(table(_rows())), "-L", "4", "-b", "0.34", "-o", str(out))
    assert json.loads(out.read_text()) == data


def test_yaml_overlay_is_valid_with_floats_and_provenance(table, tmp_path):
    out = tmp_path / "overlay.yaml"
    data = _json(
        str(table(_rows(spread=0.0))),
        "-L",
        "4",
        "-b",
        "0.34",
        "--yaml",
        str(out),
        "--controller",
        "base_controller",
    )
    text = out.read_text()
    assert text.startswith("# Written by umbmark")
    params = yaml.safe_load(text)["base_controller"]["ros__parameters"]
    assert params["wheel_separation_multiplier"] == pytest.approx(data["E_b"], rel=1e-9)
    assert params["left_wheel_radius_multiplier"] == pytest.approx(data["c_L"], rel=1e-9)
    assert params["right_wheel_radius_multiplier"] == pytest.approx(data["c_R"], rel=1e-9)
    for value in re.findall(r"multiplier: (\S+)", text):
        assert "." in value  # ros2 parameters are doubles: 1.0, never 1


def test_yaml_of_a_perfect_robot_still_writes_doubles(table, tmp_path):
    out = tmp_path / "overlay.yaml"
    rows = runs_around({"cw": (0.0, 0.0), "ccw": (0.0, 0.0)}, 0.01)
    result = _calibrate(str(table(rows)), "-L", "4", "-b", "0.34", "--yaml", str(out), "--json")
    assert result.exit_code == 0
    assert re.findall(r"multiplier: (\S+)", out.read_text()) == ["1.0", "1.0", "1.0"]


def test_correction_multiplies_into_the_active_parameters(table, tmp_path):
    data = _json(
        str(table(_rows())),
        "-L",
        "4",
        "-b",
        "0.30",
        "--current-c-l",
        "1.01",
        "--current-c-r",
        "0.98",
        "--current-separation-multiplier",
        "1.1",
    )
    # The odometry used b = 0.30 * 1.1 during the runs: Eq. 4.22 sees that wheelbase.
    radius = (L / 2) / math.sin(BETA / 2)
    E_d = (radius + 0.33 / 2) / (radius - 0.33 / 2)
    assert data["E_d"] == pytest.approx(E_d, rel=1e-12)
    assert data["new"]["c_L"] == pytest.approx(1.01 * 2 / (E_d + 1), rel=1e-12)
    assert data["new"]["c_R"] == pytest.approx(0.98 * 2 / (1 / E_d + 1), rel=1e-12)
    E_b = 90 / (90 + 1.0254)
    assert data["new"]["wheel_separation_multiplier"] == pytest.approx(1.1 * E_b, rel=1e-9)
    assert data["wheelbase_corrected"] == pytest.approx(0.33 * E_b, rel=1e-9)


def test_active_parameters_from_a_ros2_control_file(table, tmp_path):
    params = tmp_path / "controllers.yaml"
    params.write_text(
        "controller_manager:\n  ros__parameters:\n    update_rate: 50\n"
        "diff_cont:\n  ros__parameters:\n    wheel_separation: 0.30\n    wheel_radius: 0.05\n"
        "    wheel_separation_multiplier: 1.1\n    left_wheel_radius_multiplier: 1.01\n"
        "    right_wheel_radius_multiplier: 0.98\n"
    )
    overlay = tmp_path / "overlay.yaml"
    from_file = _json(
        str(table(_rows())), "-L", "4", "--current-params", str(params), "--yaml", str(overlay)
    )
    # The overlay goes to the controller the file named.
    assert set(yaml.safe_load(overlay.read_text())) == {"diff_cont"}
    from_flags = _json(
        str(table(_rows(), name="again.csv")),
        "-L",
        "4",
        "-b",
        "0.30",
        "--wheel-diameter",
        "0.1",
        "--current-c-l",
        "1.01",
        "--current-c-r",
        "0.98",
        "--current-separation-multiplier",
        "1.1",
    )
    for key in ("E_d", "E_b", "wheelbase", "wheel_diameter_left", "wheel_diameter_right"):
        assert from_file[key] == pytest.approx(from_flags[key], rel=1e-12), key
    assert from_file["new"] == pytest.approx(from_flags["new"], rel=1e-12)
    assert from_file["wheel_diameter_left"] == pytest.approx(0.1 * from_file["new"]["c_L"])


def test_heading_method_from_degrees(table):
    # cw: eps_theta = 4 alpha + 4 beta; ccw: -4 alpha + 4 beta (four turns, four legs).
    a, b = 1.0, 0.25
    rows = [
        ("cw", 0.1, 0.1, 0, 0, -360 + 4 * a + 4 * b, -360),
        ("cw", 0.1, 0.1, 0, 0, -360 + 4 * a + 4 * b, -360),
        ("ccw", 0.1, 0.1, 0, 0, 360 - 4 * a + 4 * b, 360),
        ("ccw", 0.1, 0.1, 0, 0, 360 - 4 * a + 4 * b, 360),
    ]
    path = table(rows, header="direction,x_abs,y_abs,x_odo,y_odo,theta_abs,theta_odo")
    data = _json(str(path), "-L", "4", "-b", "0.34", "--angle-unit", "deg", "--method", "heading")
    assert data["method"] == "heading"
    assert data["alpha"] == pytest.approx(math.radians(a))
    assert data["beta"] == pytest.approx(math.radians(b))


@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_plot_on_a_machine_without_display(table, tmp_path, suffix):
    out = tmp_path / f"clusters{suffix}"
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "MPLBACKEND")}
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "umbmark",
            "calibrate",
            str(table(_rows())),
            "-L",
            "4",
            "-b",
            "0.34",
            "--plot",
            str(out),
            "--json",
        ],
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    data = out.read_bytes()
    if suffix == ".png":
        assert data.startswith(b"\x89PNG\r\n\x1a\n")
        assert len(data) > 20_000
    else:
        root = ET.fromstring(data)
        assert root.tag.endswith("svg")
        assert b"E_max,syst" in data  # the circle's legend entry
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".clusters")]


def _bad(*args: str) -> str:
    result = _calibrate(*args)
    assert result.exit_code == 2, result.output
    err = result.stderr
    assert err.startswith("umbmark: error: ")
    assert err.count("\n") == 1, err
    assert "Traceback" not in result.output
    return err


def test_bad_input_gives_one_line_and_exit_2(table, tmp_path):
    good = str(table(_rows(), name="good.csv"))
    one_direction = [r for r in _rows() if r[0] == "cw"]
    assert "good.csv" not in _bad(good, "-L", "0", "-b", "0.34")
    assert "--side-length must be > 0, got 0 m" in _bad(good, "-L", "0", "-b", "0.34")
    assert "--wheelbase must be > 0, got -0.34 m" in _bad(good, "-L", "4", "-b", "-0.34")
    assert "--wheelbase is required" in _bad(good, "-L", "4")
    assert "--side-length is required" in _bad(good, "-b", "0.34")
    assert "--side-length 4000 m is implausibly large" in _bad(good, "-L", "4000", "-b", "0.34")
    err = _bad(str(table(one_direction, name="cw_only.csv")), "-L", "4", "-b", "0.34")
    assert "cw_only.csv: 0 ccw run(s): UMBmark needs at least 2 runs in each direction" in err
    err = _bad(str(table(one_direction[:1] + _rows()[5:], name="few.csv")), "-L", "4", "-b", "1")
    assert "few.csv: 1 cw run(s)" in err
    assert "no such file" in _bad(str(tmp_path / "missing.csv"), "-L", "4", "-b", "0.34")
    err = _bad(good, "-L", "4", "-b", "0.34", "--yaml", str(tmp_path / "no" / "dir.yaml"))
    assert "dir.yaml: cannot be written (No such file or directory)" in err
    assert "should end in .png" in _bad(good, "-L", "4", "-b", "0.34", "--plot", "x.jpg")
    err = _bad(good, "-L", "4", "-b", "0.34", "--method", "heading")
    assert "good.csv: the heading method needs theta_abs and theta_odo; missing for row 2" in err


def test_bad_input_through_the_installed_command_has_no_traceback(table):
    path = table([("cw", 1, 2, 3), ("ccw", 1, 2, 3, 4)])
    proc = subprocess.run(
        ["umbmark", "calibrate", str(path), "-L", "4", "-b", "0.34"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    assert proc.stderr == f"umbmark: error: {path}, row 2: has 4 cells, the header has 5\n"
    assert proc.stdout == ""


def test_example_runs_calibrate_as_the_readme_says(tmp_path):
    path = tmp_path / "runs.csv"
    assert runner.invoke(app, ["example", str(path)]).exit_code == 0
    again = runner.invoke(app, ["example", str(path)])
    assert again.exit_code == 2
    assert "exists already" in again.stderr
    data = _json(str(path), "--side-length", "4", "--wheelbase", "0.34", "--unit", "mm")
    assert 0.2 < data["e_max_syst"] < 0.5  # the size of the paper's Fig. 11, before
    assert data["second_pass_recommended"]


def test_help_does_not_import_numpy():
    code = "import sys, umbmark.cli.main; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
