"""The package's architecture (docs/architecture.md): imports go down the layers, no
import cycle, small modules and functions, jobs hold values only and import no other
command's job, one definition per public class name.

Every module of ``src/umbmark`` is parsed (not imported): every ``import`` statement
counts, at module level, inside functions and under ``TYPE_CHECKING`` alike.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

from helpers import ROOT, parsed, walked

SRC = ROOT / "src"
PACKAGE = SRC / "umbmark"

#: The layers, lowest first (docs/architecture.md). A module may import from its own
#: top-level folder and from lower layers only.
LAYERS = (
    "core",
    "options",
    "model",
    "sources",
    "runs",
    "scans",
    "returns",
    "estimators",
    "calibration",
    "sim",
    "store",
    "outputs",
    "robot",
    "routines",
    "monitor",
    "fleets",
    "jobs",
    "cli",
)
#: Modules above every layer: the lazy facade and the console script's entry.
TOP = ("umbmark", "umbmark.__main__", "umbmark._entry")
#: Data the package ships (below every layer; imports nothing of umbmark).
DATA = "umbmark.data"
#: Most lines a module may have.
MAX_LINES = 600
#: Most lines a function may have (its docstring included).
MAX_FUNCTION_LINES = 120


def _modules(root: Path = PACKAGE) -> dict[str, Path]:
    """Every module by dotted name (a package by its own name)."""
    found = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


def _imports(name: str, path: Path, modules: dict[str, Path]) -> list[tuple[str, int]]:
    """The umbmark modules ``name`` imports, with the line of each import statement."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: list[tuple[str, int]] = []
    for node in walked(path):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join([*base, *([node.module] if node.module else [])])
            else:
                target = node.module or ""
            subs = [f"{target}.{alias.name}" for alias in node.names]
            found = [t for t in subs if t in modules]
            if target in modules and (target != "umbmark" or len(found) < len(subs)):
                found.append(target)  # ``from umbmark import data`` imports the data only
            out += [(t, node.lineno) for t in found]
        elif isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names if a.name in modules]
    return [(t, line) for t, line in out if t != name]


def _layer(name: str) -> int | None:
    """The rank of a module's layer (None: in no layer)."""
    if name in TOP:
        return len(LAYERS)
    if name == DATA or name.startswith(DATA + "."):
        return -1
    folder = name.split(".")[1]
    return LAYERS.index(folder) if folder in LAYERS else None


def _folder(name: str) -> str:
    return ".".join(name.split(".")[:2])


def layer_violations(root: Path = PACKAGE) -> list[str]:
    """Every import that does not go down the layers, and every module in no layer."""
    modules = _modules(root)
    bad = [f"{name}: in no layer" for name in modules if _layer(name) is None]
    for name, path in modules.items():
        ours = _layer(name)
        if ours is None:
            continue
        for target, line in _imports(name, path, modules):
            theirs = _layer(target)
            if theirs is None or _folder(name) == _folder(target):
                continue
            if name.startswith("umbmark.cli.") and target == "umbmark":
                continue  # the command line calls the library through its facade
            if theirs >= ours and name not in TOP:
                bad.append(f"{name} (line {line}) imports {target}")
    return bad


def import_cycles(root: Path = PACKAGE) -> list[list[str]]:
    """The modules that import each other, directly or not: the strongly connected
    components of more than one module (Tarjan's algorithm, iterative)."""
    modules = _modules(root)
    graph = {
        name: sorted({t for t, _ in _imports(name, p, modules)}) for name, p in modules.items()
    }
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []
    for start in graph:
        if start in index:
            continue
        work = [(start, 0)]
        while work:
            node, i = work.pop()
            if i == 0:
                index[node] = low[node] = len(index)
                stack.append(node)
                on_stack.add(node)
            if i < len(graph[node]):
                work.append((node, i + 1))
                nxt = graph[node][i]
                if nxt not in index:
                    work.append((nxt, 0))
                elif nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
                continue
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    cycles.append(sorted(component))
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
    return cycles


def long_modules(root: Path = PACKAGE) -> list[str]:
    """Every module over :data:`MAX_LINES` lines."""
    out = []
    for name, path in _modules(root).items():
        lines = len(path.read_text(encoding="utf-8").splitlines())
        if lines > MAX_LINES:
            out.append(f"{name}: {lines} lines")
    return out


def job_classes_not_values(root: Path = PACKAGE) -> list[str]:
    """Every class of ``jobs/`` that is not a frozen dataclass (a report or a part of
    one): the jobs hold no machinery of their own."""
    out = []
    for name, path in _modules(root).items():
        if not name.startswith("umbmark.jobs."):
            continue
        for node in walked(path):
            if not isinstance(node, ast.ClassDef):
                continue
            frozen = any(
                isinstance(d, ast.Call)
                and getattr(d.func, "id", None) == "dataclass"
                and any(
                    k.arg == "frozen" and getattr(k.value, "value", None) is True
                    for k in d.keywords
                )
                for d in node.decorator_list
            )
            if not frozen:
                out.append(f"{name}.{node.name} (line {node.lineno})")
    return out


