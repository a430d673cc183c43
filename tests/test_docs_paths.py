"""Every module, folder and file the docs name exists (issue 24: one map, and true).

Three kinds of mention are checked, in README.md, ``docs/*.md`` and the package
docstrings:

- a path in backticks (``estimators/registry.py``, ``sources/bag/``, ``tools/x.py``),
  resolved against ``src/umbmark/`` and the repository;
- a dotted name in backticks (in docstrings, only in ``:mod:``, ``:func:``, ``:class:``
  roles), such as ``umbmark.runs.read`` or ``runs.active.read_runs``, resolved as a
  module or a name defined at a module's top level (by parsing, not importing);
- in the map of ``docs/architecture.md`` ("Module by module"), each bare name in the
  bullet of a layer: a module or folder of that layer, or a name one of its modules
  defines.
"""

from __future__ import annotations

import ast
import re
from functools import cache
from pathlib import Path

import pytest

from helpers import parsed

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "umbmark"
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
REPOSITORY = ("src", "tests", "tools", "benchmarks", "docs", ".ci")
LAYERS = sorted(p.name for p in PACKAGE.iterdir() if p.is_dir() and not p.name.startswith("_"))

_FILE_ENDINGS = {"csv", "html", "json", "yaml", "yml", "png", "svg", "txt", "md", "py", "db"}
_TICKED = re.compile(r"`([^`\n]+)`")
_ROLE = re.compile(r":(?:mod|func|class|meth|data|attr):`~?([\w.]+)`")
_PATH = re.compile(r"^[\w./-]+(?:\.py|/)$")
_DOTTED = re.compile(r"^(?:umbmark\.)?([a-z_]+(?:\.[A-Za-z_]\w*)+)$")


@cache
def _defined(module: Path) -> frozenset[str]:
    """Top-level names a module defines (functions, classes, assignments, imports)."""
    tree = parsed(module)
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
        elif isinstance(node, ast.ImportFrom | ast.Import):
            names.update((a.asname or a.name).split(".")[0] for a in node.names)
        elif isinstance(node, ast.ClassDef):
            names.add(node.name)
    return frozenset(names)


def _module_file(parts: list[str]) -> Path | None:
    base = PACKAGE.joinpath(*parts)
    if base.with_suffix(".py").is_file():
        return base.with_suffix(".py")
    if (base / "__init__.py").is_file():
        return base / "__init__.py"
    return None


def _class_attribute(module: Path, cls: str, attr: str) -> bool:
    for node in parsed(module).body:
        if isinstance(node, ast.ClassDef) and node.name == cls:
            for item in ast.walk(node):
                if isinstance(item, ast.FunctionDef | ast.AsyncFunctionDef) and item.name == attr:
                    return True
                if (
                    isinstance(item, ast.AnnAssign)
                    and isinstance(item.target, ast.Name)
                    and item.target.id == attr
                ):
                    return True
    return False


def dotted_exists(name: str) -> bool:
    """``a.b.c``: a module of the package, or a name (or a class's member) one defines."""
    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        module = _module_file(parts[:cut])
        if module is None:
            continue
        rest = parts[cut:]
        if not rest:
            return True
        if rest[0] not in _defined(module):
            return False
        return len(rest) == 1 or (len(rest) == 2 and _class_attribute(module, *rest))
    return False


def path_exists(text: str, page: Path) -> bool:
    candidates = [PACKAGE / text, ROOT / text, page.parent / text, ROOT / "tests" / text]
    return any(c.exists() for c in candidates)


def _mentions(text: str) -> list[str]:
    return _TICKED.findall(text) + _ROLE.findall(text)


def _docstrings() -> list[tuple[Path, str]]:
    found = []
    for module in sorted(PACKAGE.rglob("*.py")):
        doc = ast.get_docstring(parsed(module))
        if doc:
            found.append((module, doc))
    return found


def _problems(page: Path, text: str, *, code: bool = False) -> list[str]:
    """What ``text`` names that does not exist; in a docstring (``code``), a dotted name in
    plain backticks is code (``options.reload``), and only the roles name modules."""
    problems = []
    roles = set(_ROLE.findall(text))
    for mention in (m.strip() for m in _mentions(text)):
        first = mention.split("/")[0]
        if _PATH.match(mention) and "/" in mention and first in (*LAYERS, *REPOSITORY):
            if not path_exists(mention, page):
                problems.append(f"{page.name}: `{mention}` is no file or folder")
            continue
        dotted = _DOTTED.match(mention)
        if mention.rsplit(".", 1)[-1] in _FILE_ENDINGS:
            continue  # a file's name (runs.csv, calibration.html), not a module
        if code and mention not in roles:
            continue
        if dotted and mention.split(".")[0] in (*LAYERS, "umbmark"):
            name = dotted.group(1)
            if name.split(".")[0] in LAYERS and not dotted_exists(name):
                problems.append(f"{page.name}: `{mention}` is no module or name of umbmark")
    return problems


@pytest.mark.parametrize("page", DOCS, ids=lambda p: p.name)
def test_paths_and_modules_the_pages_name_exist(page: Path) -> None:
    assert _problems(page, page.read_text(encoding="utf-8")) == []


def test_paths_and_modules_the_docstrings_name_exist() -> None:
    problems = []
    for module, doc in _docstrings():
        problems += _problems(module, doc, code=True)
    assert problems == []


def _map_bullets() -> list[tuple[str, str]]:
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    section = text.split("## Module by module", 1)[1].split("\n## ", 1)[0]
    bullets = re.split(r"\n- ", section)
    found = []
    for bullet in bullets:
        head = re.match(r"\*\*`(\w+)/`\*\*", bullet.strip().removeprefix("- "))
        if head:
            found.append((head.group(1), bullet))
    return found


def test_the_map_covers_every_layer() -> None:
    assert sorted(layer for layer, _ in _map_bullets()) == sorted(
        layer for layer in LAYERS if layer != "data"
    )


@pytest.mark.parametrize(("layer", "bullet"), _map_bullets(), ids=lambda v: str(v)[:20])
def test_each_name_in_the_map_is_in_its_layer(layer: str, bullet: str) -> None:
    folder = PACKAGE / layer
    defined = set()
    for module in folder.rglob("*.py"):
        defined |= _defined(module)
    names = {p.stem for p in folder.rglob("*.py")} | {layer}
    names |= {p.name for p in folder.rglob("*") if p.is_dir()}
    missing = []
    for mention in _TICKED.findall(bullet):
        bare = mention.rstrip("/")
        if not re.fullmatch(r"[A-Za-z_]\w*", bare):
            continue  # paths and dotted names: checked above
        if bare not in names and bare not in defined:
            missing.append(mention)
    assert missing == [], f"{layer}/: the map names {missing}, which the layer does not hold"


def test_every_module_of_the_package_is_on_the_map() -> None:
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    section = text.split("## Module by module", 1)[1].split("\n## ", 1)[0]
    ticked = set(_TICKED.findall(section))
    missing = []
    for module in sorted(PACKAGE.rglob("*.py")):
        rel = module.relative_to(PACKAGE)
        if len(rel.parts) < 2 or rel.parts[0] == "data" or module.stem == "__init__":
            continue
        stem = module.stem
        if stem not in ticked and f"{stem}/" not in ticked and f"{rel.parts[0]}/" != str(rel):
            missing.append(str(rel))
    assert missing == [], f"modules the map of docs/architecture.md does not name: {missing}"
