"""The hostile-input corpus (tests/corpus/, run by tests/corpus_runner.py) in CI: its
classifier, and a fast subset of its cases run as a user runs them.

The classifier is checked on outcomes written by hand, one per class, so that each class
can be told apart. The subset takes one or two cases per reader and class of hostility
from the corpus, runs ``python -m umbmark ...`` under the corpus' wall-time and 1 GB
address-space limits, and asserts what the corpus asserts: a result or one clean error
line, never a traceback, a hang or memory beyond the limit, and the refusal or warning
each known-wrong case needs.
"""

from __future__ import annotations

import pytest

pytest.importorskip("rosbags")

import corpus_cases
import corpus_runner as corpus_tool

Case, Outcome, classify = corpus_tool.Case, corpus_tool.Outcome, corpus_tool.classify


# --- the classifier -------------------------------------------------------------------


def _case(expect: str = "any", argv: tuple[str, ...] = ("calibrate", "x.csv"), **kw) -> Case:
    return Case("c", "table", list(argv), expect=expect, **kw)


@pytest.mark.parametrize(
    ("case", "outcome", "klass"),
    [
        (_case(), Outcome(0, "E_max,syst = 3.1 mm\n", "umbmark: wrote r.json\n", 0.1), "ok-result"),
        (_case(), Outcome(2, "", "umbmark: error: x.csv, row 3: bad\n", 0.1), "clean-error"),
        (
            _case(),
            Outcome(2, "", "umbmark: warning: shaky\numbmark: error: x.csv: bad\n", 0.1),
            "clean-error",
        ),
        (
            _case(),
            Outcome(3, "", "umbmark: error: /out: No space left on device\n", 0.1),
            "clean-error",
        ),
        (
            _case(),
            Outcome(1, "", 'Traceback (most recent call last):\n  File "x"\nValueError\n', 0.1),
            "traceback",
        ),
        (
            _case(),
            Outcome(70, "", "umbmark: error: internal error (KeyError: 'x'); ...\n", 0.1),
            "traceback",
        ),
        (_case(), Outcome(1, "", "", 0.1), "traceback"),
        (_case(), Outcome(-11, "", "", 0.1), "traceback"),
        (_case(), Outcome(None, "", "", 60.0), "hang"),
        (
            _case(),
            Outcome(3, "", "umbmark: error: out of memory: the input is too large\n", 0.1),
            "memory",
        ),
        (_case(), Outcome(-9, "", "", 3.0), "memory"),
        (_case(), Outcome(1, "", "MemoryError\n", 3.0), "memory"),
        (
            _case(),
            Outcome(2, "", "Usage: umbmark calibrate\nTry -h\n\nError: bad\n", 0.1),
            "unclean",
        ),
        (_case(), Outcome(0, "", "RuntimeWarning: overflow encountered\n", 0.1), "unclean"),
        (_case(), Outcome(2, "", "umbmark: error: a\numbmark: error: b\n", 0.1), "unclean"),
        (_case("error"), Outcome(0, "done\n", "", 0.1), "wrong-result"),
        (_case("warn"), Outcome(0, "done\n", "", 0.1), "wrong-result"),
        (_case("warn"), Outcome(0, "", "umbmark: warning: run 3 label\n", 0.1), "ok-result"),
        (
            _case("warn", warn=("run-03",)),
            Outcome(0, "", "umbmark: warning: other\n", 0.1),
            "wrong-result",
        ),
        (_case("warn"), Outcome(2, "", "umbmark: error: x.csv: refused\n", 0.1), "clean-error"),
        (_case("ok"), Outcome(2, "", "umbmark: error: x.csv: refused\n", 0.1), "refused-valid"),
        (_case("do-not-apply"), Outcome(4, "Verdict: do not apply: ...\n", "", 0.1), "ok-result"),
        (_case("do-not-apply"), Outcome(0, "Verdict: apply.\n", "", 0.1), "wrong-result"),
        (
            _case("do-not-apply"),
            Outcome(2, "", "umbmark: error: x.bag: refused\n", 0.1),
            "refused-valid",
        ),
        (_case(argv=("simulate", "--json")), Outcome(0, '{"E_d": NaN}', "", 0.1), "wrong-result"),
        (_case(argv=("simulate", "--json")), Outcome(0, '{"E_d": 1.0}', "", 0.1), "ok-result"),
        (_case(stdout="head"), Outcome(1, "", "", 0.1), "ok-result"),
        (
            _case(stdout="head"),
            Outcome(120, "", "Exception ignored in: <_io.TextIOWrapper name='<stdout>'>\n", 0.1),
            "traceback",
        ),
        (
            _case(stdout="head"),
            Outcome(1, "", "Exception ignored in: <_io.TextIOWrapper name='<stdout>'>\n", 0.1),
            "unclean",
        ),
    ],
)
def test_classify(case, outcome, klass):
    assert classify(case, outcome)[0] == klass


