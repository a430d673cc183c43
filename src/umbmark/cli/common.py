"""What every command shares: error and warning lines, progress bars, the console."""

from __future__ import annotations

import contextlib
import math
import shlex
import sys
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import click

if TYPE_CHECKING:
    from rich.console import Console
    from rich.progress import Progress, TaskID

    from umbmark.core.errors import InputError

__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_DO_NOT_APPLY",
    "command_line",
    "console",
    "error_line",
    "flags_of",
    "input_error_line",
    "note",
    "progress_bar",
    "progress_lines",
    "reading_bar",
    "warn",
    "working",
    "wrote",
]

#: Exit status for bad input (as for a usage error).
EXIT_BAD_INPUT = 2
#: Exit status of a calibration done whose verdict is "do not apply" (its overlay
#: withheld): a valid result that a script must not apply. 3 is the environment's, 70
#: umbmark's own failure, 130 an interrupt (``cli.main.main``).
EXIT_DO_NOT_APPLY = 4
#: Width of output that goes to a file or a pipe: wide enough that no table is narrowed
#: (a long path in a cell would otherwise be cut, or a value split across lines).
_PIPE_WIDTH = 10_000


#: Longest error line [characters]: a value of megabytes is not echoed whole.
LONGEST_LINE = 1000


def error_line(message: str) -> None:
    """Print one error line to stderr (plain text: no wrapping, no colour codes; at most
    :data:`LONGEST_LINE` characters of the message, the rest left out and counted)."""
    text = " ".join(message.split())
    if len(text) > LONGEST_LINE:
        half = LONGEST_LINE // 2
        text = f"{text[:half]} ... ({len(text) - 2 * half} characters left out) ... {text[-half:]}"
    sys.stderr.write(f"umbmark: error: {text}\n")


def flags_of(command: click.Command | None) -> dict[str, str]:
    """The flag that names each of ``command``'s options in its messages, by keyword: the
    first long one (``--from`` for ``previous``, ``--output`` for ``output``). Switches
    that share one keyword (``selfcal``'s ``--sim``, ``--ros1``, ``--ros2``) name none."""
    if command is None:
        return {}
    out: dict[str, str] = {}
    for param in command.params:
        if isinstance(param, click.Option) and param.name:
            if param.is_flag and not param.is_bool_flag:
                continue
            long = [flag for flag in param.opts if flag.startswith("--")]
            out[param.name] = (long or param.opts)[0]
    return out


def input_error_line(error: InputError, command: click.Command | None) -> str:
    """An :class:`~umbmark.core.errors.InputError` as ``command`` names its options."""
    return error.command_line(flags_of(command))


def warn(message: str) -> None:
    """Print one warning line to stderr."""
    sys.stderr.write(f"umbmark: warning: {' '.join(message.split())}\n")


def note(message: str) -> None:
    """Print one line of what was done to stderr (a success, never a ``warning:``)."""
    sys.stderr.write(f"umbmark: {' '.join(message.split())}\n")


def wrote(paths: Iterable[str | Path]) -> None:
    """Say on stderr which files were written (stdout stays for the result)."""
    for path in paths:
        sys.stderr.write(f"umbmark: wrote {path}\n")


def console() -> Console:
    """A console on stdout; not wrapped at 80 columns when piped."""
    from rich.console import Console

    out = Console(highlight=False)
    if not out.is_terminal:
        out = Console(highlight=False, width=_PIPE_WIDTH, soft_wrap=True)
    return out


@contextlib.contextmanager
def progress_bar(description: str) -> Iterator[Callable[[float], None]]:
    """A progress bar on stderr; yields a callback taking the fraction done (0 to 1).

    Shown only on a terminal, so that pipes and ``--json`` output stay clean.
    """
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    err = Console(stderr=True)
    if not err.is_terminal:
        yield lambda fraction: None
        return
    with Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeElapsedColumn(),
        console=err,
        transient=True,
    ) as bar:
        task = bar.add_task(description, total=1.0)
        _LIVE.append(bar)  # a bag read meanwhile shows its bar in this display
        try:
            yield lambda fraction: bar.update(task, completed=fraction)
        finally:
            _LIVE.remove(bar)


def progress_lines(
    every: float = 0.0, clock: Callable[[], float] = time.monotonic
) -> Callable[[int, int, str], None]:
    """Progress for logs (stderr not a terminal: cron, a log file, CI): a callback
    ``(done, of, text)`` printing ``umbmark: progress: TEXT`` when ``done`` has grown, at
    most one line every ``every`` seconds of ``clock`` (0: at each step), the last step
    (``done`` reaching ``of``) always."""
    said = {"done": 0, "at": -math.inf}

    def line(done: int, of: int, text: str) -> None:
        now = clock()
        if done <= said["done"] or (done < of and now - said["at"] < every):
            return
        said.update(done=done, at=now)
        note(f"progress: {text}")

    return line


