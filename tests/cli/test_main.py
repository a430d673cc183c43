"""The user's view: the installed ``umbmark`` command, run as a user runs it.

The maths are tested through the library (``test_calibrate.py`` and the others); here the
command must print what the library found, with units, write what it is asked to, and
fail with one line.
"""

from __future__ import annotations

import dataclasses
import importlib
import json
import math
import os
import re
import subprocess
import sys
import typing
import xml.etree.ElementTree as ET

import click
import pytest

import umbmark
from umbmark.cli.main import cli

from helpers import OPTIODOM, cli_error, cli_json, linear_cgs, run_cli, runs_around

L = 4.0
ALPHA, BETA = math.radians(-1.0254), math.radians(0.566)
SQUARE = OPTIODOM / "square" / "230620202042"


def _rows():
    return runs_around(linear_cgs(ALPHA, BETA, L), 0.025)


@pytest.mark.slow
def test_summary_states_every_figure_with_its_unit(table):
    args = ["calibrate", str(table(_rows())), "--side-length", "4", "--wheelbase", "0.34"]
    proc = run_cli(*args, "--method", "paper")
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    e_max = math.hypot(*linear_cgs(ALPHA, BETA, L)["ccw"]) * 1000
    assert f"E_max,syst = {e_max:.1f} mm" in out
    assert "centre of gravity x [mm]" in out
    assert "SEM = sigma / sqrt(n) [mm]" in out
    assert "> 3 x SEM" in out
    assert re.search(r"alpha, Type A error per turn +-1\.0254 ± \d\.\d+ deg", out)
    assert "wheelbase [mm] (Eq. 4.26)" in out
    assert "ros__parameters:" in out
    assert "wheel_separation_multiplier:" in out
    # Piped output is not wrapped at 80 columns: the verdict is one line.
    assert re.search(r"run UMBmark again; another pass is worth it while E_max,syst stays", out)
    assert proc.stderr == ""


def test_the_bundled_example_is_written_with_what_to_run_next(tmp_path):
    path = tmp_path / "runs.csv"
    proc = run_cli("example", str(path))
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == f"umbmark: wrote {path}\n"
    assert "now run: umbmark calibrate" in proc.stdout
    assert path.read_text(encoding="utf-8") == umbmark.example()


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """The inputs of the commands compared with the library: the bundled runs table, two
    sessions of run logs of one virtual robot (E_d 1.004, E_b 1.02, 2 + 2 runs on 2 m
    squares), a ROS 2 bag of the first, and the calibration of the first."""
    folder = tmp_path_factory.mktemp("recorded")
    table = folder / "runs.csv"
    umbmark.example(table)
    robot = {"E_d": 1.004, "E_b": 1.02, "runs": 2, "side_length": 2}
    for seed in (1, 2):
        umbmark.simulate(**robot, seed=seed, logs=folder / f"session-{seed}")
    umbmark.simulate(**robot, seed=1, bag=folder / "bag")
    umbmark.calibrate(folder / "session-1", output=folder / "result.json")
    return {
        "table": str(table),
        **{f"session-{seed}": str(folder / f"session-{seed}") for seed in (1, 2)},
        "bag": str(folder / "bag"),
        "result": str(folder / "result.json"),
    }


