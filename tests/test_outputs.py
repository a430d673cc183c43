"""Writing files whole or not at all, and reading controller parameter files."""

from __future__ import annotations

import pytest

from umbmark.core.atomic import atomic_path, atomic_write_text
from umbmark.core.errors import InputError
from umbmark.sources.params.reader import read_controller_params as read_active_multipliers


def test_a_failed_write_leaves_the_old_file_and_no_litter(tmp_path):
    target = tmp_path / "overlay.yaml"
    target.write_text("the user's file\n")

    def interrupted_write() -> None:
        with atomic_path(target) as tmp:
            tmp.write_text("half of a new fi")
            raise RuntimeError("disk full, say")

    with pytest.raises(RuntimeError):
        interrupted_write()
    assert target.read_text() == "the user's file\n"
    assert list(tmp_path.iterdir()) == [target]


def test_a_finished_write_replaces_the_file_with_normal_permissions(tmp_path):
    target = tmp_path / "result.json"
    target.write_text("old")
    atomic_write_text(target, "new")
    assert target.read_text() == "new"
    assert target.stat().st_mode & 0o044  # readable by others, as files usually are


def test_writing_onto_a_directory_is_refused(tmp_path):
    with pytest.raises(InputError, match="is a directory"):
        atomic_write_text(tmp_path, "x")


def _params(tmp_path, text: str):
    path = tmp_path / "params.yaml"
    path.write_text(text)
    return path


def test_reads_ros1_style_parameters(tmp_path):
    path = _params(
        tmp_path,
        "mobile_base_controller:\n  type: diff_drive_controller/DiffDriveController\n"
        "  wheel_separation: 0.5\n  left_wheel_radius_multiplier: 1.02\n",
    )
    active = read_active_multipliers(path)
    assert active.controller == "mobile_base_controller"
    assert active.wheel_separation == 0.5
    assert active.left_wheel_radius_multiplier == 1.02
    assert active.right_wheel_radius_multiplier == 1.0


def test_namespaced_controller_is_found_by_its_name(tmp_path):
    path = _params(
        tmp_path,
        "robot1:\n  diff_cont:\n    ros__parameters:\n      wheel_separation: 0.4\n"
        "robot2:\n  diff_cont:\n    ros__parameters:\n      wheel_separation: 0.5\n",
    )
    assert read_active_multipliers(path, "robot2/diff_cont").wheel_separation == 0.5
    with pytest.raises(InputError, match="several controllers"):
        read_active_multipliers(path)


@pytest.mark.parametrize(
    ("text", "controller", "message"),
    [
        ("a: [1, 2\n", None, "is not valid YAML"),
        (
            "controller_manager:\n  ros__parameters:\n    update_rate: 50\n",
            None,
            "has no diff_drive_controller parameters",
        ),
        (
            "dd:\n  ros__parameters:\n    wheel_separation: 0.3\n",
            "other",
            "has no single diff-drive controller 'other' (none matches; controllers with "
            "diff-drive parameters: dd)",
        ),
        (
            "dd:\n  ros__parameters:\n    wheel_separation_multiplier: fast\n",
            None,
            "wheel_separation_multiplier is 'fast', not a number",
        ),
        (
            "dd:\n  ros__parameters:\n    wheel_radius: -0.05\n",
            None,
            "wheel_radius is -0.05 m, outside 0.001 to 10 m",
        ),
        (
            "dd:\n  ros__parameters:\n    wheel_separation: 340.0\n",
            None,
            "wheel_separation is 340 m, outside 0.001 to 10 m (lengths are in metres)",
        ),
        (
            "dd:\n  ros__parameters:\n    left_wheel_names: [a, b]\n    right_wheel_names: [c]\n",
            None,
            "names 2 left and 1 right wheel joints",
        ),
    ],
)
def test_bad_parameter_files(tmp_path, text, controller, message):
    path = _params(tmp_path, text)
    with pytest.raises(InputError) as info:
        read_active_multipliers(path, controller)
    assert str(info.value).startswith(str(path))
    assert message in str(info.value)