def long_functions(root: Path = PACKAGE) -> list[str]:
    """Every function or method over :data:`MAX_FUNCTION_LINES` lines."""
    out = []
    for name, path in _modules(root).items():
        for node in walked(path):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = (node.end_lineno or node.lineno) - node.lineno + 1
                if lines > MAX_FUNCTION_LINES:
                    out.append(f"{name}.{node.name} (line {node.lineno}): {lines} lines")
    return out


def _command(job: str) -> str:
    """The command a module of ``jobs/`` belongs to: ``selfcal`` for ``selfcal_report``."""
    return job.split(".")[2].split("_", maxsplit=1)[0]


def jobs_importing_jobs(root: Path = PACKAGE) -> list[str]:
    """Every import of one command's job by another's: jobs share library functions."""
    modules = _modules(root)
    out = []
    for name, path in modules.items():
        if not name.startswith("umbmark.jobs."):
            continue
        for target, line in _imports(name, path, modules):
            if target.startswith("umbmark.jobs.") and _command(target) != _command(name):
                out.append(f"{name} (line {line}) imports {target}")
    return out


def public_class_names_defined_twice(root: Path = PACKAGE) -> list[str]:
    """Every public class name (no leading underscore) defined in more than one module."""
    where: dict[str, list[str]] = {}
    for name, path in _modules(root).items():
        for node in parsed(path).body:
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                where.setdefault(node.name, []).append(name)
    return [f"{cls}: {', '.join(mods)}" for cls, mods in sorted(where.items()) if len(mods) > 1]


def test_imports_go_down_the_layers():
    bad = layer_violations()
    assert not bad, "imports against the layers:\n" + "\n".join(bad)


def test_no_import_cycle():
    cycles = import_cycles()
    assert not cycles, "import cycles:\n" + "\n".join(", ".join(c) for c in cycles)


def test_no_module_over_600_lines():
    long = long_modules()
    assert not long, f"modules over {MAX_LINES} lines:\n" + "\n".join(long)


def test_jobs_hold_only_frozen_dataclasses():
    bad = job_classes_not_values()
    assert not bad, "classes in jobs/ that are not frozen dataclasses:\n" + "\n".join(bad)


def test_no_function_over_120_lines():
    long = long_functions()
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines:\n" + "\n".join(long)


def test_jobs_import_no_other_commands_job():
    bad = jobs_importing_jobs()
    assert not bad, "jobs importing another command's job:\n" + "\n".join(bad)


def test_one_definition_per_public_class_name():
    twice = public_class_names_defined_twice()
    assert not twice, "public class names defined in several modules:\n" + "\n".join(twice)


def _package(tmp_path: Path, files: dict[str, str]) -> Path:
    root = tmp_path / "umbmark"
    for rel, text in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return root


def test_the_checks_find_what_they_look_for(tmp_path):
    """Each check names the offender in a package made to break it."""
    root = _package(
        tmp_path,
        {
            "__init__.py": "",
            "core/__init__.py": "",
            "core/low.py": "def f():\n    from umbmark.jobs.high import g\n",
            "jobs/__init__.py": "",
            "jobs/high.py": "from umbmark.core import low\n\n\nclass Machine:\n    pass\n",
            "jobs/a.py": "from umbmark.jobs.b import x\n\n\nclass Machine:\n    pass\n",
            "jobs/b.py": "import typing\nif typing.TYPE_CHECKING:\n    import umbmark.jobs.a\n"
            + "x = 1\n" * 601,
            "misc/__init__.py": "",
            "cli/__init__.py": "",
            "cli/main.py": "import umbmark\nfrom umbmark import data\n\n\ndef f():\n"
            + "    pass\n" * 120,
            "data/__init__.py": "",
        },
    )
    assert layer_violations(root) == [
        "umbmark.misc: in no layer",
        "umbmark.core.low (line 2) imports umbmark.jobs.high",
    ]
    assert sorted(import_cycles(root)) == [
        ["umbmark.core.low", "umbmark.jobs.high"],
        ["umbmark.jobs.a", "umbmark.jobs.b"],
    ]
    assert long_modules(root) == ["umbmark.jobs.b: 604 lines"]
    assert job_classes_not_values(root) == [
        "umbmark.jobs.a.Machine (line 4)",
        "umbmark.jobs.high.Machine (line 4)",
    ]
    assert long_functions(root) == ["umbmark.cli.main.f (line 5): 121 lines"]
    assert jobs_importing_jobs(root) == [
        "umbmark.jobs.a (line 1) imports umbmark.jobs.b",
        "umbmark.jobs.b (line 3) imports umbmark.jobs.a",
    ]
    assert public_class_names_defined_twice(root) == ["Machine: umbmark.jobs.a, umbmark.jobs.high"]


if __name__ == "__main__":  # pragma: no cover - a listing for people
    for line in [*layer_violations(), *map(str, import_cycles()), *long_modules()]:
        sys.stdout.write(line + "\n")


