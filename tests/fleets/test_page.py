"""The fleet's page: self-contained, one row per usable robot with a plot per figure, the
flags where a robot changed, the robots with no usable recording and why."""

from __future__ import annotations

from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from umbmark.fleets.outcome import RecordingOutcome
from umbmark.fleets.page import fleet_page
from umbmark.fleets.summary import summarize

from fleet_tasks import daily_outcomes


class _Shape(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.tags: dict[str, int] = {}
        self.sources: list[str] = []

    def handle_starttag(self, tag, attrs):  # type: ignore[no-untyped-def]
        self.tags[tag] = self.tags.get(tag, 0) + 1
        self.sources += [v for k, v in attrs if k in ("src", "href") and v]


def test_the_page_shows_every_robot_its_plots_and_its_flags():
    rng = np.random.default_rng(9)
    outcomes = [
        *daily_outcomes("steady", 12, rng),
        *daily_outcomes("wheel", 12, rng, step_day=6, figure="E_d", jump=2e-3),
        RecordingOutcome("blind/a.mcap", "blind", None, 1.0, None, reason="no laser <b>"),
    ]
    page = fleet_page(summarize(outcomes), made="umbmark fleet fleet/")
    shape = _Shape()
    shape.feed(page)
    assert shape.sources == []  # self-contained: nothing loaded from elsewhere
    assert shape.tags["tr"] == 1 + 2  # the header and the two usable robots
    assert shape.tags["svg"] == 2 * 6  # each robot's six figures
    assert "E_d stepped by +0.002" in page
    assert "within its intervals" in page
    assert "blind/a.mcap: no laser &lt;b&gt;" in page  # escaped
    assert "umbmark fleet fleet/" in page
    assert page.count('class="changed"') == 1


@pytest.mark.slow
def test_the_page_in_headless_chromium(tmp_path: Path):
    """The page as a browser shows it: no error, every plot drawn with its points, the
    body never scrolling sideways (the wide table scrolls in its box), on a desk and a
    phone."""
    from test_report_command import Chromium

    rng = np.random.default_rng(9)
    outcomes = [
        *daily_outcomes("steady", 12, rng),
        *daily_outcomes("wheel", 12, rng, step_day=6, figure="E_d", jump=2e-3),
    ]
    page = tmp_path / "fleet.html"
    page.write_text(fleet_page(summarize(outcomes)), encoding="utf-8")
    browser = Chromium(tmp_path / "profile")
    try:
        for width, mobile in ((1200, False), (390, True)):
            browser.open(page, width, mobile=mobile)
            assert browser.errors() == []
            plots = browser.evaluate(
                "[...document.querySelectorAll('svg')].map(s => {const b = "
                "s.getBoundingClientRect(); return [b.width, b.height, "
                "s.querySelectorAll('circle').length]})"
            )
            assert len(plots) == 12
            assert all(w > 100 and h > 40 and n == 12 for w, h, n in plots), plots
            overflow = "document.documentElement.scrollWidth - document.documentElement.clientWidth"
            assert browser.evaluate(overflow) <= 0, width
            flagged = browser.evaluate("document.querySelectorAll('tr.changed').length")
            assert flagged == 1
    finally:
        browser.close()


def test_what_to_apply_is_the_present_state_and_offered_only_where_the_verdicts_let_it():
    """The overlay of the robot's present state (the mean of its steady calibrations: the
    outcomes' truth is E_b 0.98), keyed by its controller; a newest calibration whose
    verdict is do not apply is not part of the course and makes the rest "apply with
    care", said why; a robot whose every calibration failed its checks is offered nothing.
    The laser's mounting, the fleet's estimate of it, in the forms a user declares it (the
    outcomes' truth is 0.12 m forward, 22 mm off the 0.098 m stated here)."""
    import re
    from dataclasses import replace

    rng = np.random.default_rng(3)
    ok = daily_outcomes("ok", 4, rng)
    stated = {"x": 0.098, "y": 0.0, "yaw": 0.0, "lift": None, "source": "/tf_static"}
    record = {"controller": {"key_path": ["diff_cont"], "named": True},
              "mounting": {"base_frame": "base_link", "laser_frame": "scan_link",
                           "stated": stated, "z_roll_pitch_stated": False}}  # fmt: skip
    ok = [replace(o, record=record) for o in ok]
    bad = daily_outcomes("bad", 4, rng)
    why = {"level": "do-not-apply", "reasons": ["the runs scatter more than they err"]}
    bad[-1] = replace(bad[-1], verdict="do-not-apply", record={"verdict": why})
    worse = [replace(o, verdict="do-not-apply", record={"verdict": why})
             for o in daily_outcomes("worse", 2, rng)]  # fmt: skip
    summary = summarize([*ok, *bad, *worse])
    page = fleet_page(summary)
    overlays = re.findall(r"<pre>(.*?)</pre>", page, flags=re.S)
    (mine,) = [o for o in overlays if "diff_cont:" in o]
    sep = float(re.search(r"wheel_separation_multiplier: ([0-9.]+)", mine)[1])  # type: ignore[index]
    assert abs(sep - 0.98) < 4 * 3e-4 / 2  # the mean of four calibrations, se 3e-4 each
    assert "the mean of 4 recordings" in mine
    assert "failed its checks" in page  # bad's newest
    assert page.count("ros__parameters") == 2  # ok's and bad's (from its first three)
    assert "not used: bad/day03.mcap" in page
    assert summary.unusable == ("worse",)
    forms = {r.robot: r.mounting for r in summary.robots}
    assert forms["ok"] is not None
    assert forms["ok"].fitted.frame == "scan_link"
    assert "outside the fit&#x27;s 95 % interval in x" in page
    assert "--frame-id base_link --child-frame-id scan_link" in page
