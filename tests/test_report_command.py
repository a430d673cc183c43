"""``umbmark report``: UMBmark passes on one robot as one self-contained HTML page.

The pages are made from real data (the OptiOdom square session shipped with umbmark) and
from a simulated two-pass experiment whose robot has known errors, and opened in real
headless Chromium (Debian's ``chromium``) driven over the DevTools protocol on a pipe.
"""

from __future__ import annotations

import base64
import contextlib
import fcntl
import json
import math
import os
import re
import select
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import pytest

import umbmark
from umbmark.cli.main import main

# The simulated robot: D_R / D_L and b_actual / b, as the paper's Fig. 11 robot roughly.
TRUE_E_D = 1.002
TRUE_E_B = 1.006
SIDE = 4.0
WHEELBASE = 0.34


# --- the pages -------------------------------------------------------------------------


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The real OptiOdom square session (3 cw + 3 ccw runs, motion-capture truth)."""
    folder = tmp_path_factory.mktemp("real")
    return umbmark.example_sessions(folder)[0]


@pytest.fixture(scope="module")
def two_passes(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """Runs tables of a virtual robot with known errors, before and after its correction.

    Pass 2 is driven by the same robot whose odometry uses pass 1's new parameters (as
    ``umbmark demo`` does), so that it shows what the correction left.
    """
    folder = tmp_path_factory.mktemp("sim")
    before, after = folder / "before.csv", folder / "after.csv"
    common: dict[str, Any] = {"E_d": TRUE_E_D, "E_b": TRUE_E_B, "side_length": SIDE}
    umbmark.simulate(**common, wheelbase=WHEELBASE, runs=5, seed=11, output=before)
    first = umbmark.calibrate(before, side_length=SIDE, wheelbase=WHEELBASE)
    umbmark.simulate(**common, wheelbase=WHEELBASE, runs=5, seed=12, params=first, output=after)
    return before, after


class _Page(HTMLParser):
    """The tags with their attributes and the text of a page."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, dict[str, str | None]]] = []
        self.text: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append((tag, dict(attrs)))

    def handle_data(self, data: str) -> None:
        self.text.append(data)

    @property
    def body(self) -> str:
        return " ".join(" ".join(self.text).split())


def _parse(text: str) -> _Page:
    page = _Page()
    page.feed(text)
    page.close()
    return page


def _self_contained(text: str) -> None:
    """No address anywhere in the page, nothing loaded from elsewhere."""
    assert re.search(r"https?:|//[a-z0-9.-]+\.[a-z]{2,}/", text) is None
    assert "<script" not in text
    assert "@import" not in text
    assert re.search(r"url\((?!#)", text) is None  # only the figure's own clip paths
    for tag, attrs in _parse(text).tags:
        assert tag not in ("img", "link", "iframe", "object", "embed"), tag
        for key in ("src", "href", "xlink:href"):
            value = attrs.get(key)
            assert value is None or value.startswith("#"), (tag, key, value)


@pytest.mark.slow
def test_two_passes_page_states_each_pass(two_passes: tuple[Path, Path], tmp_path: Path) -> None:
    before, after = two_passes
    # Each pass calibrated on its own, as a user would with two calibrate commands.
    alone = [
        umbmark.calibrate(before, side_length=SIDE, wheelbase=WHEELBASE),
        umbmark.calibrate(after, side_length=SIDE, wheelbase=WHEELBASE),
    ]
    out = tmp_path / "two.html"
    page = umbmark.report(
        before, after, side_length=SIDE, wheelbase=WHEELBASE, output=out, command="made here"
    )
    e_before, e_after = (one.e_max_syst for one in alone)
    assert e_before is not None
    assert e_after is not None
    assert page.e_max_syst == pytest.approx((e_before, e_after), rel=1e-12)
    # The correction worked: pass 2 is several times closer (true E_b 1.006 gives about
    # 0.3 m at L = 4 m; the scatter of 5 runs about 10 mm).
    assert e_after < e_before / 5
    text = out.read_text(encoding="utf-8")
    _self_contained(text)
    parsed = _parse(text)
    body = parsed.body
    assert f"pass 1 (before): E_max,syst = {e_before * 1000:.1f} mm" in body
    assert f"pass 2 (after): E_max,syst = {e_after * 1000:.1f} mm" in body
    assert f"{e_before / e_after:.1f} times smaller" in body
    bench = alone[1].benchmark
    assert bench is not None
    assert f"3 x SEM = {bench.second_pass_threshold * 1000:.1f} mm" in body
    assert "Predicted after" not in body  # two measured passes: no prediction
    # The per-pass table: each pass's centres of gravity as calibrate computes them.
    for one in alone:
        assert one.benchmark is not None
        cg = one.benchmark.cw.cg * 1000
        assert f"{cg[0]:.1f}, {cg[1]:.1f}" in body
    # Pass 2 composes with pass 1's new parameters: its active c_L is pass 1's new one.
    second = page.passes[1].calibration
    assert second.active.c_left == pytest.approx(alone[0].calibration.new_c_left, rel=1e-12)
    assert page.last.overlay_yaml() in " ".join(parsed.text)
    assert "made here" in body
    for path in (before, after):
        digest = __import__("hashlib").sha256(path.read_bytes()).hexdigest()
        assert digest in body
    d = json.loads(page.to_json())
    assert d["e_max_syst"] == pytest.approx([e_before, e_after], rel=1e-12)
    assert [p["source"] for p in d["passes"]] == [str(before), str(after)]


