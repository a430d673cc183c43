"""The project's own fuzzing (issue 10): random and mutated runs tables, random option
values. Invariant: a report, or :class:`umbmark.InputError` with a one-line message;
never another exception, and each example quickly."""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import umbmark
from umbmark.core.errors import InputError

#: Examples per test: 40 keep the file under 15 s; set UMBMARK_FUZZ_EXAMPLES for a deep run.
FAST = settings(
    max_examples=int(os.environ.get("UMBMARK_FUZZ_EXAMPLES", "40")),
    deadline=2000,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
    database=None,
)

#: Cell values that have broken readers elsewhere.
NASTY_CELLS = [
    "",
    " ",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e999",
    "9" * 400,
    "1_000",
    "\u0661\u0662\u0663",  # Arabic-Indic 123
    "\uff11\uff12",  # full-width 12
    "\u00bd",
    "0x10",
    "1,5",
    "1.5.5",
    "--1",
    "e5",
    '"',
    "'",
    "\x00",
    "\u202e12",
    "cw",
    "ccw",
    "straight",
]

#: Option values that have broken option checks elsewhere.
NASTY_FLOATS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([math.nan, math.inf, -math.inf, 1e308, -1e308, 1e-300, -1.0, 0.0, 5e-324]),
    st.integers(min_value=-(10**400), max_value=10**400).filter(lambda n: abs(n) > 10**6),
)


@pytest.fixture(scope="module")
def example_lines(tmp_path_factory: pytest.TempPathFactory) -> list[str]:
    path = tmp_path_factory.mktemp("example") / "runs.csv"
    umbmark.example(path)
    return path.read_text(encoding="utf-8").splitlines()


def _holds(call: Callable[[], object]) -> None:
    """The invariant: a result, or an InputError of one line."""
    try:
        call()
    except InputError as exc:
        message = str(exc)
        assert message, repr(message)
        assert "\n" not in message, repr(message)


def _table_rows(lines: list[str]) -> tuple[list[str], list[list[str]]]:
    comments = [line for line in lines if line.startswith("#") or not line.strip()]
    rows = [line.split(",") for line in lines if line not in comments]
    return comments, rows


@st.composite
def mutated_tables(draw: st.DrawFn, lines: list[str]) -> str:
    comments, rows = _table_rows(lines)
    rows = [list(row) for row in rows]
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["cell", "text", "add_col", "drop_col", "drop_row", "dup_row"]))
        r = draw(st.integers(0, len(rows) - 1))
        if kind in ("cell", "text") and rows[r]:
            c = draw(st.integers(0, len(rows[r]) - 1))
            rows[r][c] = (
                draw(st.sampled_from(NASTY_CELLS))
                if kind == "cell"
                else draw(st.text(max_size=12).filter(lambda t: "\n" not in t and "\r" not in t))
            )
        elif kind == "add_col":
            for row in rows:
                row.append(draw(st.sampled_from(["1", "", "extra", "theta_abs"])))
        elif kind == "drop_col" and rows[0]:
            c = draw(st.integers(0, len(rows[0]) - 1))
            for row in rows:
                if c < len(row):
                    del row[c]
        elif kind == "drop_row" and len(rows) > 1:
            del rows[r]
        elif kind == "dup_row":
            rows.insert(r, list(rows[r]))
    delimiter = draw(st.sampled_from([",", ";", "\t", " ", "|"]))
    body = [delimiter.join(row) for row in rows]
    if delimiter == ";" and draw(st.booleans()):
        body = [line.replace(".", ",") for line in body]
    return "\n".join([*comments, *body]) + "\n"


@FAST
@given(data=st.data())
def test_mutated_runs_tables_give_a_report_or_one_line(
    example_lines: list[str], data: st.DataObject
) -> None:
    text = data.draw(mutated_tables(example_lines))
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "runs.csv"
        path.write_text(text, encoding="utf-8")
        _holds(lambda: umbmark.calibrate(path, side_length=4, wheelbase=0.34, unit="mm"))


@FAST
@given(text=st.text(max_size=300))
def test_random_text_tables_give_a_report_or_one_line(text: str) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "runs.csv"
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        _holds(lambda: umbmark.calibrate(path, side_length=4, wheelbase=0.34))


