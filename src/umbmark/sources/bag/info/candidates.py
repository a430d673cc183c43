"""The candidates ``umbmark info`` proposes for each input: wheels, odometry, ground truth.

Wheels
    A moving left/right pair of joints of a ``sensor_msgs/JointState`` topic, left/right
    ``std_msgs`` counter topics, or a left/right pair of wheel frames on ``/tf`` whose
    transforms only turn (``base_link -> wheel_left_link`` from ``robot_state_publisher``).
Controller odometry
    ``nav_msgs/Odometry`` topics in an odometry frame that are neither ground truth nor a
    fused odometry by their names, and ``odom -> base_*`` transforms.
Ground truth, ranked
    1. motion capture and ground-truth names (``/mocap/pose``, ``/ground_truth/odom``,
       transforms from ``mocap`` or ``vicon`` frames);
    2. Gazebo's ``gazebo_msgs/ModelStates``, one candidate per model that moves;
    3. transforms from a fixed frame (``world -> base_link``), and chains through a
       localization (``map -> odom -> base_link`` where ``map -> odom`` moves);
    4. localization poses (AMCL's ``/amcl_pose``; odometry topics in a fixed frame);
    5. position-only references (``geometry_msgs/PointStamped``, ``sensor_msgs/NavSatFix``:
       the estimators paper, exact and endpose use them);
    6. a fused odometry (robot_localization's ``/odometry/filtered``), with a warning: it
       contains the wheel odometry.

    The controller's own odometry (and a chain whose only moving transforms are the
    odometry's) is never a ground-truth candidate: calibrating against it measures
    nothing. Candidates that do not move go last. Each carries its rate and the
    ``--max-gap`` it needs: 10 % more than 95 % of the intervals between its messages
    (:func:`umbmark.sources.bag.info.scan.needed_gap`). Candidates with a warning (a fused
    odometry, GNSS fixes coarser than :data:`MAX_SUGGESTED_SIGMA`) are listed but never
    suggested.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from umbmark.model.recording import DEFAULT_MAX_GAP
from umbmark.sources.bag.info.frames import odometry_transform
from umbmark.sources.bag.msgtypes import (
    JOINT_STATE,
    MODEL_STATES,
    NAV_SAT_FIX,
    ODOMETRY,
    POINT_STAMPED,
    POSE_COV_STAMPED,
    POSE_STAMPED,
    TICK_TYPES,
    TRUTH_TYPES,
)
from umbmark.sources.bag.names import (
    fixed_frame,
    fused_like,
    mirrored_pairs,
    odometry_frame,
    truth_like,
    words,
)
from umbmark.sources.bag.truth.references import moving_models

if TYPE_CHECKING:
    from umbmark.sources.bag.info.frames import TransformInfo
    from umbmark.sources.bag.info.scan import ScannedTopic as _Topic

__all__ = [
    "MAX_SUGGESTED_SIGMA",
    "Candidate",
    "odometry_candidates",
    "truth_candidates",
    "wheel_candidates",
]

Role = Literal["wheels", "odometry", "truth"]

#: GNSS fixes with a larger median horizontal standard deviation [m] are not suggested:
#: UMBmark's return errors are centimetres.
MAX_SUGGESTED_SIGMA = 0.05


@dataclass(frozen=True)
class Candidate:
    """A way to read one input from the bag.

    Attributes
    ----------
    role : {"wheels", "odometry", "truth"}
        The input: wheel rotation, the controller's own odometry, ground truth.
    kind : str
        ``joint_states``, ``ticks``, ``wheel_tf``, ``topic``, ``model`` (a Gazebo
        model), ``tf`` (a direct transform) or ``tf_chain`` (transforms to compose).
    label : str
        What it is, for people: ``/mocap/pose (geometry_msgs/msg/PoseStamped)``.
    options : tuple of (str, str)
        The command-line options that select it (empty where no option reads it).
    moving : bool or None
        Whether it moves in the messages read; None if not looked into.
    rate : float or None
        Its rate [Hz] (a transform's share of its topic's), None if unknown.
    max_gap : float or None
        The ``--max-gap`` [s] it needs (:func:`~umbmark.sources.bag.info.scan.needed_gap`),
        None if unknown.
    warning : str or None
        Why it is no sound reference although listed (a fused odometry); such a
        candidate is never suggested.
    headings : bool
        Whether it measures headings (False: positions only).
    """

    role: Role
    kind: str
    label: str
    options: tuple[tuple[str, str], ...] = ()
    moving: bool | None = None
    rate: float | None = None
    max_gap: float | None = None
    warning: str | None = None
    headings: bool = True

    @property
    def command_line(self) -> str:
        """The options as typed: ``--truth-topic /mocap/pose``."""
        return " ".join(f"{flag} {value}" for flag, value in self.options)

    @property
    def gap_option(self) -> tuple[str, str] | None:
        """``("--max-gap", "0.6")`` where it needs more than the default, else None."""
        if self.max_gap is None or self.max_gap <= DEFAULT_MAX_GAP:
            return None
        return ("--max-gap", f"{self.max_gap:g}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``kind``, ``label``, ``options`` (flag to value), ``moving``,
        ``rate`` [Hz], ``max_gap`` [s], ``warning``, ``headings``."""
        return {
            "kind": self.kind,
            "label": self.label,
            "options": dict(self.options),
            "moving": self.moving,
            "rate": self.rate,
            "max_gap": self.max_gap,
            "warning": self.warning,
            "headings": self.headings,
        }


