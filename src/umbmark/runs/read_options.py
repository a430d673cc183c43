"""How a job reads a source: the options of ``umbmark calibrate`` and ``umbmark replay``
beyond the square's geometry, checked once (:class:`ReadOptions`).

Every keyword here is an option of the commands with the same name and meaning
(``--current-c-l`` is ``current_c_l``); lengths in metres, times in seconds. The fields and
:class:`SourceOptions` are generated from the option spec (:mod:`umbmark.runs.read_fields`);
messages name the options by keyword (:func:`umbmark.core.errors.option`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields

from umbmark.core.errors import InputError, option
from umbmark.options.spec import READ_OPTIONS, check_pairs
from umbmark.runs.read_fields import PathLike, ReadFields, SourceOptions

__all__ = [
    "SAME_ROBOT_TOLERANCE",
    "PathLike",
    "ReadOptions",
    "SourceOptions",
]

#: How far a result's nominal parameters may be from a source's (relative).
SAME_ROBOT_TOLERANCE = 0.01


@dataclass(frozen=True)
class ReadOptions(ReadFields):
    """The values of :class:`SourceOptions`, with their defaults, checked: the fields (and
    their meaning) are :class:`~umbmark.runs.read_fields.ReadFields`', generated from
    :data:`umbmark.options.spec.READ`, whose choices and bounds are checked here, with
    the rules between options (both or neither, the wheel fields, ``split="windows"``).

    ``windows`` is a text (``"0:95,100:190"``) or ``[(0, 95), (100, 190)]`` [s from the
    recording's start]; ``left_joint`` and ``right_joint`` a name, names separated by
    commas or a sequence of names (averaged, as ros2_control does).
    """

    def __post_init__(self) -> None:
        for spec in READ_OPTIONS:
            spec.check(getattr(self, spec.name))
        check_pairs(vars(self))
        if (self.left_field, self.right_field, self.msg_dir) != (None, None, None):
            self._check_wheel_fields()
        if self.split == "windows" and not self.windows:
            raise InputError(
                f"{option('split', 'windows')} needs "
                f"{option('windows', 'start:end[,start:end...]')}"
            )

    def _check_wheel_fields(self) -> None:
        """The wheel-field options' one check (in the bag's options, imported only when
        they are given: a runs table's start-up does not need the bag)."""
        from umbmark.sources.bag.bag_options import check_wheel_fields

        check_wheel_fields(
            self.left_field,
            self.right_field,
            self.msg_dir,
            (
                ("left_joint", self.left_joint),
                ("right_joint", self.right_joint),
                ("left_ticks_topic", self.left_ticks_topic),
                ("right_ticks_topic", self.right_ticks_topic),
                ("odom_topic", self.odom_topic),
                ("odom_tf", self.odom_tf),
                ("left_wheel_frame", self.left_wheel_frame),
            ),
        )

    @classmethod
    def of(cls, options: Mapping[str, object]) -> ReadOptions:
        """Build from keywords, refusing names that are no option (as Python would)."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(options) - known)
        if unknown:
            raise TypeError(f"unexpected keyword argument {unknown[0]!r}")
        return cls(**options)  # type: ignore[arg-type]

    @property
    def time_windows(self) -> list[tuple[float, float]]:
        """``windows`` as ``(start, end)`` pairs [s]."""
        if not self.windows:
            return []
        if isinstance(self.windows, str):
            return _parse_windows(self.windows)
        return [(float(a), float(b)) for a, b in self.windows]


def _parse_windows(text: str) -> list[tuple[float, float]]:
    out = []
    for part in text.split(","):
        try:
            a, b = (float(v) for v in part.split(":"))
        except ValueError:
            raise InputError(
                f"{option('windows', repr(text))}: write start:end pairs in seconds, "
                "e.g. '0:95,100:190'"
            ) from None
        out.append((a, b))
    return out
