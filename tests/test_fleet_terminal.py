"""What ``umbmark fleet`` prints, as a person sees it: the table within a 120-column
terminal (the figures split into parts rather than squeezed; robots with long names), every
flag whole on lines of its own under it, the summary line, then the files written; and the
progress a log is told.

The quick tests render a fleet of known outcomes (``fleet_tasks.daily_outcomes``: each
figure's truth and standard error chosen, a step injected) on a rich console of width 120,
and on the piped console; the slow one runs the command on a pseudo-terminal with
``COLUMNS=120`` over simulated recordings whose robots have long names.
"""

from __future__ import annotations

import io
import json
import re
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console

from umbmark.cli.fleet import _render
from umbmark.fleets.outcome import RecordingOutcome
from umbmark.fleets.summary import summarize
from umbmark.jobs.fleet import FleetProgress, FleetReport, FleetStopped

from fleet_tasks import T0, daily_outcomes

WIDTH = 120
#: Robots with long names, and the figure stepped on each (by 60 and 40 standard errors: a
#: change any test of a change finds).
STEPPED = {
    "warehouse-north-aisle-07-amr-000123-left-dock": ("E_d", 0.006),
    "warehouse-south-amr-000456-charging-bay": ("laser_yaw", 0.02),
    "warehouse-east-amr-000789-tugger": ("E_b", 0.012),
}
STEADY = "lab-r1"
UNUSABLE = "warehouse-west-amr-000999-no-laser-mounted-yet"
REASON = (
    "no usable recording: it holds wheels but neither a laser scan nor an independent "
    "reference (motion capture, a ground-truth odometry) to calibrate them against"
)


def _report() -> FleetReport:
    rng = np.random.default_rng(35)
    outcomes: list[RecordingOutcome] = []
    for robot, (figure, jump) in STEPPED.items():
        outcomes += daily_outcomes(robot, 12, rng, step_day=6, figure=figure, jump=jump)
    outcomes += daily_outcomes(STEADY, 12, rng)
    outcomes += [
        RecordingOutcome(f"{UNUSABLE}/day{d:02d}.mcap", UNUSABLE, T0, 8.0, "0" * 64,
                         reason=REASON)
        for d in range(2)
    ]  # fmt: skip
    summary = summarize(outcomes)
    return FleetReport(summary, len(outcomes), tuple(outcomes), 0, "/data/fleet/history.sqlite3")


def _words(text: str) -> str:
    return " ".join(text.split())


def test_the_table_fits_120_columns_and_every_flag_is_whole():
    report = _report()
    shown = io.StringIO()
    _render(report, Console(file=shown, width=WIDTH, highlight=False))
    text = shown.getvalue()
    lines = text.splitlines()
    assert max(len(line) for line in lines) <= WIDTH, text
    # The flags are those injected, one robot each (the steady one has none) ...
    by = {r.robot: r for r in report.summary.robots}
    for robot, (figure, _) in STEPPED.items():
        assert [figure in flag for flag in by[robot].flags] == [True], by[robot].flags
    assert by[STEADY].flags == ()
    # ... each printed whole, after its robot's name, under the table (after its rows).
    last_row = max(k for k, line in enumerate(lines) if line.strip().startswith(STEADY))
    for robot in STEPPED:
        (flag,) = by[robot].flags
        assert f"{robot}: {flag}" in _words(text)
        at = next(k for k, line in enumerate(lines) if line.startswith(f"{robot}: "))
        assert at > last_row
    # Every robot's name and every figure shown whole in a cell: none cut or wrapped.
    for robot in (*STEPPED, STEADY):
        for track in by[robot].tracks.values():
            assert track.shown(unit=False) in text
        assert sum(line.strip().startswith(f"{robot} ") for line in lines) >= 1
    assert f"{UNUSABLE}: no usable recording" in text
    # The summary line is the last.
    assert _words("\n".join(lines[-2:])).endswith(_words(report.summary.line()) + ".")


def test_piped_every_flag_is_one_line(capsys: pytest.CaptureFixture[str]):
    """A log (stdout piped) is not wrapped: each flag a line of its own, ``ROBOT: FLAG``."""
    from umbmark.cli.common import console

    report = _report()
    _render(report, console())
    lines = capsys.readouterr().out.splitlines()
    for robot in report.summary.robots:
        for flag in robot.flags:
            assert f"{robot.robot}: {flag}" in lines


