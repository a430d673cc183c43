"""The self-contained HTML report of a calibration (``calibrate --report``)."""

from __future__ import annotations

import hashlib
import math
import os
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import pytest
from click.testing import CliRunner

import umbmark
from umbmark.cli.main import cli
from umbmark.core.errors import InputError


@pytest.fixture(scope="module")
def runs_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The bundled example runs table (mm), in a folder of its own."""
    path = tmp_path_factory.mktemp("in") / "runs.csv"
    umbmark.example(path, force=True)
    return path


@pytest.fixture(scope="module")
def report(runs_csv: Path) -> umbmark.CalibrationReport:
    return umbmark.calibrate(runs_csv, side_length=4, wheelbase=0.34, unit="mm")


class _Page(HTMLParser):
    """Collects the tags, their attributes, the section ids and the text of a page."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, dict[str, str | None]]] = []
        self.text: list[str] = []
        self.stack: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append((tag, dict(attrs)))

    def handle_data(self, data: str) -> None:
        self.text.append(data)

    def ids(self) -> list[str]:
        return [a["id"] or "" for _, a in self.tags if a.get("id")]


def _parse(text: str) -> _Page:
    page = _Page()
    page.feed(text)
    page.close()
    return page


def test_html_report_structure(report: umbmark.CalibrationReport, runs_csv: Path) -> None:
    text = report.html()
    page = _parse(text)
    ids = page.ids()
    sections = ["verdict", "clusters", "runs", "estimates", "messages", "overlay", "provenance"]
    assert [i for i in ids if i in sections] == sections  # the verdict first
    tags = [t for t, _ in page.tags]
    assert tags.count("svg") == 1
    assert "img" not in tags
    assert "script" not in tags
    assert any(t == "meta" and a.get("name") == "viewport" for t, a in page.tags)
    assert "@media print" in text
    assert "max-width" in text
    for _, attrs in page.tags:
        for key in ("src", "href", "xlink:href"):
            value = attrs.get(key) or ""
            assert not value.startswith(("http://", "https://", "//")), (key, value)
    assert "url(http" not in text
    assert "@import" not in text

    d = report.to_dict()
    body = "".join(page.text)
    assert f"E_max,syst = {d['e_max_syst'] * 1000:.1f} mm" in body
    assert f"3 x SEM = {d['second_pass_threshold'] * 1000:.1f} mm" in body
    for name, (low, high) in d["intervals_95"].items():
        if name in ("alpha", "beta"):  # shown in degrees, as on the terminal
            assert f"{math.degrees(low):.4f}" in body, name
            assert f"{math.degrees(high):.4f}" in body, name
            continue
        assert f"{low:.6f}" in body, name
        assert f"{high:.6f}" in body, name
    assert f"{d['E_d']:.6f}" in body
    assert f"{d['E_b']:.6f}" in body
    for run in d["runs"]:
        assert f"{run['eps_x'] * 1000:.1f}" in body
        assert f"{run['eps_y'] * 1000:.1f}" in body
    assert report.overlay_yaml() in body  # the <pre>, unescaped by the parser
    assert hashlib.sha256(runs_csv.read_bytes()).hexdigest() in body
    assert f"umbmark {d['umbmark_version']}" in body
    assert f"method: {d['method']}" in body


def test_html_report_of_a_runs_table_predicts_nothing(report: umbmark.CalibrationReport) -> None:
    """End points alone cannot be replayed: no predicted after, said nowhere."""
    body = "".join(_parse(report.html().split("<body>", 1)[1]).text)
    assert "Predicted after" not in body
    assert "predicted" not in body.lower()


def test_html_report_escapes_text(report: umbmark.CalibrationReport) -> None:
    from dataclasses import replace

    hostile = replace(report, notes=("<script>alert(1)</script> & more",))
    text = hostile.html()
    assert "<script>" not in text
    assert "&lt;script&gt;alert(1)&lt;/script&gt; &amp; more" in text


