"""Ctrl-C (issue 10): a long job interrupted ends at once with exit status 130 and one
line, leaves no process running and no temporary file behind.

Real subprocesses of the installed command, real signals: the process is started in its
own process group (as a shell starts a job), and its group is looked up in /proc
afterwards, so that a worker process left running is seen.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

import umbmark

from helpers import umbmark_command

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc"),
]

#: The line a Ctrl-C leaves on stderr (stderr is not a terminal here: no line break first).
INTERRUPTED = "umbmark: interrupted\n"


def _group(pgid: int) -> list[int]:
    """The live (not zombie) processes of process group ``pgid``."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            stat = Path(f"/proc/{entry}/stat").read_text()
        except OSError:  # gone meanwhile
            continue
        fields = stat.rsplit(")", 1)[1].split()
        state, group = fields[0], int(fields[2])
        if group == pgid and state != "Z":
            found.append(int(entry))
    return found


def _wait_for(condition: Callable[[], bool], timeout: float) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.05)
    return condition()


def _start(*args: str, cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [umbmark_command(), *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=cwd,
        start_new_session=True,  # its own process group, as a shell's job
    )


def _interrupt(
    proc: subprocess.Popen[str], *, whole_group: bool
) -> tuple[int, str, float, list[int]]:
    """Send SIGINT (to the process, or to its group as a terminal's Ctrl-C does); return
    the exit status, stderr, the seconds it took to end and what is left of its group."""
    start = time.monotonic()
    if whole_group:
        os.killpg(proc.pid, signal.SIGINT)
    else:
        os.kill(proc.pid, signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        pytest.fail("still running 60 s after SIGINT")
    took = time.monotonic() - start
    _wait_for(lambda: not _group(proc.pid), 10.0)
    left = _group(proc.pid)
    for pid in left:  # never leave them to the next test
        os.kill(pid, signal.SIGKILL)
    return proc.returncode, err, took, left


@pytest.mark.parametrize("whole_group", [False, True], ids=["process", "terminal"])
def test_study_interrupted_ends_its_workers(tmp_path: Path, whole_group: bool) -> None:
    # 100000 robots: hours of work on two processes, so it is surely running at SIGINT.
    proc = _start(
        "study", "--trials", "100000", "--methods", "exact", "--workers", "2", cwd=tmp_path
    )
    started = _wait_for(lambda: len(_group(proc.pid)) >= 3, 60.0)  # the parent, 2 workers
    if not started:
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail(f"the workers did not start: {proc.communicate()}")
    time.sleep(1.0)  # they are at work
    code, err, took, left = _interrupt(proc, whole_group=whole_group)
    assert code == 130, err
    assert err == INTERRUPTED
    assert left == [], f"processes left running: {left}"
    assert took < 20.0


def test_simulation_interrupted_while_writing_leaves_no_temporary_file(tmp_path: Path) -> None:
    # 2 x 60 runs of time series (7 MB of run logs): written one file after the other.
    logs = tmp_path / "logs"
    proc = _start("simulate", "--runs", "60", "--logs", str(logs), "-o", "runs.csv", cwd=tmp_path)
    writing = _wait_for(lambda: logs.is_dir() and any(logs.iterdir()), 120.0)
    if not writing:
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail(f"no run log appeared: {proc.communicate()}")
    code, err, _, left = _interrupt(proc, whole_group=True)
    if code == 0:
        pytest.skip("the writing finished before the signal arrived")
    assert code == 130, err
    assert err.endswith(INTERRUPTED)
    assert err.count("\n") == 1 + err.count("umbmark: wrote "), err
    assert "Traceback" not in err
    assert left == []
    written = [p.name for p in logs.iterdir()] + [p.name for p in tmp_path.iterdir()]
    assert not [name for name in written if name.startswith(".")], written
    # What was written is whole: every run log has its last line.
    for path in logs.glob("run-*.csv"):
        assert path.read_text(encoding="utf-8").endswith("\n")


@pytest.mark.parametrize(
    "args",
    [
        ("reproduce", "table1", "--seeds", "1000"),  # about a second a seed
        ("simulate", "--runs", "1000", "--dt", "0.001", "-o", "runs.csv"),  # 1.7e7 periods
    ],
    ids=["reproduce", "simulate"],
)
def test_long_jobs_end_at_once_on_ctrl_c(tmp_path: Path, args: tuple[str, ...]) -> None:
    proc = _start(*args, cwd=tmp_path)
    time.sleep(2.0)  # past the start-up, into the work (each runs for a minute or more)
    assert proc.poll() is None, proc.communicate()
    code, err, took, left = _interrupt(proc, whole_group=True)
    assert code == 130, err
    assert err == INTERRUPTED
    assert left == []
    assert took < 10.0
    assert not list(tmp_path.rglob("*")), "nothing is written when the work is interrupted"


# --- on a terminal: the progress display is shown, and goes on Ctrl-C -------------------


def _on_terminal(
    args: list[str], shown: bytes | re.Pattern[bytes], cwd: Path, timeout: float = 120.0
) -> tuple[int, bytes, list[int]]:
    """Run ``umbmark ARGS`` on a pseudo-terminal; once ``shown`` (text, or a pattern) is on
    its screen, press Ctrl-C (SIGINT to its process group, as a terminal does). Returns the
    exit status, everything it wrote and what is left of its group."""
    import pty
    import select

    pattern = shown if isinstance(shown, re.Pattern) else re.compile(re.escape(shown))

    pid, fd = pty.fork()  # the child leads a new session and process group
    if pid == 0:  # pragma: no cover - the child
        os.chdir(cwd)
        os.execv(umbmark_command(), [umbmark_command(), *args])
    screen = b""
    end = time.monotonic() + timeout
    while not pattern.search(screen) and time.monotonic() < end:
        if select.select([fd], [], [], 0.1)[0]:
            try:
                screen += os.read(fd, 65536)
            except OSError:
                break
    if not pattern.search(screen):
        os.killpg(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        pytest.fail(f"{shown!r} never appeared: {screen[-500:]!r}")
    os.killpg(pid, signal.SIGINT)
    while select.select([fd], [], [], 30.0)[0]:
        try:
            chunk = os.read(fd, 65536)
        except OSError:  # the terminal closed: the process ended
            break
        if not chunk:
            break
        screen += chunk
    _, status = os.waitpid(pid, 0)
    os.close(fd)
    _wait_for(lambda: not _group(pid), 10.0)
    left = _group(pid)
    for stray in left:
        os.kill(stray, signal.SIGKILL)
    return os.waitstatus_to_exitcode(status), screen, left


def test_study_on_a_terminal_shows_its_bar_and_stops_on_ctrl_c(tmp_path: Path) -> None:
    args = ["study", "--trials", "100000", "--methods", "exact", "--workers", "2"]
    code, screen, left = _on_terminal(args, b"0:00:01", tmp_path)  # the bar's clock
    assert code == 130
    assert b"study" in screen
    # The bar is taken away; after the ^C the terminal echoed, one line.
    assert screen.endswith(b"\r\numbmark: interrupted\r\n"), screen[-200:]
    assert b"Traceback" not in screen
    assert left == []


def test_a_trajectory_fit_on_a_terminal_shows_it_is_working(tmp_path: Path) -> None:
    # 2 + 2 runs sampled at 500 Hz: the fit takes seconds.
    logs = tmp_path / "logs"
    umbmark.simulate(runs=2, dt=0.002, logs=logs)
    args = ["calibrate", str(logs), "--method", "trajectory"]
    code, screen, left = _on_terminal(args, b"calibrating, --method trajectory", tmp_path)
    assert code == 130
    assert b"(Ctrl-C stops)" in screen
    assert screen.endswith(b"umbmark: interrupted\r\n"), screen[-200:]
    assert b"Traceback" not in screen
    assert left == []


def test_ctrl_c_while_the_command_line_loads_is_one_line():
    # Ctrl-C arriving while umbmark.cli.main (click, rich, numpy) is being imported: an
    # import hook raises KeyboardInterrupt at that import, as the signal would.
    code = (
        "import sys\n"
        "class Interrupt:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'umbmark.cli.main':\n"
        "            raise KeyboardInterrupt\n"
        "        return None\n"
        "sys.meta_path.insert(0, Interrupt())\n"
        "from umbmark._entry import main\n"
        "main()\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=False
    )
    assert proc.returncode == 130
    assert proc.stderr == "umbmark: interrupted\n"


def test_the_console_script_starts_at_the_guarded_entry():
    from importlib.metadata import entry_points

    (script,) = [e for e in entry_points(group="console_scripts") if e.name == "umbmark"]
    assert script.value == "umbmark._entry:main"


# --- a fleet run: what the history keeps, said in one line; the next run does the rest ---

FLEET_ROBOTS, FLEET_DAYS = 2, 6
FLEET_PATTERN = "{robot}/{date}/*"
#: A plain progress line (stderr not a terminal): ``umbmark fleet``'s, each recording's.
FLEET_PROGRESS = re.compile(
    r"umbmark: progress: \d+ of 12 recordings, \d robots?, \d+(\.\d)? (s|min|h) recorded, "
    r"\d+(\.\d)? (s|min|h) elapsed"
)


@pytest.fixture(scope="module")
def small_fleet(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """12 recordings (2 robots, 6 days of 1.5 min: about a second each on a worker)."""
    pytest.importorskip("distributed", reason="the fleet's extra: pip install '.[fleet]'")
    folder = tmp_path_factory.mktemp("fleet") / "fleet"
    umbmark.simulate_fleet(folder, fleet=FLEET_ROBOTS, days=FLEET_DAYS, minutes=1.5, seed=6)
    return folder


def _fleet_args(fleet: Path, history: Path) -> list[str]:
    return ["fleet", str(fleet), "--robot-from", FLEET_PATTERN, "--history", str(history)]


@pytest.mark.parametrize("whole_group", [False, True], ids=["process", "terminal"])
def test_a_fleet_interrupted_says_what_it_kept_and_the_next_run_does_the_rest(
    small_fleet: Path, tmp_path: Path, whole_group: bool
) -> None:
    """``umbmark fleet`` on the default local cluster (two worker processes), SIGINT once
    two recordings are in the history: to the process, or to its whole process group as a
    terminal's Ctrl-C (the workers get it too). stderr is the progress lines and one line
    saying how many recordings the history keeps, where, and how to finish: no engine's
    traceback, from this process or its workers; exit status 130, nothing left running. The
    same command again does only the rest."""
    from fleet_tasks import recorded_rows

    history = tmp_path / "h.sqlite3"
    total = FLEET_ROBOTS * FLEET_DAYS
    proc = _start(*_fleet_args(small_fleet, history), "--workers", "2", cwd=tmp_path)
    if not _wait_for(lambda: recorded_rows(history) >= 2 or proc.poll() is not None, 300.0):
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail(f"no recording came back: {proc.communicate()}")
    assert proc.poll() is None, proc.communicate()
    code, err, took, left = _interrupt(proc, whole_group=whole_group)
    kept = recorded_rows(history)
    assert code == 130, err
    assert left == [], f"processes left running: {left}"
    assert took < 30.0
    assert 2 <= kept < total, err
    *progress, last = err.splitlines()
    assert last == (
        f"umbmark: error: interrupted: {kept} of the {total} recordings to do are done, "
        f"recorded in the history ({history}); to finish, run the same command again: only "
        f"the other {total - kept} are done"
    ), err
    assert progress, err  # the first recording's line at least
    assert [line for line in progress if not FLEET_PROGRESS.fullmatch(line)] == [], err
    assert err.endswith("\n")
    assert not list(tmp_path.glob("*.html"))  # nothing written but the history
    # The same command again: only what was not kept.
    again = subprocess.run(
        [umbmark_command(), *_fleet_args(small_fleet, history), "--workers", "2", "--json"],
        capture_output=True, text=True, timeout=600, check=False, cwd=tmp_path,
    )  # fmt: skip
    assert again.returncode == 0, again.stderr
    data = json.loads(again.stdout)
    assert (data["recordings_done"], data["recordings_skipped"]) == (total - kept, kept)
    assert data["failed"] == []
    assert recorded_rows(history) == total


def test_a_fleet_on_a_terminal_shows_its_bar_and_says_what_it_kept(
    small_fleet: Path, tmp_path: Path
) -> None:
    """On a terminal: the bar (how many recordings of how many), and after Ctrl-C (to the
    process group, with the workers) the bar taken away and the one line."""
    args = [*_fleet_args(small_fleet, tmp_path / "h.sqlite3"), "--workers", "2"]
    # any count short of all: two workers may finish their first recordings within one of
    # the bar's refreshes, and it never shows "1 of 12"
    done = re.compile(rb"\b([1-9]|1[01]) of 12 recordings")
    code, screen, left = _on_terminal(args, done, tmp_path, timeout=300.0)
    assert code == 130, screen[-500:]
    assert b"Traceback" not in screen
    tail = screen.rsplit(b"\r\n", 2)[-2]
    assert tail.startswith(b"umbmark: error: interrupted: "), screen[-500:]
    assert b"recordings to do are done, recorded in the history" in tail
    assert left == []
