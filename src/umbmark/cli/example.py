"""``umbmark example``: parse the options, call :func:`umbmark.example`, render."""

from __future__ import annotations

import click

from umbmark.cli.click_options import force_option

__all__ = ["example"]


@click.command()
@click.argument("path", required=False, type=click.Path())
@force_option()
@click.option(
    "--real",
    is_flag=True,
    help="Write the two real OptiOdom sessions shipped with "
    "umbmark (a square and circles, motion-capture ground truth, MIT) into the "
    "folder PATH instead.",
)
def example(path: str | None, force: bool, real: bool) -> None:
    """Write the bundled example runs table (five cw and five ccw runs, in mm).

    PATH: where to write it; prints it when omitted. Its header says where its numbers
    come from. Calibrate it with:
    umbmark calibrate PATH --side-length 4 --wheelbase 0.34 --unit mm

    With --real, PATH is a folder that receives two real sessions of the OptiOdom data
    set: square/230620202042 (calibrate on it) and circular/250620202104 (check on it).
    """
    from umbmark import example as bundled_example
    from umbmark.cli.common import wrote

    if real:
        from pathlib import Path

        from umbmark.jobs.example import REAL_SESSIONS

        bundled_example(path, force=force, real=True)
        square, circles = (Path(str(path)) / session for session in REAL_SESSIONS)
        wrote([str(path)])
        click.echo(f"now run: umbmark calibrate {square} -o square.json")
        click.echo(f"    and: umbmark replay {circles} --params square.json")
        return

    text = bundled_example(path, force=force)
    if path is None:
        click.echo(text, nl=False)
        return
    wrote([path])
    click.echo(f"now run: umbmark calibrate {path} --side-length 4 --wheelbase 0.34 --unit mm")
