"""Never lose a user's file (issue 21, items 2, 7, 8): no command replaces a file or writes
into a folder holding files without --force (``force=True``); simulate --logs never mixes
runs; a read of a history never creates one; a library call writes only where its caller
names a folder, and the command's default folder never refuses a second run."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest
from tests.helpers import api_error, cli_error, run_cli

import umbmark
from umbmark.robot.virtual import VirtualRobot

GEOMETRY = ("-L", "4", "-b", "0.34", "--unit", "mm")
#: What each refused target holds before, to compare byte for byte after.
MINE = b"my own file, typed by hand\n"


def _snapshot(path: Path) -> dict[str, bytes]:
    """Every file under ``path`` (or ``path`` itself) by relative name, with its bytes."""
    if path.is_file():
        return {".": path.read_bytes()}
    return {str(p.relative_to(path)): p.read_bytes() for p in path.rglob("*") if p.is_file()}


@pytest.fixture(scope="module")
def sources(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A runs table, a run log and a history with one robot, made once."""
    root = tmp_path_factory.mktemp("sources")
    table = root / "runs.csv"
    umbmark.example(table)
    log = root / "log"
    umbmark.simulate(E_d=1.002, side_length=1.0, runs=2, dt=0.02, logs=log)
    history = root / "history.sqlite3"
    umbmark.calibrate(table, side_length=4, wheelbase=0.34, unit="mm", robot="R", history=history)
    return {"table": table, "log": log, "history": history}


#: Every command that writes, with the option that names the output: ``{out}`` is the
#: output (a file that exists, or a folder holding a file), ``{table}``, ``{log}``,
#: ``{history}`` the sources.
WRITERS = {
    "calibrate -o": ("file", ["calibrate", "{table}", *GEOMETRY, "-o", "{out}.json"]),
    "calibrate --yaml": ("file", ["calibrate", "{table}", *GEOMETRY, "--yaml", "{out}.yaml"]),
    "calibrate --ros1-yaml": (
        "file",
        ["calibrate", "{table}", *GEOMETRY, "--ros1-yaml", "{out}.yaml"],
    ),
    "calibrate --plot": ("file", ["calibrate", "{table}", *GEOMETRY, "--plot", "{out}.png"]),
    "calibrate --report": (
        "file",
        ["calibrate", "{table}", *GEOMETRY, "--report", "{out}.html"],
    ),
    "calibrate --tum": ("folder", ["calibrate", "{log}", "--tum", "{out}"]),
    "replay --plot": ("file", ["replay", "{log}", "--plot", "{out}.png"]),
    "replay --tum": ("folder", ["replay", "{log}", "--tum", "{out}"]),
    "report -o": ("file", ["report", "{table}", *GEOMETRY, "-o", "{out}.html"]),
    "history --plot": ("file", ["history", "R", "--history", "{history}", "--plot", "{out}.png"]),
    "reproduce fig4 --plot": ("file", ["reproduce", "fig4", "--plot", "{out}.png"]),
    "simulate -o": ("file", ["simulate", "-o", "{out}.csv"]),
    "simulate --logs": ("folder", ["simulate", "--logs", "{out}"]),
    "demo --out": ("demo", ["demo", "--out", "{out}"]),
    "example": ("file", ["example", "{out}.csv"]),
    "example --real": ("folder", ["example", "--real", "{out}"]),
    "selfcal --out": ("selfcal", ["selfcal", "--sim", "--out", "{out}"]),
}


def _target(kind: str, out: Path, args: list[str]) -> Path:
    """Make the output ``args`` name exist, holding :data:`MINE`; return it."""
    if kind == "file":
        (named,) = (a for a in args if a.startswith(str(out)))
        path = Path(named)
        path.write_bytes(MINE)
        return path
    out.mkdir()
    name = {"demo": "runs_before.csv", "selfcal": "report.html"}.get(kind, "notes.txt")
    (out / name).write_bytes(MINE)
    return out


@pytest.mark.parametrize("command", list(WRITERS))
def test_every_writing_command_refuses_to_replace(
    command: str, sources: dict[str, Path], tmp_path: Path
) -> None:
    """The output exists: exit 2, one line naming it and --force; nothing changed."""
    kind, template = WRITERS[command]
    out = tmp_path / "out"
    names = {k: str(v) for k, v in sources.items()}
    args = [a.format(out=out, **names) for a in template]
    target = _target(kind, out, args)
    before = _snapshot(target)
    line = cli_error(*args)
    assert str(target) in line, line
    assert "--force" in line, line
    assert _snapshot(target) == before