#: ``--json`` of each job's command against its library function on the same inputs
#: (``{name}``: a path of :func:`recorded`): command-line arguments, library call.
_AGREE: dict[str, tuple[list[str], typing.Callable[[dict[str, str]], object]]] = {
    "calibrate a runs table": (
        ["calibrate", "{table}", "-L", "4", "-b", "0.34", "--unit", "mm"],
        lambda r: umbmark.calibrate(r["table"], side_length=4, wheelbase=0.34, unit="mm"),
    ),
    "calibrate a bag": (
        [
            "calibrate",
            "{bag}",
            "-L",
            "2",
            "-b",
            "0.34",
            "--wheel-diameter",
            "0.15",
            "--truth-topic",
            "/mocap/robot/pose",
        ],
        lambda r: umbmark.calibrate(
            r["bag"],
            side_length=2,
            wheelbase=0.34,
            wheel_diameter=0.15,
            truth_topic="/mocap/robot/pose",
        ),
    ),
    "info": (["info", "{bag}"], lambda r: umbmark.info(r["bag"])),
    "validate": (
        ["validate", "{session-1}", "{session-2}", "--methods", "exact"],
        lambda r: umbmark.validate(r["session-1"], r["session-2"], methods=["exact"]),
    ),
    "replay": (
        ["replay", "{session-2}", "--params", "{result}"],
        lambda r: umbmark.replay(r["session-2"], params=r["result"]),
    ),
    "plan": (
        ["plan", "--scatter", "0.01", "-L", "4", "--runs", "5"],
        lambda r: umbmark.plan(scatter=0.01, side_length=4, runs=5),
    ),
    "simulate": (
        ["simulate", "--E-d", "1.002", "--seed", "7", "--runs", "2"],
        lambda r: umbmark.simulate(E_d=1.002, seed=7, runs=2),
    ),
    "calibrate-real": (  # a real OptiOdom session (the shared data, or the package's copy)
        ["calibrate", str(SQUARE), "-m", "exact"],
        lambda r: umbmark.calibrate(SQUARE, method="exact"),
    ),
}


#: The agreements that take most of a second (bags, simulations): in the full suite only.
_SLOW_AGREE = ("calibrate a bag", "info", "validate", "simulate", "replay")


@pytest.mark.parametrize(
    "job",
    [pytest.param(j, marks=pytest.mark.slow) if j in _SLOW_AGREE else j for j in _AGREE],
)
def test_the_command_prints_the_dictionary_of_what_the_library_returns(
    job: str, recorded: dict[str, str]
) -> None:
    """A command's ``--json`` is ``to_dict()`` of its library function's report on the same
    inputs (one test for the rendering all commands share)."""
    args, call = _AGREE[job]
    printed = cli_json(*(a.format(**recorded) for a in args))
    report = call(recorded)
    assert printed == report.to_dict()  # type: ignore[attr-defined]


@pytest.mark.slow
def test_output_files_and_what_was_written(table, tmp_path):
    out, overlay = tmp_path / "result.json", tmp_path / "overlay.yaml"
    proc = run_cli(
        "calibrate", str(table(_rows())), "-L", "4", "-b", "0.34", "-o", str(out),
        "--yaml", str(overlay), "--json",
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert json.loads(out.read_text()) == json.loads(proc.stdout)
    # What was written, after what the overlay is keyed by (no controller named).
    assert proc.stderr == (
        "umbmark: no controller named: keyed diff_drive_controller; give --controller NAME "
        "(with its namespace, e.g. /robot1/diff_cont) or --current-params with its "
        f"parameter file\numbmark: wrote {out}\numbmark: wrote {overlay}\n"
    )
    assert overlay.read_text().startswith("# Written by umbmark")


@pytest.mark.slow
@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_plot_on_a_machine_without_display(table, tmp_path, suffix):
    out = tmp_path / f"clusters{suffix}"
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "MPLBACKEND")}
    args = ["calibrate", str(table(_rows())), "-L", "4", "-b", "0.34", "--plot", str(out)]
    proc = run_cli(*args, env=env)
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


