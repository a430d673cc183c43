"""Every example of the reference pages (docs/*.md) runs as written, twice in a row in one
folder, as a user trying it again (or a notebook's cells run again) does.

A page's fenced ``bash`` blocks run command by command, in order, in one folder; its
``python`` blocks run together as one script (one session, as a notebook's cells: a later
block uses what an earlier one made). A block that cannot run as it stands (the user's own
bag, a ROS robot) carries ``<!-- not run: REASON -->`` on the line before it, as in the
README (``tests/test_readme.py``, whose block parser this uses).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from test_readme import SHELLS, Block, blocks, commands

from helpers import ROOT, umbmark_command

DOCS = ROOT / "docs"
#: Pages whose examples take more than a few seconds (self-calibrations, simulations, a
#: fleet on its local cluster, scan matching, a simulated bag with an IMU read back).
SLOW_PAGES = {
    "selfcal.md",
    "commands.md",
    "recorded.md",
    "fleet.md",
    "scan-matching.md",
    "recordings.md",
}


def _runnable(page: Path) -> list[Block]:
    return [
        b
        for b in blocks(page.read_text(encoding="utf-8"))
        if (b.lang in SHELLS or b.lang == "python") and not b.note.startswith("not run")
    ]


def _pages() -> list[Path]:
    return [page for page in sorted(DOCS.glob("*.md")) if _runnable(page)]


def _environment() -> dict[str, str]:
    bin_dir = str(Path(umbmark_command()).parent)
    env = {**os.environ, "PATH": os.pathsep.join([bin_dir, os.environ.get("PATH", "")])}
    env.pop("UMBMARK_HISTORY", None)
    return env


def _run_page(page: Path, folder: Path) -> None:
    env = {**_environment(), "UMBMARK_HISTORY": str(folder / "history.sqlite3")}
    mine = _runnable(page)
    for block in (b for b in mine if b.lang in SHELLS):
        for command in commands(block.body):
            proc = subprocess.run(
                ["bash", "-c", "set -euo pipefail\n" + command],
                cwd=folder, env=env, capture_output=True, text=True, timeout=300, check=False,
            )  # fmt: skip
            assert proc.returncode == 0, f"{page.name}: {command}\n{proc.stdout}\n{proc.stderr}"
            assert "Traceback" not in proc.stderr, proc.stderr
    script = "\n".join(b.body for b in mine if b.lang == "python")
    if script:
        proc = subprocess.run(
            [sys.executable, "-c", script],
            cwd=folder, env=env, capture_output=True, text=True, timeout=300, check=False,
        )  # fmt: skip
        assert proc.returncode == 0, f"{page.name}:\n{script}\n{proc.stdout}\n{proc.stderr}"


def test_the_pages_have_examples_to_run():
    names = {page.name for page in _pages()}
    assert {"selfcal.md", "planning.md", "recorded.md", "commands.md"} <= names
    assert names >= SLOW_PAGES


@pytest.mark.parametrize(
    "page",
    [
        pytest.param(p, id=p.name, marks=[pytest.mark.slow] if p.name in SLOW_PAGES else [])
        for p in _pages()
    ],
)
def test_every_example_of_the_page_runs_twice_in_one_folder(page: Path, tmp_path: Path):
    _run_page(page, tmp_path)
    _run_page(page, tmp_path)
