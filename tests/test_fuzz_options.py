"""Fuzzing every command's options through the real command line (issue 10, item 6).

Each example runs ``umbmark CMD ... OPTION VALUE`` in this process, through
:func:`umbmark.cli.main.main` (click's parsing, the library's checks and the boundary
that turns failures into lines), with one option given a value drawn from: huge, tiny,
negative, zero, NaN and infinite numbers, integers of hundreds of digits, words, empty
and very long strings, odd digits, and plausible values. The invariant:

* exit status 0 (a result; 4 for a calibration's valid result not to apply), or 2 with
  exactly one line on stderr that starts ``umbmark: error: `` and, for a value that is no
  usable number at all, names the flag;
* never a traceback, never another status (70 is a bug of ours), never a Python warning
  (warnings are errors in this test suite, so a numpy RuntimeWarning fails it);
* within a time bound (a timer interrupts an example that runs longer) and a memory
  bound (the process's peak resident size).

Plausible values are drawn only where the work they ask for is small (``--runs 2`` to 3,
not 1000); values beyond the documented bounds are drawn everywhere. Examples per
command: 10 by default (the file takes about 10 s); UMBMARK_FUZZ_EXAMPLES raises it.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import resource
import shutil
import signal
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import umbmark
from umbmark.cli.common import EXIT_DO_NOT_APPLY
from umbmark.cli.main import main

#: Examples per command; UMBMARK_FUZZ_EXAMPLES (also read by test_fuzz.py) raises it.
EXAMPLES = max(10, int(os.environ.get("UMBMARK_FUZZ_EXAMPLES", "10")))
#: Longest an example may run [s]: the cheap values here take well under a second.
TIME_LIMIT = 30.0
#: Largest peak resident size of this process [bytes] after an example.
MEMORY_LIMIT = 2 * 1024**3

FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,  # the explicit timer below bounds the time, robust to a loaded machine
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
    database=None,
)

#: Values that are no usable number: the error line must name the flag.
NOT_NUMBERS = [
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e400",
    "-1e400",
    "9" * 400,
    "-" + "9" * 400,
    "abc",
    "",
    " ",
    "1,5",
    "0x10",
    "1_000",
    "\u0661\u0662",  # Arabic-Indic 12
    "\uff11\uff12",  # full-width 12
    "x" * 20_000,
    "--json",
]
#: Numbers that are numbers, but out of every option's range or at its edges.
ODD_NUMBERS = [
    "1e308",
    "-1e308",
    "1e-300",
    "-1e-300",
    "5e-324",
    "0",
    "-0",
    "-1",
    "9223372036854775808",
    "-9223372036854775809",
    "1000000",
]


@dataclass(frozen=True)
class Opt:
    """An option to fuzz: its flag, how its plausible values are drawn, and the long flag
    its error lines name."""

    flag: str
    cheap: st.SearchStrategy[str]
    names: tuple[str, ...] = ()
    numeric: bool = True
    nargs: int = 1

    @property
    def named(self) -> tuple[str, ...]:
        return self.names or (self.flag,)


def real(low: float, high: float) -> st.SearchStrategy[str]:
    """Plausible floats, as the user would type them."""
    return st.floats(low, high, allow_nan=False, allow_infinity=False).map(repr)


def whole(low: int, high: int) -> st.SearchStrategy[str]:
    return st.integers(low, high).map(str)


def choice(*values: str) -> st.SearchStrategy[str]:
    return st.sampled_from(values)


def number_opt(flag: str, cheap: st.SearchStrategy[str], *names: str) -> Opt:
    return Opt(flag, cheap, names)


def choice_opt(flag: str, *values: str, names: tuple[str, ...] = ()) -> Opt:
    return Opt(flag, choice(*values), names, numeric=False)


def text_opt(flag: str, cheap: st.SearchStrategy[str], *names: str) -> Opt:
    return Opt(flag, cheap, names, numeric=False)


def values_for(option: Opt) -> st.SearchStrategy[str]:
    """A value for ``option``: plausible, odd, no number, or random text."""
    return st.one_of(
        option.cheap,
        st.sampled_from(ODD_NUMBERS),
        st.sampled_from(NOT_NUMBERS),
        st.floats().map(repr),
        st.integers(-(10**30), 10**30).filter(lambda n: abs(n) > 10**7).map(str),
        st.text(max_size=20),
    )


@dataclass
class Command:
    """A command line to fuzz: what comes before the fuzzed option, and its options."""

    base: list[str]
    options: list[Opt] = field(default_factory=list)

    @property
    def path(self) -> str:
        """The command as ``--help`` names it: ``calibrate``, ``reproduce table1``."""
        return " ".join(self.base[:2]) if self.base[0] == "reproduce" else self.base[0]


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A runs table (mm), run logs of a virtual robot, its result file and a history."""
    folder = tmp_path_factory.mktemp("fuzz-options")
    umbmark.example(folder / "runs.csv")
    umbmark.simulate(runs=2, dt=0.05, speed=1.0, logs=folder / "logs")
    umbmark.calibrate(folder / "logs", output=folder / "result.json")
    umbmark.calibrate(
        folder / "runs.csv",
        side_length=4,
        wheelbase=0.34,
        unit="mm",
        robot="labmate",
        history=folder / "history.db",
    )
    return folder