@contextlib.contextmanager
def status_line(description: str) -> Iterator[Callable[[str], None]]:
    """A spinner with a changing text and the time elapsed on stderr (on a terminal
    only); yields a callback taking the text to show now."""
    from rich.console import Console
    from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    err = Console(stderr=True)
    if not err.is_terminal:
        yield lambda text: None
        return
    with Progress(
        SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(),
        console=err, transient=True,
    ) as bar:  # fmt: skip
        task = bar.add_task(f"{description} (Ctrl-C stops)", total=None)
        yield lambda text: bar.update(task, description=f"{description}: {text} (Ctrl-C stops)")


@contextlib.contextmanager
def working(description: str) -> Iterator[None]:
    """A spinner with the time elapsed on stderr, for work whose fraction done is unknown
    (an iterative fit): shown only on a terminal, gone when the block ends."""
    from rich.console import Console
    from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    err = Console(stderr=True)
    if not err.is_terminal:
        yield
        return
    with Progress(
        SpinnerColumn(),
        TextColumn("{task.description}"),
        TimeElapsedColumn(),
        console=err,
        transient=True,
    ) as bar:
        bar.add_task(f"{description} (Ctrl-C stops)", total=None)
        _LIVE.append(bar)  # a bag read meanwhile shows its bar in this display
        try:
            yield
        finally:
            _LIVE.remove(bar)


#: The progress displays of :func:`progress_bar` on screen, innermost last.
_LIVE: list[Progress] = []
#: Reading a bag of at least this many messages shows a bar at once ...
BAR_MESSAGES = 200_000
#: ... reading a smaller one, once it has taken this long [s].
BAR_AFTER = 1.0


class _ReadingBar:
    """The callback of :func:`reading_bar`: ``(messages read, messages to read)``.

    A bar appears when a read is long (:data:`BAR_MESSAGES`, :data:`BAR_AFTER`) and
    stderr is a terminal, and goes when the read is done. Inside a :func:`progress_bar`
    (``validate``) it is one more line of that display.
    """

    def __init__(self, console: Console | None = None) -> None:
        self.start = time.monotonic()
        self.console = console  # stderr's, made when first needed
        self.bar: Progress | None = None
        self.task: TaskID | None = None
        self.own = False

    def __call__(self, read: int, total: int) -> None:
        if read == 0:  # a read begins
            self.start = time.monotonic()
        if self.task is None:
            if read >= total:
                return
            if total < BAR_MESSAGES and time.monotonic() - self.start < BAR_AFTER:
                return
            if not self._show(read, total):
                return
        assert self.bar is not None
        assert self.task is not None
        self.bar.update(self.task, completed=read, total=total)
        if read >= total:
            self.close()

    def _show(self, read: int, total: int) -> bool:
        from rich.console import Console

        if self.console is None:
            self.console = Console(stderr=True)
        if not self.console.is_terminal:
            return False
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        if _LIVE:
            self.bar, self.own = _LIVE[-1], False
            self.task = self.bar.add_task("reading bag", total=total, completed=read)
        else:
            self.bar = Progress(
                TextColumn("{task.description}"),
                BarColumn(),
                MofNCompleteColumn(),
                TextColumn("messages"),
                TimeElapsedColumn(),
                TimeRemainingColumn(),
                console=self.console,
                transient=True,
            )
            self.own = True
            self.task = self.bar.add_task("reading bag", total=total, completed=read)
            self.bar.start()
        return True

    def close(self) -> None:
        """Take the bar off the screen."""
        if self.bar is not None and self.task is not None:
            if self.own:
                self.bar.stop()
            else:
                self.bar.remove_task(self.task)
        self.bar, self.task = None, None


@contextlib.contextmanager
def reading_bar() -> Iterator[None]:
    """Show the progress of the bags read inside the block, on stderr.

    Only long reads get a bar, and only on a terminal: pipes, ``--json`` output and the
    output captured by tests stay clean. The library reports the progress
    (:func:`umbmark.sources.progress.reading_progress`); rich is imported only when a
    bar is shown.
    """
    from umbmark.sources.progress import reading_progress

    callback = _ReadingBar()
    try:
        with reading_progress(callback):
            yield
    finally:
        callback.close()


def command_line(argv: list[str]) -> str:
    """The command line as a shell would take it back: ``umbmark`` and the quoted args."""
    return " ".join(shlex.quote(arg) for arg in ["umbmark", *argv[1:]])