def test_the_array_types_are_named_once():
    """``FloatArray``, ``IntArray`` and ``BoolArray`` are assigned in ``core/arrays`` only."""
    where = []
    for name, path in _modules().items():
        for node in parsed(path).body:
            targets = node.targets if isinstance(node, ast.Assign) else []
            for target in targets:
                alias = getattr(target, "id", "")
                if alias in ("FloatArray", "IntArray", "BoolArray"):
                    where.append(f"{name}.{alias}")
    assert sorted(where) == [
        "umbmark.core.arrays.BoolArray",
        "umbmark.core.arrays.FloatArray",
        "umbmark.core.arrays.IntArray",
    ]


TESTS = ROOT / "tests"


def misplaced_tests(tests: Path = TESTS, package: Path = PACKAGE) -> list[str]:
    """Test files under ``tests/<folder>/`` whose folder is no layer, or whose name
    ``test_<module>.py`` names no module or package of that layer (``bag_custom``: the
    layer's ``bag/custom.py``, at any depth)."""
    out = []
    for path in sorted(tests.glob("*/test_*.py")):
        layer = path.parent.name
        if layer not in LAYERS:
            out.append(f"{path.relative_to(tests)}: {layer} is no layer")
            continue
        name = path.stem.removeprefix("test_")
        names = {
            "_".join(p.relative_to(package / layer).with_suffix("").parts)
            for p in (package / layer).rglob("*")
            if p.suffix == ".py" or (p.is_dir() and p.name != "__pycache__")
        }
        tails = {n.split("_", 1)[-1] for n in names if "_" in n} | {
            n.rsplit("_", 1)[-1] for n in names
        }
        if name not in names and name not in tails:
            out.append(f"{path.relative_to(tests)}: no module {name} in {layer}/")
    return out


def test_tests_of_one_module_sit_in_its_layers_folder(tmp_path):
    """``tests/<layer>/test_<module>.py``; tests of the whole (the command line against the
    library, the corpus, the docs) stay in ``tests/``."""
    assert misplaced_tests() == []
    assert len(list(TESTS.glob("*/test_*.py"))) >= 25
    (tmp_path / "tests" / "core").mkdir(parents=True)
    (tmp_path / "tests" / "nowhere").mkdir()
    (tmp_path / "src" / "core").mkdir(parents=True)
    (tmp_path / "src" / "core" / "stats.py").write_text("")
    for name in ("core/test_stats.py", "core/test_missing.py", "nowhere/test_x.py"):
        (tmp_path / "tests" / name).write_text("")
    assert misplaced_tests(tmp_path / "tests", tmp_path / "src") == [
        "core/test_missing.py: no module missing in core/",
        "nowhere/test_x.py: nowhere is no layer",
    ]


#: Third-party packages only one module of umbmark may import: the engine at the edge, and
#: the filesystems of recordings at URLs.
EDGE_IMPORTS = {
    "dask": "umbmark.fleets.cluster",
    "distributed": "umbmark.fleets.cluster",
    "fsspec": "umbmark.sources.remote",
    "aiohttp": "umbmark.sources.remote",
}


def edge_import_violations(root: Path = PACKAGE) -> list[str]:
    """Modules that import an edge package (Dask, fsspec) other than the one module
    allowed."""
    bad = []
    for name, path in _modules(root).items():
        for node in walked(path):
            if isinstance(node, ast.ImportFrom) and not node.level:
                names = [node.module or ""]
            elif isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            else:
                continue
            for imported in names:
                top = imported.split(".")[0]
                if top in EDGE_IMPORTS and name != EDGE_IMPORTS[top]:
                    bad.append(f"{name}:{node.lineno} imports {imported}")
    return bad


def test_the_engine_stays_at_the_edge(tmp_path):
    """Only ``umbmark.fleets.cluster`` imports Dask: calibrating one recording knows nothing
    of the engine. The check finds an import elsewhere."""
    assert edge_import_violations() == []
    package = tmp_path / "umbmark"
    (package / "jobs").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "jobs" / "__init__.py").write_text("")
    (package / "jobs" / "fleet.py").write_text("from distributed import Client\n")
    assert edge_import_violations(package) == ["umbmark.jobs.fleet:1 imports distributed"]


def test_remote_reading_stays_at_the_edge(tmp_path):
    """Only ``umbmark.sources.remote`` imports fsspec and its HTTP client: finding,
    knowing and calibrating a recording at a URL go through it. The check finds an import
    elsewhere, even inside a function."""
    assert edge_import_violations() == []
    package = tmp_path / "umbmark"
    (package / "fleets").mkdir(parents=True)
    (package / "sources").mkdir()
    for init in ("__init__.py", "fleets/__init__.py", "sources/__init__.py"):
        (package / init).write_text("")
    (package / "sources" / "remote.py").write_text("import fsspec\nimport aiohttp\n")
    (package / "fleets" / "outcome.py").write_text(
        "def f():\n    from fsspec.core import url_to_fs\n    import aiohttp.client\n"
    )
    assert edge_import_violations(package) == [
        "umbmark.fleets.outcome:2 imports fsspec.core",
        "umbmark.fleets.outcome:3 imports aiohttp.client",
    ]
