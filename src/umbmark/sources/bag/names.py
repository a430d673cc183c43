"""What names say: left and right pairs, ground-truth names, fixed frames, fused odometry.

The heuristics :mod:`umbmark.sources.bag.info.candidates` ranks candidates by, and
:mod:`umbmark.sources.bag.urdf` finds wheel joints by. Names are topics, joints and
frames as the bag spells them.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

__all__ = [
    "BASE_LINKS",
    "fixed_frame",
    "fused_like",
    "mirrored_pairs",
    "odometry_frame",
    "truth_like",
    "words",
]

#: The frames (links) a sensor's mounting is stated in, where its chain passes through one.
BASE_LINKS = ("base_link", "base_footprint")

_MIRRORS: tuple[tuple[re.Pattern[str], str], ...] = (
    (re.compile(r"left"), "right"),
    (re.compile(r"Left"), "Right"),
    (re.compile(r"LEFT"), "RIGHT"),
    (re.compile(r"(?<![A-Za-z])l(?![a-z])"), "r"),  # wheel_l, l_wheel, /l/
    (re.compile(r"(?<![A-Za-z])L(?![a-z])"), "R"),
    (re.compile(r"(?<![A-Za-z])l(?=wheel|_?whl|enc|tick)"), "r"),  # lwheel, lenc
    (re.compile(r"(?<![A-Za-z])([fbrm])l(?![a-z])"), r"\1r"),  # fl_wheel, rl_wheel
)


def mirrored_pairs(names: Sequence[str]) -> list[tuple[str, str]]:
    """``(left, right)`` pairs of ``names`` whose names differ by left for right.

    ``left``/``right`` in any case, and ``l``/``r`` as a word of their own (``wheel_l``,
    ``l_wheel``), before ``wheel`` (``lwheel``) or after ``f``, ``b``, ``r``, ``m``
    (``fl_wheel``); in the order of ``names``.
    """
    present = set(names)
    pairs: list[tuple[str, str]] = []
    for name in names:
        for pattern, repl in _MIRRORS:
            for match in pattern.finditer(name):
                other = name[: match.start()] + match.expand(repl) + name[match.end() :]
                if other != name and other in present and (name, other) not in pairs:
                    pairs.append((name, other))
    return pairs


_TRUTH_WORDS = ("mocap", "vicon", "optitrack", "qualisys", "ground_truth", "groundtruth",
                "truth", "gt", "natnet", "motion_capture", "tracker")  # fmt: skip
_FIXED_FRAMES = ("world", "map", "mocap", "vicon", "optitrack", "earth", "odom_gt")
#: Words of a fused odometry (robot_localization's ``/odometry/filtered``, an EKF's output):
#: it contains the wheel odometry.
_FUSED_WORDS = ("filtered", "ekf", "ukf", "fused", "fusion", "localization", "combined")


def words(name: str) -> set[str]:
    """The lower-case words of ``name`` (split at anything but letters and digits)."""
    return {w for w in re.split(r"[^a-z0-9]+", name.lower()) if w}


def truth_like(name: str) -> bool:
    """Whether ``name`` says ground truth (``/mocap/pose``, ``/ground_truth/odom``)."""
    low = name.lower()
    return any(w in words(name) for w in _TRUTH_WORDS) or any(
        w in low for w in _TRUTH_WORDS if len(w) > 3
    )


def fixed_frame(frame: str) -> bool:
    """Whether ``frame`` is a fixed frame a reference is given in (``map``, ``world``)."""
    low = frame.lower()
    return low in _FIXED_FRAMES or any(w in words(low) for w in _FIXED_FRAMES)


def fused_like(name: str) -> bool:
    """Whether ``name`` says a fused odometry (``/odometry/filtered``, ``/ekf/odom``)."""
    found = words(name)
    return any(w in found for w in _FUSED_WORDS)


def odometry_frame(frame: str) -> bool:
    """Whether ``frame`` is an odometry frame (``odom``, ``wheel_odom``) and not fixed."""
    return "odom" in words(frame) and not fixed_frame(frame)
