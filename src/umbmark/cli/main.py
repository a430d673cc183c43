"""The ``umbmark`` command line: one subcommand per job, each a thin layer over the
library function of the same name (parse the options, call, render).

Every failure the user can cause ends as one line on stderr and exit status 2: bad
input (:class:`umbmark.InputError`) and malformed options alike.
"""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import ItemsView, Iterator, KeysView, Sequence, ValuesView

import click

from umbmark.cli.common import EXIT_BAD_INPUT, error_line, input_error_line, reading_bar
from umbmark.core.errors import InputError, SafetyError, with_flags
from umbmark.core.version import __version__

__all__ = ["cli", "main"]

#: Exit status after Ctrl-C, as shells report it.
EXIT_INTERRUPTED = 130
#: Exit status when the environment fails us: a full disk, a folder we may not write.
EXIT_ENVIRONMENT = 3
#: Exit status of a failure of umbmark itself (a bug): BSD's EX_SOFTWARE.
EXIT_INTERNAL = 70


class _InterruptedError(Exception):
    """A Ctrl-C inside a command, kept from click (which would print a blank line)."""


#: The subcommands, each in its module of ``umbmark.cli`` under its own name.
COMMANDS = (
    "demo",
    "calibrate",
    "replay",
    "report",
    "validate",
    "info",
    "plan",
    "simulate",
    "study",
    "reproduce",
    "example",
    "history",
    "selfcal",
    "fleet",
    "monitor",
)


class _Commands(dict[str, click.Command]):
    """The subcommands, each imported the first time it is asked for, so that running one
    command does not import the others (``--help`` asks for all of them)."""

    def _load(self, name: str) -> click.Command | None:
        if name not in COMMANDS:
            return None
        if not dict.__contains__(self, name):
            command = getattr(importlib.import_module(f"umbmark.cli.{name}"), name)
            dict.__setitem__(self, name, command)
        return dict.__getitem__(self, name)

    def __getitem__(self, name: str) -> click.Command:
        command = self._load(name)
        if command is None:
            raise KeyError(name)
        return command

    def get(self, name: str, default: click.Command | None = None) -> click.Command | None:  # type: ignore[override]
        return self._load(name) or default

    def __contains__(self, name: object) -> bool:
        return name in COMMANDS

    def __iter__(self) -> Iterator[str]:
        return iter(COMMANDS)

    def __len__(self) -> int:
        return len(COMMANDS)

    def keys(self) -> KeysView[str]:  # type: ignore[override]
        return dict.fromkeys(COMMANDS).keys()

    def values(self) -> ValuesView[click.Command]:  # type: ignore[override]
        return {name: self[name] for name in COMMANDS}.values()

    def items(self) -> ItemsView[str, click.Command]:  # type: ignore[override]
        return {name: self[name] for name in COMMANDS}.items()


class _Group(click.Group):
    """The ``umbmark`` group: a Ctrl-C inside a command reaches :func:`main` whole."""

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except KeyboardInterrupt:
            raise _InterruptedError from None


@click.group(
    cls=_Group,
    commands=_Commands(),
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100},
    no_args_is_help=True,
)
@click.version_option(__version__, "--version", prog_name="umbmark", message="%(prog)s %(version)s")
def cli() -> None:
    """Measure and correct the systematic odometry errors of differential-drive robots
    (Borenstein & Feng's UMBmark). Lengths in metres and angles in radians unless an
    option says otherwise; every command has --help."""


def _usage(exc: click.UsageError) -> str:
    command = exc.ctx.command_path if exc.ctx is not None else "umbmark"
    return f"{exc.format_message()} (see {command} --help)"


def _command(argv: Sequence[str] | None) -> click.Command | None:
    """The command ``argv`` ran (a command of a group followed to its end), if any."""
    command: click.Command = cli
    for word in list(sys.argv[1:] if argv is None else argv):
        if not isinstance(command, click.Group):
            break
        found = command.commands.get(word)
        if found is None:
            if not word.startswith("-"):
                break
            continue
        command = found
    return None if command is cli else command


def main(argv: Sequence[str] | None = None) -> None:
    """Entry point of the ``umbmark`` console script.

    Exit status: 0 done, 2 bad input or options (one line on stderr naming the file or
    flag), 3 the environment failed (disk full, permission denied, a path too long) or
    the robot was stopped for safety, 4 a calibration done whose verdict is "do not
    apply" (its overlay withheld; ``--override-verdict`` gives 0), 70 a failure of
    umbmark itself (one line; please report it), 130 interrupted.
    """
    for stream in (sys.stdout, sys.stderr):  # an ASCII-only terminal: escape, never crash
        reconfigure = getattr(stream, "reconfigure", None)
        if reconfigure is not None:
            reconfigure(errors="backslashreplace")
    try:
        with reading_bar():  # long bags show their progress on a terminal's stderr
            code = cli.main(args=argv, prog_name="umbmark", standalone_mode=False)
    except click.exceptions.NoArgsIsHelpError as exc:
        click.echo(exc.ctx.get_help() if exc.ctx is not None else cli.get_help(click.Context(cli)))
        sys.exit(0)
    except click.UsageError as exc:
        error_line(_usage(exc))
        sys.exit(EXIT_BAD_INPUT)
    except SafetyError as exc:  # the robot was stopped: a zero velocity was sent
        error_line(f"stopped for safety: {exc}")
        sys.exit(EXIT_ENVIRONMENT)
    except InputError as exc:
        error_line(input_error_line(exc, _command(argv)))  # options as flags (--unit mm)
        sys.exit(EXIT_BAD_INPUT)
    except (click.Abort, KeyboardInterrupt, _InterruptedError):
        # One line; on a terminal after a line break, as the ^C the terminal echoed has none.
        sys.stderr.write(("\n" if sys.stderr.isatty() else "") + "umbmark: interrupted\n")
        sys.exit(EXIT_INTERRUPTED)
    except BrokenPipeError:
        # The reader of our output went away (``umbmark ... | head``): not an error of ours.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        sys.exit(1)
    except OSError as exc:
        where = f"{exc.filename}: " if exc.filename else ""
        error_line(f"{where}{exc.strerror or exc}")
        sys.exit(EXIT_ENVIRONMENT)
    except MemoryError:
        error_line("out of memory: the input is too large for this machine")
        sys.exit(EXIT_ENVIRONMENT)
    except Exception as exc:  # a bug of ours: still one line, never a traceback
        first = with_flags(str(exc)).splitlines()[0] if str(exc) else ""
        error_line(
            f"internal error ({type(exc).__name__}: {first})"
            "; please report it with the command that caused it"
        )
        sys.exit(EXIT_INTERNAL)
    sys.exit(code if isinstance(code, int) else 0)
