"""What a case of the hostile-input corpus is, and how the case files
(``tests/corpus/*.yaml``, see its README) make one: the loader, the text specs, the setup
steps that build a case's files from the valid inputs (``tests/corpus_inputs.py``) and
the checks of its outputs."""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
import random
import re
import shutil
import sqlite3
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from corpus_inputs import bag_step, umbmark

__all__ = ["CHECKS", "Case", "Outcome", "corpus", "digest", "run_step", "text"]

#: The case files.
CORPUS = Path(__file__).with_name("corpus")


@dataclass
class Outcome:
    """What one case did: exit status (None: timed out), output, time [s], and the
    SHA-256 of each file of the case's folder as the setup left it (relative path to hex
    digest: what :func:`unchanged` compares with)."""

    returncode: int | None
    stdout: str
    stderr: str
    seconds: float
    peak_mib: float | None = None
    before: dict[str, str] = field(default_factory=dict)


Check = Callable[[Path, Outcome], "str | None"]


@dataclass
class Case:
    """One hostile input: files made by the ``setup`` steps in the case's folder, then
    the command.

    ``argv`` follows ``python -m umbmark``; ``{d}`` is the case's folder, ``{b}`` the
    folder of the valid inputs. ``expect``: ``any`` (a result or one clean error),
    ``error`` (must be refused), ``warn`` (refused, or exit 0 with a warning holding one
    of ``warn``, any warning when empty), ``ok`` (a valid input: must succeed),
    ``do-not-apply`` (a result whose verdict is "do not apply": exit status 4).
    ``stdout``: ``pipe``, ``full`` (/dev/full) or ``head`` (closed after 10 bytes).
    """

    name: str
    reader: str
    argv: list[str]
    setup: list[dict[str, Any]] = field(default_factory=list)
    expect: str = "any"
    warn: tuple[str, ...] = ()
    env: dict[str, str] = field(default_factory=dict)
    stdout: str = "pipe"
    needs_modes: bool = False
    check: Check | None = None
    timeout: float | None = None


# --- output checks (``check: [name, args...]`` in a case file) ------------------------