@pytest.mark.slow
def test_real_session_page_predicts_after(session: Path, tmp_path: Path) -> None:
    out = tmp_path / "real.html"
    page = umbmark.report(session, output=out)
    alone = umbmark.calibrate(session)
    assert page.e_max_syst == (alone.e_max_syst,)
    predicted = page.predicted
    assert predicted is not None
    # The prediction is what umbmark replay computes for the same runs and parameters:
    # each run's end error with the calibrated parameters.
    replayed = umbmark.replay(session, alone)
    ends = [math.hypot(*run.return_error) for run in predicted.runs]
    assert ends == pytest.approx(list(replayed.end_errors["calibrated"]), abs=1e-9)
    # ... and its E_max,syst the distance of the farther centre of those return errors.
    for direction in ("cw", "ccw"):
        errors = [r.return_error for r in predicted.runs if r.direction.value == direction]
        cg = [sum(e[i] for e in errors) / len(errors) for i in (0, 1)]
        cluster = getattr(predicted.benchmark, direction)
        assert math.hypot(*cg) == pytest.approx(cluster.r_cg, abs=1e-12)
    text = out.read_text(encoding="utf-8")
    _self_contained(text)
    body = _parse(text).body
    assert alone.e_max_syst is not None
    assert f"E_max,syst = {alone.e_max_syst * 1000:.1f} mm" in body
    shown = f"Predicted after: E_max,syst = {predicted.benchmark.e_max_syst * 1000:.1f} mm"
    assert shown in body
    assert "not a measured pass" in body
    assert "predicted eps_x [mm]" in body
    # calibrate --report writes the same page, prediction included.
    assert "predicted after (replayed)" in alone.html()


