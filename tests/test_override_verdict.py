"""``--force`` replaces files, nothing else; ``--override-verdict`` overrides a verdict
(issue 21, item 2: one meaning each).

Before the split, ``calibrate --force`` given only to replace ``result.json`` also wrote
the overlay of a calibration whose verdict is "do not apply". The table: the bundled
example with every cw and ccw label swapped, whose model check fails strongly (the
clusters sit 307 mm and 90 mm from the model's nearest robot, with a scatter of ~25 mm),
so its verdict is "do not apply" whatever the flags.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import umbmark

from helpers import run_cli

ARGS = ("-L", "4", "-b", "0.34", "--unit", "mm")


@pytest.fixture(scope="module")
def swapped(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The bundled example with every cw label made ccw and every ccw label cw."""
    folder = tmp_path_factory.mktemp("swapped")
    lines = umbmark.example().splitlines()
    swap = {"cw": "ccw", "ccw": "cw"}
    out = []
    for line in lines:
        label, sep, rest = line.partition(",")
        out.append(f"{swap[label]}{sep}{rest}" if label in swap else line)
    assert sum(line.startswith("cw,") for line in out) == 5  # the example's 5 + 5 runs
    path = folder / "swapped.csv"
    path.write_text("\n".join(out) + "\n")
    return path


def test_force_replaces_the_result_but_writes_no_overlay(swapped: Path, tmp_path: Path):
    result, overlay = tmp_path / "result.json", tmp_path / "overlay.yaml"
    result.write_text("an earlier result\n")
    proc = run_cli("calibrate", str(swapped), *ARGS, "--force", "-o", str(result),
                   "--yaml", str(overlay))  # fmt: skip
    # The result is valid and written, the overlay withheld with a warning, and the exit
    # status says "do not apply" (4), so that a script can tell (docs/commands.md).
    assert proc.returncode == 4, proc.stderr
    data = json.loads(result.read_text())  # replaced: the old text is no JSON
    assert data["verdict"]["level"] == "do-not-apply"
    assert not overlay.exists()
    assert proc.stdout.startswith("Verdict: do not apply: the model check fails strongly")
    assert "ros__parameters" not in proc.stdout
    assert (
        "No ros2_control overlay: the verdict is do not apply (--override-verdict prints "
        "and writes it)."
    ) in proc.stdout
    assert (
        "umbmark: warning: --yaml not written: the verdict is do not apply "
        "(--override-verdict writes it; --force only replaces files that exist)\n"
    ) in proc.stderr
    assert f"umbmark: wrote {result}\n" in proc.stderr
    assert f"wrote {overlay}" not in proc.stderr


@pytest.mark.slow
def test_the_override_writes_the_overlay(swapped: Path, tmp_path: Path):
    result, overlay = tmp_path / "result.json", tmp_path / "overlay.yaml"
    proc = run_cli("calibrate", str(swapped), *ARGS, "--override-verdict", "-o", str(result),
                   "--yaml", str(overlay))  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "ros__parameters" in proc.stdout
    text = overlay.read_text()
    assert "# Verdict: do not apply: " in text
    assert "wheel_separation_multiplier" in text
    assert json.loads(result.read_text())["verdict"]["level"] == "do-not-apply"
    # The override replaces nothing: a second run onto the same files is refused.
    again = run_cli("calibrate", str(swapped), *ARGS, "--override-verdict", "-o", str(result))
    assert again.returncode == 2
    assert again.stderr == f"umbmark: error: {result}: exists already; pass --force to replace it\n"


def test_the_library_keeps_the_two_apart(swapped: Path, tmp_path: Path):
    result, overlay = tmp_path / "result.json", tmp_path / "overlay.yaml"
    result.write_text("an earlier result\n")
    report = umbmark.calibrate(swapped, side_length=4, wheelbase=0.34, unit="mm",
                               output=result, yaml=overlay, force=True)  # fmt: skip
    assert report.withheld == ("yaml",)
    assert report.overlay_withheld
    assert not overlay.exists()
    assert json.loads(result.read_text())["verdict"]["level"] == "do-not-apply"
    with pytest.raises(umbmark.InputError, match="override_verdict=True writes it"):
        report.write(yaml=overlay, force=True)
    assert not overlay.exists()
    assert report.write(yaml=overlay, override_verdict=True) == [overlay]
