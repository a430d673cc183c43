"""The error users see: bad input, named by file (and row) and problem, read as the caller
writes.

An :class:`InputError`'s problem names the options it is about by their keyword, the
option spec's name (:func:`option`: ``option("unit", "mm")``), never by a spelling; each
layer renders them its own way. The command prints them as flags
(:meth:`InputError.command_line`, with the flags of the command that ran: ``--unit mm``,
``--side-length``, ``--from``); raised out of a library function called from Python
(``umbmark.calibrate(...)``: the functions of the package are wrapped by
:func:`python_api`) the same error reads as Python (:meth:`InputError.python`):
``unit="mm"``, ``side_length``, a flag ``force=True``, and an option the command takes in
degrees or millimetres in the library's radians and metres (``turn_angle=6.28319 rad``).
:func:`python_api` also refuses a keyword the function does not take as Python does,
naming the close one (``did you mean unit=?``).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import re
import typing
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import ParamSpec, TypeVar

__all__ = [
    "InputError",
    "Keyword",
    "ProblemError",
    "SafetyError",
    "given",
    "keywords_of",
    "option",
    "option_names",
    "python_api",
    "unexpected_keyword",
    "with_flags",
]

P = ParamSpec("P")
R = TypeVar("R")

#: An option named in a problem (:func:`option`) is kept between these characters (Unicode's
#: private use: never printed, as every rendering replaces them).
_OPEN, _SEP, _CLOSE = "\ue000", "\ue001", "\ue002"
_OPTION = re.compile(f"{_OPEN}([^{_SEP}]*){_SEP}([^{_SEP}]*){_SEP}([^{_CLOSE}]*){_CLOSE}")


def option(name: str, value: object = None, unit: str = "") -> str:
    """An option named in an :class:`InputError`'s problem, by its keyword (the option
    spec's name: ``side_length``), with the value given as the command line takes it and
    that value's unit. The command line reads ``--side-length 4 m``; Python
    ``side_length=4 m`` (``--turn-angle 360 deg``: ``turn_angle=6.28319 rad``).

    ``value``: a text as it is to be shown (quote it, ``repr(text)``, where the sentence
    needs it), a float shown with ``g``, or any other number; None: the option alone.
    """
    return f"{_OPEN}{name}{_SEP}{_shown(value)}{_SEP}{unit}{_CLOSE}"


def _shown(value: object) -> str:
    """A value as a message shows it: a text as it is, a float with ``g``; None: nothing."""
    if value is None:
        return ""
    if isinstance(value, str):
        return value
    return format(value, "g") if isinstance(value, float) else str(value)


def given(named: str, value: object, unit: str = "") -> str:
    """``named`` with the value given: an :func:`option` alone takes it (``--wheelbase 340
    m``, from Python ``wheelbase=340 m``); anything else (a file's field, ``Li``) is
    followed by it (``Li 340 m``)."""
    match = _OPTION.fullmatch(named)
    if match is not None and not match[2]:
        return option(match[1], value, unit or match[3])
    return " ".join(part for part in (named, _shown(value), unit) if part)


def option_names(text: str) -> list[str]:
    """The keywords of the options :func:`option` named in ``text``, in order."""
    return [match[1] for match in _OPTION.finditer(text)]


@dataclass(frozen=True)
class Keyword:
    """A keyword of a library function, as its errors name it.

    Attributes
    ----------
    name : str
        The keyword (``side_length``).
    flag : bool
        A flag (``bool``): the command's ``--force`` is ``force=True``.
    choices : tuple of str
        The values it takes, when they are a few words (``Literal["m", "cm", "mm"]``).
    path : bool
        It takes a file or folder: the command's ``--report r.txt`` is ``report='r.txt'``.
    text : bool
        It takes a text (``str``): the command's ``--method paper`` is ``method='paper'``.
    """

    name: str
    flag: bool = False
    choices: tuple[str, ...] = ()
    path: bool = False
    text: bool = False


class InputError(ValueError):
    """Input that umbmark cannot use.

    Its text is one line: ``FILE, row N: PROBLEM`` (file and row when known). The command
    prints it naming options as flags (:meth:`command_line`); raised out of a function of
    the package called from Python, it names them as keywords (:meth:`python`). It is a
    ``ValueError``, so code that already catches those catches it too.

    Parameters
    ----------
    problem : str
        What is wrong, naming options as the command line spells them.
    source, row : optional
        The file (or folder) and the row.
    python : str, optional
        The problem as Python reads it, where the rule of :meth:`python` would not do.
    """

    def __init__(
        self,
        problem: str,
        *,
        source: str | Path | None = None,
        row: int | None = None,
        python: str | None = None,
    ) -> None:
        self.problem = problem
        self.python_problem = python
        self.source = None if source is None else str(source)
        self.row = row
        #: The keywords of the function it was raised from (set by :func:`python_api`).
        self.keywords: Mapping[str, Keyword] | None = None
        super().__init__(self.command_line())

    def _where(self, problem: str) -> str:
        where = self.source or ""
        if self.row is not None:
            where = f"{where}, row {self.row}" if where else f"row {self.row}"
        return f"{where}: {problem}" if where else problem

    def command_line(self, flags: Mapping[str, str] | None = None) -> str:
        """The line the command prints: options as flags (``--unit mm``).

        ``flags``: the command's flag for each keyword (``{"previous": "--from"}``); a
        keyword it does not name is ``--`` and the keyword with ``-`` for ``_``.
        """
        return self._where(_as_flags(self.problem, flags or {}))

    def python(self, keywords: Mapping[str, Keyword] | None = None) -> str:
        """The line as Python reads it: options as keywords (``unit="mm"``).

        ``keywords``: those of the function called [default: the ones recorded when it
        was raised out of one]; flags that name none of them stay as they are.
        """
        keywords = self.keywords if keywords is None else keywords
        problem = self.problem if self.python_problem is None else self.python_problem
        return self._where(_as_python(problem, keywords or {}))

    def __str__(self) -> str:
        return self.command_line() if self.keywords is None else self.python()


class ProblemError(ValueError):
    """A ``ValueError`` of a computation (a fit that diverged) whose text names options
    (:func:`option`): it reads with flags wherever it is shown as it is, and keeps the
    names in :attr:`problem` for the :class:`InputError` a caller makes of it."""

    def __init__(self, problem: str) -> None:
        self.problem = problem
        super().__init__(with_flags(problem))


class SafetyError(RuntimeError):
    """A robot was stopped for safety (a zero velocity was sent before this was raised):
    stale odometry, an obstacle ahead, the robot leaving its path, a move taking too long.
    Its text says why, in one line."""


# --- options as flags, and as keywords --------------------------------------------------

_NUMBER = re.compile(r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf|nan")
#: A text value that is a name, not a word of the sentence (``base_link``, ``wheel-1``).
_NAME_LIKE = re.compile(r"[_\-/.0-9]")
#: Units a command takes that the library takes in SI: factor, SI unit.
_TO_SI = {"deg": (math.pi / 180.0, "rad"), "mm": (1e-3, "m"), "cm": (1e-2, "m")}


def _flag(name: str, flags: Mapping[str, str]) -> str:
    """The flag of the option ``name``: the command's, else ``--`` and the keyword."""
    return flags.get(name) or "--" + name.replace("_", "-")


def _as_flags(text: str, flags: Mapping[str, str]) -> str:
    """``text`` with its options as the command line spells them (``--unit mm``)."""

    def one(match: re.Match[str]) -> str:
        name, value, unit = match.groups()
        return " ".join(part for part in (_flag(name, flags), value, unit) if part)

    return _OPTION.sub(one, text)


def with_flags(text: str) -> str:
    """``text`` with the options :func:`option` named as the command line's flags: for a
    text that is no :class:`InputError`'s problem (a warning, a verdict's reason) built
    from one that is."""
    return _as_flags(text, {})


def _as_python(text: str, keywords: Mapping[str, Keyword]) -> str:
    """``text`` with its options that are ``keywords`` as Python spells them
    (``unit="mm"``); the others (``--json``: the command's alone) as flags."""

    def one(match: re.Match[str]) -> str:
        keyword = keywords.get(match[1])
        if keyword is None:  # not an option of this function
            return _as_flags(match[0], {})
        name, value, unit = keyword.name, match[2] or None, match[3] or None
        suffix = f" {unit}" if unit else ""
        if value is not None and _NUMBER.fullmatch(value):
            if unit in _TO_SI:
                factor, unit = _TO_SI[unit]
                value = format(float(value) * factor, ".6g")
            return f"{name}={value}" + (f" {unit}" if unit else "")
        if value is not None and value[0] in "'\"":
            return f"{name}={value}{suffix}"
        if value is not None and value in keyword.choices:
            return f'{name}="{value}"{suffix}'
        if value is not None and (
            (keyword.path and ("." in value or "/" in value))
            or value.startswith("/")  # a ROS name (a topic, a frame)
            or (keyword.text and bool(_NAME_LIKE.search(value)))
        ):
            return f"{name}={value!r}{suffix}"
        rest = "".join(f" {part}" for part in (value, unit) if part is not None)
        return (f"{name}=True" if keyword.flag else name) + rest

    return _OPTION.sub(one, text)


# --- the keywords of a function -----------------------------------------------------------


def _literals(annotation: object, namespace: Mapping[str, object]) -> tuple[str, ...]:
    """The string values of the ``Literal`` types in ``annotation`` (text or type)."""
    if isinstance(annotation, typing.ForwardRef):
        annotation = annotation.__forward_arg__
    if isinstance(annotation, str):
        import ast

        text = annotation
        try:  # the code's own annotation, as typing.get_type_hints evaluates it
            annotation = eval(text, dict(namespace))
        except Exception:  # a name imported only for type checking: read the text
            values: list[str] = []
            for inner in re.findall(r"Literal\[([^\]]*)\]", text):
                values += [v for v in ast.literal_eval(f"({inner},)") if isinstance(v, str)]
            return tuple(values)
    if typing.get_origin(annotation) is typing.Literal:
        return tuple(v for v in typing.get_args(annotation) if isinstance(v, str))
    return tuple(v for arg in typing.get_args(annotation) for v in _literals(arg, namespace))


def _keyword(
    name: str, annotation: object, default: object, namespace: Mapping[str, object]
) -> Keyword:
    """A parameter's :class:`Keyword`, from its annotation (text or type) and default."""
    text = annotation.__forward_arg__ if isinstance(annotation, typing.ForwardRef) else annotation
    return Keyword(
        name,
        flag=text in ("bool", bool) or isinstance(default, bool),
        choices=_literals(annotation, namespace),
        path=isinstance(text, str) and bool(re.search(r"\bPath(Like)?\b", text)),
        text=text is str or (isinstance(text, str) and bool(re.fullmatch(r"str( \| None)?", text))),
    )


def keywords_of(fn: Callable[..., object]) -> dict[str, Keyword] | None:
    """The keywords ``fn`` takes (those of a ``**options: Unpack[TypedDict]`` too, and the
    fields of the dataclass ``fn.__keyword_fields__`` names for its ``**changes``), or
    None when it takes any."""
    import inspect

    namespace = getattr(inspect.unwrap(fn), "__globals__", {})
    out: dict[str, Keyword] = {}
    for p in inspect.signature(fn).parameters.values():
        fields_of = getattr(inspect.unwrap(fn), "__keyword_fields__", None)
        if p.kind is p.VAR_KEYWORD and fields_of is not None:  # a dataclass's fields
            module = inspect.getmodule(fields_of)
            space = vars(module) if module is not None else namespace
            for f in dataclasses.fields(fields_of):
                out[f.name] = _keyword(f.name, f.type, f.default, space)
        elif p.kind is p.VAR_KEYWORD:
            text = p.annotation if isinstance(p.annotation, str) else ""
            inner = re.fullmatch(r"Unpack\[(\w+)\]", text)
            typed = namespace.get(inner[1]) if inner else None
            hints = getattr(typed, "__annotations__", None)
            if not isinstance(hints, dict):
                return None
            module = inspect.getmodule(typed)
            space = vars(module) if module is not None else namespace
            for name, annotation in hints.items():
                out[name] = _keyword(name, annotation, None, space)
        elif p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY):
            out[p.name] = _keyword(p.name, p.annotation, p.default, namespace)
    return out


def unexpected_keyword(function: str, name: str, known: Collection[str]) -> TypeError:
    """Python's error for a keyword ``function`` does not take, naming the close one."""
    import difflib

    by_lower = {k.lower(): k for k in known}
    close = difflib.get_close_matches(name.lower().replace("-", "_"), by_lower, n=1)
    hint = f"; did you mean {by_lower[close[0]]}=?" if close else ""
    return TypeError(f"{function}() got an unexpected keyword argument {name!r}{hint}")


def python_api(fn: Callable[P, R]) -> Callable[P, R]:
    """``fn`` as Python callers meet it: a keyword it does not take is a ``TypeError``
    naming the close one, and its :class:`InputError` names options as keywords."""
    keywords = keywords_of(fn)

    @functools.wraps(fn)
    def call(*args: P.args, **kwargs: P.kwargs) -> R:
        if keywords is not None:
            for name in kwargs:
                if name not in keywords:
                    raise unexpected_keyword(fn.__name__, name, keywords)
        try:
            return fn(*args, **kwargs)
        except InputError as error:
            if keywords is not None:  # with those of a function it came through
                error.keywords = {**keywords, **(error.keywords or {})}
                error.args = (error.python(),)
            raise

    return call