def digest(path: Path) -> str:
    """The SHA-256 of a file's bytes (hex)."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def unchanged(rel: str) -> Check:
    """``rel`` holds the bytes the setup left in it (:attr:`Outcome.before`)."""

    def check(d: Path, out: Outcome) -> str | None:
        if rel not in out.before:
            return f"{rel} was not made by the setup"
        if not (d / rel).is_file() or digest(d / rel) != out.before[rel]:
            return f"{rel} was overwritten"
        return None

    return check


def still_link(rel: str) -> Check:
    return lambda d, out: None if (d / rel).is_symlink() else f"{rel} is no longer a symlink"


def mode_is(rel: str, mode: str) -> Check:
    def check(d: Path, out: Outcome) -> str | None:
        got = (d / rel).stat().st_mode & 0o777
        return None if got == int(mode, 8) else f"{rel} has mode {got:o}, was {mode}"

    return check


def absent(rel: str) -> Check:
    return lambda d, out: (
        f"{rel} was written although the command failed" if (d / rel).exists() else None
    )


def wrote(n: str) -> Check:
    def check(d: Path, out: Outcome) -> str | None:
        got = sum(line.startswith("umbmark: wrote ") for line in out.stderr.splitlines())
        return None if got >= int(n) else f"{got} 'wrote' lines for {n} outputs"

    return check


def not_wrapped() -> Check:
    """Piped, the summary keeps each line whole: the overlay's header line ends with its
    method, not broken at 80 columns."""

    def check(d: Path, out: Outcome) -> str | None:
        head = [ln for ln in out.stdout.splitlines() if ln.startswith("# Written by umbmark")]
        if not head:
            return "no overlay header line in the summary"
        return (
            None if head[0].rstrip().endswith("(method exact).") else "a line wrapped at 80 columns"
        )

    return check


def second_pass_used() -> Check:
    """The table's header records the parameters active while it was simulated: they are
    used (active c_L not 1) or a warning says they were not."""

    def check(d: Path, out: Outcome) -> str | None:
        if "umbmark: warning:" in out.stderr:
            return None
        try:
            data = json.loads(out.stdout)
        except ValueError:
            return "no JSON"
        if abs(float(data.get("active", {}).get("c_L", 1.0)) - 1.0) < 1e-12:
            return "the active parameters the table records were neither used nor warned about"
        return None

    return check


CHECKS: dict[str, Callable[..., Check]] = {
    f.__name__: f
    for f in (unchanged, still_link, mode_is, absent, wrote, not_wrapped, second_pass_used)
}


# --- the case files -----------------------------------------------------------------


def corpus() -> list[Case]:
    """Every case of ``tests/corpus/*.yaml``, in file order, with unique names."""
    common = _load(CORPUS / "common.yaml")["vars"]
    cases: list[Case] = []
    for path in sorted(CORPUS.glob("*.yaml")):
        if path.name != "common.yaml":
            doc = _load(path)
            scope = {**common, **doc.get("vars", {})}
            for entry in doc["cases"]:
                cases.extend(_expand(entry, {}, scope, {"reader": doc["reader"]}))
    dupes = [n for n, k in Counter(c.name for c in cases).items() if k > 1]
    assert not dupes, dupes
    return cases


def _load(path: Path) -> Any:
    with path.open(encoding="utf-8") as file:  # every scalar a string, as written
        return yaml.load(file, Loader=yaml.BaseLoader)


def _expand(
    entry: Any, bound: dict[str, Any], refs: dict[str, Any], defaults: dict[str, Any]
) -> Iterator[Case]:
    """The cases of one entry: a case, or a group (``cases``) whose other keys are the
    defaults of its cases; ``for`` repeats either over the rows of values it gives."""
    body = {**defaults, **{k: v for k, v in entry.items() if k != "for"}}
    for row in _rows(_subst(entry.get("for"), bound), refs):
        scope = {**bound, **row}
        if "cases" in body:
            inner = {k: v for k, v in body.items() if k != "cases"}
            for sub in body["cases"]:
                yield from _expand(sub, scope, refs, inner)
        else:
            yield _case(_subst(_resolve(_subst(body, scope), refs), scope))


def _rows(loops: Any, refs: dict[str, Any]) -> list[dict[str, Any]]:
    """``for``: a list of rows (mappings), or a mapping of each name to its values (a
    list, ``{range: n}`` or a ``$reference``), whose product it makes (first name
    outermost)."""
    loops = _resolve(loops, refs)
    if loops is None:
        return [{}]
    if isinstance(loops, list):
        return loops
    values = []
    for spec in loops.values():
        if isinstance(spec, dict) and "range" in spec:
            values.append([str(i) for i in range(int(spec["range"]))])
        else:
            values.append(list(spec))
    return [dict(zip(loops, combo, strict=True)) for combo in itertools.product(*values)]


def _subst(obj: Any, scope: dict[str, Any]) -> Any:
    """``{name}`` replaced by the value bound to ``name`` (a whole string: the value, in
    which names are replaced in turn)."""
    if isinstance(obj, dict):
        return {k: _subst(v, scope) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_subst(v, scope) for v in obj]
    if isinstance(obj, str):
        for name, value in scope.items():
            if obj == "{" + name + "}":
                return _subst(value, scope)
            if "{" + name + "}" in obj:
                obj = obj.replace("{" + name + "}", as_str(value))
    return obj


def _resolve(obj: Any, refs: dict[str, Any]) -> Any:
    """``$name`` and ``$name.key`` replaced by the value of the file's or common vars."""
    if isinstance(obj, dict):
        return {k: _resolve(v, refs) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_resolve(v, refs) for v in obj]
    if isinstance(obj, str) and obj.startswith("$"):
        name, _, key = obj[1:].partition(".")
        value = refs[name]
        return _resolve(value[key] if key else value, refs)
    return obj


def _argv(items: list[Any]) -> Iterator[str]:
    """Arguments: a list is spliced, ``{repeat: [arg, n]}`` n copies, a text spec is
    its text."""
    for item in items:
        if isinstance(item, list):
            yield from _argv(item)
        elif isinstance(item, dict) and "repeat" in item:
            yield from [as_str(item["repeat"][0])] * int(item["repeat"][1])
        else:
            yield as_str(item)


def _case(spec: dict[str, Any]) -> Case:
    check = spec.get("check")
    if check is not None:
        name, *args = check if isinstance(check, list) else [check]
        check = CHECKS[name](*args)
    return Case(
        name=spec["name"],
        reader=spec["reader"],
        argv=list(_argv(spec["argv"])),
        setup=spec.get("setup", []),
        expect=spec.get("expect", "any"),
        warn=tuple(spec.get("warn", ())),
        env=dict(spec.get("env", {})),
        stdout=spec.get("stdout", "pipe"),
        needs_modes=spec.get("needs_modes") == "true",
        check=check,
        timeout=float(spec["timeout"]) if "timeout" in spec else None,
    )


# --- text specs and file mutations ------------------------------------------------------


def text(spec: Any) -> str | bytes:
    """A text spec of a case file as ``str`` (written as UTF-8) or ``bytes``.

    A string is itself; a list is its parts joined, and so is ``{join: [specs]}``;
    ``{times: [s, n]}`` is ``s`` n times; ``{latin1: spec}`` the bytes of ``spec`` in
    Latin-1; ``{deep_block: n}`` n nested YAML block mappings; ``{windows: n}`` n
    ``--windows`` pairs; ``{columns: n}`` n column names.
    """
    if isinstance(spec, str):
        return spec
    if isinstance(spec, list):
        parts = [text(s) for s in spec]
        return b"".join(parts) if any(isinstance(p, bytes) for p in parts) else "".join(parts)  # type: ignore[arg-type]
    ((kind, arg),) = spec.items()
    if kind == "times":
        return text(arg[0]) * int(arg[1])
    if kind == "join":
        return text(list(arg))
    if kind == "latin1":
        return str(text(arg)).encode("latin-1")
    if kind == "deep_block":
        depth = int(arg)
        return "".join(" " * i + f"k{i}:\n" for i in range(depth)) + " " * depth + "v: 1\n"
    if kind == "windows":
        return ",".join(f"{i}:{i + 1}" for i in range(int(arg)))
    if kind == "columns":
        return ",".join(f"c{i}" for i in range(int(arg)))
    raise ValueError(f"unknown text spec {kind!r}")


def as_str(spec: Any) -> str:
    value = text(spec)
    return value if isinstance(value, str) else value.decode("utf-8", "surrogateescape")


def _data_rows(data: bytes) -> tuple[list[bytes], list[int]]:
    """Lines, and the indices of the data rows (first cell a number)."""
    lines = data.split(b"\n")
    rows = [
        i
        for i, line in enumerate(lines)
        if line[:1].isdigit() or (line[:1] == b"-" and line[1:2].isdigit())
    ]
    return lines, rows


def _cells(
    data: bytes, rows: Callable[[list[int]], list[int]], fn: Callable[[list[bytes]], None]
) -> bytes:
    """``fn`` applied to the cells of the data rows ``rows`` picks."""
    lines, all_rows = _data_rows(data)
    for i in rows(all_rows):
        cells = lines[i].split(b",")
        fn(cells)
        lines[i] = b",".join(cells)
    return b"\n".join(lines)


def _bytes(data: str | bytes) -> bytes:
    return data if isinstance(data, bytes) else data.encode("utf-8")


def _set(col: int, value: Callable[[bytes], float] | bytes) -> Callable[[list[bytes]], None]:
    def fn(cells: list[bytes]) -> None:
        if col < len(cells):
            cells[col] = value if isinstance(value, bytes) else repr(value(cells[col])).encode()

    return fn


def _replace(data: bytes, old: str, new: Any, count: int) -> bytes:
    body = data.decode("utf-8")
    assert old in body, old
    return body.replace(old, as_str(new), count).encode("utf-8")


def _yaml_set(data: bytes, key: str, value: Any) -> bytes:
    lines = data.decode("utf-8").splitlines()
    i = next(i for i, line in enumerate(lines) if line.lstrip().startswith(key + ":"))
    indent = lines[i][: len(lines[i]) - len(lines[i].lstrip())]
    lines[i] = f"{indent}{key}: {as_str(value)}"
    return ("\n".join(lines) + "\n").encode("utf-8")


def _flips(data: bytes, seed: int, step: int, modulo: int = 0) -> bytes:
    """``1 + step * seed`` (modulo ``modulo``) random bytes replaced, drawn by ``seed``."""
    count = 1 + (step * seed) % modulo if modulo else 1 + step * seed
    rng = random.Random(seed)
    out = bytearray(data)
    for _ in range(count):
        i = rng.randrange(len(out))
        out[i] = rng.randrange(256)
    return bytes(out)


def _repeat_rows(data: bytes, times: int) -> bytes:
    """A run-log CSV driven ``times`` over, as one long recording: time goes on, the
    counts (columns 4, 5) keep adding up, the truth starts each lap where the last ended."""
    lines, rows = _data_rows(data)
    kept = set(rows)
    head = [line for i, line in enumerate(lines) if i not in kept and line]
    parsed = [[float(c) for c in lines[i].split(b",")] for i in rows]
    step = parsed[1][0] - parsed[0][0]
    out = []
    for lap in range(times):
        for n, cells in enumerate(parsed, lap * len(parsed)):
            left, right = (cells[j] + lap * parsed[-1][j] for j in (4, 5))
            values = [f"{n * step:.6f}", *(f"{c:.6f}" for c in cells[1:4])]
            out.append(",".join([*values, f"{left:.0f}", f"{right:.0f}"]).encode())
    return b"\n".join([*head, *out]) + b"\n"


def _reverse_rows(data: bytes, start: int, stop: int) -> bytes:
    lines, rows = _data_rows(data)
    chosen = rows[start:stop]
    for i, line in zip(chosen, [lines[i] for i in chosen][::-1], strict=True):
        lines[i] = line
    return b"\n".join(lines)


def _duplicate_times(data: bytes, every: int) -> bytes:
    lines, rows = _data_rows(data)
    for a, b in zip(rows[::every], rows[1::every], strict=False):
        lines[b] = b",".join([lines[a].split(b",")[0], *lines[b].split(b",")[1:]])
    return b"\n".join(lines)


def _drop_column(data: bytes, index: int) -> bytes:
    out = []
    for line in data.decode("utf-8").splitlines():
        cells = line.split(",")
        out.append(line if line.startswith("#") else ",".join(cells[:index] + cells[index + 1 :]))
    return ("\n".join(out) + "\n").encode("utf-8")


def _many_rows(data: bytes, n: int) -> bytes:
    rows = [line for line in data.decode("utf-8").splitlines()[6:] if line]
    body = "\n".join(rows[i % len(rows)] for i in range(n))
    return ("direction,x_abs,y_abs,x_odo,y_odo\n" + body + "\n").encode("utf-8")


def _degrees(data: bytes) -> bytes:
    """A runs table's headings (columns 3 and 6) from radians to degrees."""
    out = []
    for line in data.decode("utf-8").splitlines():
        cells = line.split(",")
        if len(cells) == 7 and cells[0] in ("cw", "ccw"):
            for j in (3, 6):
                cells[j] = f"{math.degrees(float(cells[j])):.6f}"
        out.append(",".join(cells))
    return ("\n".join(out) + "\n").encode("utf-8")


def _json(data: bytes, path: str, value: str | None) -> bytes:
    """Set (``value``: JSON text) or delete (None) the member at dotted ``path``."""
    doc = json.loads(data)
    *parents, key = path.split(".")
    target = doc
    for p in parents:
        target = target[p]
    if value is None:
        del target[key]
    else:
        target[key] = json.loads(value)
    return json.dumps(doc).encode("utf-8")


#: Rewrites of a file the case already holds: ``{op: [path, *args]}`` in a case file.
MUTATIONS: dict[str, Callable[..., bytes]] = {
    "truncate": lambda data, frac: data[: int(len(data) * float(frac))],
    "flips": lambda data, *args: _flips(data, *map(int, args)),
    "reencode": lambda data, codec: data.decode("utf-8").encode(codec),
    "replace": lambda data, old, new: _replace(data, old, new, 1),
    "replace_all": lambda data, old, new: _replace(data, old, new, -1),
    "prepend": lambda data, head: _bytes(text(head)) + data,
    "append": lambda data, tail: data + _bytes(text(tail)),
    "drop_lines": lambda data, pattern: b"\n".join(
        ln for ln in data.splitlines() if not re.match(pattern.encode(), ln)
    ),
    "yaml_set": _yaml_set,
    "set_cell": lambda data, row, col, value: _cells(
        data,
        lambda rows: [rows[min(int(row), len(rows) - 1)]],
        _set(int(col), as_str(value).encode()),
    ),
    "scale_column": lambda data, col, factor: _cells(
        data, lambda rows: rows, _set(int(col), lambda c: float(c) * float(factor))
    ),
    "jump_column": lambda data, col, jump: _cells(
        data, lambda rows: rows[len(rows) // 2 :], _set(int(col), lambda c: float(c) + float(jump))
    ),
    "reverse_rows": lambda data, start, stop: _reverse_rows(data, int(start), int(stop)),
    "duplicate_times": lambda data, every: _duplicate_times(data, int(every)),
    "repeat_rows": lambda data, times: _repeat_rows(data, int(times)),
    "drop_column": lambda data, index: _drop_column(data, int(index)),
    "many_rows": lambda data, n: _many_rows(data, int(n)),
    "degrees": _degrees,
    "json_set": _json,
    "json_del": lambda data, path: _json(data, path, None),
}


def _copy(d: Path, b: Path, src: str, dst: str = "") -> None:
    source, target = b / src, d / (dst or Path(src).name)
    if source.is_dir():
        shutil.copytree(source, target)
    else:
        shutil.copy(source, target)


def _write(d: Path, b: Path, name: str, spec: Any) -> None:
    target = d / name
    target.parent.mkdir(parents=True, exist_ok=True)
    data = text(spec)
    if isinstance(data, str):
        target.write_text(data, encoding="utf-8")
    else:
        target.write_bytes(data)


def _loop(d: Path, b: Path, name: str) -> None:
    target = d / name
    other = target.with_name(target.name + ".other")
    target.symlink_to(other.name)
    other.symlink_to(target.name)


def _sqlite(d: Path, b: Path, name: str, table: str, column: str) -> None:
    """A database that is not umbmark's: ``table`` with one text ``column``, one row."""
    con = sqlite3.connect(d / name)
    with con:
        con.execute(f"create table {table} ({column} text)")
        con.execute(f"insert into {table} values ('x')")
    con.close()


#: Steps other than :data:`MUTATIONS`: ``{step: args}`` in a case file, run with the case
#: folder ``d`` and the folder of valid inputs ``b``.
STEPS: dict[str, Callable[..., None]] = {
    "copy": _copy,
    "write": _write,
    "mkdir": lambda d, b, name, mode="777": (d / name).mkdir(int(mode, 8)),
    "chmod": lambda d, b, name, mode: (d / name).chmod(int(mode, 8)),
    "symlink": lambda d, b, name, target: (d / name).symlink_to(target.replace("{d}", str(d))),
    "loop": _loop,
    "remove": lambda d, b, name: (d / name).unlink(),
    "fifo": lambda d, b, name: os.mkfifo(d / name),
    "sqlite": _sqlite,
    "bag": bag_step,
    "umbmark": lambda d, b, *args: umbmark(
        *(a.replace("{d}", str(d)).replace("{b}", str(b)) for a in args), cwd=d
    ),
}


def run_step(step: dict[str, Any], d: Path, b: Path) -> None:
    """Run one setup step of a case in its folder ``d`` (a mutation: of every file its
    path matches, when that is a glob pattern)."""
    ((name, args),) = step.items()
    args = args if isinstance(args, list) else [args]
    if name in MUTATIONS:
        pattern = any(c in args[0] for c in "*?[")
        for target in sorted(d.glob(args[0])) if pattern else [d / args[0]]:
            target.chmod(0o600)
            target.write_bytes(MUTATIONS[name](target.read_bytes(), *args[1:]))
    elif name == "umbmark":
        STEPS[name](d, b, *_flat(args))
    else:
        STEPS[name](d, b, *args)


def _flat(items: list[Any]) -> list[str]:
    return [s for item in items for s in (_flat(item) if isinstance(item, list) else [item])]
