"""A fleet's per-robot reading options: a small YAML file read by keyword, bad ones named
in one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from umbmark.core.errors import InputError
from umbmark.sources.robot_options import read_robot_options


def test_per_robot_options_are_read_by_keyword(tmp_path: Path):
    path = tmp_path / "robots.yaml"
    path.write_text(
        "amr1:\n  truth_topic: /mocap/amr1\n  wheelbase: 0.41\namr2:\n  scan_topic: /front/scan\n"
    )
    assert read_robot_options(path) == {
        "amr1": {"truth_topic": "/mocap/amr1", "wheelbase": 0.41},
        "amr2": {"scan_topic": "/front/scan"},
    }
    empty = tmp_path / "empty.yaml"
    empty.write_text("# nothing yet\n")
    assert read_robot_options(empty) == {}


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("- a\n- b\n", "should map each robot's name to its options"),
        ("amr1: 3\n", "robot 'amr1': give a mapping of options"),
        ("amr1:\n  turth_topic: /x\n", "'turth_topic' is no reading option"),
        ("amr1: [unclosed\n", "is not YAML"),
    ],
)
def test_bad_files_are_one_line(tmp_path: Path, text: str, said: str):
    path = tmp_path / "robots.yaml"
    path.write_text(text)
    with pytest.raises(InputError, match=said.replace("(", r"\(").replace("[", r"\[")):
        read_robot_options(path)
    with pytest.raises(InputError, match="no such file"):
        read_robot_options(tmp_path / "missing.yaml")
