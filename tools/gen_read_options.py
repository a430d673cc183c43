"""Write ``src/umbmark/runs/read_fields.py``: the reading options as Python types, from the
option spec (``src/umbmark/options/spec.py``, ``READ_OPTIONS``).

mypy needs the keywords of ``**options: Unpack[SourceOptions]`` and the fields of
``ReadOptions`` as classes it can read, not built at run time; so they are generated text:
one key of ``SourceOptions`` and one field of ``ReadFields`` (the base of ``ReadOptions``)
per spec entry, in the spec's order, typed by :func:`python_type`, defaulting to the
spec's default, documented by its help. ``tests/runs/test_read_fields.py`` fails when the file
is not what this tool writes now: adding a reading option is adding a ``Spec`` and running

    PYTHONPATH=src python tools/gen_read_options.py          (writes the module)
    PYTHONPATH=src python tools/gen_read_options.py --check  (exit 1 if it is stale)
"""

from __future__ import annotations

import argparse
import re
import sys
import textwrap
from pathlib import Path

from umbmark.options.spec import READ_OPTIONS, Spec

#: The generated module.
TARGET = Path(__file__).resolve().parents[1] / "src" / "umbmark" / "runs" / "read_fields.py"

_WIDTH = 100
_FLAG = re.compile(r"(?<![\w-])--([a-z][a-z0-9-]*)")

_HEADER = '''"""The reading options as Python types: :class:`SourceOptions`, the keywords of
``**options`` (:func:`umbmark.calibrate`, :func:`umbmark.replay`, :func:`umbmark.report`,
:func:`umbmark.validate`), and :class:`ReadFields`, the fields of
:class:`umbmark.runs.read_options.ReadOptions` (which checks them): one per entry of
:data:`umbmark.options.spec.READ_OPTIONS`, in its order, with its type
(``Spec.py_type``, else by its kind), default and help.

Generated from src/umbmark/options/spec.py by tools/gen_read_options.py; do not edit
(tests/runs/test_read_fields.py fails when it is not what the tool writes now).
"""

from __future__ import annotations

import os
{imports}
from umbmark.options.spec import READ

__all__ = ["PathLike", "ReadFields", "SourceOptions"]

#: A path as the library takes it.
PathLike = str | os.PathLike[str]


class SourceOptions(TypedDict, total=False):
    """How to read a source: the keywords of the reading functions beyond the square's
    geometry, typed for ``**options`` (what each means: :class:`ReadFields`)."""

'''


def _doc(spec: Spec) -> str:
    """The spec's help as Python reads it: flags as keywords (``--max-gap``: ``max_gap``)."""
    return _FLAG.sub(lambda match: f"``{match[1].replace('-', '_')}``", spec.help)


def python_type(spec: Spec) -> str:
    """The spec's value's Python type, as text: its ``py_type``, else by its kind (a
    ``Literal`` of the choices, ``str``, ``float``, ``int``, ``PathLike``; a tuple for
    ``nargs`` values, ``bool`` for a flag), with ``| None`` where not given is None."""
    by_kind = {
        "text": "str",
        "number": "float",
        "integer": "int",
        "file": "PathLike",
        "folder": "PathLike",
    }
    if spec.py_type:
        text = spec.py_type
    elif spec.kind == "choice":
        text = "Literal[" + ", ".join(f'"{choice}"' for choice in spec.choices) + "]"
    elif spec.kind == "flag":
        return "bool"
    else:
        text = by_kind[spec.kind]
        if spec.nargs > 1:
            text = f"tuple[{', '.join([text] * spec.nargs)}]"
    return f"{text} | None" if spec.default is None else text


def _default(spec: Spec) -> str:
    return "None" if spec.default is None else f'READ["{spec.name}"].default'


def render() -> str:
    """The text of the generated module."""
    types = "".join(python_type(spec) for spec in READ_OPTIONS)
    imports = []
    if "Sequence[" in types:
        imports.append("from collections.abc import Sequence\n")
    imports.append("from dataclasses import dataclass\n")
    typing_names = ["Literal", "TypedDict"] if "Literal[" in types else ["TypedDict"]
    imports.append(f"from typing import {', '.join(typing_names)}\n")
    out = [_HEADER.format(imports="".join(imports))]
    out += [f"    {spec.name}: {python_type(spec)}\n" for spec in READ_OPTIONS]
    out.append(
        "\n\n@dataclass(frozen=True)\n"
        "class ReadFields:\n"
        '    """The reading options with their defaults, those of\n'
        "    :data:`umbmark.options.spec.READ` (lengths in metres, times in seconds);\n"
        "    :class:`umbmark.runs.read_options.ReadOptions` checks them.\n"
        "\n"
        "    Attributes\n"
        "    ----------\n"
    )
    for spec in READ_OPTIONS:
        out.append(f"    {spec.name} : {python_type(spec)}\n")
        out.append(
            textwrap.fill(
                _doc(spec),
                _WIDTH,
                initial_indent=" " * 8,
                subsequent_indent=" " * 8,
                break_on_hyphens=False,
            )
            + "\n"
        )
    out.append('    """\n\n')
    out += [f"    {spec.name}: {python_type(spec)} = {_default(spec)}\n" for spec in READ_OPTIONS]
    return "".join(out)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--check", action="store_true", help="only say whether the module is up to date"
    )
    args = parser.parse_args(argv)
    text = render()
    current = TARGET.read_text(encoding="utf-8") if TARGET.exists() else ""
    if args.check:
        if current != text:
            print(f"{TARGET} is stale: run python tools/gen_read_options.py", file=sys.stderr)
            return 1
        return 0
    if current != text:
        TARGET.write_text(text, encoding="utf-8")
        print(f"wrote {TARGET}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
