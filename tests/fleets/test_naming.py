"""How a fleet's unreadable recordings find their robot by their path, and the wording of
the naming's warnings (the fleet end to end: tests/test_fleet_naming.py)."""

from __future__ import annotations

import pytest

from umbmark.core.errors import with_flags
from umbmark.fleets.naming import (
    NAMES_SHOWN,
    NO_ROBOT,
    UNNAMED,
    options_warning,
    pattern_warning,
    robot_in_path,
)

ROBOTS = {"amr7", "amr70", "robot02", UNNAMED, NO_ROBOT}


@pytest.mark.parametrize(
    ("parts", "robot"),
    [
        (("amr7", "2026-11-02", "drive"), "amr7"),  # a robot's folder
        (("2026-11-02", "amr70", "drive.bag"), "amr70"),  # its own name, not amr7 in it
        (("day", "amr7_2026-11-02.mcap"), "amr7"),  # a word of the file's name
        (("day", "amr70-2026-11-02.mcap"), "amr70"),  # amr7 is no word of amr70
        (("amr7", "old", "robot02", "x.bag"), "robot02"),  # the deepest that names one
        (("amr7x", "2026-11-02", "drive"), None),  # no word is a robot's name
        (("unnamed", "drive"), None),  # 'unnamed' is nobody's name in a path
        (("spare", "2026-11-03", "drive.bag"), None),
        ((), None),
    ],
)
def test_a_path_names_the_robot_of_its_deepest_component_that_holds_a_name(parts, robot):
    assert robot_in_path(parts, ROBOTS) == robot


def test_a_component_holding_two_names_alike_names_no_robot():
    assert robot_in_path(("amr1_amr2.bag",), {"amr1", "amr2"}) is None
    # Of two names one component holds, the longer (amr7 is a word of amr7-b too).
    assert robot_in_path(("amr7-b_day1.bag",), {"amr7", "amr7-b"}) == "amr7-b"


def test_the_pattern_warning_says_how_many_matched_and_how_the_others_were_named():
    said = pattern_warning(
        "{robot}/{date}/*.mcap", 6, 2, {"description": 1, "history": 1, "none": 1, None: 1},
        "robot01/2026-11-02/drive",
    )  # fmt: skip
    assert with_flags(said) == (
        "--robot-from '{robot}/{date}/*.mcap' matched 2 of the 6 recordings found (not "
        "robot01/2026-11-02/drive, for one); the 4 others are named: 1 by their robot "
        "description, 1 as before (done before, in the history), 1 'unnamed' (nothing in "
        "them names a robot) and 1 not at all (unreadable, and their path names no robot "
        "found)"
    )
    assert pattern_warning("{robot}/*", 3, 3, {}, "") is None


def test_the_options_warning_names_the_entries_and_the_robots_found():
    said = options_warning({"amr9", "robot01"}, {"robot01", "robot02", NO_ROBOT}, "r.yaml")
    assert with_flags(said) == (
        "--robot-options r.yaml: no robot found is named amr9, so its entry is used for no "
        "recording; the robots found: robot01 and robot02"
    )
    many = {f"r{k:03d}" for k in range(NAMES_SHOWN + 5)}
    said = with_flags(options_warning({"x", "y"}, many, "r.yaml"))
    assert "named x or y, so their entries are used" in said
    assert said.endswith(", r009 and 5 more")
    assert options_warning({"robot01"}, {"robot01"}, "r.yaml") is None