@pytest.mark.slow
def test_bad_input_gives_one_line_and_exit_2(table, tmp_path):
    good = str(table(_rows(), name="good.csv"))
    assert cli_error("calibrate", good, "-L", "0", "-b", "0.34") == (
        "umbmark: error: --side-length must be > 0, got 0 m\n"
    )
    broken = table([("cw", 1, 2, 3), ("ccw", 1, 2, 3, 4)], name="broken.csv")
    err = cli_error("calibrate", str(broken), "-L", "4", "-b", "0.34")
    assert err == f"umbmark: error: {broken}, row 2: has 4 cells, the header has 5\n"
    err = cli_error("calibrate", good, "-L", "4", "-b", "0.34", "-o", good)
    assert "would overwrite an input" in err


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["calibrate", "x.csv", "-L", "four"], "Invalid value for '--side-length' / '-L'"),
        (
            ["calibrate", "x.csv", "--sidelength", "4"],
            "No such option '--sidelength'. Did you mean '--side-length'?",
        ),
        (["calibrate", "x.csv", "--method", "median"], "Invalid value for '--method'"),
        (["calibrate", "x.csv", "-L"], "Option '-L' requires an argument"),
        (["simulate", "--runs", "many"], "'many' is not a valid integer"),
        (["calibrat"], "No such command 'calibrat'"),
    ],
)
def test_malformed_options_give_one_line_and_exit_2(args, message):
    err = cli_error(*args)
    assert message in err
    assert "--help)" in err


def test_help_lists_options_by_section_tape_measure_first():
    proc = run_cli("calibrate", "--help")
    assert proc.returncode == 0
    sections = re.findall(r"^([A-Z][^\n:]*):$", proc.stdout, flags=re.MULTILINE)
    assert sections == [
        "The square test",
        "Runs table",
        "Parameters active during the runs",
        "Logged runs (run logs, OptiOdom sessions, ROS bags)",
        "ROS bags",
        "Outputs",
        "Other options",
    ]
    square = proc.stdout.split("The square test:")[1].split("Runs table:")[0]
    for name in ("--side-length", "--wheelbase", "--method"):
        assert name in square


def test_version():
    proc = run_cli("--version")
    assert proc.stdout == f"umbmark {umbmark.__version__}\n"


