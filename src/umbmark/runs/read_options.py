"""How a job reads a source: the options of ``umbmark calibrate`` and ``umbmark replay``
beyond the square's geometry, checked once (:class:`ReadOptions`).

Every keyword here is an option of the commands with the same name and meaning
(``--current-c-l`` is ``current_c_l``); lengths in metres, times in seconds. Messages name
the options as the command line spells them.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from typing import Literal, TypedDict

from umbmark.core.errors import InputError, option
from umbmark.options.spec import READ, READ_OPTIONS, check_pairs

__all__ = [
    "SAME_ROBOT_TOLERANCE",
    "ReadOptions",
    "SourceOptions",
]

PathLike = str | os.PathLike[str]

#: How far a result's nominal parameters may be from a source's (relative).
SAME_ROBOT_TOLERANCE = 0.01


class SourceOptions(TypedDict, total=False):
    """How to read a source: the keywords of :func:`umbmark.calibrate` and
    :func:`umbmark.replay` beyond the square's geometry (see :class:`ReadOptions`): the
    keys of :data:`umbmark.options.spec.READ`, typed for ``**options`` (a test holds them
    equal)."""

    format: Literal["auto", "table", "log", "optiodom", "bag", "tuples"]
    unit: Literal["m", "cm", "mm"]
    angle_unit: Literal["rad", "deg"]
    wheel_diameter: float | None
    current_c_l: float | None
    current_c_r: float | None
    current_separation_multiplier: float | None
    current_params: PathLike | None
    controller: str | None
    split: Literal["rests", "none", "windows"]
    windows: str | Sequence[tuple[float, float]] | None
    max_gap: float
    min_rest: float
    wheel_topic: str
    left_joint: str | Sequence[str] | None
    right_joint: str | Sequence[str] | None
    left_ticks_topic: str | None
    right_ticks_topic: str | None
    ticks_per_rev: float | None
    truth_topic: str | None
    tf_parent: str | None
    tf_child: str | None
    time_source: Literal["header", "bag"]
    odom_topic: str | None
    odom_tf: tuple[str, str] | None
    truth_offset: tuple[float, float] | None
    left_field: str | None
    right_field: str | None
    msg_dir: PathLike | None
    truth_model: str | None
    left_wheel_frame: str | None
    right_wheel_frame: str | None
    scan_topic: str | None


@dataclass(frozen=True)
class ReadOptions:
    """The values of :class:`SourceOptions`, with their defaults, checked: defaults,
    choices and bounds are those of :data:`umbmark.options.spec.READ`.

    Attributes
    ----------
    format : {"auto", "table", "log", "optiodom", "bag", "tuples"}
        Source format; ``auto`` decides by the path (``tuples``: motion intervals, a
        ``.tuple`` file, for the estimators of motion intervals).
    unit, angle_unit : str
        Units of a runs table's lengths (``m``, ``cm``, ``mm``) and headings (``rad``,
        ``deg``).
    wheel_diameter : float or None
        Nominal wheel diameter ``D_n`` [m]; for logged sources, overrides the source's.
    current_c_l, current_c_r, current_separation_multiplier : float or None
        The wheel factors and ``wheel_separation_multiplier`` active during the runs
        (default 1.0, or from ``current_params``).
    current_params : path or None
        A ros2_control / ROS 1 parameter YAML, or a previous result whose new values were
        applied during the runs.
    controller : str or None
        Controller name in parameter files.
    split : {"rests", "none", "windows"}
        How to find runs in a recording.
    windows : str or sequence of (float, float) or None
        Runs as time windows [s from the recording's start]: ``"0:95,100:190"`` or
        ``[(0, 95), (100, 190)]``.
    max_gap : float
        Longest ground-truth gap to interpolate across [s].
    min_rest : float
        Shortest rest between runs [s].
    wheel_topic : str
        Bags: the ``sensor_msgs/JointState`` topic (any type with ``left_field``).
    left_joint, right_joint : str, sequence of str or None
        Bags: the wheel joints, several per side averaged (a sequence, or names separated
        by commas); None: the controller file's ``left_wheel_names`` /
        ``right_wheel_names``, else found in the bag.
    left_ticks_topic, right_ticks_topic : str or None
        Bags: cumulative encoder counts instead of joint states.
    ticks_per_rev : float or None
        Encoder counts per wheel revolution (with the ticks topics).
    truth_topic : str or None
        Bags: ground-truth pose topic.
    tf_parent, tf_child : str or None
        Bags: ground truth from a transform on ``/tf`` instead.
    time_source : {"header", "bag"}
        Bags: message header stamps or receive times.
    odom_topic : str or None
        Bags without wheel data: the controller's odometry topic, turned back into wheel
        rotation with the controller's geometry.
    odom_tf : (str, str) or None
        ... or the controller's odometry as a transform chain ``(parent, child)``.
    truth_offset : (float, float) or None
        Recorded ground truth tracks a point this far forward and to the left of the axle
        centre [m] (a motion-capture marker, an antenna): it is moved to the axle centre.
    left_field, right_field : str or None
        Bags: the wheels as field paths into ``wheel_topic``'s messages, of any type
        (``left_ticks``, ``wheels.left.position``, ``positions[0]``): angles [rad], or
        encoder counts with ``ticks_per_rev``. Both or neither.
    msg_dir : path or None
        Bags that do not carry the definition of ``wheel_topic``'s type: a folder of its
        ``.msg`` files (``<pkg>/msg/<Name>.msg`` or ``<pkg>/<Name>.msg``, searched
        recursively). Only with the fields.
    truth_model : str or None
        Bags: with a ``gazebo_msgs/ModelStates`` ground truth, the robot's model (default:
        the one model that moves).
    left_wheel_frame, right_wheel_frame : str or None
        Bags: the wheels as the child frames of their transforms on ``/tf``
        (``wheel_left_link``), instead of joint states. Both or neither.
    scan_topic : str or None
        Bags, ``calibrate`` only: a ``sensor_msgs/LaserScan`` topic; the wheels are
        calibrated against the laser's scan matching (``docs/scan-matching.md``).
    """

    format: str = READ["format"].default
    unit: str = READ["unit"].default
    angle_unit: str = READ["angle_unit"].default
    wheel_diameter: float | None = None
    current_c_l: float | None = None
    current_c_r: float | None = None
    current_separation_multiplier: float | None = None
    current_params: PathLike | None = None
    controller: str | None = None
    split: str = READ["split"].default
    windows: str | Sequence[tuple[float, float]] | None = None
    max_gap: float = READ["max_gap"].default
    min_rest: float = READ["min_rest"].default
    wheel_topic: str = READ["wheel_topic"].default
    left_joint: str | Sequence[str] | None = None
    right_joint: str | Sequence[str] | None = None
    left_ticks_topic: str | None = None
    right_ticks_topic: str | None = None
    ticks_per_rev: float | None = None
    truth_topic: str | None = None
    tf_parent: str | None = None
    tf_child: str | None = None
    time_source: str = READ["time_source"].default
    odom_topic: str | None = None
    odom_tf: tuple[str, str] | None = None
    truth_offset: tuple[float, float] | None = None
    left_field: str | None = None
    right_field: str | None = None
    msg_dir: PathLike | None = None
    truth_model: str | None = None
    left_wheel_frame: str | None = None
    right_wheel_frame: str | None = None
    scan_topic: str | None = None

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