def commands(folder: Path) -> dict[str, Command]:
    """Every command, from a cheap base, with its numeric, choice and parsed options."""
    runs, logs, result = str(folder / "runs.csv"), str(folder / "logs"), str(folder / "result.json")
    out = str(folder / "out")
    factors = [
        number_opt("--current-c-l", real(0.9, 1.1)),
        number_opt("--current-c-r", real(0.9, 1.1)),
        number_opt("--current-separation-multiplier", real(0.9, 1.1)),
    ]
    reading = [
        choice_opt("--unit", "m", "cm", "mm", "in"),
        choice_opt("--angle-unit", "rad", "deg", "grad"),
        choice_opt("--format", "auto", "table", "log", "optiodom", "bag", "csv"),
        number_opt("--wheel-diameter", real(0.01, 1.0)),
        number_opt("--ticks-per-rev", real(100.0, 1e5)),
        number_opt("--gyro-scale-tolerance", real(0.0, 0.2)),
    ]
    logged = [
        number_opt("--max-gap", real(0.01, 60.0)),
        number_opt("--min-rest", real(0.1, 600.0)),
        choice_opt("--split", "rests", "none", "windows", "sideways"),
        text_opt("--windows", choice("0:10,10:20", "5:1", "a:b", "0:1e400", ":", "0:nan")),
        Opt("--truth-offset", real(-0.2, 0.2), numeric=True, nargs=2),
        choice_opt("--time-source", "header", "bag", "clock"),
    ]
    return {
        "demo": Command(
            ["demo", "--out", out],
            [
                number_opt("--seed", whole(0, 2**63 - 1)),
                number_opt("--runs", whole(2, 3)),
                choice_opt("--method", "paper", "exact", "heading", "endpose", "trajectory"),
            ],
        ),
        "calibrate": Command(
            ["calibrate", runs, "-L", "4", "-b", "0.34", "--unit", "mm"],
            [
                number_opt("-L", real(0.5, 100.0), "--side-length"),
                number_opt("-b", real(0.01, 1.9), "--wheelbase"),
                number_opt("--wheel-diameter", real(0.01, 1.0)),
                *factors,
                choice_opt("--unit", "m", "cm", "mm", "in"),
                choice_opt("--angle-unit", "rad", "deg", "grad"),
                choice_opt("--method", "paper", "exact", "heading", "endpose", "auto", "best"),
                choice_opt("--format", "auto", "table", "log", "csv"),
                number_opt("--gyro-scale-tolerance", real(0.0, 0.2)),
            ],
        ),
        "calibrate-logs": Command(
            ["calibrate", logs],
            [
                *logged,
                number_opt("--ticks-per-rev", real(100.0, 1e5)),
                choice_opt("--method", "exact", "trajectory", "trajectory-scrub", "auto", "x"),
                choice_opt("--tum-time", "recording", "run", "wall"),
            ],
        ),
        "replay": Command(
            ["replay", logs, "--params", result],
            [
                *reading,
                *logged,
                *factors,
                number_opt("-b", real(0.3, 0.4), "--wheelbase"),
                choice_opt("--tum-time", "recording", "run", "wall"),
            ],
        ),
        "validate": Command(
            ["validate", logs, "--methods", "exact"],
            [
                number_opt("-L", real(3.9, 4.1), "--side-length"),
                number_opt("-b", real(0.3, 0.4), "--wheelbase"),
                text_opt("--methods", choice("paper,exact", "exact,,", "nope", ",", "truth")),
                *reading,
                *logged,
                *factors,
            ],
        ),
        "info": Command(
            ["info", logs],
            [
                number_opt("--max-messages", whole(1, 10**6)),
                choice_opt("--format", "auto", "bag", "log", "optiodom", "table"),
            ],
        ),
        "plan": Command(
            ["plan", "--scatter", "0.02"],
            [
                number_opt("--scatter", real(1e-5, 1.0)),
                choice_opt("--noise", "slip", "tape", "both"),
                number_opt("--scatter-side", real(0.5, 100.0)),
                number_opt("--reading-error", real(0.0, 0.05)),
                number_opt("-b", real(0.01, 1.0), "--wheelbase"),
                number_opt("-L", real(1.0, 100.0), "--side-length"),
                number_opt("--runs", whole(2, 100)),
                number_opt("--floor", real(1.0, 100.0)),
                number_opt("--margin", real(0.0, 5.0)),
                number_opt("--target-E-d", real(1e-6, 0.1)),
                number_opt("--target-E-b", real(1e-6, 0.1)),
                number_opt("--target-e-max", real(0.001, 1.0)),
            ],
        ),
        "simulate": Command(
            ["simulate", "-L", "0.5", "--speed", "1", "--dt", "0.05", "--runs", "2"],
            [
                number_opt("--E-d", real(0.5, 2.0)),
                number_opt("--E-b", real(0.5, 2.0)),
                number_opt("--E-s", real(0.5, 2.0)),
                number_opt("-b", real(0.01, 0.2), "--wheelbase"),
                number_opt("--wheel-diameter", real(0.01, 1.0)),
                number_opt("--encoder-resolution", real(1.0, 1e7)),
                number_opt("--gear-ratio", real(1e-3, 1e4)),
                number_opt("-L", real(0.5, 20.0), "--side-length"),
                number_opt("--runs", whole(1, 3)),
                number_opt("--dt", real(0.005, 0.1)),
                number_opt("--speed", real(0.1, 5.0)),
                number_opt("--slip", real(0.0, 0.1)),
                number_opt("--bump-rate", real(0.0, 100.0)),
                number_opt("--bump-size", real(0.0, 0.05)),
                number_opt("--seed", whole(0, 2**63 - 1)),
                choice_opt("--path", "square", "straight", "turn", "circle"),
                choice_opt("--direction", "both", "cw", "ccw", "up"),
                choice_opt("--bag-storage", "sqlite3", "mcap", "zip"),
            ],
        ),
        "simulate-turn": Command(
            ["simulate", "--path", "turn", "--speed", "1", "--dt", "0.05", "--runs", "1"],
            [number_opt("--turn-angle", real(-3600.0, 3600.0))],
        ),
        "study": Command(
            ["study", "--trials", "1", "--methods", "exact", "--workers", "1", "-n", "2"],
            [
                number_opt("--trials", whole(1, 2)),
                number_opt("--E-d-spread", real(0.0, 0.2)),
                number_opt("--E-b-spread", real(0.0, 0.2)),
                text_opt("--slip", real(0.0, 0.01), "--slip"),
                text_opt("--side-length", real(0.5, 10.0), "--side-length"),
                text_opt("-n", whole(2, 3), "--runs"),
                text_opt("-b", real(0.01, 0.2), "--wheelbase"),
                text_opt("--slip", choice(",".join(["0"] * 30), "0,,0", "0;0"), "--slip"),
                number_opt("--seed", whole(0, 2**63 - 1)),
                number_opt("--workers", whole(1, 64)),
                text_opt("--methods", choice("exact,paper", "truth", "", "nope,exact")),
            ],
        ),
        "table1": Command(
            ["reproduce", "table1", "--seeds", "1"],
            [
                number_opt("--seeds", whole(1, 1)),
                number_opt("--seed", whole(0, 2**63 - 1)),
                number_opt("--tape-thickness", real(0.01, 0.3)),
            ],
        ),
        "report": Command(
            ["report", logs, "-o", str(folder / "page.html"), "--force"],
            [
                number_opt("-L", real(3.9, 4.1), "--side-length"),
                number_opt("-b", real(0.3, 0.4), "--wheelbase"),
                choice_opt("--method", "paper", "exact", "heading", "endpose", "nope"),
                *reading,
                *logged,
                *factors,
            ],
        ),
        "selfcal": Command(
            # The virtual robot on small squares, one pass: a second or two per example.
            [
                "selfcal",
                "--sim",
                "-n",
                "2",
                "-L",
                "1",
                "--max-passes",
                "1",
                "--no-verify",
                "--no-coarse",
                "--out",
                str(folder / "selfcal"),
            ],
            [
                number_opt("--sim-E-d", real(0.99, 1.01)),
                number_opt("--sim-E-b", real(0.97, 1.03)),
                number_opt("--sim-E-s", real(0.99, 1.01)),
                number_opt("--sim-slip", real(0.0, 0.001)),
                number_opt("--seed", whole(0, 2**63 - 1)),
                number_opt("-L", real(0.8, 1.2), "--side-length"),
                number_opt("-n", whole(2, 3), "--runs"),
                choice_opt("--measure", "lidar", "ranges", "truth", "sonar"),
                choice_opt("--routine", "umbmark", "anywhere", "corner"),
                choice_opt("--apply", "reconfigure", "yaml", "none", "always"),
                number_opt("--max-passes", whole(1, 2)),
                number_opt("--speed", real(0.15, 0.5)),
                number_opt("--acceleration", real(0.1, 1.0)),
                number_opt("--turn-rate", real(0.5, 1.5)),
                number_opt("--obstacle-margin", real(0.05, 0.5)),
                choice_opt("--corner-side", "auto", "right", "left", "behind"),
                number_opt("--robot-width", real(0.2, 0.5)),
                number_opt("--sim-imu-rate", real(20.0, 400.0)),
                number_opt("--sim-gyro-scale", real(0.97, 1.03)),
                number_opt("--sim-gyro-bias", real(-0.5, 0.5)),
                number_opt("--sim-gyro-bias-walk", real(0.0, 0.01)),
                number_opt("--sim-gyro-noise", real(0.0, 0.05)),
                number_opt("--sim-gyro-range", real(250.0, 2000.0)),
                number_opt("--sim-imu-roll", real(-2.0, 2.0)),
                number_opt("--sim-imu-pitch", real(-2.0, 2.0)),
                number_opt("--sim-imu-yaw", real(-2.0, 2.0)),
                number_opt("--gyro-scale-tolerance", real(0.0, 0.05)),
            ],
        ),
        "monitor": Command(
            # the monitor's core on the simulated warehouse robot, a minute of driving
            ["monitor", "--sim", "--minutes", "1", "--speedup", "0"],
            [
                number_opt("--timeout", real(0.5, 30.0)),
                number_opt("--window-metres", real(10.0, 100.0)),
                number_opt("--window-radians", real(2.0, 20.0)),
                number_opt("--stretch-metres", real(5.0, 40.0)),
                number_opt("--scan-period", real(0.2, 2.0)),
                number_opt("--stale-after", real(0.5, 10.0)),
                number_opt("--tolerance", real(0.001, 0.1)),
                choice_opt("--apply", "never", "at-rest"),
                number_opt("--rest-time", real(1.0, 30.0)),
                number_opt("--minutes", real(1.0, 1.5)),
                number_opt("--change-after", real(0.0, 1.0)),
                number_opt("--wheel-change", real(-0.01, 0.01)),
                number_opt("--speedup", real(0.0, 0.0)),
                number_opt("--seed", whole(0, 2**31 - 1)),
            ],
        ),
        # The IMU of a small bag (its options do nothing without --imu and --bag).
        "simulate-imu": Command(
            [
                "simulate",
                "-L",
                "0.5",
                "--speed",
                "1",
                "--dt",
                "0.05",
                "--runs",
                "2",
                "--bag",
                str(folder / "imu"),
                "--bag-storage",
                "mcap",
                "--imu",
                "--force",
            ],
            [
                number_opt("--imu-rate", real(10.0, 1000.0)),
                number_opt("--gyro-scale", real(0.8, 1.25)),
                number_opt("--gyro-bias", real(-10.0, 10.0)),
                number_opt("--gyro-bias-walk", real(0.0, 0.05)),
                number_opt("--gyro-noise", real(0.0, 0.5)),
                number_opt("--gyro-range", real(30.0, 4000.0)),
                number_opt("--imu-roll", real(-180.0, 180.0)),
                number_opt("--imu-pitch", real(-90.0, 90.0)),
                number_opt("--imu-yaw", real(-180.0, 180.0)),
            ],
        ),
        "simulate-fleet": Command(
            [
                "simulate",
                "--fleet",
                "1",
                "--days",
                "1",
                "--minutes",
                "0.2",
                "--force",
                "--out",
                str(folder / "fleet"),
            ],
            [
                number_opt("--fleet", whole(1, 2)),
                number_opt("--days", whole(1, 2)),
                number_opt("--minutes", real(0.2, 0.3)),
            ],
        ),
        # The run logs: a valid value starts the engine (a local cluster, seconds each). On
        # an empty folder the reading options are not checked before "no recording found".
        "fleet": Command(
            ["fleet", str(folder), "--history", str(folder / "fleet.sqlite3")],
            [
                number_opt("--workers", whole(1, 64)),
                number_opt("-b", real(0.01, 1.9), "--wheelbase"),
                *reading,
                *logged,
                *factors,
            ],
        ),
        "fig4": Command(["reproduce", "fig4"], [number_opt("--leg-bend", real(-10.0, 10.0))]),
        "history": Command(
            ["history", "labmate", "--history", str(folder / "history.db")],
            [number_opt("--applied", whole(1, 3))],
        ),
    }


