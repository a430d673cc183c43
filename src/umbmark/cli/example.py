"""``umbmark example``: write the bundled example runs table."""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Annotated

import typer

from .common import reports_input_errors

__all__ = ["EXAMPLE_RUNS", "example"]

#: The bundled example, in ``umbmark/data``.
EXAMPLE_RUNS = "labmate_runs_mm.csv"


@reports_input_errors
def example(
    path: Annotated[
        Path | None,
        typer.Argument(help="Where to write it; prints it when omitted.", show_default=False),
    ] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite an existing file.")] = False,
) -> None:
    """Write the bundled example runs table (five cw and five ccw runs, in mm).

    Its header says where its numbers come from. Calibrate it with:
    umbmark calibrate PATH --side-length 4 --wheelbase 0.34 --unit mm
    """
    from ..errors import InputError
    from ..io.atomic import atomic_write_text

    text = resources.files("umbmark.data").joinpath(EXAMPLE_RUNS).read_text(encoding="utf-8")
    if path is None:
        typer.echo(text, nl=False)
        return
    if path.exists() and not force:
        raise InputError("exists already; pass --force to overwrite it", source=path)
    atomic_write_text(path, text)
    typer.echo(
        f"wrote {path}; now run: umbmark calibrate {path} --side-length 4 --wheelbase 0.34 "
        "--unit mm"
    )