# --- wheels --------------------------------------------------------------------------------


def wheel_candidates(
    scanned: Sequence[_Topic], transforms: Sequence[TransformInfo]
) -> list[Candidate]:
    """Joint pairs, counter topics and wheel frames, likeliest first."""
    found: list[tuple[tuple[int, int, int], Candidate]] = []
    for topic in scanned:
        content = topic.content
        if topic.msgtype != JOINT_STATE or content is None:
            continue
        stats = content.joints
        for left, right in mirrored_pairs(list(stats)):
            moving = stats[left].moving and stats[right].moving
            wheel = "wheel" in left.lower() and "wheel" in right.lower()
            options = (("--wheel-topic", topic.name), ("--left-joint", left),
                       ("--right-joint", right))  # fmt: skip
            label = f"{topic.name}: joints {left} and {right}"
            rank = (
                0 if moving else 1,
                0 if wheel else 1,
                0 if topic.name == "/joint_states" else 1,
            )
            found.append(
                (rank, Candidate("wheels", "joint_states", label, options, moving, topic.rate))
            )
    ticks = [t for t in scanned if t.msgtype in TICK_TYPES]
    by_name = {t.name: t for t in ticks}
    for left, right in mirrored_pairs([t.name for t in ticks]):
        moving_l, moving_r = by_name[left].moving, by_name[right].moving
        counting = None if moving_l is None or moving_r is None else moving_l and moving_r
        options = (("--left-ticks-topic", left), ("--right-ticks-topic", right),
                   ("--ticks-per-rev", "N"))  # fmt: skip
        label = (
            f"{left} and {right} ({by_name[left].msgtype}; N: encoder counts per wheel revolution)"
        )
        rank = (0 if counting else 1, 1, 1)
        candidate = Candidate("wheels", "ticks", label, options, counting, by_name[left].rate)
        found.append((rank, candidate))
    turning = {tf.child: tf for tf in transforms if not tf.static and tf.turns_only}
    for left, right in mirrored_pairs(list(turning)):
        if "wheel" not in left.lower() or "wheel" not in right.lower():
            continue
        tf = turning[left]
        frames = (("--left-wheel-frame", left), ("--right-wheel-frame", right))
        label = f"TF {tf.parent} -> {left} and {turning[right].parent} -> {right} (wheel frames)"
        # behind joint states: robot_state_publisher makes these transforms from them
        candidate = Candidate("wheels", "wheel_tf", label, frames, tf.moving, tf.rate)
        found.append(((0 if tf.moving else 1, 2, 1), candidate))
    found.sort(key=lambda item: item[0])
    return [c for _, c in found]


# --- odometry ------------------------------------------------------------------------------


def odometry_label(topic: _Topic) -> str:
    """``/odom (nav_msgs/msg/Odometry, odom -> base_link)``."""
    frames = topic.content.frames if topic.content is not None else None
    if frames is not None and frames[0] and frames[1]:
        return f"{topic.name} ({topic.msgtype}, {frames[0]} -> {frames[1]})"
    if frames is not None and frames[0]:
        return f"{topic.name} ({topic.msgtype}, frame {frames[0]})"
    return f"{topic.name} ({topic.msgtype})"


def _header_frame(topic: _Topic) -> str:
    frames = topic.content.frames if topic.content is not None else None
    return frames[0] if frames is not None else ""


def controller_odometry(topic: _Topic) -> bool:
    """Whether a ``nav_msgs/Odometry`` topic is a controller's odometry: not ground truth,
    not fused by its name, and not in a fixed frame (``map``, ``world``)."""
    return (
        topic.msgtype == ODOMETRY
        and not truth_like(topic.name)
        and not fused_like(topic.name)
        and not fixed_frame(_header_frame(topic))
    )


def odometry_candidates(
    scanned: Sequence[_Topic], transforms: Sequence[TransformInfo]
) -> list[Candidate]:
    """The controller's odometry topics and ``odom -> base`` transforms, moving first."""
    out = [
        Candidate(
            "odometry", "topic", odometry_label(t), (("--odom-topic", t.name),), t.moving, t.rate
        )
        for t in scanned
        if controller_odometry(t)
    ]
    for tf in transforms:
        if odometry_transform(tf):
            options = (("--odom-tf", f"{tf.parent} {tf.child}"),)
            label = f"TF {tf.parent} -> {tf.child}"
            out.append(Candidate("odometry", "tf", label, options, tf.moving, tf.rate))
    out.sort(key=lambda c: c.moving is False)
    return out


