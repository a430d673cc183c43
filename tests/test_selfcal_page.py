"""The self-calibration's page says what its terminal says (issue 29, item 5): the command
that ran, the passes by the same names (pass 1, pass 2, verification), each run's return
error (Eq. 3.1: the corner fixes' end pose against the odometry's) with the same digits,
how each correction was applied, and a pass measured after a coarse turning correction
has its E_b marked as the residual on the corrected wheelbase.

The robot: the virtual one with E_b 1.1 (its wheelbase 10 % longer than its controller
believes: the coarse turning check corrects it before UMBmark) and the command's IMU, whose
gyro reads 1/1.02 of the turns (``--sim-gyro-scale`` 1.02, the default): the coarse check
turns by the gyro, so it corrects by 1.1 x 1.02, and pass 1 finds the residual 1/1.02.
"""

from __future__ import annotations

import re
import shlex
from html import unescape
from pathlib import Path

import pytest

from helpers import run_cli

TRUE_E_B = 1.1
#: The virtual robot's gyro scale k_g (selfcal --sim's default --sim-gyro-scale).
GYRO_SCALE = 1.02

_RUN_LINE = re.compile(
    r"umbmark: (pass \d|verification), run (\d) of \d+ \((?:cw|ccw) \d of \d\): return error "
    r"x ([+-]\d+\.\d) mm, y ([+-]\d+\.\d) mm, ([+-]\d+\.\d{3}) deg"
)


@pytest.fixture(scope="module")
def ran(tmp_path_factory: pytest.TempPathFactory) -> tuple[list[str], str, str, str, Path]:
    out = tmp_path_factory.mktemp("selfcal") / "out"
    args = [
        "selfcal", "--sim", "--sim-E-b", str(TRUE_E_B), "-L", "1", "-n", "2",
        "--max-passes", "2", "--out", str(out),
    ]  # fmt: skip
    proc = run_cli(*args)
    assert proc.returncode == 0, proc.stderr
    page = (out / "report.html").read_text(encoding="utf-8")
    return args, proc.stdout, proc.stderr, page, out


def _cells(page: str, section: str) -> list[list[str]]:
    """The rows of the section's first table body, each cell's text."""
    body = page.split(f'<section id="{section}">', 1)[1].split("</section>", 1)[0]
    rows = re.findall(r"<tr>(.*?)</tr>", body.split("<tbody>", 1)[1], flags=re.S)
    return [
        [unescape(re.sub("<[^>]+>", "", c)) for c in re.findall(r"<td[^>]*>(.*?)</td>", r)]
        for r in rows
    ]


@pytest.mark.slow
def test_the_page_shows_the_command_that_ran(ran):
    args, _, _, page, _ = ran
    assert "made from Python" not in page
    shown = unescape(re.search(r'<code id="command">(.*?)</code>', page)[1])
    assert shlex.split(shown)[1:] == args


@pytest.mark.slow
def test_the_passes_have_the_terminals_names(ran):
    _, stdout, _, page, _ = ran
    for label in ("pass 1", "pass 2", "verification"):
        assert re.search(rf"^\s+{label}\s", stdout, flags=re.M), label
    runs = _cells(page, "runs")
    assert [r[0] for r in runs] == ["pass 1"] * 4 + ["pass 2"] * 4 + ["verification"] * 4
    assert "pass 3" not in page
    assert "(after pass" not in page
    assert "3 UMBmark passes" not in page


@pytest.mark.slow
def test_each_runs_return_error_is_the_terminals(ran):
    _, _, stderr, page, _ = ran
    said = {(m[1], m[2]): m.groups()[2:] for m in _RUN_LINE.finditer(stderr)}
    assert len(said) == 12, stderr
    shown = {(r[0], r[1]): (r[5], r[6], r[7]) for r in _cells(page, "runs")}
    assert len(shown) == 12
    for key, (x, y, theta) in said.items():
        assert tuple(float(v) for v in shown[key]) == (float(x), float(y), float(theta)), key


@pytest.mark.slow
def test_the_applied_method_is_named(ran):
    _, stdout, _, page, _ = ran
    assert re.search(r"^\s+pass 1 .*\breconfigure\s*$", stdout, flags=re.M)
    text = unescape(re.sub("<[^>]+>", "", page))
    assert "applied: Apply" not in text
    assert "pass 2, applied by reconfigure; its verdict: apply" in text.lower()


@pytest.mark.slow
def test_the_e_b_after_a_coarse_correction_is_the_residual(ran):
    _, stdout, stderr, page, _ = ran
    ratio = float(re.search(r"\(ratio (\d\.\d+)\): corrected", stderr)[1])
    # by the gyro: the odometry's turn over the gyro's, which reads 1 / k_g of the true one
    assert "Coarse turning check by the gyro" in stderr
    assert ratio == pytest.approx(TRUE_E_B * GYRO_SCALE, abs=0.01)
    # the terminal: pass 1's E_b residual, composed beside it; pass 2's not marked
    found = re.search(r"(\d\.\d{6}) residual, (\d\.\d{6}) composed", stdout)
    assert found, stdout
    residual, composed = float(found[1]), float(found[2])
    assert residual == pytest.approx(1.0 / GYRO_SCALE, abs=0.01)
    assert composed == pytest.approx(residual * ratio, abs=6e-5)  # the ratio printed to 4 digits
    assert composed == pytest.approx(TRUE_E_B, abs=0.005)
    assert len(re.findall(r"\d residual, ", stdout)) == 1  # pass 1 only
    # the page: the same words in pass 1's estimates
    estimates = page.split('<section id="estimates">', 1)[1].split("</section>", 1)[0]
    first = estimates.split("<h3>", 2)[1]
    assert f"{found[1]} residual, {found[2]} composed" in unescape(first)
    assert "residual" not in estimates.split("<h3>", 2)[2]


@pytest.mark.slow
def test_the_page_in_headless_chromium(ran, tmp_path: Path):
    from test_report_command import Chromium

    _, _, stderr, page, _ = ran
    path = tmp_path / "report.html"
    path.write_text(page, encoding="utf-8")
    browser = Chromium(tmp_path / "profile")
    try:
        browser.open(path, 1200)
        assert browser.errors() == []
        command = browser.evaluate("document.getElementById('command').textContent")
        rows = browser.evaluate(
            "[...document.querySelectorAll('#runs tbody tr')]"
            ".map(r => [...r.cells].map(c => c.innerText))"
        )
        verdict = browser.evaluate("document.getElementById('apply').innerText")
    finally:
        browser.close()
    assert command.startswith("umbmark selfcal --sim")
    said = [m.groups() for m in _RUN_LINE.finditer(stderr)]
    assert [(r[0], r[1], r[5], r[6], r[7]) for r in rows] == [
        (label, k, f"{float(x):.1f}", f"{float(y):.1f}", f"{float(t):.3f}")
        for label, k, x, y, t in said
    ]
    assert "applied by reconfigure" in verdict


@pytest.mark.slow
def test_each_run_file_says_the_terminals_return_error(ran):
    _, _, stderr, _, out = ran
    said = list(_RUN_LINE.finditer(stderr))
    assert len(said) == 12, stderr
    for m in said:
        label, k = m[1], int(m[2])
        (path,) = (out / label.replace(" ", "-")).glob(f"run-{k:02d}-*.csv")
        head = path.read_text(encoding="utf-8").splitlines()[1]
        assert head == (
            "# return error (Eq. 3.1, the corner fixes against the odometry): "
            f"x {m[3]} mm, y {m[4]} mm, {m[5]} deg"
        )