def test_report_written_by_calibrate_and_cli(runs_csv: Path, tmp_path: Path) -> None:
    out = tmp_path / "r.html"
    umbmark.calibrate(runs_csv, side_length=4, wheelbase=0.34, unit="mm", report=out)
    assert out.read_text().startswith("<!DOCTYPE html>")
    with pytest.raises(InputError, match=r"report='r.txt': .*html"):
        umbmark.calibrate(runs_csv, side_length=4, wheelbase=0.34, unit="mm", report="r.txt")
    with pytest.raises(InputError, match=r"report and output|output and report"):
        umbmark.calibrate(
            runs_csv, side_length=4, wheelbase=0.34, unit="mm", report=out, output=out
        )
    with pytest.raises(InputError):
        umbmark.calibrate(
            runs_csv, side_length=4, wheelbase=0.34, unit="mm", report=tmp_path / "no" / "r.html"
        )
    cli_out = tmp_path / "cli.html"
    args = [str(runs_csv), "-L", "4", "-b", "0.34", "--unit", "mm", "--report", str(cli_out)]
    result = CliRunner().invoke(cli, ["calibrate", *args])
    assert result.exit_code == 0, result.output
    assert "<svg" in cli_out.read_text()


def _distinct_colours(png: Path) -> int:
    from matplotlib.image import imread

    pixels = imread(png)
    flat = pixels.reshape(-1, pixels.shape[-1])
    return len({tuple(p) for p in flat[:: max(1, len(flat) // 200_000)].tolist()})


@pytest.mark.slow
def test_html_report_in_headless_chromium(
    report: umbmark.CalibrationReport, tmp_path: Path
) -> None:
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        if os.environ.get("CI"):
            pytest.fail("chromium is missing on CI (apt-get install chromium)")
        pytest.skip("chromium is not installed")
    page = tmp_path / "report.html"
    report.write(report=page)
    shot = tmp_path / "shot.png"
    common = [chromium, "--headless", "--disable-gpu", "--no-sandbox", "--hide-scrollbars"]
    common += [f"--user-data-dir={tmp_path / 'profile'}"]
    url = page.resolve().as_uri()
    subprocess.run(
        [*common, f"--screenshot={shot}", "--window-size=1200,2000", url],
        check=True,
        capture_output=True,
        timeout=60,
        cwd=tmp_path,
    )
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert _distinct_colours(shot) > 1
    dom = subprocess.run(
        [*common, "--dump-dom", url], check=True, capture_output=True, text=True, timeout=60
    ).stdout
    parsed = _parse(dom)
    assert [t for t, _ in parsed.tags].count("svg") == 1
    assert "overlay-yaml" in parsed.ids()


def _section(text: str, key: str) -> str:
    """The text of the page's section ``key``."""
    part = text.split(f'<section id="{key}">', 1)[1].split("</section>", 1)[0]
    return "".join(_parse(part).text)


def test_alpha_and_beta_in_degrees_on_page_and_terminal(
    report: umbmark.CalibrationReport, runs_csv: Path
) -> None:
    """One unit for alpha and beta wherever a person reads them: degrees (JSON: rad)."""
    estimates = _section(report.html(), "estimates")
    assert "[rad]" not in estimates
    args = [str(runs_csv), "-L", "4", "-b", "0.34", "--unit", "mm"]
    terminal = CliRunner().invoke(cli, ["calibrate", *args]).output
    se = report.estimate.standard_errors
    for name in ("alpha", "beta"):
        value, error = math.degrees(getattr(report.estimate, name)), math.degrees(se[name])
        assert f"{name} [deg]" in estimates
        assert f"{value:.4f}" in estimates
        assert f"{value:.4f} ± {error:.4f} deg" in terminal
    assert report.to_dict()["alpha"] == report.estimate.alpha  # JSON stays in radians
    plan = CliRunner().invoke(cli, ["plan", "--scatter", "0.01", "-L", "4"]).output
    assert "mrad" not in plan
    assert re.search(r"se\(alpha\) = se\(beta\)\s+[0-9.]+\s+deg", plan), plan


def test_fit_section_promises_what_it_shows(runs_csv: Path) -> None:
    """Each figure of the fit with its unit and meaning; a p-value only where one is."""
    exact = umbmark.calibrate(runs_csv, side_length=4, wheelbase=0.34, unit="mm")
    shown = _section(exact.html(), "messages")
    assert "p-value" not in shown
    assert "model_check_p" not in shown
    assert "Hotelling" not in shown
    residual = exact.estimate.components["residual_rms"] * 1000
    assert "misfit of the exact geometry (rms) [mm]" in shown
    assert f"{residual:.3f}" in shown
    endpose = umbmark.calibrate(
        runs_csv, side_length=4, wheelbase=0.34, unit="mm", method="endpose"
    )
    shown = _section(endpose.html(), "messages")
    p = endpose.estimate.components["model_check_p"]
    assert "model check p-value" in shown
    assert f"{p:.3g}" in shown
