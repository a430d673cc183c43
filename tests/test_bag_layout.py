"""The bag's modules import down the order its package docstring gives, without cycles.

Imports are read from the source (module level, inside functions and under
``TYPE_CHECKING`` alike), so a cycle or an upward import anywhere fails here.
"""

from __future__ import annotations

import ast
from pathlib import Path

from helpers import ROOT

PACKAGE = ROOT / "src" / "umbmark"
BAG = "umbmark.sources.bag"

#: The concerns of ``umbmark/sources/bag/__init__.py``, lowest first. A module may import
#: from a lower concern, and from its own (modules of one subpackage, or the top-level
#: modules of one rank): ``wheels`` and ``truth`` share a rank and import neither the other.
ORDER = {
    "msgtypes": 1,
    "names": 1,
    "fieldpath": 1,
    "bag_options": 2,
    "reader": 3,
    "writer": 3,
    "imu_writer": 3,
    "fastpath": 4,
    "samples": 4,
    "custom": 4,
    "scans": 4,
    "wheels": 5,
    "truth": 5,
    "recording": 6,
    "urdf": 7,
    "imu_frames": 7,
    "imu": 7,
    "info": 8,
}
#: What the bag may use of the rest of umbmark: the layers below sources/, and the two
#: helpers every source shares.
OUTSIDE = (
    "umbmark.core",
    "umbmark.options",
    "umbmark.model",
    "umbmark.sources.text",
    "umbmark.sources.progress",
)


def _modules() -> dict[str, Path]:
    out = {}
    for path in (PACKAGE / "sources" / "bag").rglob("*.py"):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _imports(path: Path, modules: dict[str, Path]) -> set[str]:
    """The umbmark modules ``path`` imports (``from a import b`` counts ``a.b`` where that
    is a module, else ``a``)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            for alias in node.names:
                name = f"{node.module}.{alias.name}"
                found.add(name if name in modules else node.module)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return {name for name in found if name.startswith("umbmark")}


def _concern(module: str) -> tuple[int, str]:
    """The rank of a bag module's concern, and the concern (its subpackage, or its rank)."""
    first = module[len(BAG) + 1 :].split(".", maxsplit=1)[0]
    rank = ORDER[first]
    return rank, first if first in ("wheels", "truth", "info") else str(rank)


def test_every_bag_module_has_a_place_in_the_order():
    modules = [m for m in _modules() if m != BAG]
    assert modules
    unplaced = [m for m in modules if m[len(BAG) + 1 :].split(".")[0] not in ORDER]
    assert not unplaced


def test_bag_modules_import_only_down_the_order():
    modules = _modules()
    upward = []
    for name, path in modules.items():
        if name == BAG:
            continue
        rank, concern = _concern(name)
        for target in _imports(path, modules):
            if target == BAG:
                upward.append(f"{name} -> {target} (the package)")
            elif target.startswith(BAG + "."):
                to_rank, to_concern = _concern(target)
                if to_rank > rank or (to_rank == rank and to_concern != concern):
                    upward.append(f"{name} -> {target}")
    assert not upward


def test_bag_imports_nothing_above_sources():
    modules = _modules()
    above = [
        f"{name} -> {target}"
        for name, path in modules.items()
        for target in _imports(path, modules)
        if not target.startswith((BAG, *OUTSIDE))
    ]
    assert not above


def test_the_bag_package_holds_no_code():
    tree = ast.parse((PACKAGE / "sources" / "bag" / "__init__.py").read_text(encoding="utf-8"))
    assert len(tree.body) == 1
    assert isinstance(tree.body[0], ast.Expr)


def test_bag_modules_form_no_import_cycle():
    modules = _modules()
    graph = {name: _imports(path, modules) & set(modules) for name, path in modules.items()}
    done: set[str] = set()

    def cycle_from(start: str) -> list[str] | None:
        path: list[str] = []
        on_path: set[str] = set()

        def visit(node: str) -> list[str] | None:
            if node in on_path:
                return [*path[path.index(node) :], node]
            if node in done:
                return None
            path.append(node)
            on_path.add(node)
            for nxt in sorted(graph[node]):
                found = visit(nxt)
                if found:
                    return found
            path.pop()
            on_path.discard(node)
            done.add(node)
            return None

        return visit(start)

    cycles = [c for c in (cycle_from(m) for m in sorted(modules)) if c]
    assert not cycles
