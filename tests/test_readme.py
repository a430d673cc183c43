"""The README as a new user meets it, and the pages of docs/ it links to.

The README is a short page: its commands run as written from a plain install, the figures
it quotes are the ones the commands print today, and every link stays inside the
repository and lands on a file (and heading) that exists. The reference pages name only
options the commands have, and docs/python.md lists the functions' keywords as they are.

Marks in the README (HTML comments, invisible on the rendered page) placed on the line
before a fenced block:

- ``<!-- not run: REASON -->`` before a shell block that cannot run as it stands (a
  placeholder for the user's own bag); every other ``bash`` block of the README runs.
- ``<!-- output of: COMMAND -->`` before a ``text`` block quoting what ``COMMAND`` (a
  command of a block above it in the same section, written as there, whitespace
  collapsed; ``python`` for the section's Python block) prints: each quoted line must be
  a line of its output.
"""

from __future__ import annotations

import inspect
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

import umbmark

from helpers import ROOT, umbmark_command

README = ROOT / "README.md"
DOCS = ROOT / "docs"
SHELLS = {"bash", "sh", "shell"}
MAX_LINES = 300

FENCE = re.compile(r"^```([\w-]*)[^\n]*\n(.*?)^```[ \t]*$", re.MULTILINE | re.DOTALL)
NOTE = re.compile(r"<!--((?:(?!-->).)*)-->\s*\Z", re.DOTALL)


@dataclass(frozen=True)
class Block:
    """A fenced block of a Markdown page."""

    lang: str
    body: str
    note: str  # the HTML comment on the line before it, or ""
    section: str  # the ``## `` heading it is under ("" before the first)


def blocks(text: str) -> list[Block]:
    """The fenced blocks of ``text`` in order, with their marks and sections."""
    found = []
    last_end = 0
    for match in FENCE.finditer(text):
        before = text[last_end : match.start()]
        note = NOTE.search(before.rstrip("\n") + "\n")
        headings = re.findall(r"^## (.+)$", text[: match.start()], flags=re.MULTILINE)
        found.append(
            Block(
                lang=match.group(1),
                body=match.group(2),
                note=note.group(1).strip() if note else "",
                section=headings[-1] if headings else "",
            )
        )
        last_end = match.end()
    return found


def commands(body: str) -> list[str]:
    """The commands of a shell block: continuation lines joined, comments left out."""
    joined = re.sub(r"\\\n", " ", body)
    lines = (line.strip() for line in joined.splitlines())
    return [line for line in lines if line and not line.startswith("#")]


def collapse(text: str) -> str:
    return " ".join(text.split())


def prose(text: str) -> str:
    """``text`` without its fenced blocks, HTML comments and inline code."""
    text = FENCE.sub("", text)
    text = re.sub(r"<!--.*?-->", "", text, flags=re.DOTALL)
    return re.sub(r"`[^`\n]*`", "", text)


def sections(text: str) -> dict[str, str]:
    """The text of every ``## `` section by its heading."""
    parts = re.split(r"^## (.+)$", text, flags=re.MULTILINE)
    return {parts[i]: parts[i + 1] for i in range(1, len(parts), 2)}


def readme() -> str:
    return README.read_text(encoding="utf-8")


def pages() -> list[Path]:
    return [README, *sorted(DOCS.glob("*.md"))]


# (a) A short page ---------------------------------------------------------------------


def test_the_readme_is_a_short_page():
    lines = readme().splitlines()
    assert len(lines) <= MAX_LINES, f"README.md has {len(lines)} lines, at most {MAX_LINES}"


def test_the_readme_starts_with_the_two_commands():
    """The install-and-run command and the test command come first; the test command is
    the one CI runs, byte for byte the last line of .ci/run."""
    first, second = [b for b in blocks(readme()) if b.section == ""]
    assert (first.lang, first.body) == ("bash", "python -m pip install . && umbmark demo\n")
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").rstrip("\n").splitlines()[-1]
    assert second.lang == "bash"
    assert second.body == ci + "\n"


def test_ci_runs_the_linters_and_the_type_check_before_the_tests():
    """ruff and mypy run in CI's command, not inside pytest (where they cost the quick loop
    a minute): lint, format, strict types, then the tests."""
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").rstrip("\n").splitlines()[-1]
    steps = ci.split(" && ")
    tail = [".venv/bin/ruff check .", ".venv/bin/ruff format --check .", ".venv/bin/mypy"]
    assert steps[-4:] == [*tail, ".venv/bin/python -m pytest"]


# (b) Links stay in the repository and land -------------------------------------------