@FAST
@given(
    option=st.sampled_from(
        [
            "side_length",
            "wheelbase",
            "wheel_diameter",
            "current_c_l",
            "current_c_r",
            "current_separation_multiplier",
        ]
    ),
    value=NASTY_FLOATS,
)
def test_calibrate_options_give_a_report_or_one_line(
    example_lines: list[str], option: str, value: Any
) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "runs.csv"
        path.write_text("\n".join(example_lines) + "\n", encoding="utf-8")
        options: dict[str, Any] = {"side_length": 4.0, "wheelbase": 0.34, "unit": "mm"}
        options[option] = value
        _holds(lambda: umbmark.calibrate(path, **options))


SIMULATE_OPTIONS = [
    "E_d",
    "E_b",
    "E_s",
    "side_length",
    "wheelbase",
    "wheel_diameter",
    "encoder_resolution",
    "gear_ratio",
    "turn_angle",
    "slip",
    "bump_rate",
    "bump_size",
]


@FAST
@given(
    option=st.sampled_from(SIMULATE_OPTIONS),
    value=NASTY_FLOATS,
    runs=st.one_of(st.integers(-(10**30), 3), st.integers(1001, 10**400)),
    seed=st.one_of(st.integers(0, 10), st.integers(-(10**30), -1), st.integers(2**63, 10**40)),
)
def test_simulate_options_give_a_report_or_one_line(
    option: str, value: Any, runs: int, seed: int
) -> None:
    options: dict[str, Any] = {"side_length": 0.5, "speed": 1.0, "dt": 0.05, "runs": 2}
    options[option] = value
    _holds(lambda: umbmark.simulate(**options))
    _holds(lambda: umbmark.simulate(side_length=0.5, speed=1.0, dt=0.05, runs=runs, seed=seed))


# --- what fuzzing found, kept as plain tests ---------------------------------------------


def _write(tmp_path: Path, example_lines: list[str], cell: str, delimiter: str = ",") -> Path:
    comments, rows = _table_rows(example_lines)
    rows[1][1] = cell
    path = tmp_path / "runs.csv"
    path.write_text("\n".join([*comments, *(delimiter.join(r) for r in rows)]) + "\n")
    return path


@pytest.mark.parametrize("cell", ["1_000", "\u0661\u0662\u0663", "\uff11\uff12", "0x10", "\u00bd"])
def test_only_ascii_decimals_are_numbers(
    tmp_path: Path, example_lines: list[str], cell: str
) -> None:
    path = _write(tmp_path, example_lines, cell)
    with pytest.raises(InputError, match="is not a number"):
        umbmark.calibrate(path, side_length=4, wheelbase=0.34, unit="mm")


def test_semicolon_tables_may_use_decimal_commas(tmp_path: Path, example_lines: list[str]) -> None:
    comments, rows = _table_rows(example_lines)
    plain = tmp_path / "plain.csv"
    plain.write_text("\n".join([*comments, *(",".join(r) for r in rows)]) + "\n")
    european = tmp_path / "european.csv"
    european.write_text(
        "\n".join([*comments, *(";".join(c.replace(".", ",") for c in r) for r in rows)]) + "\n"
    )
    a = umbmark.calibrate(plain, side_length=4, wheelbase=0.34, unit="mm")
    b = umbmark.calibrate(european, side_length=4, wheelbase=0.34, unit="mm")
    assert a.estimate.E_d == pytest.approx(b.estimate.E_d, rel=1e-12)
    assert a.estimate.E_b == pytest.approx(b.estimate.E_b, rel=1e-12)


def test_decimal_comma_in_a_comma_table_is_refused(
    tmp_path: Path, example_lines: list[str]
) -> None:
    path = _write(tmp_path, example_lines, "1,5")
    with pytest.raises(InputError, match="has 6 cells, the header has 5 \\(a decimal comma"):
        umbmark.calibrate(path, side_length=4, wheelbase=0.34, unit="mm")


@FAST
@given(
    E_d=st.floats(0.51, 1.99),
    E_b=st.floats(0.51, 1.99),
    wheelbase=st.floats(0.001, 0.2),
    wheel_diameter=st.floats(0.001, 10.0),
    slip=st.floats(0.0, 0.1),
    seed=st.integers(0, 2**63 - 1),
)
def test_plausible_simulations_give_a_report_or_one_line(
    E_d: float, E_b: float, wheelbase: float, wheel_diameter: float, slip: float, seed: int
) -> None:
    _holds(
        lambda: umbmark.simulate(
            E_d=E_d,
            E_b=E_b,
            side_length=0.5,
            wheelbase=wheelbase,
            wheel_diameter=wheel_diameter,
            slip=slip,
            seed=seed,
            speed=1.0,
            dt=0.05,
            runs=2,
        )
    )
