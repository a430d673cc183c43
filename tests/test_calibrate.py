"""``umbmark.calibrate`` on runs tables: the figures, JSON, overlays, composition, bad input.

The command line's view of the same job is in ``test_cli.py``.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import yaml

import umbmark

from helpers import api_error, linear_cgs, runs_around

L, B = 4.0, 0.34
ALPHA, BETA = math.radians(-1.0254), math.radians(0.566)


def _rows(unit_scale: float = 1.0, spread: float = 0.025):
    return [
        (d, xa * unit_scale, ya * unit_scale, xo, yo)
        for d, xa, ya, xo, yo in runs_around(linear_cgs(ALPHA, BETA, L), spread)
    ]


def _json(*sources, **options) -> dict:
    """The paper's method unless told otherwise: the runs are made with its first-order
    formulas, which it inverts exactly."""
    return umbmark.calibrate(*sources, **{"method": "paper", **options}).to_dict()


def test_json_has_the_promised_keys_in_metres_and_radians(table):
    data = _json(table(_rows()), side_length=4, wheelbase=0.34)
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


def test_the_report_offers_its_figures_as_attributes(table):
    report = umbmark.calibrate(table(_rows()), side_length=4, wheelbase=0.34, method="paper")
    cg = linear_cgs(ALPHA, BETA, L)
    assert report.e_max_syst == pytest.approx(math.hypot(*cg["ccw"]))
    assert report.estimate.alpha == pytest.approx(ALPHA)
    assert report.benchmark is not None
    assert report.benchmark.second_pass_recommended
    assert report.calibration.wheelbase_corrected == pytest.approx(0.34 * 90 / (90 + 1.0254))
    assert len(report.runs) == 10
    assert report.warnings == ()


def test_lengths_in_mm_give_the_same_result(table):
    in_m = _json(table(_rows(), name="m.csv"), side_length=4, wheelbase=0.34)
    in_mm = _json(table(_rows(1000.0), name="mm.csv"), side_length=4, wheelbase=0.34, unit="mm")
    for key in ("E_d", "E_b", "alpha", "beta", "e_max_syst", "wheelbase_corrected", "sem"):
        assert in_mm[key] == pytest.approx(in_m[key], rel=1e-12), key


def test_runs_in_memory_calibrate_like_their_table(table):
    path = table(_rows())
    runs = umbmark.read_runs_table(path)
    from_memory = _json(runs, side_length=4, wheelbase=0.34)
    from_file = _json(path, side_length=4, wheelbase=0.34)
    for key in ("E_d", "E_b", "e_max_syst", "new"):
        assert from_memory[key] == from_file[key]
    assert from_memory["source"] == "runs"


def test_two_tables_are_pooled(table):
    rows = _rows()
    cw = table([r for r in rows if r[0] == "cw"], name="cw.csv")
    ccw = table([r for r in rows if r[0] == "ccw"], name="ccw.csv")
    pooled = _json(cw, ccw, side_length=4, wheelbase=0.34)
    whole = _json(table(rows, name="all.csv"), side_length=4, wheelbase=0.34)
    for key in ("E_d", "E_b", "e_max_syst", "cg_cw", "cg_ccw"):
        assert pooled[key] == pytest.approx(whole[key], rel=1e-12), key
    assert pooled["sources"] == [str(cw), str(ccw)]
    assert pooled["runs"][0]["label"] == "cw.csv row 2"


def test_output_file_holds_the_same_object(table, tmp_path):
    out = tmp_path / "result.json"
    data = _json(table(_rows()), side_length=4, wheelbase=0.34, output=out)
    import json

    assert json.loads(out.read_text()) == data


def test_yaml_overlay_is_valid_with_floats_and_provenance(table, tmp_path):
    out = tmp_path / "overlay.yaml"
    report = umbmark.calibrate(
        table(_rows(spread=0.0)),
        side_length=4,
        wheelbase=0.34,
        yaml=out,
        controller="base_controller",
    )
    text = out.read_text()
    assert text == report.overlay_yaml()
    assert text.startswith("# Written by umbmark")
    params = yaml.safe_load(text)["base_controller"]["ros__parameters"]
    data = report.to_dict()
    assert params["wheel_separation_multiplier"] == pytest.approx(data["E_b"], rel=1e-9)
    assert params["left_wheel_radius_multiplier"] == pytest.approx(data["c_L"], rel=1e-9)
    assert params["right_wheel_radius_multiplier"] == pytest.approx(data["c_R"], rel=1e-9)
    for value in re.findall(r"multiplier: (\S+)", text):
        assert "." in value  # ros2 parameters are doubles: 1.0, never 1
    ros1 = yaml.safe_load(report.ros1_yaml())["base_controller"]
    assert ros1 == params


def test_yaml_of_a_perfect_robot_still_writes_doubles(table, tmp_path):
    out = tmp_path / "overlay.yaml"
    rows = runs_around({"cw": (0.0, 0.0), "ccw": (0.0, 0.0)}, 0.01)
    umbmark.calibrate(table(rows), side_length=4, wheelbase=0.34, yaml=out)
    assert re.findall(r"multiplier: (\S+)", out.read_text()) == ["1.0", "1.0", "1.0"]


def test_correction_multiplies_into_the_active_parameters(table):
    data = _json(
        table(_rows()),
        side_length=4,
        wheelbase=0.30,
        current_c_l=1.01,
        current_c_r=0.98,
        current_separation_multiplier=1.1,
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
    from_file = _json(table(_rows()), side_length=4, current_params=params, yaml=overlay)
    # The overlay goes to the controller the file named.
    assert set(yaml.safe_load(overlay.read_text())) == {"diff_cont"}
    from_flags = _json(
        table(_rows(), name="again.csv"),
        side_length=4,
        wheelbase=0.30,
        wheel_diameter=0.1,
        current_c_l=1.01,
        current_c_r=0.98,
        current_separation_multiplier=1.1,
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
    data = _json(path, side_length=4, wheelbase=0.34, angle_unit="deg", method="heading")
    assert data["method"] == "heading"
    assert data["alpha"] == pytest.approx(math.radians(a))
    assert data["beta"] == pytest.approx(math.radians(b))


def test_figure_is_the_clusters_view(table):
    fig = umbmark.calibrate(table(_rows()), side_length=4, wheelbase=0.34).figure()
    (ax,) = fig.axes
    assert ax.get_xlabel() == "return error x [mm]"
    labels = ax.get_legend_handles_labels()[1]
    e_max = math.hypot(*linear_cgs(ALPHA, BETA, L)["ccw"]) * 1000
    assert f"E_max,syst = {e_max:.1f} mm" in labels


def test_bad_input_raises_one_input_error_naming_the_keywords(table, tmp_path):
    good = table(_rows(), name="good.csv")
    one_direction = [r for r in _rows() if r[0] == "cw"]

    def bad(*sources, **options) -> str:
        return api_error(umbmark.calibrate, *sources, **options)

    assert issubclass(umbmark.InputError, ValueError)
    assert bad(good, side_length=0, wheelbase=0.34) == "side_length must be > 0, got 0 m"
    assert "wheelbase must be > 0, got -0.34 m" in bad(good, side_length=4, wheelbase=-0.34)
    assert "wheelbase is required" in bad(good, side_length=4)
    assert "side_length is required" in bad(good, wheelbase=0.34)
    assert "side_length=4000 m is implausibly large" in bad(good, side_length=4000, wheelbase=1)
    err = bad(table(one_direction, name="cw_only.csv"), side_length=4, wheelbase=0.34)
    assert "cw_only.csv: 0 ccw run(s): UMBmark needs at least 2 runs in each direction" in err
    few = table(one_direction[:1] + _rows()[5:], name="few.csv")
    assert "few.csv: 1 cw run(s)" in bad(few, side_length=4, wheelbase=1)
    assert "no such file" in bad(tmp_path / "missing.csv", side_length=4, wheelbase=0.34)
    err = bad(good, side_length=4, wheelbase=0.34, yaml=tmp_path / "no" / "dir.yaml")
    assert "dir.yaml: cannot be written (No such file or directory)" in err
    assert "should end in .png" in bad(good, side_length=4, wheelbase=0.34, plot="x.jpg")
    err = bad(good, side_length=4, wheelbase=0.34, method="heading")
    assert "good.csv: the heading method needs theta_abs and theta_odo; missing for row 2" in err
    assert "method='median': use one of paper" in bad(good, side_length=4, method="median")
    assert "unit='km'" in bad(good, side_length=4, wheelbase=0.34, unit="km")
    err = bad(good, side_length=4, wheelbase=0.34, output=good)
    assert "would overwrite an input" in err
    assert good.read_text().startswith("direction")  # untouched
    same = tmp_path / "r.yaml"
    assert "both name" in bad(good, side_length=4, wheelbase=0.34, output=same, yaml=same)


def test_an_unknown_keyword_is_a_type_error(table):
    with pytest.raises(TypeError, match="side_lenght"):
        umbmark.calibrate(table(_rows()), side_lenght=4, wheelbase=0.34)


def test_example_runs_calibrate_as_the_readme_says(tmp_path):
    path = tmp_path / "runs.csv"
    text = umbmark.example(path)
    assert path.read_text() == text
    assert "exists already" in api_error(umbmark.example, path)
    data = _json(path, side_length=4, wheelbase=0.34, unit="mm")
    assert 0.2 < data["e_max_syst"] < 0.5  # the size of the paper's Fig. 11, before
    assert data["second_pass_recommended"]


def test_straight_runs_measure_the_scale_and_compose_into_the_diameters(table):
    # Three straight runs: the odometry counted 2 m each time, the tape says 2.04 m.
    straights = [("straight", 2.04, 0.01, 2.0, 0.0), ("straight", 2.038, -0.01, 2.0, 0.0)]
    straights.append(("straight", 2.042, 0.0, 2.0, 0.0))
    squares = _rows()
    both = _json(table(squares + straights), side_length=4, wheelbase=0.34, method="paper")
    alone = _json(table(squares, name="squares.csv"), side_length=4, wheelbase=0.34)
    driven = [math.hypot(2.04, 0.01), math.hypot(2.038, 0.01), 2.042]
    E_s = sum(driven) / 3 / 2.0
    assert both["E_s"] == pytest.approx(E_s, rel=1e-12)
    # The turns saw E_b / E_s: the wheelbase is E_b itself, the diameters carry E_s.
    assert both["E_b"] == pytest.approx(alone["E_b"] * E_s, rel=1e-12)
    assert both["E_d"] == pytest.approx(alone["E_d"], rel=1e-12)
    assert both["new"]["c_L"] == pytest.approx(alone["new"]["c_L"] * E_s, rel=1e-12)
    assert both["wheelbase_corrected"] == pytest.approx(alone["wheelbase_corrected"] * E_s)
    se_ratio = np.std(driven, ddof=1) / math.sqrt(3) / 2.0
    assert both["standard_errors"]["E_s"] == pytest.approx(se_ratio, rel=1e-9)
    assert both["n_runs"] == 13
    assert both["n_cw"] == both["n_ccw"] == 5
    assert [r["kind"] for r in both["runs"]][-3:] == ["straight"] * 3


def test_straight_runs_alone_correct_the_diameters_only(table):
    rows = [("straight", 4.02, 0.0, 4.0, 0.0), ("straight", 4.03, 0.0, 4.0, 0.0)]
    report = umbmark.calibrate(table(rows), side_length=4, wheelbase=0.34)
    assert report.estimate.E_s == pytest.approx(1.00625)
    assert report.calibration.new_c_left == pytest.approx(1.00625)
    assert report.calibration.new_separation_multiplier == 1.0
    assert report.benchmark is None
    assert "Drive UMBmark next" in report.warnings[0]
    err = api_error(
        umbmark.calibrate,
        table([("straight", 4.0, 0.0, 0.001, 0.0)] * 2),
        side_length=4,
        wheelbase=1,
    )
    assert "row 2: its odometry distance 0.001 m is too short" in err
