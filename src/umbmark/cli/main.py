"""The ``umbmark`` command line: one subcommand per job.

Heavy imports (numpy, scipy, matplotlib, rosbags) happen inside the commands, so that
``umbmark --help`` answers at once.
"""

from __future__ import annotations

import typer

from .. import __version__
from .calibrate import calibrate
from .demo import demo
from .example import example
from .replay import replay
from .reproduce import reproduce_app
from .simulate import simulate

app = typer.Typer(
    name="umbmark",
    help="Measure and correct the systematic odometry errors of differential-drive robots "
    "(Borenstein & Feng's UMBmark). Lengths in metres and angles in radians unless a flag "
    "says otherwise.",
    no_args_is_help=True,
    rich_markup_mode=None,  # help texts say "[m]" and "[s]": no markup
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"umbmark {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """umbmark: UMBmark and beyond."""


app.command()(demo)
app.command()(calibrate)
app.command()(replay)
app.command()(simulate)
app.add_typer(reproduce_app, name="reproduce")
app.command()(example)


def main() -> None:
    """Entry point of the ``umbmark`` console script."""
    import os
    import sys

    try:
        app()
    except BrokenPipeError:
        # The reader of our output went away (``umbmark ... | head``): not an error of ours.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        sys.exit(1)