# --- ground truth -----------------------------------------------------------------------------

_FUSED = (
    "a fused odometry (an EKF's output) contains the wheel odometry: it agrees with it more "
    "than an independent reference would, and biases E_d and E_b towards 1"
)


def _topic_candidates(scanned: Sequence[_Topic]) -> list[tuple[int, Candidate]]:
    found: list[tuple[int, Candidate]] = []
    order = {POSE_STAMPED: 0, POSE_COV_STAMPED: 1, ODOMETRY: 2}
    for t in scanned:
        if t.msgtype in TRUTH_TYPES:
            if controller_odometry(t):
                continue  # the controller's own odometry is no ground truth
            warning = None
            if truth_like(t.name):
                rank = order[t.msgtype]
            elif t.msgtype == ODOMETRY and fused_like(t.name):
                rank, warning = 60, _FUSED
            else:
                rank = 40 + order[t.msgtype]
            label = odometry_label(t) if t.msgtype == ODOMETRY else f"{t.name} ({t.msgtype})"
            found.append((rank, _truth(t, "topic", label, warning=warning)))
        elif t.msgtype == MODEL_STATES and t.content is not None:
            for model in moving_models(t.content.model_motion()):
                options = (("--truth-topic", t.name), ("--truth-model", model))
                label = f"{t.name}: model {model} ({t.msgtype}; no header, bag time)"
                found.append((10, _truth(t, "model", label, options)))
        elif t.msgtype in (POINT_STAMPED, NAV_SAT_FIX):
            sigma = t.content.sigma if t.content is not None else None
            shown = "" if sigma is None else f", sigma {1000 * sigma:.0f} mm"
            label = f"{t.name} ({t.msgtype}; positions only{shown})"
            warning = None
            if sigma is not None and sigma > MAX_SUGGESTED_SIGMA:
                warning = (
                    f"its fixes scatter by {1000 * sigma:.0f} mm (their covariance), more "
                    "than the centimetres UMBmark measures: an RTK fix is needed"
                )
            elif t.msgtype == NAV_SAT_FIX and sigma is None:
                warning = "its fixes give no covariance: how precise they are is unknown"
            found.append((50, _truth(t, "topic", label, warning=warning, headings=False)))
    return found


def _truth(
    topic: _Topic,
    kind: str,
    label: str,
    options: tuple[tuple[str, str], ...] | None = None,
    *,
    warning: str | None = None,
    headings: bool = True,
) -> Candidate:
    chosen = options if options is not None else (("--truth-topic", topic.name),)
    return Candidate(
        "truth", kind, label, chosen, topic.moving, topic.rate, topic.needed_gap, warning, headings
    )


def truth_candidates(
    scanned: Sequence[_Topic],
    transforms: Sequence[TransformInfo],
    chains: Sequence[tuple[str, ...]],
    gaps: Mapping[tuple[str, str], float | None],
) -> list[Candidate]:
    """The ground-truth candidates, ranked (see the module docstring).

    ``gaps`` gives the ``--max-gap`` each transform pair needs.
    """
    found = _topic_candidates(scanned)
    seen: set[tuple[str, str]] = set()
    by_pair = {(tf.parent, tf.child): tf for tf in transforms}
    for tf in transforms:
        if tf.static or not fixed_frame(tf.parent) or "odom" in words(tf.child):
            continue
        seen.add((tf.parent, tf.child))
        options = (("--tf-parent", tf.parent), ("--tf-child", tf.child))
        label = f"TF {tf.parent} -> {tf.child}"
        rank = 0 if truth_like(tf.parent) else 20
        gap = gaps.get((tf.parent, tf.child))
        candidate = Candidate("truth", "tf", label, options, tf.moving, tf.rate, gap)
        found.append((rank, candidate))
    for chain in chains:
        if len(chain) < 3 or not fixed_frame(chain[0]):
            continue
        bases = [f for f in chain[1:] if f.lower().startswith("base")]
        child = bases[0] if bases else chain[-1]
        path = chain[: chain.index(child) + 1]
        if len(path) < 3 or (path[0], child) in seen:
            continue
        edges = [by_pair.get(pair) for pair in itertools.pairwise(path)]
        moving = [tf for tf in edges if tf is not None and tf.moving]
        if not moving or all(odometry_frame(tf.parent) for tf in moving):
            continue  # it moves only with the odometry: no reference
        seen.add((path[0], child))
        fastest = max(moving, key=lambda tf: tf.rate or 0.0)
        options = (("--tf-parent", path[0]), ("--tf-child", child))
        label = "TF chain " + " -> ".join(path)
        gap = gaps.get((fastest.parent, fastest.child))
        candidate = Candidate("truth", "tf_chain", label, options, True, fastest.rate, gap)
        found.append((30, candidate))
    found = [(rank + (100 if c.moving is False else 0), c) for rank, c in found]
    found.sort(key=lambda item: item[0])
    return [c for _, c in found]