def slug(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    text = FENCE.sub("", path.read_text(encoding="utf-8"))
    seen: dict[str, int] = {}
    found = set()
    for heading in re.findall(r"^#{1,6} (.+)$", text, flags=re.MULTILINE):
        base = slug(heading)
        n = seen.get(base, 0)
        seen[base] = n + 1
        found.add(base if n == 0 else f"{base}-{n}")
    return found


def links(path: Path) -> list[str]:
    """Targets of the Markdown links of a page (inline and reference style), code left out."""
    text = FENCE.sub("", path.read_text(encoding="utf-8"))
    text = re.sub(r"`[^`\n]*`", "", text)
    inline = re.findall(r"\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)", text)
    reference = re.findall(r"^\s*\[[^\]]+\]:\s*<?(\S+?)>?(?:\s.*)?$", text, flags=re.MULTILINE)
    html = re.findall(r"(?:href|src)\s*=\s*[\"']([^\"']+)[\"']", text)
    return inline + reference + html


@pytest.mark.parametrize("page", pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_link_resolves_inside_the_repository(page):
    bad = []
    for target in links(page):
        if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target) or target.startswith("/"):
            bad.append(f"{target}: not a relative link into the repository")
            continue
        file_part, _, anchor = target.partition("#")
        resolved = (page.parent / file_part).resolve() if file_part else page
        if not resolved.is_relative_to(ROOT):
            bad.append(f"{target}: leaves the repository")
        elif not resolved.is_file():
            bad.append(f"{target}: no such file")
        elif anchor and anchor not in anchors(resolved):
            bad.append(f"{target}: no heading #{anchor} in {resolved.name}")
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("page", pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_page_points_at_files_outside_the_repository(page):
    """Not even in code: the user has no ../shared or /work, nor the project's notes."""
    text = page.read_text(encoding="utf-8")
    for outside in ("../shared", "/work/", "paper-notes"):
        assert outside not in text, f"{page.name} names {outside}"


def test_the_link_checker_catches_what_it_should(tmp_path, monkeypatch):
    """The checks above can fail: a missing file, a missing heading, a way out."""
    page = tmp_path / "page.md"
    page.write_text("# Top\n[a](missing.md) [b](#nowhere) [c](#top) [d](../../x.md)\n")
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    with pytest.raises(AssertionError) as caught:
        test_every_link_resolves_inside_the_repository(page)
    message = str(caught.value)
    assert "missing.md: no such file" in message
    assert "#nowhere: no heading #nowhere" in message
    assert "../../x.md: leaves the repository" in message
    assert "#top" not in message.replace("#nowhere", "")
    assert slug("One page to keep: `--report`") == "one-page-to-keep---report"


def test_the_docs_table_lists_every_page():
    """Every page of docs/ has its line in the README's table, and no line is left over."""
    table = sections(readme())["Documentation"]
    listed = set(re.findall(r"^\| \[docs/([\w.-]+\.md)\]", table, flags=re.MULTILINE))
    assert listed == {p.name for p in DOCS.glob("*.md")}


# (c), (d) The commands run as written and print what the README quotes ---------------


def _environment() -> dict[str, str]:
    """PATH with the test interpreter's bin folder (its ``umbmark``, its ``python``) first."""
    bin_dir = str(Path(umbmark_command()).parent)
    env = {**os.environ, "PATH": os.pathsep.join([bin_dir, os.environ.get("PATH", "")])}
    env.pop("UMBMARK_HISTORY", None)
    return env


def _run_section(blocks_: list[Block], folder: Path) -> dict[str, str]:
    """Run a section's blocks in order in ``folder`` (made if new; a second run finds what
    the first wrote); the output of every command."""
    folder.mkdir(exist_ok=True)
    env = _environment()
    outputs: dict[str, str] = {}
    for block in blocks_:
        if block.note.startswith("not run"):
            continue
        if block.lang in SHELLS:
            for command in commands(block.body):
                proc = subprocess.run(
                    ["bash", "-c", "set -euo pipefail\n" + command],
                    cwd=folder,
                    env=env,
                    capture_output=True,
                    text=True,
                    timeout=300,
                    check=False,
                )
                assert proc.returncode == 0, f"{command}\n{proc.stdout}\n{proc.stderr}"
                assert "Traceback" not in proc.stderr, proc.stderr
                outputs[collapse(command)] = proc.stdout
        elif block.lang == "python":
            proc = subprocess.run(
                [sys.executable, "-c", block.body],
                cwd=folder,
                env=env,
                capture_output=True,
                text=True,
                timeout=300,
                check=False,
            )
            assert proc.returncode == 0, f"{block.body}\n{proc.stdout}\n{proc.stderr}"
            outputs["python"] = proc.stdout
    return outputs


def _check_quotes(blocks_: list[Block], outputs: dict[str, str], section_prose: str) -> None:
    for block in blocks_:
        if not block.note.startswith("output of:"):
            continue
        command = collapse(block.note.removeprefix("output of:"))
        assert command in outputs, f"'{command}' is not a command run above it in its section"
        printed = {collapse(line) for line in outputs[command].splitlines()}
        for line in block.body.splitlines():
            if collapse(line) and collapse(line) != "...":
                assert collapse(line) in printed, f"{command} no longer prints:\n{line}"
    # Every figure in millimetres of the section's prose is one its commands print.
    printed_numbers = set(re.findall(r"-?\d+\.\d+", " ".join(outputs.values())))
    for figure in re.findall(r"(\d+\.\d+) mm", section_prose):
        assert figure in printed_numbers, f"{figure} mm is not printed by the section's commands"


def _runnable_sections() -> list[str]:
    return sorted(
        {
            b.section
            for b in blocks(readme())
            if b.section
            and (b.lang in SHELLS or b.lang == "python")
            and not b.note.startswith("not run")
        }
    )


def test_every_readme_section_with_commands_is_checked():
    """The sections run below are all the sections with commands, and all fenced shell
    blocks either run or say why not."""
    for block in blocks(readme()):
        if block.lang in {"console", "shell-session"}:
            pytest.fail(f"a {block.lang} block: fence it as bash (it runs) or mark it not run")
    assert set(_runnable_sections()) >= {
        "Try it without a robot",
        "Quick start: a tape measure",
        "Quick start: motion capture or run logs",
        "Use from Python",
    }


#: Sections whose commands take more than a few seconds (validate: about 10 s).
SLOW_SECTIONS = {
    "Quick start: motion capture or run logs",
    "Quick start: the robot calibrates itself",
    "Quick start: a ROS bag",
    "Quick start: a fleet",
}


def test_the_slow_sections_are_readme_sections():
    assert set(_runnable_sections()) >= SLOW_SECTIONS


@pytest.mark.parametrize(
    "section",
    [
        pytest.param(s, marks=[pytest.mark.slow] if s in SLOW_SECTIONS else [])
        for s in _runnable_sections()
    ],
)
def test_the_readme_commands_run_as_written_and_print_what_it_quotes(section, tmp_path):
    """Each section's commands, run in a fresh folder with the installed ``umbmark``, exit
    0; what the section quotes of their output and the millimetres in its prose are what
    they print today. Run a second time in the same folder, as a user trying them again
    (or a notebook's cells run again) does, they still exit 0 and print the same: here for
    the slow sections, in the full run (the next test) for the others."""
    _run_twice(section, tmp_path, 2 if section in SLOW_SECTIONS else 1)


@pytest.mark.slow
@pytest.mark.parametrize("section", sorted(set(_runnable_sections()) - SLOW_SECTIONS))
def test_the_quick_sections_run_again_in_the_same_folder(section, tmp_path):
    _run_twice(section, tmp_path, 2)


def _run_twice(section: str, tmp_path: Path, times: int) -> None:
    """The section's commands run ``times`` times in one folder, each time printing what
    the section quotes."""
    text = readme()
    mine = [b for b in blocks(text) if b.section == section]
    for _ in range(times):
        outputs = _run_section(mine, tmp_path / "section")
        _check_quotes(mine, outputs, prose(sections(text)[section]))


@pytest.mark.slow
def test_the_quoted_figures_are_todays(tmp_path):
    """The demo's figures (README and docs/paper.md) and the tape-measure quick start's,
    as the commands print them today (quick: the two commands alone, not the whole
    README run)."""
    text = readme()
    env = _environment()

    def run(*args: str) -> str:
        proc = subprocess.run(
            [umbmark_command(), *args],
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            check=False,
            timeout=300,
        )
        assert proc.returncode == 0, proc.stderr
        return proc.stdout

    demo = sections(text)["Try it without a robot"]
    printed = run("demo", "--out", "demo")
    before, after = re.search(r"before: ([\d.]+) mm, after: ([\d.]+) mm", printed).groups()
    assert collapse(f"falls from {before} mm to {after} mm") in collapse(demo), (
        f"the demo prints {before} mm -> {after} mm"
    )
    assert collapse(f"E_max,syst before: {before} mm, after: {after} mm") in collapse(demo)
    paper = (DOCS / "paper.md").read_text(encoding="utf-8")
    assert collapse(f"falls from {before} mm to {after} mm") in collapse(paper)
    estimated = re.search(r"^Estimated (E_d = .*\)), (E_b = .*\))\.$", printed, re.MULTILINE)
    for figure in estimated.groups():
        assert figure in demo, figure
        assert figure in collapse(paper), figure

    tape = sections(text)["Quick start: a tape measure"]
    run("example", "runs.csv")
    printed = run(
        "calibrate", "runs.csv", "--side-length", "4", "--wheelbase", "0.34", "--unit", "mm"
    )
    e_max = re.findall(r"^E_max,syst = ([\d.]+) mm", printed, flags=re.MULTILINE)[0]
    assert f"(here {e_max} mm)" in collapse(tape)
    for name in ("E_b", "E_d"):
        (row,) = [line for line in printed.splitlines() if line.strip().startswith(f"{name} =")]
        assert collapse(row) in collapse(tape), f"the quoted {name} row is not today's: {row}"


def test_the_quote_checker_catches_drift():
    """A quoted line the command does not print, a prose figure it does not print, and a
    quote of a command that was not run all fail."""
    quote = Block("text", "E_max,syst = 27.4 mm\n", "output of: umbmark demo", "s")
    with pytest.raises(AssertionError, match="no longer prints"):
        _check_quotes([quote], {"umbmark demo": "E_max,syst = 27.5 mm\n"}, "")
    with pytest.raises(AssertionError, match="is not printed"):
        _check_quotes([], {"umbmark demo": "after: 27.5 mm\n"}, "falls to 31.0 mm")
    with pytest.raises(AssertionError, match="is not a command run"):
        _check_quotes([quote], {}, "")
    _check_quotes([quote], {"umbmark demo": "  E_max,syst  =  27.4 mm \n"}, "to 27.4 mm")


# The reference pages: the API and the options they name exist ------------------------


def _api_listing() -> str:
    text = (DOCS / "python.md").read_text(encoding="utf-8")
    (listing,) = [b.body for b in blocks(text) if b.note == "signatures"]
    return listing


def test_the_python_reference_lists_the_functions_as_they_are():
    """docs/python.md's signatures name every keyword each function takes, no other."""
    listing = _api_listing()
    calls = re.findall(r"^umbmark\.(\w+)\((.*?)\)\s*(?:->|$)", listing, re.MULTILINE | re.DOTALL)
    assert len(calls) >= 14
    for name, params in calls:
        written = []
        for part in re.split(r",(?![^()\[\]]*[)\]])", params):
            word = part.strip().split("=")[0].strip().lstrip("*")
            if word:
                written.append(word)
        actual = [p.name for p in inspect.signature(getattr(umbmark, name)).parameters.values()]
        assert written == actual, f"umbmark.{name}: docs say {written}, the code has {actual}"


def _cli_options() -> set[str]:
    from umbmark.cli.main import cli

    found: set[str] = set()

    def walk(command) -> None:  # type: ignore[no-untyped-def]
        for param in command.params:
            found.update(param.opts + param.secondary_opts)
        for sub in getattr(command, "commands", {}).values():
            walk(sub)

    walk(cli)
    return found | {"--help"}  # every command's, from click's context settings


#: Options of other programs that the pages name (pip, venv, ruff, evo, ros2).
OTHER_PROGRAMS = {
    "--upgrade", "--upgrade-strategy", "--clear", "--system-site-packages", "--check", "--ref",
    "--align_origin", "--once", "--list", "--filter", "--strict",
    # ROS 2's static_transform_publisher, in the laser mounting's forms
    "--roll", "--pitch", "--yaw", "--frame-id", "--child-frame-id",
    # Dask's scheduler and workers, in docs/fleet.md's cluster (over TLS too)
    "--port", "--nworkers", "--nthreads", "--protocol", "--tls-ca-file", "--tls-cert",
    "--tls-key",
    # ROS 2's own arguments, passed through by umbmark monitor --ros2
    "--ros-args",
}  # fmt: skip


def _script_options() -> set[str]:
    """The options the project's own scripts (``tools/``, ``benchmarks/``, the corpus runner,
    the tests' robot nodes and mission driver) declare."""
    found: set[str] = set()
    scripts = [*(ROOT / "tools").glob("*.py"), *(ROOT / "benchmarks").glob("*.py")]
    # the tests' own processes: the corpus runner, the ROS robot nodes, the mission driver
    scripts += [ROOT / "tests" / "corpus_runner.py", *(ROOT / "tests").glob("*_node*.py")]
    scripts += [ROOT / "tests" / "mission_driver.py"]
    for script in scripts:
        text = script.read_text(encoding="utf-8")
        found |= set(re.findall(r"add_argument\(\s*\"(--[a-z][a-z0-9-]*)\"", text))
    return found


@pytest.mark.parametrize("page", pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_option_the_pages_name_exists(page):
    options = _cli_options() | OTHER_PROGRAMS | _script_options()
    named = set(re.findall(r"(?<![\w-])(--[A-Za-z][\w-]*[A-Za-z0-9])", page.read_text("utf-8")))
    assert named - options == set(), f"{page.name} names options no command has"