@pytest.fixture(scope="module")
def validated(session: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    """The real session's page with the validation table (held-out replay: slow)."""
    out = tmp_path_factory.mktemp("validated") / "real.html"
    return out, umbmark.report(session, output=out, validate=True)


@pytest.mark.slow
def test_validate_adds_its_table(validated: tuple[Path, Any]) -> None:
    out, page = validated
    assert page.html().split("made ")[0] == out.read_text(encoding="utf-8").split("made ")[0]
    assert page.validation is not None
    body = _parse(page.html()).body
    assert "Validation: held-out end error [mm], leave one run out" in body
    for fold in page.validation.folds:
        assert fold.held_out in body
    nominal = page.validation.mean_error("nominal")
    assert nominal is not None
    assert f"{nominal * 1000:.1f}" in body


# --- the command line ------------------------------------------------------------------


def test_every_option_is_a_keyword_of_umbmark_report() -> None:
    import inspect

    import click

    from umbmark.cli.main import cli
    from umbmark.runs.read_options import SourceOptions

    keywords = set(inspect.signature(umbmark.report).parameters)
    keywords |= set(SourceOptions.__annotations__)
    command = cli.commands["report"]
    names = [p.name for p in command.params if not isinstance(p, click.Argument)]
    assert {"side_length", "wheelbase", "method", "output", "validate", "unit"} <= set(names)
    for name in names:
        assert name in keywords or name in ("json_out", "help"), name


def _run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exit_info:
        main(args)
    out, err = capsys.readouterr()
    code = exit_info.value.code
    return (code if isinstance(code, int) else 1), out, err


@pytest.mark.slow
def test_cli_writes_the_page_and_states_its_command(
    two_passes: tuple[Path, Path], tmp_path: Path
) -> None:
    before, after = two_passes
    out = tmp_path / "page.html"
    args = ["report", str(before), str(after), "-L", "4", "-b", "0.34", "-o", str(out)]
    done = subprocess.run(
        [sys.executable, "-m", "umbmark", *args, "--json"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    d = json.loads(done.stdout)
    assert len(d["passes"]) == 2
    assert f"umbmark: wrote {out}" in done.stderr
    command = "umbmark " + " ".join([*args, "--json"])  # no argument needs quoting here
    assert d["command"] == command
    assert command in _parse(out.read_text(encoding="utf-8")).body


def test_cli_bad_input_is_one_line(
    two_passes: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before, _ = two_passes
    one_way = tmp_path / "cw.csv"
    lines = before.read_text(encoding="utf-8").splitlines()
    one_way.write_text(
        "\n".join(line for line in lines if ",ccw," not in line and not line.startswith("ccw"))
        + "\n",
        encoding="utf-8",
    )
    assert "ccw" not in one_way.read_text(encoding="utf-8").split("\n", 3)[-1]
    out = tmp_path / "p.html"
    common = ["-L", "4", "-b", "0.34"]
    cases = [
        ([str(one_way), *common, "-o", str(out)], str(one_way)),
        ([str(tmp_path / "missing.csv"), *common, "-o", str(out)], "missing.csv"),
        ([str(before), *common, "-o", str(before)], "would overwrite an input"),
        ([str(before), *common, "-o", str(tmp_path / "p.txt")], "-o "),
        ([str(before), *common], "--output"),
    ]
    for args, named in cases:
        code, stdout, err = _run(["report", *args], capsys)
        assert code == 2, (args, err)
        assert err.count("\n") == 1, err
        assert err.startswith("umbmark: error: "), err
        assert named in err, (named, err)
        assert stdout == ""
    assert not out.exists()
    assert before.read_text(encoding="utf-8").splitlines() == lines


# --- headless Chromium -------------------------------------------------------------------


class Chromium:
    """Headless Chromium driven over the DevTools protocol on a pipe (no extra package)."""

    def __init__(self, profile: Path) -> None:
        binary = shutil.which("chromium") or shutil.which("chromium-browser")
        if binary is None:
            if os.environ.get("CI"):
                pytest.fail("chromium is missing on CI (apt-get install chromium)")
            pytest.skip("chromium is not installed")
        to_browser, self._write = os.pipe()
        self._read, from_browser = os.pipe()
        # The browser reads commands on fd 3 and writes answers on fd 4: put the pipe's
        # ends there in the child (from copies above 10, so that no dup2 clobbers another;
        # the copies themselves close on exec).
        ends = [fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 10) for fd in (to_browser, from_browser)]
        for fd in (to_browser, from_browser):
            os.close(fd)
        to_browser, from_browser = ends

        def child_fds() -> None:
            os.dup2(to_browser, 3)
            os.dup2(from_browser, 4)

        self.process = subprocess.Popen(
            [
                binary,
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--hide-scrollbars",
                "--remote-debugging-pipe",
                f"--user-data-dir={profile}",
                "about:blank",
            ],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            close_fds=False,  # fds 3 and 4 as made below; Python's own are not inherited
            preexec_fn=child_fds,  # noqa: PLW1509 - the tests start no threads
        )
        os.close(to_browser)
        os.close(from_browser)
        self._buffer = b""
        self._next = 0
        self.events: list[dict[str, Any]] = []
        self.session = ""
        targets = self.call("Target.getTargets")["targetInfos"]
        page = next(t for t in targets if t["type"] == "page")
        attached = self.call("Target.attachToTarget", targetId=page["targetId"], flatten=True)
        self.session = attached["sessionId"]
        for domain in ("Page", "Runtime", "Log"):
            self.call(f"{domain}.enable")

    def _message(self, deadline: float) -> dict[str, Any]:
        while b"\0" not in self._buffer:
            left = deadline - time.monotonic()
            ready, _, _ = select.select([self._read], [], [], max(left, 0.0))
            if not ready:
                raise TimeoutError("chromium did not answer")
            chunk = os.read(self._read, 1 << 20)
            if not chunk:
                raise RuntimeError("chromium closed the pipe")
            self._buffer += chunk
        text, self._buffer = self._buffer.split(b"\0", 1)
        message: dict[str, Any] = json.loads(text)
        return message

    def call(self, method: str, timeout: float = 60.0, **params: Any) -> dict[str, Any]:
        """Send a command and return its result (events meanwhile go to ``events``)."""
        self._next += 1
        message: dict[str, Any] = {"id": self._next, "method": method, "params": params}
        if self.session and not method.startswith(("Target.", "Browser.")):
            message["sessionId"] = self.session
        os.write(self._write, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            answer = self._message(deadline)
            if answer.get("id") == self._next:
                if "error" in answer:
                    raise RuntimeError(f"{method}: {answer['error']}")
                result: dict[str, Any] = answer.get("result", {})
                return result
            self.events.append(answer)

    def wait_for(self, event: str, timeout: float = 60.0) -> None:
        deadline = time.monotonic() + timeout
        while not any(e.get("method") == event for e in self.events):
            self.events.append(self._message(deadline))

    def evaluate(self, expression: str) -> Any:
        result = self.call("Runtime.evaluate", expression=expression, returnByValue=True)
        assert "exceptionDetails" not in result, result
        return result["result"].get("value")

    def open(self, path: Path, width: int, height: int = 900, mobile: bool = False) -> None:
        self.call(
            "Emulation.setDeviceMetricsOverride",
            width=width,
            height=height,
            deviceScaleFactor=1,
            mobile=mobile,
        )
        self.events.clear()
        self.call("Page.navigate", url=path.resolve().as_uri())
        self.wait_for("Page.loadEventFired")

    def errors(self) -> list[dict[str, Any]]:
        """Console errors, uncaught exceptions and failed loads since the last open."""
        bad = []
        for event in self.events:
            method, params = event.get("method"), event.get("params", {})
            error = (
                method == "Runtime.exceptionThrown"
                or (
                    method == "Runtime.consoleAPICalled"
                    and params.get("type") in ("error", "assert")
                )
                or (method == "Log.entryAdded" and params["entry"].get("level") == "error")
            )
            if error:
                bad.append(params)
        return bad

    def close(self) -> None:
        with contextlib.suppress(RuntimeError, TimeoutError, OSError):
            self.call("Browser.close", timeout=10)
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        os.close(self._read)
        os.close(self._write)


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Chromium]:
    chromium = Chromium(tmp_path_factory.mktemp("profile"))
    try:
        yield chromium
    finally:
        chromium.close()


def _distinct_colours(png: bytes) -> int:
    import io

    from matplotlib.image import imread

    pixels = imread(io.BytesIO(png), format="png")
    flat = pixels.reshape(-1, pixels.shape[-1])
    return len({tuple(p) for p in flat[:: max(1, len(flat) // 200_000)].tolist()})


_FIGURES = """
[...document.querySelectorAll('svg')].map(svg => {
  const box = svg.getBoundingClientRect();
  const drawn = [...svg.querySelectorAll('path')].filter(p => {
    const b = p.getBBox(); return b.width > 0 || b.height > 0; }).length;
  return {width: box.width, height: box.height, drawn: drawn,
          inside: box.right <= document.documentElement.clientWidth + 0.5};
})
"""
_OVERFLOW = "document.documentElement.scrollWidth - document.documentElement.clientWidth"


def _check_in_browser(browser: Chromium, page: Path, figures: int) -> None:
    for width, mobile in ((1200, False), (390, True)):
        browser.open(page, width, mobile=mobile)
        assert browser.errors() == []
        svgs = browser.evaluate(_FIGURES)
        assert len(svgs) == figures
        for svg in svgs:
            assert svg["width"] > 100, svg
            assert svg["height"] > 100, svg
            assert svg["drawn"] > 20, svg  # markers, circles, axes, text as paths
            assert svg["inside"], (width, svg)
        assert browser.evaluate(_OVERFLOW) <= 0, width  # the body never scrolls sideways
        assert browser.evaluate("document.body.scrollWidth <= window.innerWidth")
        shot = base64.b64decode(browser.call("Page.captureScreenshot", format="png")["data"])
        assert shot[:8] == b"\x89PNG\r\n\x1a\n"
        assert _distinct_colours(shot) > 8  # text, rules, the verdict's colours
    # Printing: the print sheet applies, and a PDF of several pages comes out.
    browser.call("Emulation.setEmulatedMedia", media="print")
    try:
        assert browser.evaluate("matchMedia('print').matches") is True
        assert browser.evaluate("getComputedStyle(document.body).maxWidth") == "none"
        pdf = base64.b64decode(browser.call("Page.printToPDF", timeout=120)["data"])
        assert pdf.startswith(b"%PDF-")
        assert pdf.count(b"/Type /Page\n") + pdf.count(b"/Type/Page") >= 2 or len(pdf) > 20_000
    finally:
        browser.call("Emulation.setEmulatedMedia", media="")
    assert browser.errors() == []


@pytest.mark.slow
def test_two_pass_page_in_headless_chromium(
    browser: Chromium, two_passes: tuple[Path, Path], tmp_path: Path
) -> None:
    out = tmp_path / "two.html"
    umbmark.report(*two_passes, side_length=SIDE, wheelbase=WHEELBASE, output=out)
    _check_in_browser(browser, out, figures=1)


@pytest.mark.slow
def test_real_page_in_headless_chromium(browser: Chromium, validated: tuple[Path, Any]) -> None:
    out, _ = validated
    _check_in_browser(browser, out, figures=1)
    # The prediction is drawn in the figure: its legend entry is there as text paths, so
    # check the markup's legend label instead.
    assert "predicted after (replayed)" in out.read_text(encoding="utf-8")


@pytest.mark.slow
def test_browser_check_catches_a_broken_page(browser: Chromium, tmp_path: Path) -> None:
    """The checks above can fail: a page with an error and a wide table fails them."""
    bad = tmp_path / "bad.html"
    bad.write_text(
        "<!DOCTYPE html><html><head><meta charset='utf-8'></head><body>"
        "<script>console.error('broken')</script>"
        "<table><tr><td style='white-space:nowrap'>" + "x" * 400 + "</td></tr></table>"
        "</body></html>",
        encoding="utf-8",
    )
    browser.open(bad, 390, mobile=True)
    assert browser.errors() != []
    assert browser.evaluate(_OVERFLOW) > 0
    assert browser.evaluate(_FIGURES) == []


# --- what a person sees on the page ---------------------------------------------------

_BOXES = """
[...document.querySelectorAll('.scroll')].map(box => ({
  section: box.closest('section').id, scroll: box.scrollWidth, client: box.clientWidth}))
"""


@pytest.mark.slow
def test_every_table_fits_1200_px_without_scrolling(
    browser: Chromium, session: Path, tmp_path: Path
) -> None:
    """The widest page: one real session, its runs with the predicted columns."""
    out = tmp_path / "real.html"
    umbmark.calibrate(session, report=out)
    browser.open(out, 1200)
    boxes = browser.evaluate(_BOXES)
    assert any(box["section"] == "runs" for box in boxes)
    for box in boxes:
        assert box["scroll"] <= box["client"], box  # no table scrolls sideways in its box
    assert browser.evaluate(_OVERFLOW) <= 0


@pytest.mark.slow
def test_one_pass_draws_cw_and_ccw_apart(session: Path, tmp_path: Path) -> None:
    """A single calibration: legend "cw runs", "ccw runs" (no "before"), two colours."""
    svg = umbmark.calibrate(session).html().split("<svg", 1)[1].split("</svg>", 1)[0]
    legend = re.findall(r"<!-- ([^>]*runs) -->", svg)
    assert "cw runs" in legend
    assert "ccw runs" in legend
    assert not any(label.startswith("before") for label in legend)
    # The markers' outlines: two colours (not greys) besides the prediction's grey.
    strokes = set(re.findall(r"stroke: (#[0-9a-f]{6})", svg))
    coloured = {s for s in strokes if len({s[1:3], s[3:5], s[5:7]}) > 1}
    assert len(coloured) >= 2, strokes


@pytest.mark.slow
def test_two_passes_keep_their_names(two_passes: tuple[Path, Path]) -> None:
    page = umbmark.report(*two_passes, side_length=SIDE, wheelbase=WHEELBASE)
    legend = re.findall(r"<!-- ([^>]*runs) -->", page.html())
    assert legend == [
        "pass 1 (before): cw runs",
        "pass 1 (before): ccw runs",
        "pass 2 (after): cw runs",
        "pass 2 (after): ccw runs",
    ]