def test_output_checks_make_a_wrong_result(tmp_path):
    (tmp_path / "link.json").symlink_to("elsewhere.json")
    kept = _case(check=corpus_cases.still_link("link.json"))
    assert classify(kept, Outcome(0, "", "", 0.1), tmp_path)[0] == "ok-result"
    (tmp_path / "link.json").unlink()
    (tmp_path / "link.json").write_text("{}")
    assert classify(kept, Outcome(0, "", "", 0.1), tmp_path)[0] == "wrong-result"


def test_a_refusal_that_changed_a_file_is_a_wrong_result(tmp_path):
    # the bytes the setup left, by their digest: a JSON result kept as it was (the check
    # once took any file not starting with "#" for overwritten, and never ran on refusals)
    (tmp_path / "r.json").write_text("{}")
    before = {"r.json": corpus_cases.digest(tmp_path / "r.json")}
    case = _case("error", check=corpus_cases.unchanged("r.json"))
    refused = Outcome(2, "", "umbmark: error: r.json: exists already\n", 0.1, before=before)
    assert classify(case, refused, tmp_path)[0] == "clean-error"
    (tmp_path / "r.json").write_text('{"E_d": 1.0}')
    assert classify(case, refused, tmp_path)[0] == "wrong-result"


def test_the_corpus_covers_every_reader_and_command():
    cases = corpus_tool.corpus()
    assert len(cases) >= 500
    assert len({c.name for c in cases}) == len(cases)
    readers = {c.reader for c in cases}
    assert {"table", "runlog", "optiodom", "bag", "params", "result", "outputs"} <= readers
    commands = {c.argv[0] for c in cases}
    assert {
        "demo",
        "calibrate",
        "replay",
        "validate",
        "info",
        "plan",
        "simulate",
        "study",
        "reproduce",
        "example",
        "history",
    } <= commands
    argv = [" ".join(c.argv) for c in cases]
    for fragment in ("bag_ros1.bag", "bag_sqlite3", "bag_mcap", "custom_mcap", "--msg-dir"):
        assert any(fragment in a for a in argv), fragment


# --- a fast subset, run for real --------------------------------------------------------

SUBSET = [
    "table-valid-csv",
    "table-mixed-units",
    "table-heading-rad-as-deg",
    "table-label-swapped",
    "log-run-misspelt-header",
    "table-cell-arabic-indic",
    "table-cell-130kb",
    "table-encoding-utf-16",
    "path-symlink-loop",
    "path-dev-zero",
    "path-unreadable-file",
    "out-dev-full-json",
    "out-broken-pipe",
    "out-ascii-terminal",
    "out-onto-input",
    "log-run-utf-16",
    "log-meta-mapping-bomb",
    "log-run-counts-zero",
    "optiodom-meta-encres-1e-300",
    "params-ros2-wheel_separation-nan",
    "params-deep-flow",
    "result-deep",
    "result-other-robot",
    "bag-mcap-wheel-type-string",
    "bag-ros1-truncated-0.5",
    "bag-sqlite3-positions-1e300",
    "cmd-simulate-turn-0-json",
    "cmd-simulate-logs-existing",
    "opt-current-c-l-1e300",
    # found by the corpus and fixed with it
    "path-fifo",
    "log-meta-deep-flow",
    "bag-sqlite3-metadata-deep",
    "log-run-cell-huge",
    "optiodom-run-cell-underscore",
    "params-dev-zero",
    "result-dev-zero",
    "bag-ros1-opt--left-joint=,,,",
    "bag-mcap-opt--tf-parent=map",
]


