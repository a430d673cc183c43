"""Every file umbmark writes is safe: never onto an input, all checked first, atomic.

Issue 10 ("Outputs"). Tests run as root too, so a folder that cannot be written is a
path whose parent is a regular file (which fails for root as well).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

import umbmark
from umbmark.core.atomic import atomic_path, atomic_write_text
from umbmark.outputs.files import OutputPlan, check_folder_output

from helpers import api_error, cli_error, run_cli

GEOMETRY = ("-b", "0.34", "-L", "4", "--unit", "mm")


@pytest.fixture
def runs(tmp_path: Path) -> Path:
    """The bundled example runs table, written into ``tmp_path``."""
    path = tmp_path / "runs.csv"
    umbmark.example(path)
    return path


def _calibrate(runs: Path, **outputs: Path | bool) -> umbmark.CalibrationReport:
    return umbmark.calibrate(runs, side_length=4, wheelbase=0.34, unit="mm", **outputs)


@pytest.mark.slow
def test_output_onto_input_refused_before_anything_written(runs: Path, tmp_path: Path) -> None:
    before = runs.read_bytes()
    line = cli_error("calibrate", str(runs), *GEOMETRY, "-o", str(runs))
    assert "would overwrite an input" in line
    assert runs.read_bytes() == before
    # also through a link, for any output, and with another output that alone is fine
    link = tmp_path / "link.yaml"
    link.symlink_to(runs)
    ok = tmp_path / "ok.json"
    line = cli_error("calibrate", str(runs), *GEOMETRY, "-o", str(ok), "--yaml", str(link))
    assert "--yaml" in line
    assert "would overwrite an input" in line
    assert not ok.exists()
    assert runs.read_bytes() == before


def test_output_inside_input_folder_refused(runs: Path, tmp_path: Path) -> None:
    folder = tmp_path / "src"
    folder.mkdir()
    runs.rename(folder / "runs.csv")
    message = api_error(_calibrate, folder, output=folder / "result.json")
    assert "inside an input folder" in message
    assert sorted(p.name for p in folder.iterdir()) == ["runs.csv"]


def test_simulate_output_onto_params_refused(runs: Path) -> None:
    message = api_error(umbmark.simulate, runs=2, output=runs, params=runs)
    assert "would overwrite an input" in message


def test_two_outputs_onto_one_path_refused(runs: Path, tmp_path: Path) -> None:
    same = tmp_path / "x.yaml"
    line = cli_error("calibrate", str(runs), *GEOMETRY, "-o", str(same), "--yaml", str(same))
    assert "both name" in line
    assert not same.exists()


def test_second_output_unwritable_leaves_first_unwritten(runs: Path, tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder\n")
    first = tmp_path / "result.json"
    line = cli_error(
        "calibrate", str(runs), *GEOMETRY, "-o", str(first), "--yaml", str(blocker / "x.yaml")
    )
    assert "cannot be written" in line
    assert not first.exists()
    # a missing folder, and an output folder under a file, are refused the same way
    assert "No such file or directory" in api_error(
        OutputPlan.of, yaml=tmp_path / "missing" / "x.yaml"
    )
    assert "cannot be written" in api_error(OutputPlan.of, tum=blocker / "tum")
    assert "not a folder" in api_error(check_folder_output, blocker)
    assert "is a directory" in api_error(OutputPlan.of, output=tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "runs.csv"]


def test_demo_folder_checked_before_computing(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    message = api_error(umbmark.demo, out=blocker / "demo", runs=2)
    assert "cannot be written" in message


def test_replace_keeps_permissions(runs: Path, tmp_path: Path) -> None:
    target = tmp_path / "result.json"
    target.write_text("old\n")
    target.chmod(0o600)
    _calibrate(runs, output=target, force=True)  # replacing is asked for
    assert stat.S_IMODE(target.stat().st_mode) == 0o600
    assert target.read_text() != "old\n"
    new = tmp_path / "new.json"
    atomic_write_text(new, "x")
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(new.stat().st_mode) == 0o666 & ~umask


def test_replace_follows_symlink_and_keeps_link(runs: Path, tmp_path: Path) -> None:
    real = tmp_path / "real"
    real.mkdir()
    target = real / "result.yaml"
    target.write_text("old\n")
    link = tmp_path / "link.yaml"
    link.symlink_to(target)
    _calibrate(runs, yaml=link, force=True)
    assert link.is_symlink()
    assert link.resolve() == target.resolve()
    assert "old" not in target.read_text()
    assert sorted(p.name for p in real.iterdir()) == ["result.yaml"]


@pytest.mark.parametrize("error", [KeyboardInterrupt, RuntimeError])
def test_temporary_file_removed_on_any_exception(
    tmp_path: Path, error: type[BaseException]
) -> None:
    target = tmp_path / "out.txt"
    target.write_text("old\n")

    def interrupted() -> None:
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise error

    with pytest.raises(error):
        interrupted()
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]
    assert target.read_text() == "old\n"


@pytest.mark.slow
def test_every_written_file_reported(runs: Path, tmp_path: Path) -> None:
    outputs = {
        "-o": tmp_path / "r.json",
        "--yaml": tmp_path / "o.yaml",
        "--ros1-yaml": tmp_path / "p.yaml",
        "--plot": tmp_path / "c.png",
    }
    args = [a for flag, path in outputs.items() for a in (flag, str(path))]
    proc = run_cli("calibrate", str(runs), *GEOMETRY, *args)
    assert proc.returncode == 0, proc.stderr
    for path in outputs.values():
        assert path.is_file()
        assert f"umbmark: wrote {path}\n" in proc.stderr
    assert "wrote" not in proc.stdout
    # piped: the long line of path and test is one line, not wrapped at 80 columns (the
    # verdict comes first)
    verdict, first = proc.stdout.splitlines()[:2]
    assert verdict == "Verdict: apply."
    assert first.startswith(f"UMBmark {runs}")
    assert "wheelbase" in first
    assert len(first) > 80
    logs, table = tmp_path / "logs", tmp_path / "sim.csv"
    proc = run_cli("simulate", "-n", "2", "-L", "1", "--logs", str(logs), "-o", str(table))
    assert proc.returncode == 0, proc.stderr
    assert f"umbmark: wrote {logs}\n" in proc.stderr
    assert f"umbmark: wrote {table}\n" in proc.stderr
    tum = tmp_path / "tum"
    proc = run_cli("calibrate", str(logs), "--tum", str(tum))
    assert proc.returncode == 0, proc.stderr
    assert f"umbmark: wrote {tum}\n" in proc.stderr
    assert any(tum.iterdir())


def test_piped_console_does_not_wrap(capsys: pytest.CaptureFixture[str]) -> None:
    from umbmark.cli.common import console

    value = "x" * 150
    console().print(f"result: {value} end")
    assert capsys.readouterr().out == f"result: {value} end\n"
