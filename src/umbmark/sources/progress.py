"""Progress of reading long sources: how many messages are read, of how many.

Reading a bag of millions of messages takes seconds to minutes. The bag reader counts the
messages it reads and reports ``(read, total)`` to a callback, so that a caller can show
a progress bar. The callback is given either to :func:`umbmark.sources.bag.recording.read_bag`
(``progress=``) or, for every bag read inside a block of code, by
:func:`reading_progress`: the way to get progress out of :func:`umbmark.calibrate`,
:func:`umbmark.replay` or :func:`umbmark.validate`, which read bags deep inside::

    import umbmark
    from umbmark.sources.progress import reading_progress

    with reading_progress(lambda read, total: print(f"{read}/{total} messages")):
        report = umbmark.calibrate("run.bag", wheelbase=0.34, wheel_diameter=0.15, ...)

The command line shows a bar on stderr this way when stderr is a terminal
(:func:`umbmark.cli.common.reading_bar`).

This module imports nothing heavy: the command line enters :func:`reading_progress` on
every start.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar

__all__ = ["REPORT_EVERY", "Progress", "Tracker", "current_tracker", "reading_progress", "tracking"]

Progress = Callable[[int, int], None]
"""Called with the messages read so far and the messages to read in all, ``read <=
total``; ``read`` never decreases, and the last call of a read has ``read == total``."""

#: Messages read between two reports.
REPORT_EVERY = 4096

_CALLBACK: ContextVar[Progress | None] = ContextVar("umbmark_reading_progress", default=None)
_TRACKER: ContextVar[Tracker | None] = ContextVar("umbmark_reading_tracker", default=None)


@contextmanager
def reading_progress(callback: Progress | None) -> Iterator[None]:
    """Report the progress of every bag read inside the ``with`` block to ``callback``.

    Parameters
    ----------
    callback : callable or None
        Called as ``callback(read, total)`` with message counts (see :data:`Progress`);
        None reports nothing. It runs in the reading thread: keep it short.
    """
    token = _CALLBACK.set(callback)
    try:
        yield
    finally:
        _CALLBACK.reset(token)


def current_callback() -> Progress | None:
    """The callback of the innermost :func:`reading_progress` block, if any."""
    return _CALLBACK.get()


class Tracker:
    """Counts the messages of one read and reports them to a :data:`Progress` callback.

    The read announces the topics it means to read (``planned``) and their message
    counts; each pass over a topic's messages then calls :meth:`begin` and
    :meth:`advance`. A pass that was not planned (a topic read twice) adds its messages
    to the total when it begins, so the total can grow but ``read`` never decreases.

    Parameters
    ----------
    callback : callable
        Gets ``(read, total)``.
    planned : sequence of (str, int)
        The topics the read will go through and each one's message count (a topic read
        twice is listed twice).
    """

    def __init__(self, callback: Progress, planned: Sequence[tuple[str, int]]) -> None:
        self._callback = callback
        self._planned = [topic for topic, _ in planned]
        self.total = sum(max(0, count) for _, count in planned)
        self.read = 0
        self.every = REPORT_EVERY
        self._reported: tuple[int, int] | None = None

    def begin(self, topic: str, count: int) -> None:
        """A pass over ``count`` messages of ``topic`` starts."""
        if topic in self._planned:
            self._planned.remove(topic)
        else:
            self.total += max(0, count)
        self._report()

    def advance(self, messages: int) -> None:
        """``messages`` more messages have been read."""
        self.read += messages
        self.total = max(self.total, self.read)  # a bag whose counts are too low
        self._report()

    def finish(self) -> None:
        """The read is done (some passes may have stopped early): report it complete."""
        self.total = max(self.total, self.read)
        self.read = self.total
        self._report()

    def _report(self) -> None:
        now = (self.read, self.total)
        if now != self._reported:
            self._reported = now
            self._callback(*now)


@contextmanager
def tracking(tracker: Tracker | None) -> Iterator[None]:
    """Make ``tracker`` the one :func:`current_tracker` returns inside the block."""
    token = _TRACKER.set(tracker)
    try:
        yield
    finally:
        _TRACKER.reset(token)


def current_tracker() -> Tracker | None:
    """The tracker of the read under way, if it reports progress."""
    return _TRACKER.get()
