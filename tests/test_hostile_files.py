"""Hostile parameter, metadata and result files: one clean error line each, quickly.

Each file is written by hand to break a naive reader: YAML nested thousands deep, an
alias bomb (billions of nodes once expanded), recursive aliases, numbers beyond a float,
JSON nested 100,000 deep or with a 5000-digit number, and an endless file (/dev/zero).
"""

from __future__ import annotations

import os
import time

import pytest

import umbmark

from helpers import api_error, cli_error, linear_cgs, runs_around

ALIAS_BOMB = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + k)}: &{chr(98 + k)} [{', '.join([f'*{chr(97 + k)}'] * 9)}]\n" for k in range(8)
)


@pytest.fixture
def runs(tmp_path):
    table = tmp_path / "runs.csv"
    rows = runs_around(linear_cgs(-0.01, 0.005, 4.0), 0.02)
    lines = ["direction,x_abs,y_abs,x_calc,y_calc"]
    lines += [",".join(str(v) for v in row) for row in rows]
    table.write_text("\n".join(lines) + "\n")
    return table


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("a: " + "[" * 5000 + "]" * 5000 + "\n", "deep"),
        (ALIAS_BOMB, "aliases"),
        ("dd: &a\n  ros__parameters:\n    inner: *a\n    wheel_separation: 0.3\n", None),
        ("dd:\n  ros__parameters:\n    wheel_separation: .nan\n", "wheel_separation"),
        ("dd:\n  ros__parameters:\n    wheel_separation: 1.0e+400\n", "wheel_separation"),
        ("dd:\n  ros__parameters:\n    wheel_separation: " + "9" * 401 + "\n", "wheel_separation"),
        ("dd:\n  ros__parameters:\n    wheel_separation: 340.0\n", "metres"),
    ],
    ids=["deep", "alias-bomb", "recursive", "nan", "overflow", "401-digits", "millimetres"],
)
def test_hostile_parameter_yaml_is_one_line(tmp_path, runs, text, fragment):
    params = tmp_path / "controllers.yaml"
    params.write_text(text)
    started = time.perf_counter()
    if fragment is None:  # a mapping that holds itself: read, its parameters found
        report = umbmark.calibrate(runs, side_length=4, current_params=params)
        assert report.calibration.active.wheelbase == 0.3
        return
    message = api_error(umbmark.calibrate, runs, side_length=4, current_params=params)
    assert time.perf_counter() - started < 5
    assert fragment in message
    assert str(params) in message


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("[" * 100_000 + "]" * 100_000, "deep"),
        ('{"new": {"c_L": ' + "1" * 5000 + "}}", "digits"),
        ('{"new": {"wheelbase": 0.34, "c_L": 1e300, "c_R": 1.0}}', None),
        ('{"new": {"wheelbase": NaN, "c_L": 1.0, "c_R": 1.0}}', "wheelbase"),
    ],
    ids=["deep", "5000-digits", "huge-factor", "nan"],
)
def test_hostile_result_json_is_one_line(tmp_path, runs, text, fragment):
    result = tmp_path / "result.json"
    result.write_text(text)
    message = api_error(
        umbmark.calibrate, runs, side_length=4, wheelbase=0.34, current_params=result
    )
    if fragment is not None:
        assert fragment in message
    line = cli_error(
        "calibrate", str(runs), "-L", "4", "-b", "0.34", "--current-params", str(result)
    )
    assert str(result) in line


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="no /dev/zero")
def test_an_endless_file_is_refused_with_bounded_memory():
    from umbmark.core.errors import InputError
    from umbmark.sources.text import MAX_DOCUMENT_BYTES, read_text

    # Whole documents (YAML, JSON) are parsed into objects tens of times their size.
    assert MAX_DOCUMENT_BYTES <= 16 * 1024**2
    with pytest.raises(InputError, match="larger than 16 MB"):
        read_text("/dev/zero")
