"""The helpers several layers share, written once in core/: planar poses and SHA-256.

Expected values are worked out by hand (a quarter turn, a unit step) or come from the
SHA-256 test vector of FIPS 180-2 ("abc").
"""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest

from umbmark.core.digest import file_sha256, path_sha256
from umbmark.core.geometry import (
    compose,
    invert,
    quaternion_yaw,
    relative_positions,
    to_start_frame,
)

QUARTER = 0.5 * math.pi


@pytest.mark.parametrize("yaw", [0.0, 0.3, QUARTER, -2.5, math.pi - 1e-9])
def test_the_yaw_of_a_turn_about_z_is_its_angle(yaw):
    # q = (0, 0, sin(yaw/2), cos(yaw/2)): 2 w z = sin(yaw), 1 - 2 z^2 = cos(yaw)
    got = quaternion_yaw(0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw))
    assert got == pytest.approx(yaw, abs=1e-12)


def test_the_yaw_ignores_a_roll_and_takes_arrays():
    # q_yaw (x) q_roll = (cz sr, sz sr, sz cr, cz cr) for a roll about x after the yaw
    yaw = np.array([0.4, -1.2])
    half_roll = 0.05
    sz, cz = np.sin(0.5 * yaw), np.cos(0.5 * yaw)
    sr, cr = math.sin(half_roll), math.cos(half_roll)
    got = quaternion_yaw(cz * sr, sz * sr, sz * cr, cz * cr)
    np.testing.assert_allclose(got, yaw, atol=1e-12)


def test_composing_a_quarter_turn_with_a_step_forward():
    # at (1, 0) facing +y, one metre forward reaches (1, 1)
    a = np.array([[1.0, 0.0, QUARTER]])
    b = np.array([[1.0, 0.0, 0.0]])
    np.testing.assert_allclose(compose(a, b), [[1.0, 1.0, QUARTER]], atol=1e-15)


def test_a_pose_composed_with_its_inverse_is_the_origin():
    a = np.array([[1.0, 0.0, QUARTER], [-2.0, 3.0, -2.0], [0.5, 0.25, 3.0]])
    # the inverse of (1, 0, pi/2): the origin seen from it is 1 m to its right, (0, 1)
    # turned back: (0, 1, -pi/2)
    np.testing.assert_allclose(invert(a[:1]), [[0.0, 1.0, -QUARTER]], atol=1e-15)
    np.testing.assert_allclose(compose(a, invert(a)), np.zeros((3, 3)), atol=1e-15)
    np.testing.assert_allclose(compose(invert(a), a), np.zeros((3, 3)), atol=1e-15)


def test_poses_in_the_frame_of_the_first():
    # the first at (1, 1) facing +y: (1, 2) is 1 m ahead, (0, 1) 1 m to the left
    poses = np.array([[1.0, 1.0, QUARTER], [1.0, 2.0, QUARTER], [0.0, 1.0, math.pi]])
    expected = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, QUARTER]]
    np.testing.assert_allclose(to_start_frame(poses), expected, atol=1e-15)
    np.testing.assert_allclose(
        relative_positions(poses[:, :2], QUARTER), [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        atol=1e-15,
    )  # fmt: skip


def test_sha256_of_a_file_and_of_a_folder(tmp_path):
    file = tmp_path / "abc.txt"
    file.write_bytes(b"abc")
    abc = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"  # FIPS 180-2
    assert file_sha256(file) == abc
    assert file_sha256(str(file)) == abc
    assert path_sha256(file) == abc
    folder = tmp_path / "bag"
    (folder / "sub").mkdir(parents=True)
    (folder / "b.db3").write_bytes(b"xyz")
    (folder / "sub" / "a.yaml").write_bytes(b"abc")
    # relative names (POSIX) and contents, in sorted order of the paths
    expected = hashlib.sha256(b"b.db3\0xyz" + b"sub/a.yaml\0abc").hexdigest()
    assert path_sha256(folder) == expected
    assert path_sha256(tmp_path / "missing") is None