@pytest.mark.slow
def test_simulate_o_keeps_the_hand_typed_table_and_force_replaces_it(tmp_path: Path) -> None:
    """The README's runs.csv is a hand-typed table: simulate -o refuses it byte for byte;
    --force replaces it with the simulated runs (a table calibrate reads: 2 x 2 runs)."""
    table = tmp_path / "runs.csv"
    umbmark.example(table)
    before = table.read_bytes()
    line = cli_error("simulate", "-n", "2", "-L", "1", "-o", str(table))
    assert line == f"umbmark: error: {table}: exists already; pass --force to replace it\n"
    assert table.read_bytes() == before
    message = api_error(umbmark.simulate, runs=2, side_length=1.0, output=table)
    assert message == f"{table}: exists already; pass force=True to replace it"
    assert table.read_bytes() == before
    proc = run_cli("simulate", "-n", "2", "-L", "1", "-o", str(table), "--force")
    assert proc.returncode == 0, proc.stderr
    assert table.read_bytes() != before
    assert len(umbmark.calibrate(table, side_length=1.0, wheelbase=0.34).runs) == 4


@pytest.mark.slow
def test_simulate_logs_never_mixes_runs(tmp_path: Path) -> None:
    """A folder holding a run log: refused; --force replaces the run log whole (3 + 3 runs
    before, 2 + 2 after: calibrate reads 4, not 10); another .csv in it is never removed
    and refuses the folder even with --force."""
    logs = tmp_path / "logs"
    common = ("-L", "1", "--noise-free")
    assert run_cli("simulate", *common, "-n", "3", "--logs", str(logs)).returncode == 0
    assert len(list(logs.glob("run-*.csv"))) == 6
    before = _snapshot(logs)
    line = cli_error("simulate", *common, "-n", "2", "--logs", str(logs))
    assert f"{logs}: is not empty" in line
    assert "--force" in line
    assert _snapshot(logs) == before
    proc = run_cli("simulate", *common, "-n", "2", "--logs", str(logs), "--force")
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in logs.iterdir()) == [
        "metadata.yaml",
        "run-01.csv",
        "run-02.csv",
        "run-03.csv",
        "run-04.csv",
    ]
    assert len(umbmark.calibrate(logs).runs) == 4
    (logs / "mine.csv").write_bytes(MINE)
    before = _snapshot(logs)
    line = cli_error("simulate", *common, "-n", "2", "--logs", str(logs), "--force")
    assert "holds mine.csv" in line
    assert _snapshot(logs) == before


@pytest.mark.slow
def test_a_history_read_never_creates_one(tmp_path: Path) -> None:
    """Listing, a robot's calibrations, the library: a missing history is named, and
    neither the file nor its folder appears. Listing one that does not exist yet (a fresh
    install) is no error: it says nothing is recorded yet and how to record; a robot asked
    for is refused (exit 2) saying the same."""
    missing = tmp_path / "none.sqlite3"
    deep = tmp_path / "sub" / "h.sqlite3"
    listed = run_cli("history", "--history", str(missing))
    assert listed.returncode == 0, listed.stderr
    assert f"{missing}: nothing is recorded yet" in listed.stderr
    assert "umbmark calibrate SOURCE --robot NAME" in listed.stderr
    line = cli_error("history", "R", "--history", str(deep))
    assert line == (
        f"umbmark: error: {deep}: nothing is recorded yet: umbmark calibrate SOURCE "
        "--robot NAME (or umbmark selfcal --robot NAME) records each calibration in this file\n"
    )
    cli_error("history", "R", "--history", str(deep), "--applied", "1")
    assert "umbmark.calibrate(source, robot=name)" in api_error(
        umbmark.history, "R", history=missing
    )
    assert umbmark.history(history=missing).robots == ()
    assert sorted(tmp_path.iterdir()) == []


def test_a_history_is_read_without_being_written(sources: dict[str, Path]) -> None:
    """An existing history read (robots, a robot's calibrations and drift) keeps its
    bytes: the connection is read-only."""
    history = sources["history"]
    with sqlite3.connect(history) as db:  # fold the write-ahead log in: bytes are final
        db.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    db.close()
    before = history.read_bytes()
    assert [r.name for r in umbmark.history(history=history).robots] == ["R"]
    assert len(umbmark.history("R", history=history).calibrations) == 1
    assert history.read_bytes() == before