def test_the_progress_says_how_many_of_how_many_robots_hours_and_elapsed():
    assert FleetProgress(3, 10, 2, 16.0, 25.0).text() == (
        "3 of 10 recordings, 2 robots, 16.0 h recorded, 25 s elapsed"
    )
    assert FleetProgress(1, 12, 1, 0.5, 125.0).text() == (
        "1 of 12 recordings, 1 robot, 30 min recorded, 2 min elapsed"
    )


def test_a_stopped_run_says_what_it_kept_and_how_to_finish():
    assert FleetStopped(2, 12, "/data/h.sqlite3").text() == (
        "2 of the 12 recordings to do are done, recorded in the history (/data/h.sqlite3); "
        "to finish, run the same command again: only the other 10 are done"
    )
    assert "nothing is done again" in FleetStopped(12, 12, "h.sqlite3").text()


# --- the command on a terminal -----------------------------------------------------------

#: The simulated robots renamed (their folders, which the pattern names them by).
LONG = {
    "robot01": "warehouse-north-aisle-07-amr-000123-left-dock-steady",
    "robot02": "warehouse-south-amr-000456-charging-bay-wheel-changed",
}
ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


@pytest.fixture(scope="module")
def long_named(tmp_path_factory: pytest.TempPathFactory) -> Path:
    pytest.importorskip("distributed", reason="the fleet's extra: pip install '.[fleet]'")
    import umbmark

    folder = tmp_path_factory.mktemp("terminal") / "fleet"
    umbmark.simulate_fleet(folder, fleet=2, days=6, minutes=1.5, seed=8)
    for short, long in LONG.items():
        (folder / short).rename(folder / long)
    return folder


def _on_pty(args: list[str], cwd: Path, env: dict[str, str]) -> tuple[int, str]:
    """``umbmark ARGS`` on a pseudo-terminal to its end: its exit status and the screen's
    text (stdout and stderr as they came; colours and cursor moves taken out)."""
    import os
    import pty
    import select

    from helpers import umbmark_command

    pid, fd = pty.fork()
    if pid == 0:  # pragma: no cover - the child
        os.chdir(cwd)
        os.execve(umbmark_command(), [umbmark_command(), *args], env)
    screen = b""
    while select.select([fd], [], [], 600.0)[0]:
        try:
            chunk = os.read(fd, 65536)
        except OSError:  # the terminal closed: the process ended
            break
        if not chunk:
            break
        screen += chunk
    _, status = os.waitpid(pid, 0)
    os.close(fd)
    text = ANSI.sub("", screen.decode("utf-8", errors="replace"))
    return os.waitstatus_to_exitcode(status), text.replace("\r\n", "\n")


@pytest.mark.slow
def test_on_a_120_column_terminal(long_named: Path, tmp_path: Path):
    """On a 120-column terminal: no line wider, every flag whole, the summary line, then
    ``wrote fleet.html`` last."""
    import os

    from helpers import run_cli

    history = tmp_path / "h.sqlite3"
    args = ["fleet", str(long_named), "--robot-from", "{robot}/{date}/*", "--history",
            str(history), "--workers", "2", "--report", "fleet.html"]  # fmt: skip
    env = {**os.environ, "COLUMNS": str(WIDTH), "LINES": "50", "TERM": "xterm"}
    code, screen = _on_pty(args, tmp_path, env)
    assert code == 0, screen
    # What the screen keeps: the bar's line is redrawn in place ("\r") and taken away.
    lines = [line.rsplit("\r", 1)[-1] for line in screen.split("\n")]
    assert max(len(line) for line in lines) <= WIDTH, screen
    assert "Traceback" not in screen
    data = json.loads(run_cli(*args[:-2], "--json").stdout)  # done: the history's summary
    flags = [(r["robot"], f) for r in data["robots"] for f in r["flags"]]
    assert {robot for robot, _ in flags} == {LONG["robot02"]}, flags  # its wheel changed
    for robot, flag in flags:  # whole: a path wider than the terminal is folded, not cut
        assert "".join(f"{robot}: {flag}".split()) in "".join(screen.split())
    said = [
        k for k, line in enumerate(lines) if line.startswith(tuple(f"{r}: " for r in LONG.values()))
    ]
    summary = next(k for k, line in enumerate(lines) if line.startswith("2 robots: "))
    wrote = lines.index("umbmark: wrote fleet.html")
    assert max(said) < summary < wrote
    assert [line for line in lines[wrote + 1 :] if line.strip()] == []
