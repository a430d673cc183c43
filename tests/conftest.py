"""Fixtures shared by the tests."""

from __future__ import annotations

import signal
from collections.abc import Sequence
from pathlib import Path

import pytest

import umbmark

from dask_cluster import cluster  # noqa: F401 (a fixture: Dask started as processes)
from helpers import DemoCommand, run_cli, write_table


def pytest_configure(config: pytest.Config) -> None:
    """Ctrl-C reaches the tests' commands however pytest was started. A shell starts a
    command in the background (``pytest &``, ``nohup``, some CI runners) with SIGINT
    ignored, Python keeps it so, and every child inherits it through exec: the interrupt
    tests' real SIGINT would then do nothing. Python's own handler is set back; a child's
    SIGINT is then its default again."""
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture
def table(tmp_path: Path):
    """Factory: ``table(rows, header=...)`` writes a runs table and returns its path."""

    def make(
        rows: Sequence[Sequence[object]],
        header: str = "direction,x_abs,y_abs,x_odo,y_odo",
        name: str = "runs.csv",
    ) -> Path:
        return write_table(tmp_path / name, rows, header)

    return make


@pytest.fixture(scope="session")
def demo(tmp_path_factory: pytest.TempPathFactory) -> umbmark.DemoReport:
    """``umbmark.demo`` with its defaults (seed 1), its files in a folder of its own: one run
    for every test that reads the demo's result (do not write into its folder)."""
    return umbmark.demo(out=tmp_path_factory.mktemp("demo") / "demo")


@pytest.fixture(scope="session")
def demo_command(tmp_path_factory: pytest.TempPathFactory) -> DemoCommand:
    """``umbmark demo --out FOLDER`` (seed 1, as the library's :func:`demo` fixture): one run
    for every test of what the command prints and writes (do not write into its folder)."""
    out = tmp_path_factory.mktemp("demo-command") / "demo"
    proc = run_cli("demo", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    return DemoCommand(out, proc.stdout, proc.stderr)