def _small_selfcal(robot: VirtualRobot, **kwargs: object) -> umbmark.SelfCalReport:
    return umbmark.selfcal(
        robot, side_length=1.0, runs=2, max_passes=1, verify=False, coarse=False, **kwargs
    )


@pytest.mark.slow
def test_a_library_selfcal_writes_nothing_and_runs_twice(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """No folder named: nothing written in the working directory, the report returned
    (its passes' run logs were in a temporary folder, removed), and a second call in the
    same place works."""
    monkeypatch.chdir(tmp_path)
    for _ in range(2):
        report = _small_selfcal(VirtualRobot(seed=1))
        assert report.files == ()
        assert [p.folder for p in report.passes] == [None]
        assert len(report.passes[0].report.runs) == 4
    assert list(tmp_path.iterdir()) == []
    out = tmp_path / "mine"
    named = _small_selfcal(VirtualRobot(seed=1), out=out)
    assert named.files[0] == out / "report.html"
    assert all(path.parent == out for path in named.files)
    assert sorted(p.name for p in (out / "pass-1").iterdir())[0] == "metadata.yaml"


@pytest.mark.slow
def test_the_command_makes_a_new_folder_for_a_second_selfcal(tmp_path: Path) -> None:
    """Twice in the same place: selfcal-<robot>, then selfcal-<robot>-2; an --out holding an
    earlier self-calibration says what to do, and --force replaces it whole."""
    args = ("selfcal", "--sim", "-L", "1", "-n", "2", "--max-passes", "1", "--no-coarse")
    for _ in range(2):
        proc = run_cli(*args, "--no-verify", cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
    first, second = tmp_path / "selfcal-virtual-robot", tmp_path / "selfcal-virtual-robot-2"
    assert sorted(p.name for p in tmp_path.iterdir()) == [first.name, second.name]
    assert _snapshot(first).keys() == _snapshot(second).keys()
    before = _snapshot(first)
    line = cli_error(*args, "--out", str(first))
    assert "holds an earlier self-calibration" in line
    assert "leave --out out" in line
    assert "--force" in line
    assert _snapshot(first) == before
    proc = run_cli(*args, "--no-verify", "--out", str(first), "--force")
    assert proc.returncode == 0, proc.stderr
    assert _snapshot(first).keys() == before.keys()


def test_the_readme_first_command_writes_no_tracked_file() -> None:
    """``umbmark demo`` in the repository writes into umbmark-demo/ (or -2, ...): not part
    of the repository, ignored by git."""
    import shutil
    import subprocess

    from umbmark.cli.demo import DEMO_FOLDER

    root = Path(__file__).resolve().parents[1]
    git = shutil.which("git")
    if git is None or not (root / ".git").exists():
        pytest.skip("not a git checkout")
    listed = [git, "ls-files", "--", DEMO_FOLDER]
    tracked = subprocess.run(listed, cwd=root, capture_output=True, text=True, check=True)
    assert tracked.stdout == ""
    for name in (f"{DEMO_FOLDER}/clusters.png", f"{DEMO_FOLDER}-2/result.json"):
        asked = [git, "check-ignore", "-q", "--no-index", name]
        ignored = subprocess.run(asked, cwd=root, check=False)
        assert ignored.returncode == 0, f"{name} is not ignored by git"


@pytest.mark.slow
def test_history_on_a_fresh_install_says_nothing_is_recorded(tmp_path: Path) -> None:
    """A fresh install (no $UMBMARK_HISTORY, an empty data folder): ``umbmark history``
    exits 0 saying that nothing is recorded yet and how to record, and creates nothing."""
    import os

    env = {k: v for k, v in os.environ.items() if k != "UMBMARK_HISTORY"}
    env["XDG_DATA_HOME"] = str(tmp_path / "data")
    proc = run_cli("history", env=env)
    assert proc.returncode == 0, proc.stderr
    expected = tmp_path / "data" / "umbmark" / "history.sqlite3"
    assert f"{expected}: nothing is recorded yet" in proc.stderr
    assert "--robot NAME" in proc.stderr
    listed = run_cli("history", "--json", env=env)
    assert '"robots": []' in listed.stdout
    assert "nothing is recorded yet" in listed.stdout
    assert sorted(tmp_path.iterdir()) == []
