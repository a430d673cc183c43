"""Declaring options: click options that belong to a section of ``--help``, and the
options every command that reads runs shares (``calibrate``, ``replay``), made from their
specification (:mod:`umbmark.options.spec`) by :func:`spec_option`.

An option's destination is the keyword of the library function it feeds, with the same
name and meaning: ``--current-c-l`` is ``current_c_l`` of :func:`umbmark.calibrate`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import click

from umbmark.options.spec import FORCE, OVERRIDE_VERDICT, READ_OPTIONS, TUM_TIME, WHEELBASE, Spec

__all__ = [
    "OTHER",
    "Command",
    "apply",
    "force_option",
    "option",
    "override_option",
    "source_options",
    "spec_option",
    "tum_time_option",
]

F = TypeVar("F", bound=Callable[..., Any])
T = TypeVar("T")

OTHER = "Other options"


class SectionOption(click.Option):
    """A click option that knows which section of ``--help`` lists it."""

    def __init__(self, *args: Any, section: str = OTHER, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.section = section


class Command(click.Command):
    """A command whose ``--help`` lists its options by section, in declaration order.

    Sections come in the order their first option was declared, "Other options" (where
    ``--help`` is) last. Only options are listed: the docstring describes the arguments
    (click 8.5 began giving arguments a help record of their own; the layout must not
    depend on the click version).
    """

    def format_options(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        sections: dict[str, list[tuple[str, str]]] = {}
        for param in self.get_params(ctx):
            record = param.get_help_record(ctx) if isinstance(param, click.Option) else None
            if record is not None:
                section = getattr(param, "section", OTHER)
                sections.setdefault(section, []).append(record)
        others = sections.pop(OTHER, None)
        if others is not None:
            sections[OTHER] = others
        for name, rows in sections.items():
            with formatter.section(name):
                formatter.write_dl(rows)


def option(*decls: str, section: str, **attrs: Any) -> Callable[[F], F]:
    """A click option listed under ``section`` in ``--help``."""
    return click.option(*decls, cls=SectionOption, section=section, **attrs)


def apply(decorators: Sequence[Callable[[F], F]]) -> Callable[[F], F]:
    """Apply option decorators so that ``--help`` lists them in the given order."""

    def decorate(fn: F) -> F:
        for decorator in reversed(decorators):
            fn = decorator(fn)
        return fn

    return decorate


def spec_option(
    spec: Spec, *, section: str | None = None, help: str | None = None
) -> Callable[[F], F]:
    """The click option of a :class:`~umbmark.options.spec.Spec` entry: its flags, kind,
    default (shown by ``--help``), values and help, listed under its section [or
    ``section``]; ``help`` for a command that says it in its own words."""
    attrs: dict[str, Any] = {}
    if spec.most:  # comma-separated numbers
        attrs["callback"] = _list(int if spec.kind == "integer" else float)
    elif spec.kind == "number":
        attrs["type"] = float
    elif spec.kind == "integer":
        attrs["type"] = int
    elif spec.kind == "choice":
        attrs["type"] = click.Choice(list(spec.choices))
    elif spec.kind == "file":
        attrs["type"] = click.Path(dir_okay=False)
    elif spec.kind == "folder":
        attrs["type"] = click.Path(file_okay=False)
    elif spec.kind == "flag":
        attrs["is_flag"] = True
    if spec.most and spec.default is not None:
        attrs["default"] = ",".join(format(value, "g") for value in spec.default)
        attrs["show_default"] = True
    elif spec.default is not None:
        attrs["default"] = spec.default
        attrs["show_default"] = spec.kind != "flag"
    if spec.nargs != 1:
        attrs["nargs"] = spec.nargs
    if spec.metavar is not None:
        attrs["metavar"] = spec.metavar
    return option(
        *spec.flags,
        spec.name,
        section=spec.section if section is None else section,
        help=spec.help if help is None else help,
        **attrs,
    )


def _list(kind: Callable[[str], T]) -> Callable[[click.Context, click.Parameter, str], list[T]]:
    """A click callback reading comma-separated values (a :attr:`Spec.most` option)."""

    def parse(ctx: click.Context, param: click.Parameter, text: str) -> list[T]:
        try:
            return [kind(part) for part in text.split(",") if part.strip()]
        except ValueError:
            raise click.BadParameter(f"{text!r}: give comma-separated numbers") from None

    return parse


def force_option(also: str = "", *, section: str | None = None) -> Callable[[F], F]:
    """``--force`` (:data:`~umbmark.options.spec.FORCE`): replace existing outputs; ``also``
    says what else it lifts on this command."""
    return spec_option(FORCE, section=section, help=f"{FORCE.help} {also}".strip())


def override_option(what: str, *, section: str | None = None) -> Callable[[F], F]:
    """``--override-verdict`` (:data:`~umbmark.options.spec.OVERRIDE_VERDICT`); ``what``
    says which refusal it lifts on this command."""
    return spec_option(OVERRIDE_VERDICT, section=section, help=f"{what} {OVERRIDE_VERDICT.help}")


def tum_time_option() -> Callable[[F], F]:
    """``--tum-time``: the clock of the TUM files (calibrate and replay)."""
    return spec_option(TUM_TIME)


def source_options(*, wheelbase: bool = True) -> Callable[[F], F]:
    """Options that say how to read a source and what was active during the runs.

    ``wheelbase=False`` leaves ``--wheelbase`` out, for commands that list it elsewhere.
    """
    specs = (WHEELBASE, *READ_OPTIONS) if wheelbase else READ_OPTIONS
    return apply([spec_option(spec) for spec in specs])
