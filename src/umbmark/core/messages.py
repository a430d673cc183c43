"""Messages for people: information, or warnings.

Reading a source, choosing parameters and pooling runs collect messages for people in
one list (``notes``), in the order found. Most say that something is doubtful: the result
stands but may be shaky (a unit that looks wrong, runs left out, a conflict between an
option and a file): **warnings**, printed ``umbmark: warning: ...``. Some only say what
was done or chosen (the parameters a header recorded, the estimator ``auto`` chose):
**information**, printed as a plain ``umbmark: ...`` line. The producer of an information
marks it with :func:`info`; every other message is a warning (so that a message nobody
classified keeps being shown as one). A report splits its messages with
:func:`split_messages` into its ``notes`` and ``warnings``; the command prints what the
report says.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from umbmark.core.errors import with_flags

__all__ = ["Blocking", "Info", "blocking", "duration_words", "info", "join_names", "split_messages"]


class Info(str):
    """A message that is information (what was done, found or chosen), not a warning."""

    __slots__ = ()


class Blocking(str):
    """A warning that makes the verdict "do not apply": the input is wrong as read (a
    table in another unit than it says, a row typed wrong), so the result is no robot's.

    Attributes
    ----------
    reason : str
        Why not to apply, for the verdict.
    instead : str or None
        What to do instead.
    """

    reason: str
    instead: str | None

    def __new__(cls, text: str, reason: str, instead: str | None = None) -> Blocking:
        made = super().__new__(cls, text)
        made.reason, made.instead = reason, instead
        return made

    def __reduce__(self) -> tuple[type[Blocking], tuple[str, str, str | None]]:
        return (Blocking, (str(self), self.reason, self.instead))


def blocking(text: str, reason: str, instead: str | None = None) -> Blocking:
    """Mark ``text`` as a warning that makes the verdict "do not apply"."""
    return Blocking(text, reason, instead)


def info(text: str) -> Info:
    """Mark ``text`` as information."""
    return Info(text)


def split_messages(messages: Iterable[str]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """``(notes, warnings)``: the messages marked :func:`info`, and all the others, each
    in their order (as plain ``str``, a :class:`Blocking` warning staying one; an option a
    message names with :func:`umbmark.core.errors.option` as the command line's flag)."""
    notes: list[str] = []
    warnings: list[str] = []
    for message in messages:
        if isinstance(message, Blocking):
            instead = None if message.instead is None else with_flags(message.instead)
            warnings.append(Blocking(with_flags(str(message)), with_flags(message.reason), instead))
            continue
        (notes if isinstance(message, Info) else warnings).append(with_flags(str(message)))
    return tuple(notes), tuple(warnings)


def join_names(names: Sequence[str], conjunction: str = "and") -> str:
    """``a, b and c`` (``conjunction`` before the last)."""
    if len(names) < 2:
        return "".join(names)
    return ", ".join(names[:-1]) + f" {conjunction} " + names[-1]


def duration_words(seconds: float) -> str:
    """A wall time for people: ``20 s`` below 90 s, ``12 min`` below 90 min, else
    ``1.5 h`` (what a progress line says of the time taken or left)."""
    if seconds < 90.0:
        return f"{max(seconds, 0.0):.0f} s"
    if seconds < 5400.0:
        return f"{seconds / 60.0:.0f} min"
    return f"{seconds / 3600.0:.1f} h"
