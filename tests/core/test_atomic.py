"""A folder built whole beside its target and renamed onto it (``atomic_tree``): a new
one appears at once, an old one is replaced only at the end, and a failure leaves the old
one as it was and nothing beside it."""

from __future__ import annotations

from pathlib import Path

import pytest

from umbmark.core.atomic import atomic_tree
from umbmark.core.errors import InputError


def test_a_folder_appears_whole_and_replaces_the_old_one_at_the_end(tmp_path: Path):
    target = tmp_path / "out"
    with atomic_tree(target) as fresh:
        assert fresh.name == "out"
        assert fresh.parent.parent == tmp_path
        fresh.mkdir()
        (fresh / "a.txt").write_text("one\n")
        assert not target.exists()  # nothing at the target before the end
    assert (target / "a.txt").read_text() == "one\n"
    with atomic_tree(target) as fresh:
        fresh.mkdir()
        (fresh / "b.txt").write_text("two\n")
        assert (target / "a.txt").exists()  # the old one stays until the end
    assert [p.name for p in target.iterdir()] == ["b.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


@pytest.mark.parametrize("error", [OSError("disk"), KeyboardInterrupt()], ids=["os", "ctrl-c"])
def test_a_failure_leaves_the_old_folder_and_nothing_beside_it(tmp_path: Path, error):
    target = tmp_path / "out"
    target.mkdir()
    (target / "kept.txt").write_text("old\n")

    def build() -> None:
        with atomic_tree(target) as fresh:
            fresh.mkdir()
            (fresh / "new.txt").write_text("new\n")
            raise error

    with pytest.raises(type(error)):
        build()
    assert [p.name for p in target.iterdir()] == ["kept.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_a_file_is_built_and_renamed_too(tmp_path: Path):
    target = tmp_path / "x.bag"
    target.write_text("old")
    with atomic_tree(target) as fresh:
        fresh.write_text("new")
    assert target.read_text() == "new"
    assert [p.name for p in tmp_path.iterdir()] == ["x.bag"]


def test_a_folder_that_cannot_be_written_beside_is_one_line(tmp_path: Path):
    with (
        pytest.raises(InputError, match="cannot be written"),
        atomic_tree(tmp_path / "missing" / "out"),
    ):
        pass
