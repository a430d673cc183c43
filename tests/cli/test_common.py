"""What every command shares: the plain progress lines of a log (stderr not a terminal)."""

from __future__ import annotations

import pytest

from umbmark.cli.common import progress_lines


class Clock:
    """A wall clock the test sets [s]."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _said(capsys: pytest.CaptureFixture[str]) -> list[str]:
    return capsys.readouterr().err.splitlines()


def test_a_line_at_each_step_when_steps_are_rare(capsys: pytest.CaptureFixture[str]) -> None:
    clock = Clock()
    line = progress_lines(10.0, clock)
    for done, at in ((1, 12.0), (2, 25.0), (3, 40.0)):
        clock.now = at
        line(done, 3, f"{done} of 3")
    assert _said(capsys) == [f"umbmark: progress: {k} of 3" for k in (1, 2, 3)]


def test_at_most_a_line_every_period_but_always_the_last(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Steps every 3 s, a line at most every 10 s: the first step (t = 3 s), then the first
    step 10 s or more after the last line (t = 15 s, 27 s), and the last step (t = 30 s)
    though only 3 s after."""
    clock = Clock()
    line = progress_lines(10.0, clock)
    for done in range(1, 11):
        clock.now = 3.0 * done
        line(done, 10, f"{done} of 10")
    assert _said(capsys) == [f"umbmark: progress: {k} of 10" for k in (1, 5, 9, 10)]


def test_no_line_when_nothing_more_is_done(capsys: pytest.CaptureFixture[str]) -> None:
    """At each step (period 0, as selfcal's runs): a call that reports no more done than the
    last (the routine's plan changed, not its runs) says nothing."""
    line = progress_lines()
    line(0, 10, "0 of 10")
    line(1, 10, "1 of 10")
    line(1, 20, "1 of 20")
    line(2, 20, "2 of 20")
    assert _said(capsys) == ["umbmark: progress: 1 of 10", "umbmark: progress: 2 of 20"]
