"""The public API as a notebook user meets it: names, keywords, the README's example."""

from __future__ import annotations

import dataclasses
import json
import os
import re
import subprocess
import sys

import pytest

import umbmark
from umbmark.jobs.inputs import ReadOptions, SourceOptions

from helpers import ROOT


def test_every_public_name_resolves():
    for name in umbmark.__all__:
        assert getattr(umbmark, name) is not None, name
    assert set(umbmark.__all__) <= set(dir(umbmark))
    with pytest.raises(AttributeError):
        _ = umbmark.calibrat  # type: ignore[attr-defined]


def test_source_options_are_the_read_options():
    """The keywords a type checker knows (SourceOptions) are the ones the jobs accept."""
    assert set(SourceOptions.__annotations__) == {f.name for f in dataclasses.fields(ReadOptions)}


def test_readme_python_example_runs_as_written(tmp_path, monkeypatch):
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme.split("## Use from Python")[1].split("\n## ")[0]
    (code,) = re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})
    for name in ("runs.csv", "clusters.png", "result.json", "overlay.yaml"):
        assert (tmp_path / name).stat().st_size > 0, name
    result = json.loads((tmp_path / "result.json").read_text())
    assert (
        result == umbmark.calibrate("runs.csv", side_length=4, wheelbase=0.34, unit="mm").to_dict()
    )


def test_reports_serialize_to_what_they_hold(table):
    rows = [("cw", 0.1, 0.05, 0, 0)] * 2 + [("ccw", 0.12, -0.04, 0, 0), ("ccw", 0.13, -0.05, 0, 0)]
    report = umbmark.calibrate(table(rows), side_length=4, wheelbase=0.34)
    assert json.loads(report.to_json()) == report.to_dict()
    sim = umbmark.simulate(runs=2, noise_free=True)
    assert json.loads(sim.to_json()) == sim.to_dict()


def test_python_dash_m_is_the_command():
    proc = subprocess.run(
        [sys.executable, "-m", "umbmark", "--version"],
        capture_output=True,
        text=True,
        check=False,
        env={**os.environ},
    )
    assert proc.stdout == f"umbmark {umbmark.__version__}\n"