def test_help_does_not_import_numpy():
    code = "import sys, umbmark.cli.main; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_a_runs_table_calibration_loads_no_heavy_library(table):
    """scipy only for fits that call it, matplotlib only for figures, rosbags only for bags."""
    code = (
        "import sys, umbmark\n"
        f"umbmark.calibrate({str(table(_rows()))!r}, side_length=4, wheelbase=0.34)\n"
        "print(sorted(m for m in ('scipy', 'matplotlib', 'rosbags') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


# Options whose command-line unit differs from the library's SI keyword.
_CONVERTED = {("simulate", "turn_angle"), ("fig4", "leg_bend"), ("table1", "tape_thickness")}
#: Options a command gathers into one keyword's value, a dataclass whose fields they are
#: (in its units: ``ImuSetup.of_options``): simulate's IMU is ``imu=ImuSetup(...)``.
_GATHERED = {"simulate": ("imu", "umbmark.sim.imu.ImuSetup")}
_RENDERING = {"json_out", "help"}


def _commands() -> list[tuple[str, click.Command, object]]:
    reproduce = typing.cast("click.Group", cli.commands["reproduce"])
    return [
        ("calibrate", cli.commands["calibrate"], umbmark.calibrate),
        ("replay", cli.commands["replay"], umbmark.replay),
        ("validate", cli.commands["validate"], umbmark.validate),
        ("study", cli.commands["study"], umbmark.study),
        ("simulate", cli.commands["simulate"], umbmark.simulate),
        ("demo", cli.commands["demo"], umbmark.demo),
        ("example", cli.commands["example"], umbmark.example),
        ("plan", cli.commands["plan"], umbmark.plan),
        ("fleet", cli.commands["fleet"], umbmark.fleet),
        ("table1", reproduce.commands["table1"], umbmark.reproduce_table1),
        ("fig4", reproduce.commands["fig4"], umbmark.reproduce_fig4),
    ]


@pytest.mark.parametrize(("name", "command", "function"), _commands(), ids=lambda v: str(v)[:12])
def test_every_option_is_a_keyword_of_the_library_function(name, command, function):
    from umbmark.core.errors import keywords_of

    taken = keywords_of(function)  # **options of a TypedDict or a dataclass's fields too
    assert taken is not None, f"{name}: the library function takes any keyword"
    keywords = set(taken)
    if name == "simulate":  # simulate --fleet N is umbmark.simulate_fleet(fleet=N, ...)
        keywords |= set(keywords_of(umbmark.simulate_fleet) or ())
    gathered: set[str] = set()
    if name in _GATHERED:
        keyword, where = _GATHERED[name]
        assert keyword in keywords
        module, _, cls = where.rpartition(".")
        gathered = {
            f.name for f in dataclasses.fields(getattr(importlib.import_module(module), cls))
        }
    for param in command.params:
        if param.name in _RENDERING or (name, param.name) in _CONVERTED or param.name in gathered:
            continue
        if isinstance(param, click.Argument):
            assert param.name in keywords or param.nargs == -1, (name, param.name)
            continue
        assert param.name in keywords, f"{name} --{param.name} is no keyword of the library"
    for converted_command, keyword in _CONVERTED:
        if converted_command == name:
            assert keyword in keywords


@pytest.mark.slow
def test_a_full_disk_is_one_line_with_its_own_exit_status(tmp_path):
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full on this system")
    from helpers import umbmark_command

    table = tmp_path / "runs.csv"
    umbmark.example(table)
    with open("/dev/full", "w") as full:
        proc = subprocess.run(
            [umbmark_command(), "calibrate", str(table), "-b", "0.34", "-L", "4", "--unit", "mm",
             "--json"],
            stdout=full, stderr=subprocess.PIPE, text=True, check=False, timeout=60,
        )  # fmt: skip
    assert proc.returncode == 3, proc.stderr
    assert proc.stderr == "umbmark: error: No space left on device\n"


@pytest.mark.slow
def test_an_ascii_only_terminal_gets_escapes_not_a_traceback(tmp_path):
    table = tmp_path / "runs.csv"
    umbmark.example(table)
    env = {**os.environ, "PYTHONIOENCODING": "ascii"}
    proc = run_cli("calibrate", str(table), "-b", "0.34", "-L", "4", "--unit", "mm", env=env)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    assert "E_max,syst" in proc.stdout


def test_the_method_choices_are_the_librarys_methods():
    from umbmark.estimators.registry import NAMES as METHODS

    method = next(p for p in cli.commands["calibrate"].params if p.name == "method")
    assert list(typing.cast("click.Choice", method.type).choices) == [*METHODS, "auto"]


def test_help_layout_does_not_depend_on_arguments_having_help_records():
    """click 8.5 gave arguments a help record; our sections must not move because of it."""
    import click

    from umbmark.cli.click_options import Command, option
    from umbmark.options.spec import OUTPUTS, TEST

    class ArgumentWithHelp(click.Argument):  # what click >= 8.5 does
        def get_help_record(self, ctx: click.Context) -> tuple[str, str]:
            return (self.make_metavar(ctx), "")

    @click.command(cls=Command)
    @click.argument("sources", nargs=-1, cls=ArgumentWithHelp)
    @option("--side-length", section=TEST, help="side")
    @option("--json", section=OUTPUTS, is_flag=True, help="json")
    def cmd(**_: object) -> None:
        """Doc."""

    text = cmd.get_help(click.Context(cmd))
    sections = re.findall(r"^([A-Z][^\n:]*):$", text, flags=re.MULTILINE)
    assert sections == ["The square test", "Outputs", "Other options"]
    assert "SOURCES" not in text.split("Options:")[-1].split("The square test:")[1]


def test_group_help_says_what_each_experiment_is():
    """``reproduce --help`` listed fig4 as just "Fig." (click cut its docstring at the
    first full stop)."""
    proc = run_cli("reproduce", "--help")
    (line,) = [line for line in proc.stdout.splitlines() if line.strip().startswith("fig4")]
    assert "uni-directional trap" in line
