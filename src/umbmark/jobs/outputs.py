"""The files a job is asked to write, checked together before any is written."""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass, fields
from pathlib import Path

from ..errors import InputError
from ..outputs.plotting import FIGURE_FORMATS

__all__ = ["OutputPlan"]

_YAML = (".yaml", ".yml")
#: Option spelling of each output, for messages.
_FLAGS = {
    "output": "-o",
    "yaml": "--yaml",
    "ros1_yaml": "--ros1-yaml",
    "plot": "--plot",
    "tum": "--tum",
    "logs": "--logs",
}


@dataclass(frozen=True)
class OutputPlan:
    """Where each requested output goes (None: not requested)."""

    output: Path | None = None
    yaml: Path | None = None
    ros1_yaml: Path | None = None
    plot: Path | None = None
    tum: Path | None = None
    logs: Path | None = None

    @classmethod
    def of(cls, **paths: str | os.PathLike[str] | None) -> OutputPlan:
        """Check the requested outputs' names; the folders ``tum`` and ``logs`` may be new.

        Raises
        ------
        InputError
            For a name of the wrong kind, or two outputs onto one file.
        """
        plan = cls(**{k: None if v is None else Path(v) for k, v in paths.items()})
        for name in ("yaml", "ros1_yaml"):
            path = getattr(plan, name)
            if path is not None and path.suffix.lower() not in _YAML:
                raise InputError(
                    f"{_FLAGS[name]} {path}: the file name should end in .yaml or .yml"
                )
        if plan.plot is not None and plan.plot.suffix.lower() not in FIGURE_FORMATS:
            raise InputError(
                f"--plot {plan.plot}: the file name should end in {', '.join(FIGURE_FORMATS)}"
            )
        seen: dict[Path, str] = {}
        for name, path in plan.requested():
            key = path.resolve()
            if key in seen:
                raise InputError(
                    f"{_FLAGS[seen[key]]} and {_FLAGS[name]} both name {path}: "
                    "give each its own file"
                )
            seen[key] = name
        return plan

    def requested(self) -> list[tuple[str, Path]]:
        """``(keyword, path)`` of every requested output."""
        return [
            (f.name, getattr(self, f.name))
            for f in fields(self)
            if getattr(self, f.name) is not None
        ]

    def check_not_inputs(self, inputs: Iterable[str | os.PathLike[str]]) -> None:
        """Refuse an output that would overwrite one of the inputs."""
        read = [Path(p).resolve() for p in inputs if Path(p).exists()]
        for name, path in self.requested():
            target = path.resolve()
            for source in read:
                if target == source:
                    raise InputError(
                        f"{_FLAGS[name]} {path} would overwrite an input ({source}); "
                        "write the output elsewhere"
                    )