@pytest.fixture(scope="module")
def corpus_dirs(tmp_path_factory):
    root = tmp_path_factory.mktemp("corpus")
    base = root / "_base"
    corpus_tool.build_base(base)
    return root, base


@pytest.fixture(scope="module")
def modes(tmp_path_factory) -> bool:
    return corpus_tool.modes_apply(tmp_path_factory.mktemp("modes"))


CASES = {c.name: c for c in corpus_tool.corpus()}


#: The subset's cases that take about half a second or more (bags, deep files): in the
#: full suite only (the whole corpus runs there too).
SLOW_SUBSET = {
    "bag-sqlite3-positions-1e300", "bag-ros1-truncated-0.5", "bag-mcap-wheel-type-string",
    "params-deep-flow", "log-run-counts-zero", "log-run-cell-huge", "log-meta-deep-flow",
    "result-other-robot", "bag-sqlite3-metadata-deep", "bag-mcap-opt--tf-parent=map",
}  # fmt: skip


@pytest.mark.parametrize(
    "name",
    [pytest.param(n, marks=pytest.mark.slow) if n in SLOW_SUBSET else n for n in SUBSET],
)
def test_corpus_case(name, corpus_dirs, modes):
    case = CASES[name]
    if case.needs_modes and not modes:
        pytest.skip("file modes do not apply to this process (root with CAP_DAC_OVERRIDE)")
    root, base = corpus_dirs
    verdict = corpus_tool.run_case(case, root / "cases", base, timeout=60.0)
    assert verdict.klass in ("ok-result", "clean-error"), (
        f"{verdict.klass}: {verdict.detail}\n$ {verdict.command}\n{verdict.outcome.stderr[-2000:]}"
    )
    if case.expect in ("error", "warn") and verdict.klass == "ok-result":
        assert "umbmark: warning:" in verdict.outcome.stderr
    if case.expect == "error":
        assert verdict.klass == "clean-error", verdict.outcome.stderr


@pytest.mark.slow
def test_the_whole_corpus(tmp_path):
    """Every case of the corpus (7 minutes on one core): never a traceback, a hang, memory
    beyond the limit or stray stderr, and no wrong result."""
    import os

    verdicts, _ = corpus_tool.run_corpus(corpus_tool.corpus(), tmp_path, jobs=os.cpu_count() or 1)
    bad = [
        f"{v.klass} {v.case.name}: {v.detail}"
        for v in verdicts
        if v.klass not in ("ok-result", "clean-error")
    ]
    assert not bad, "\n".join(bad)


# --- the plausibility the corpus asked for, through the library -------------------------


def _drive(n: int = 400, dt: float = 0.01):
    """A robot driving straight at 0.5 m/s: wheel angles [rad] and true poses, by hand."""
    import numpy as np

    time = np.arange(n) * dt
    angles = np.column_stack([time * 6.0, time * 6.0])
    truth = np.column_stack([time * 0.5, np.zeros(n), np.zeros(n)])
    return time, angles, truth


def test_a_ground_truth_that_jumps_is_refused():
    from umbmark.core.errors import InputError
    from umbmark.runs.logged import check_motion

    time, angles, truth = _drive()
    check_motion("run", time, angles, truth)  # 5 mm a sample: plausible
    truth[200, 0] = 1000.0  # one cell in millimetres (or "1_000" read as a number)
    with pytest.raises(InputError, match=r"jumps by 999 m .* at 2\.00 s"):
        check_motion("run", time, angles, truth)


def test_a_tracking_gap_is_not_a_jump():
    """2 s without ground truth, 2 m driven meanwhile: 1 m/s, not a jump."""
    import numpy as np

    from umbmark.runs.logged import check_motion

    time, angles, truth = _drive(n=600)
    truth[100:300] = np.nan
    truth[300:, 0] += 1.0  # the robot went on faster while the tracker lost it
    check_motion("run", time, angles, truth)
