"""Issue 16, "one room for each thing": each of these things is written once, in its room.

The reports' JSON text, the Fig. 6 cluster drawing, the simulator (no module over 600
lines), the reference loop the simulator is checked against (beside the tests), the
hostile-input corpus (data files, not code).
"""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import pytest

import umbmark

from helpers import ROOT

SRC = ROOT / "src" / "umbmark"


def _report_classes() -> list[type]:
    from umbmark.calibration.plan import PlanReport
    from umbmark.jobs.demo import DemoReport
    from umbmark.jobs.history import HistoryReport
    from umbmark.jobs.info import InfoReport
    from umbmark.jobs.replay import ReplayReport
    from umbmark.jobs.report import PassesReport
    from umbmark.jobs.reproduce import Fig4Report, Table1Report
    from umbmark.jobs.simulate import SimulationReport
    from umbmark.jobs.study import StudyReport
    from umbmark.outputs.calibration import CalibrationReport

    return [
        CalibrationReport,
        DemoReport,
        HistoryReport,
        InfoReport,
        PlanReport,
        ReplayReport,
        PassesReport,
        Fig4Report,
        Table1Report,
        SimulationReport,
        StudyReport,
    ]


def test_the_reports_json_text_is_written_once():
    from umbmark.core.jsontext import JsonText

    for cls in _report_classes():
        assert cls.to_json is JsonText.to_json, cls.__name__
    # and no module of the package writes another
    package = Path(umbmark.__file__).parent
    written = [
        p.relative_to(package) for p in package.rglob("*.py") if "def to_json" in p.read_text()
    ]
    assert written == [Path("core/jsontext.py")]


def test_the_json_text_is_strict_indented_and_ends_in_a_newline():
    from umbmark.core.jsontext import JsonText

    class Report(JsonText):
        def __init__(self, data: object) -> None:
            self.data = data

        def to_dict(self) -> object:
            return self.data

    assert Report({"a": [1, 2.5]}).to_json() == '{\n  "a": [\n    1,\n    2.5\n  ]\n}\n'
    with pytest.raises(ValueError, match="JSON compliant"):
        Report({"a": math.nan}).to_json()
    assert json.loads(Report({"b": None}).to_json()) == {"b": None}


def test_the_fig6_cluster_view_is_drawn_in_one_place():
    # the axes of every cluster figure (--plot, the HTML page) are labelled by one function
    hits = [
        path.relative_to(SRC).as_posix()
        for path in SRC.rglob("*.py")
        if "return error x [mm]" in path.read_text()
    ]
    assert hits == ["outputs/plotting.py"]


def test_no_simulator_module_over_600_lines():
    sizes = {p.name: len(p.read_text().splitlines()) for p in (SRC / "sim").glob("*.py")}
    assert max(sizes.values()) <= 600, sizes


def test_the_reference_loop_lives_beside_the_tests():
    assert importlib.util.find_spec("umbmark.sim.reference") is None
    assert (ROOT / "tests" / "reference_sim.py").is_file()


def test_the_hostile_corpus_is_data():
    from corpus_cases import CORPUS, corpus

    assert not (ROOT / "tools" / "hostile_corpus.py").exists()
    families = sorted(p.stem for p in Path(CORPUS).glob("*.yaml"))
    assert {"tables", "logs", "optiodom", "params", "results", "bags", "commands"} <= set(families)
    cases = corpus()
    assert len(cases) == 1248
    assert len({c.name for c in cases}) == len(cases)
