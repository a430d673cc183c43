"""How a fleet's recordings get their robots, and the warnings where that went quietly
wrong.

A recording's robot is, in this order (:func:`umbmark.fleets.recordings.find_recordings`
and :func:`umbmark.fleets.outcome.calibrate_recording`):

1. the ``robot_from`` pattern's ``{robot}``, where the pattern matches its path;
2. else what the recording says when it is read: the namespace most of its topics share,
   else the name in its robot description, else ``unnamed``;
3. a recording that cannot be read says nothing: it is the robot found (by the fleet's
   other recordings) whose name its path holds, :func:`robot_in_path`; where its path
   holds none, it is no robot's (it is listed among the failed recordings and makes no
   robot of its own: :data:`NO_ROBOT`).

The warnings say what a person would not notice: a pattern that leaves recordings to be
named by what they hold (:func:`pattern_warning`), and an entry of ``robot_options`` for
a robot that no recording turned out to be (:func:`options_warning`).
"""

from __future__ import annotations

import re
from collections.abc import Collection, Mapping, Sequence

from umbmark.core.errors import option
from umbmark.core.messages import join_names

__all__ = [
    "HOW_NAMED",
    "NO_ROBOT",
    "UNNAMED",
    "options_warning",
    "pattern_warning",
    "robot_in_path",
]

#: The robot of a readable recording that names none.
UNNAMED = "unnamed"
#: The robot of a recording that cannot be read and whose path names no robot found: none.
NO_ROBOT = ""
#: How a recording's robot was found (an outcome's ``named_by``; ``history``: done before,
#: ``none``: no robot), in the words of the pattern warning; None: nothing named it.
HOW_NAMED: dict[str | None, str] = {
    "pattern": "by the pattern",
    "namespace": "by their topics' namespace",
    "description": "by their robot description",
    "path": "by a robot's name in their path (unreadable)",
    "history": "as before (done before, in the history)",
    None: f"'{UNNAMED}' (nothing in them names a robot)",
    "none": "not at all (unreadable, and their path names no robot found)",
}
#: Robot names a warning lists at most.
NAMES_SHOWN = 10


def _holds(component: str, name: str) -> bool:
    """Whether a path component is ``name`` or holds it as a word (``amr7_2026-11-02.mcap``
    holds amr7; ``amr70`` does not)."""
    if component == name:
        return True
    return re.search(rf"(?<![A-Za-z0-9]){re.escape(name)}(?![A-Za-z0-9])", component) is not None


def robot_in_path(parts: Sequence[str], robots: Collection[str]) -> str | None:
    """The robot of ``robots`` a path names: the deepest of its components ``parts``
    (below the folder searched) that is a robot's name or holds one as a word; of the
    names one component holds, the one it is, else the longest. None where no component
    holds a name, or the deepest that does holds two of the same length (the path does
    not say which).

    Parameters
    ----------
    parts : sequence of str
        The path's components (``("amr7", "2026-11-02", "drive")``).
    robots : collection of str
        The robots found (``unnamed`` and :data:`NO_ROBOT` are never names in a path).
    """
    names = [r for r in robots if r and r != UNNAMED]
    for component in reversed(parts):
        held = [r for r in names if _holds(component, r)]
        if not held:
            continue
        if component in held:
            return component
        longest = max(len(r) for r in held)
        first = sorted(r for r in held if len(r) == longest)
        return first[0] if len(first) == 1 else None
    return None


def _listed(names: Collection[str]) -> str:
    """Robot names for a warning: sorted, at most :data:`NAMES_SHOWN`, and how many more."""
    ordered = sorted(names)
    if len(ordered) > NAMES_SHOWN:
        more = len(ordered) - NAMES_SHOWN
        return ", ".join(ordered[:NAMES_SHOWN]) + f" and {more} more"
    return join_names(ordered) or "none"


def pattern_warning(
    pattern: str, found: int, matched: int, named_by: Mapping[str | None, int], example: str
) -> str | None:
    """The warning of a ``robot_from`` pattern that did not match every recording found;
    None where it did.

    Parameters
    ----------
    pattern : str
    found, matched : int
        Recordings found, and those whose path the pattern matched.
    named_by : mapping of str or None to int
        How the others were named (the keys of :data:`HOW_NAMED`), and how many each way.
    example : str
        The path of one it did not match, below the folder searched.
    """
    if matched >= found:
        return None
    ways = [f"{named_by[k]} {said}" for k, said in HOW_NAMED.items() if named_by.get(k)]
    instead = f"; the {found - matched} others are named: {join_names(ways)}" if ways else ""
    return (
        f"{option('robot_from', repr(pattern))} matched {matched} of the {found} recordings "
        f"found (not {example}, for one){instead}"
    )


def options_warning(entries: Collection[str], robots: Collection[str], source: str) -> str | None:
    """The warning of ``robot_options`` entries for robots no recording turned out to be
    (their options are used for none); None where every entry is a robot found.

    Parameters
    ----------
    entries : collection of str
        The robots the file has entries for.
    robots : collection of str
        The robots found.
    source : str
        The file.
    """
    unused = sorted(set(entries) - set(robots))
    if not unused:
        return None
    which = "its entry is" if len(unused) == 1 else "their entries are"
    return (
        f"{option('robot_options', source)}: no robot found is named "
        f"{join_names(unused, 'or')}, so {which} used for no recording; the robots found: "
        f"{_listed([r for r in robots if r != NO_ROBOT])}"
    )
