"""A fleet's recordings found in folders, globs and lists, named by a pattern of their
paths."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import pytest

from umbmark.core.errors import InputError
from umbmark.fleets.recordings import find_recordings, match_path, path_pattern


@pytest.fixture
def tree(tmp_path: Path) -> Path:
    root = tmp_path / "fleet"
    for rel in ("r1/2026-11-01/a.mcap", "r1/2026-11-02/b.mcap", "r2/20261102/c.bag"):
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_bytes(b"")
    bag2 = root / "r3" / "2026-11-03" / "session"  # a ROS 2 bag folder: one recording
    bag2.mkdir(parents=True)
    (bag2 / "metadata.yaml").write_text("rosbag2_bagfile_information:\n  version: 5\n")
    (bag2 / "session_0.db3").write_bytes(b"")
    (root / "r1" / "notes.txt").write_text("not a recording\n")
    return root


def test_a_folder_is_searched_and_the_pattern_names_robot_and_day(tree: Path):
    found = find_recordings([tree], "{robot}/{date}/*")
    assert [(Path(f.path).relative_to(tree).as_posix(), f.robot, f.day) for f in found] == [
        ("r1/2026-11-01/a.mcap", "r1", dt.date(2026, 11, 1)),
        ("r1/2026-11-02/b.mcap", "r1", dt.date(2026, 11, 2)),
        ("r2/20261102/c.bag", "r2", dt.date(2026, 11, 2)),
        ("r3/2026-11-03/session", "r3", dt.date(2026, 11, 3)),
    ]


def test_globs_lists_and_no_pattern(tree: Path):
    found = find_recordings([str(tree / "r1" / "*" / "*.mcap"), tree / "r2"])
    assert [Path(f.path).name for f in found] == ["a.mcap", "b.mcap", "c.bag"]
    assert all(f.robot is None and f.day is None for f in found)
    # The same recording given twice is taken once.
    assert len(find_recordings([tree, tree / "r2" / "20261102" / "c.bag"])) == 4


def test_each_recording_says_whether_the_pattern_matched_and_its_path_below_the_folder(
    tree: Path,
):
    """What names an unreadable recording's robot: its path's components below the folder
    searched (a glob's folder before its wildcard), all of them for a recording given
    itself; and whether the pattern matched it (a pattern without {robot} too)."""
    found = find_recordings([tree, str(tree / "r2" / "*" / "c.bag")], "r1/{date}/*.mcap")
    assert [(f.parts, f.matched, f.robot) for f in found] == [
        (("r1", "2026-11-01", "a.mcap"), True, None),
        (("r1", "2026-11-02", "b.mcap"), True, None),
        (("r2", "20261102", "c.bag"), False, None),
        (("r3", "2026-11-03", "session"), False, None),
    ]
    (only,) = find_recordings([str(tree / "r2" / "*" / "c.bag")])
    assert (only.parts, only.matched) == (("20261102", "c.bag"), False)
    (itself,) = find_recordings([tree / "r1" / "2026-11-01" / "a.mcap"])
    assert itself.parts == tuple((tree / "r1" / "2026-11-01" / "a.mcap").parts[1:])


def test_the_pattern_matches_the_end_of_the_path(tree: Path):
    found = find_recordings([tree], "{robot}/**/*.mcap")
    assert {f.robot for f in found if f.path.endswith(".mcap")} == {"r1"}
    assert all(f.robot is None for f in found if not f.path.endswith(".mcap"))
    found = find_recordings([tree / "r1" / "2026-11-01" / "a.mcap"], "{robot}/{date}/*.mcap")
    assert (found[0].robot, found[0].day) == ("r1", dt.date(2026, 11, 1))  # by the path's end
    regex = path_pattern("robots/{robot}_{date}.mcap")
    assert match_path(regex, "/x/robots/amr7_20261101.mcap", None)["robot"] == "amr7"


@pytest.mark.parametrize(
    ("pattern", "said"),
    [
        ("", "give a pattern"),
        ("{robot}/{day}/*.mcap", "holds {day}"),
        ("{robot}/{robot}", "names a field twice"),
    ],
)
def test_bad_patterns_are_one_line(pattern: str, said: str):
    with pytest.raises(InputError, match=said):
        path_pattern(pattern)


def test_bad_sources(tree: Path, tmp_path: Path):
    with pytest.raises(InputError, match="no such file or folder"):
        find_recordings([tmp_path / "nowhere"])
    with pytest.raises(InputError, match="matches no file"):
        find_recordings([str(tmp_path / "*.nothing")])
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no recording"):
        find_recordings([tmp_path / "empty"])
    bad_day = tree / "r9" / "2026-13-40"
    bad_day.mkdir(parents=True)
    (bad_day / "x.mcap").write_bytes(b"")
    with pytest.raises(InputError, match="is no date"):
        find_recordings([tree], "{robot}/{date}/*")


def test_urls_are_found_and_named_as_their_paths_are(tree: Path, tmp_path: Path):
    """The same folder served over HTTP (index pages) and as ``file://``: the same
    recordings, robots and days as on disk; a glob; a recording's URL taken as given; a glob
    that matches nothing refused."""
    pytest.importorskip("fsspec", reason="the remote extra: pip install '.[remote]'")
    pytest.importorskip("aiohttp", reason="the remote extra: pip install '.[remote]'")
    from http_served import Served

    local = [
        (Path(f.path).relative_to(tree).as_posix(), f.robot, f.day)
        for f in find_recordings([tree], "{robot}/{date}/*")
    ]
    assert len(local) == 4

    def named(found: list, prefix: str) -> list:  # type: ignore[type-arg]
        return [(f.path.removeprefix(prefix).rstrip("/"), f.robot, f.day) for f in found]

    with Served(tree.parent, tmp_path / "http.log") as server:
        url = f"{server.url}/{tree.name}/"
        assert named(find_recordings([url], "{robot}/{date}/*"), url) == local
        globbed = find_recordings([f"{url}r1/*/*.mcap", f"{server.url}/elsewhere/gone.bag"],
                                  "{robot}/{date}/*.mcap")  # fmt: skip
        assert named(globbed, url) == [
            ("r1/2026-11-01/a.mcap", "r1", dt.date(2026, 11, 1)),
            ("r1/2026-11-02/b.mcap", "r1", dt.date(2026, 11, 2)),
            (f"{server.url}/elsewhere/gone.bag", None, None),
        ]
        with pytest.raises(InputError, match="matches no file or folder"):
            find_recordings([f"{url}*/1999-*"])
    on_disk = f"file://{tree}/"
    assert named(find_recordings([on_disk], "{robot}/{date}/*"), on_disk) == local
