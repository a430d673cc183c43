"""The transforms of a bag and the chains they form: what ``umbmark info`` lists of
``/tf`` and ``/tf_static``.

:class:`TransformInfo` is one parent->child pair in the messages scanned
(:mod:`umbmark.sources.bag.info.scan`); :func:`tf_chains` follows them from each root
down to the last frame that moves (``map -> odom -> base_link``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from umbmark.sources.bag.info.scan import ScannedTopic, needed_gap
from umbmark.sources.bag.msgtypes import TF_STATIC_TOPIC, TF_TOPIC, TF_TYPES
from umbmark.sources.bag.names import odometry_frame

__all__ = [
    "MAX_DEPTH",
    "TransformInfo",
    "odometry_transform",
    "pair_gaps",
    "tf_chains",
    "transform_infos",
]

#: Frames in a chain at most.
MAX_DEPTH = 32


@dataclass(frozen=True)
class TransformInfo:
    """A parent->child pair of ``/tf`` or ``/tf_static`` (leading slashes dropped).

    Attributes
    ----------
    parent, child : str
    topic : str
        ``/tf`` or ``/tf_static``.
    count : int
        Transforms of the pair in the messages read.
    rate : float or None
        Estimated rate [Hz] (the topic's rate times the pair's share of the messages
        read); None for ``/tf_static``.
    moving : bool
        Its translation ranges over :data:`~umbmark.sources.bag.info.scan.MOVING_DISTANCE`
        or its rotation over about :data:`~umbmark.sources.bag.info.scan.MOVING_ANGLE`, in
        the messages read.
    turns_only : bool
        It moves, but only turns: its translation stays within
        :data:`~umbmark.sources.bag.info.scan.MOVING_DISTANCE` (a wheel, a spinning sensor).
    """

    parent: str
    child: str
    topic: str
    count: int
    rate: float | None
    moving: bool = False
    turns_only: bool = False

    @property
    def static(self) -> bool:
        """Whether it comes from ``/tf_static``."""
        return self.topic == TF_STATIC_TOPIC

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``parent``, ``child``, ``topic``, ``static``, ``count``, ``rate``
        [Hz], ``moving``."""
        return {
            "parent": self.parent,
            "child": self.child,
            "topic": self.topic,
            "static": self.static,
            "count": self.count,
            "rate": self.rate,
            "moving": self.moving,
            "turns_only": self.turns_only,
        }


def odometry_transform(tf: TransformInfo) -> bool:
    """Whether a transform is an odometry's: on ``/tf``, from an odometry frame
    (``odom -> base_link``)."""
    return not tf.static and odometry_frame(tf.parent)


def transform_infos(scanned: Sequence[ScannedTopic]) -> list[TransformInfo]:
    """The pairs of ``/tf``, then of ``/tf_static``, in the messages scanned."""
    out = []
    for topic in sorted(scanned, key=lambda t: t.name == TF_STATIC_TOPIC):
        content = topic.content
        if (
            topic.msgtype not in TF_TYPES
            or content is None
            or topic.name not in (TF_TOPIC, TF_STATIC_TOPIC)
        ):
            continue
        read = max(content.decoded, 1)
        static = topic.name == TF_STATIC_TOPIC
        for (parent, child), stats in content.pairs.items():
            rate = None if static or topic.rate is None else topic.rate * stats.count / read
            out.append(
                TransformInfo(
                    parent, child, topic.name, stats.count, rate, stats.moving, stats.turns_only
                )
            )
    return out


def pair_gaps(scanned: Sequence[ScannedTopic]) -> dict[tuple[str, str], float | None]:
    """The ``--max-gap`` [s] each ``/tf`` pair needs."""
    return {
        pair: needed_gap(stats.times.intervals)
        for topic in scanned
        if topic.name == TF_TOPIC and topic.content is not None
        for pair, stats in topic.content.pairs.items()
    }


def tf_chains(transforms: Sequence[TransformInfo]) -> list[tuple[str, ...]]:
    """Chains of frames from each root (a frame that is no child) down to the last frame
    that moves: a static transform is followed only if a moving one lies below it.

    Without any moving transform, the chains follow the static ones to their leaves.
    """
    children: dict[str, list[tuple[str, bool]]] = {}
    parents: set[str] = set()
    kids: set[str] = set()
    for tf in transforms:
        if tf.parent == tf.child:
            continue
        edge = (tf.child, tf.static)
        siblings = children.setdefault(tf.parent, [])
        if (tf.child, False) in siblings:
            continue
        if edge[1] is False and (tf.child, True) in siblings:
            siblings.remove((tf.child, True))
        if edge not in siblings:
            siblings.append(edge)
        parents.add(tf.parent)
        kids.add(tf.child)
    any_moving = any(not tf.static for tf in transforms)
    memo: dict[str, bool] = {}

    def moving_below(frame: str, path: frozenset[str]) -> bool:
        if frame in memo:
            return memo[frame]
        result = False
        for child, static in children.get(frame, []):
            if child in path:
                continue
            if not static or moving_below(child, path | {child}):
                result = True
                break
        memo[frame] = result
        return result

    chains: list[tuple[str, ...]] = []

    def walk(path: tuple[str, ...]) -> None:
        frame = path[-1]
        nexts = [
            child
            for child, static in children.get(frame, [])
            if child not in path
            and (not any_moving or not static or moving_below(child, frozenset(path) | {child}))
        ]
        if not nexts or len(path) >= MAX_DEPTH:
            if len(path) > 1:
                chains.append(path)
            return
        for child in nexts:
            walk((*path, child))

    roots = sorted(parents - kids) or sorted(parents)[:1]
    for root in roots:
        walk((root,))
    return chains