class TookTooLong(BaseException):
    """Raised by the timer: a BaseException, so that no ``except Exception`` hides it."""


@contextlib.contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """Interrupt the block after ``seconds`` (SIGALRM; the main thread only)."""

    def expire(signum: int, frame: object) -> None:
        raise TookTooLong(f"over {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def run(argv: list[str]) -> tuple[int, str, str]:
    """``umbmark ARGV`` in this process: exit status, stdout, stderr."""
    out, err = io.StringIO(), io.StringIO()
    code: int = 0
    with (
        contextlib.redirect_stdout(out),
        contextlib.redirect_stderr(err),
        time_limit(TIME_LIMIT),
    ):
        try:
            main(argv)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    return code, out.getvalue(), err.getvalue()


def peak_memory() -> int:
    """The process's peak resident set size [bytes] (Linux reports KiB)."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak if sys.platform == "darwin" else peak * 1024


def is_no_number(value: str) -> bool:
    """Whether ``value`` is no finite number at all (as Python reads numbers)."""
    try:
        number = float(value)
    except ValueError:
        return True
    return not math.isfinite(number) or value.strip() != value or "_" in value


def check(argv: list[str], option: Opt, value: str) -> None:
    """The invariant of the module's docstring."""
    code, out, err = run(argv)
    shown = " ".join(a if len(a) < 60 else a[:60] + "..." for a in argv)
    assert "Traceback" not in out + err, shown
    # selfcal stops the virtual robot for safety (exit 3) when a fuzzed error drives it
    # into a wall: one line as well. A valid result not to apply (a calibration's "do not
    # apply", exit 4: docs/commands.md) is a result: --method auto on two short runs is one.
    assert code in (0, 2) or (code == 3 and argv[0] == "selfcal") or code == EXIT_DO_NOT_APPLY, (
        f"{shown}: exit {code}: {err}"
    )
    lines = err.splitlines()
    if code in (2, 3) and argv[0] == "selfcal":
        # selfcal says its checks and runs as they happen: the error is its last line
        assert all(line.startswith("umbmark: ") for line in lines), f"{shown}: {err[:500]}"
        assert sum(line.startswith("umbmark: error: ") for line in lines) == 1, shown
        lines = lines[-1:]
    if code in (2, 3):
        assert len(lines) == 1, f"{shown}: {err[:2000]}"
        assert lines[0].startswith("umbmark: error: "), f"{shown}: {err[:500]}"
        assert len(lines[0]) < 1200, shown  # a long value is not echoed whole
        if option.numeric and is_no_number(value):
            assert any(name in lines[0] for name in option.named), f"{shown}: {lines[0]}"
    else:
        assert all(line.startswith("umbmark: ") for line in lines), f"{shown}: {err[:500]}"
        assert "umbmark: error" not in err, shown
        assert "NaN" not in out, shown  # JSON stays JSON
        assert "Infinity" not in out, shown
    assert peak_memory() < MEMORY_LIMIT, shown


@st.composite
def fuzzed(draw: st.DrawFn, command: Command) -> tuple[list[str], Opt, str]:
    option = draw(st.sampled_from(command.options))
    values = [draw(values_for(option)) for _ in range(option.nargs)]
    json = draw(st.booleans())
    argv = [*command.base, option.flag, *values, *(["--json"] if json else [])]
    return argv, option, values[0]


NAMES = [
    "demo",
    "calibrate",
    "calibrate-logs",
    "replay",
    "validate",
    "info",
    "plan",
    "simulate",
    "simulate-turn",
    "study",
    "table1",
    "fig4",
    "history",
    "report",
    "selfcal",
    "simulate-fleet",
    "simulate-imu",
    "fleet",
    "monitor",
]


#: The commands whose examples take seconds each (a demo, a self-calibration, a study, the
#: reproductions, a report page, a fleet on its local cluster): fuzzed in the full run only.
SLOW_COMMANDS = {"demo", "fig4", "selfcal", "study", "table1", "report", "simulate-fleet",
                 "simulate-imu", "fleet", "monitor"}  # fmt: skip


@pytest.mark.parametrize(
    "name", [pytest.param(n, marks=[pytest.mark.slow] if n in SLOW_COMMANDS else []) for n in NAMES]
)
def test_every_command_option_gives_a_result_or_one_line(data: Path, name: str) -> None:
    command = commands(data)[name]

    @FUZZ
    @given(case=fuzzed(command))
    def fuzz(case: tuple[list[str], Opt, str]) -> None:
        argv, option, value = case
        if "--out" in argv:  # selfcal writes into a new or empty folder
            shutil.rmtree(argv[argv.index("--out") + 1], ignore_errors=True)
        check(argv, option, value)

    fuzz()


def test_every_command_is_fuzzed(tmp_path: Path) -> None:
    """Each command of ``umbmark --help`` is in the table above, with each of its options
    that takes a number or a choice."""
    import click

    from umbmark.cli.main import cli

    table = commands(tmp_path)
    fuzzed_flags: dict[str, set[str]] = {}
    for command in table.values():
        flags = fuzzed_flags.setdefault(command.path, set())
        flags.update(o.flag for o in command.options)
        flags.update(n for o in command.options for n in o.names)
    leaves: dict[str, click.Command] = {}
    for name, sub in cli.commands.items():
        if isinstance(sub, click.Group):
            leaves.update({f"{name} {n}": c for n, c in sub.commands.items()})
        else:
            leaves[name] = sub
    missing = []
    for path, sub in leaves.items():
        if path == "example":  # no option that takes a number or a choice
            continue
        for param in sub.params:
            if not isinstance(param, click.Option) or param.is_flag:
                continue
            if not isinstance(
                param.type, (click.types.FloatParamType, click.types.IntParamType, click.Choice)
            ):
                continue
            if not set(param.opts) & fuzzed_flags.get(path, set()):
                missing.append(f"{path} {param.opts[0]}")
    assert not missing, ", ".join(missing)
