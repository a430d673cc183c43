"""The fleet's page: self-contained, one compact row per usable robot (its flags, its
E_max,syst and what to apply in view, the overlay folded with a way to copy it), a plot per
figure with its time axis (the first and last day, the change's day marked), the failed
recordings and the robots with no usable recording listed and counted. Checked in the
markup, and in headless Chromium as a person sees it (``fleet_page_view``)."""

from __future__ import annotations

import datetime as dt
import re
from dataclasses import replace
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from umbmark.fleets.outcome import RecordingOutcome
from umbmark.fleets.page import fleet_page
from umbmark.fleets.summary import summarize

from fleet_page_view import inside, plot_of, rows_as_seen
from fleet_tasks import T0, daily_outcomes


class _Shape(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.tags: dict[str, int] = {}
        self.sources: list[str] = []
        self.scripts: list[dict[str, str | None]] = []

    def handle_starttag(self, tag, attrs):  # type: ignore[no-untyped-def]
        self.tags[tag] = self.tags.get(tag, 0) + 1
        self.sources += [v for k, v in attrs if k in ("src", "href") and v]
        if tag == "script":
            self.scripts.append(dict(attrs))


def _day(k: int) -> str:
    """Day ``k`` of the outcomes (T0 is 2026-09-21 14:13 UTC), as the page writes it."""
    return (dt.date(2026, 9, 21) + dt.timedelta(days=k)).isoformat()


def _fleet() -> list[RecordingOutcome]:
    """Three robots of twelve daily calibrations (steady; E_d stepped from day 6; the
    laser's yaw from day 7), the wheel robot with one recording that failed, and a robot
    whose one recording was left out and other failed: 39 recordings, 36 calibrated."""
    rng = np.random.default_rng(9)
    wheel = daily_outcomes("wheel", 12, rng, step_day=6, figure="E_d", jump=2e-3)
    return [
        *daily_outcomes("steady", 12, rng),
        *wheel,
        *daily_outcomes("laser", 12, rng, step_day=7, figure="laser_yaw", jump=0.03),
        RecordingOutcome("wheel/day12.mcap", "wheel", None, 0.0, None,
                         reason="wheel/day12.mcap: cannot read the bag: File magic is invalid.",
                         failed=True),
        RecordingOutcome("blind/a.mcap", "blind", T0, 1.0, None, reason="no laser <b>"),
        RecordingOutcome("blind/b.mcap", "blind", None, 0.0, None, reason="cannot be read",
                         failed=True),
    ]  # fmt: skip


def test_the_page_shows_every_robot_its_plots_its_flags_and_its_failures():
    page = fleet_page(summarize(_fleet()), made="umbmark fleet fleet/")
    shape = _Shape()
    shape.feed(page)
    # Self-contained: nothing loaded from elsewhere, links only within the page, its one
    # script inline.
    assert all(s.startswith("#") for s in shape.sources), shape.sources
    assert [s.get("src") for s in shape.scripts] == [None]
    assert page.count('<section class="robot') == 3  # the usable robots
    assert page.count('<section class="robot changed"') == 2
    assert shape.tags["svg"] == 3 * 6  # each robot's six figures
    # Every plot's time axis: the first and the last day; the change's day marked.
    assert page.count(f">{_day(0)}</text>") == page.count(f">{_day(11)}</text>") == 18
    assert re.findall(r'<text class="since"[^>]*>([^<]*)</text>', page) == [_day(7), _day(6)]
    assert "within its intervals" in page
    assert "umbmark fleet fleet/" in page
    # Counted: the wheel robot has the recordings it has; the fleet's line counts them.
    assert "13 recordings (12 calibrated, 1 failed)" in page
    assert (
        "4 robots: 2 changed beyond their intervals, 1 with no usable recording; 39 "
        "recordings: 36 calibrated, 1 left out, 2 failed" in page
    )
    # Listed: the failed recordings with their reasons (the path once), the robot with
    # no usable recording with why (escaped).
    assert "Failed recordings (2)" in page
    assert page.count("wheel/day12.mcap: cannot read the bag") == 1
    assert "blind/b.mcap: cannot be read" in page
    assert "blind/a.mcap: no laser &lt;b&gt;" in page
    assert "1 failed (listed above)" in page
    # Each overlay folded, with its copy button (hidden until the script shows it): the
    # present state's multipliers (the outcomes' truth: E_b 0.98, E_d 1.003, stepped by
    # 0.002 for the wheel robot; twelve calibrations or six since the step), keyed by the
    # controller the latest recording names (the default where none).
    folded = re.findall(
        r"<details><summary>the overlay for the controller \(YAML\)</summary>"
        r'<pre id="([^"]+)">([^<]*)</pre><button type="button" class="copy" data-for="\1" '
        r"hidden>copy</button></details>",
        page,
    )
    assert len(folded) == 3
    for (_, text), E_d in zip(folded, (1.003, 1.003, 1.005), strict=True):  # laser, steady, wheel
        value = {k: float(v) for k, v in re.findall(r"(\w+_multiplier): ([0-9.]+)", text)}
        assert abs(value["wheel_separation_multiplier"] - 0.98) < 4 * 3e-4 / 6**0.5
        ratio = value["right_wheel_radius_multiplier"] / value["left_wheel_radius_multiplier"]
        assert abs(ratio - E_d) < 4 * 1e-4 / 6**0.5
        assert "diff_drive_controller:" in text
    assert "E_d: the 6 recordings since its step on 2026-09-27" in folded[2][1]


def _click(browser, selector: str) -> None:  # type: ignore[no-untyped-def]
    """A person's click at the middle of the element (scrolled into view first)."""
    x, y = browser.evaluate(
        f"(() => {{const e = document.querySelector({selector!r}); e.scrollIntoView("
        "{block: 'center'}); const b = e.getBoundingClientRect(); "
        "return [b.left + b.width / 2, b.top + b.height / 2]})()"
    )
    for kind in ("mousePressed", "mouseReleased"):
        browser.call("Input.dispatchMouseEvent", type=kind, x=x, y=y, button="left",
                     clickCount=1)  # fmt: skip


_OVERFLOW = "document.documentElement.scrollWidth - document.documentElement.clientWidth"
_BOX = (
    "(() => {const b = document.querySelector(%r).getBoundingClientRect(); "
    "return [b.left, b.top, b.right, b.bottom]})()"
)


@pytest.mark.slow
def test_the_page_as_a_person_sees_it_on_a_desk_and_a_phone(tmp_path: Path):
    """At 1280 and 390 px: each robot one compact row wholly in view (name, flags,
    E_max,syst, what to apply drawn inside it), nothing scrolling sideways; each plot's
    first and last day under it, the change's mark drawn at the day it changed; the
    summary line at the top counting the failed recordings, and those listed."""
    from test_report_command import Chromium

    page = tmp_path / "fleet.html"
    page.write_text(fleet_page(summarize(_fleet())), encoding="utf-8")
    browser = Chromium(tmp_path / "profile")
    try:
        seen = rows_as_seen(browser, page)
        for width, rows in seen.items():
            assert [r["robot"] for r in rows] == ["laser", "steady", "wheel"], width
            by = {r["robot"]: r for r in rows}
            assert by["steady"]["flags"] == []
            assert by["wheel"]["flags"]
            assert by["laser"]["flags"]
            assert "apply" in by["wheel"]["apply"]
            for row in rows:
                for plot in row["plots"]:
                    assert plot["days"] == [_day(0), _day(11)], (width, plot)
            changed = {(r["robot"], p["caption"][:4]) for r in rows for p in r["plots"]
                       if p["since"]}  # fmt: skip
            assert changed == {("wheel", "E_d "), ("laser", "lase")}
            for robot, label, k in (("wheel", "E_d", 6), ("laser", "laser yaw", 7)):
                plot = plot_of(by[robot], label)
                assert plot["since"] == [_day(k)]
                assert plot["since_x"][0] == pytest.approx(plot["points_x"][k], abs=0.2)
            # The summary line at the top, in view; the failed recordings listed.
            browser.evaluate("window.scrollTo(0, 0)")
            assert inside(browser.evaluate(_BOX % ".summary"), width, 844), width
            assert "2 failed" in browser.evaluate("document.querySelector('.summary').innerText")
            items = browser.evaluate("[...document.querySelectorAll('#failed + p + ul li')]"
                                     ".map(li => li.innerText)")  # fmt: skip
            assert items == [  # by robot
                "blind: blind/b.mcap: cannot be read",
                "wheel: wheel/day12.mcap: cannot read the bag: File magic is invalid.",
            ]
    finally:
        browser.close()


@pytest.mark.slow
def test_the_overlay_is_folded_and_copied_with_a_script_or_without(tmp_path: Path):
    """Folded (not shown) until its summary is clicked; then inside the view,
    and its copy button puts it on the clipboard whole. Without scripts the button is not
    shown, and a click on the overlay selects it whole, to copy."""
    from test_report_command import Chromium

    page = tmp_path / "fleet.html"
    summary = summarize(_fleet())
    page.write_text(fleet_page(summary), encoding="utf-8")
    wheel = {r.robot: r for r in summary.robots}["wheel"].apply
    assert wheel is not None
    overlay = str(wheel.overlay).strip()  # the text the page holds, as a person copies it
    browser = Chromium(tmp_path / "profile")
    pre = "section.robot:nth-of-type(3) .apply details pre"
    try:
        browser.call("Browser.grantPermissions",
                     permissions=["clipboardReadWrite", "clipboardSanitizedWrite"])  # fmt: skip
        for width, height, mobile in ((1280, 900, False), (390, 844, True)):
            browser.open(page, width, height, mobile=mobile)
            assert browser.evaluate(f"document.querySelector({pre!r}).checkVisibility()") is False
            _click(browser, pre.replace(" pre", " summary"))
            assert inside(browser.evaluate(_BOX % pre), width, height), width
            wide = f"(e => e.scrollWidth - e.clientWidth)(document.querySelector({pre!r}))"
            assert browser.evaluate(wide) <= 0, width  # every line seen whole, wrapped
            assert browser.evaluate(_OVERFLOW) <= 0, width
            button = pre.replace(" pre", " button.copy")
            _click(browser, button)
            copied = browser.call("Runtime.evaluate", expression="navigator.clipboard.readText()",
                                  awaitPromise=True, returnByValue=True)  # fmt: skip
            assert copied["result"]["value"] == overlay
            assert browser.evaluate(f"document.querySelector({button!r}).textContent") == "copied"
            assert browser.errors() == []
        browser.call("Emulation.setScriptExecutionDisabled", value=True)
        browser.open(page, 390, 844, mobile=True)
        assert browser.evaluate("document.querySelectorAll('button.copy').length") == 6
        hidden = "[...document.querySelectorAll('button.copy')].every(b => b.offsetWidth == 0)"
        assert browser.evaluate(hidden) is True
        _click(browser, pre.replace(" pre", " summary"))
        _click(browser, pre)
        assert browser.evaluate("getSelection().toString()") == overlay
    finally:
        browser.close()


def test_what_to_apply_is_the_present_state_and_offered_only_where_the_verdicts_let_it():
    """The overlay of the robot's present state (the mean of its steady calibrations: the
    outcomes' truth is E_b 0.98), keyed by its controller; a newest calibration whose
    verdict is do not apply is not part of the course and makes the rest "apply with
    care", said why; a robot whose every calibration failed its checks is offered nothing.
    The laser's mounting, the fleet's estimate of it, in the forms a user declares it (the
    outcomes' truth is 0.12 m forward, 22 mm off the 0.098 m stated here)."""
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
    overlays = re.findall(r"<pre[^>]*>(.*?)</pre>", page, flags=re.S)
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
