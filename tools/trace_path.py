"""The way one command takes through the package: each module it enters, in order.

Runs an ``umbmark`` command in this process with a profile hook that notes each call from
one layer of the package into another (``jobs.calibrate`` calling ``runs.active``; a
call within a layer, ``estimators.exact`` calling ``estimators.solve``, is part of the
same step). Consecutive calls into one module are one visit. The tool prints the visits in
order (module, then the functions called there, first few) and two counts: how many
distinct modules the command passes through, and how many times it returns to a module it
had left (the zig-zags of issue 24). Import-time code (module and class bodies) and
generators resuming are left out: they are the facade loading and data streaming, not
the command's way.

Run: python tools/trace_path.py calibrate src/umbmark/data/labmate_runs_mm.csv --units mm
     python tools/trace_path.py --summary calibrate ...   (the counts only)
     python tools/trace_path.py --skip core,options ...   (leave layers out of the way)

The command's own output goes to a null stream; its exit status is printed.
"""

from __future__ import annotations

import argparse
import contextlib
import inspect
import io
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from types import FrameType
from typing import Any

_GENERATOR = inspect.CO_GENERATOR | inspect.CO_ASYNC_GENERATOR


@dataclass
class Visit:
    """One stretch of calls inside one module."""

    module: str
    functions: list[str] = field(default_factory=list)


@dataclass
class Trace:
    visits: list[Visit] = field(default_factory=list)
    skip: tuple[str, ...] = ()
    every_call: bool = False

    def hook(self, frame: FrameType, event: str, _arg: Any) -> None:  # noqa: ANN401
        if event != "call":
            return
        module = frame.f_globals.get("__name__", "")
        if not module.startswith("umbmark.") and module != "umbmark":
            return
        name = frame.f_code.co_name
        if frame.f_code.co_flags & _GENERATOR:  # a stream resumed, not a step taken
            return
        if name.startswith(("<", "__create_fn__")) or _importing(frame):
            return
        short = module.removeprefix("umbmark.")
        if short.split(".")[0] in self.skip:
            return
        caller = frame.f_back
        before = "" if caller is None else caller.f_globals.get("__name__", "")
        if not self.every_call and _layer(before) == _layer(module):
            return  # within one layer: one step of the way, not a new one
        if self.visits and self.visits[-1].module == short:
            last = self.visits[-1]
            if name not in last.functions:
                last.functions.append(name)
            return
        self.visits.append(Visit(short, [name]))

    def returns(self) -> int:
        """Visits to a module that had been visited and then left before."""
        seen: set[str] = set()
        count = 0
        for visit in self.visits:
            if visit.module in seen:
                count += 1
            seen.add(visit.module)
        return count


def _layer(module: str) -> str:
    """``umbmark.runs.read`` -> ``runs``; outside umbmark, the empty string."""
    parts = module.split(".")
    return parts[1] if parts[0] == "umbmark" and len(parts) > 1 else ""


def _importing(frame: FrameType) -> bool:
    """Whether a call is part of importing a module (a module or class body above it)."""
    caller = frame.f_back
    while caller is not None:
        code = caller.f_code
        if code.co_name == "<module>":
            return caller.f_globals.get("__name__") != "__main__"
        if code.co_name == "main" and caller.f_globals.get("__name__") == "__main__":
            return False
        if code.co_name[:1].isupper() and code.co_qualname == code.co_name:  # a class body
            return True
        caller = caller.f_back
    return False


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--summary", action="store_true", help="print the counts only")
    parser.add_argument("--skip", default="", help="layers to leave out, comma-separated")
    parser.add_argument(
        "--every-call",
        action="store_true",
        help="count calls within a layer too (by default a step is a call into another layer)",
    )
    parser.add_argument("command", nargs=argparse.REMAINDER, help="umbmark's arguments")
    args = parser.parse_args(argv)
    if not args.command:
        parser.error("give the command, e.g. calibrate runs.csv")

    from umbmark.cli.main import main as umbmark_main

    trace = Trace(skip=tuple(s for s in args.skip.split(",") if s), every_call=args.every_call)
    sink = io.StringIO()
    status: int | str | None = 0
    sys.setprofile(trace.hook)
    try:
        with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
            umbmark_main(args.command)
    except SystemExit as exit_:
        status = exit_.code
    finally:
        sys.setprofile(None)
    modules = {v.module for v in trace.visits}
    if not args.summary:
        for i, visit in enumerate(trace.visits, 1):
            shown = ", ".join(visit.functions[:4])
            more = f" (+{len(visit.functions) - 4})" if len(visit.functions) > 4 else ""
            print(f"{i:4d}  {visit.module:40s} {shown}{more}")
    print(f"umbmark {' '.join(args.command)}: exit {status}")
    print(f"{len(modules)} modules, {len(trace.visits)} visits, {trace.returns()} returns")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
