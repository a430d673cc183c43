"""``umbmark example``: parse the options, call :func:`umbmark.example`, render."""

from __future__ import annotations

import click

__all__ = ["example"]


@click.command()
@click.argument("path", required=False, type=click.Path(dir_okay=False))
@click.option("--force", is_flag=True, help="Overwrite an existing file.")
def example(path: str | None, force: bool) -> None:
    """Write the bundled example runs table (five cw and five ccw runs, in mm).

    PATH: where to write it; prints it when omitted. Its header says where its numbers
    come from. Calibrate it with:
    umbmark calibrate PATH --side-length 4 --wheelbase 0.34 --unit mm
    """
    from .. import example as bundled_example
    from .common import wrote

    text = bundled_example(path, force=force)
    if path is None:
        click.echo(text, nl=False)
        return
    wrote([path])
    click.echo(f"now run: umbmark calibrate {path} --side-length 4 --wheelbase 0.34 --unit mm")
