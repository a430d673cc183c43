"""The IMU's mounting its turns show (``estimators/gyro_mounting.py``): the rotation the
readings say, as a URDF origin's ``rpy``, against closed forms and scipy's rotations."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from umbmark.estimators.gyro_mounting import GyroMounting, rpy_of

DEG = math.pi / 180.0


@pytest.mark.parametrize(
    "rpy", [(0.0, 0.0, 0.0), (1.0, -0.7, 30.0), (180.0, 0.0, 90.0), (-2.0, 3.0, -170.0)]
)
def test_rpy_is_the_urdfs_fixed_axes_xyz(rpy):
    rotation = Rotation.from_euler("xyz", rpy, degrees=True)  # extrinsic x, y, z: URDF's
    found = np.degrees(rpy_of(rotation.as_matrix()))
    back = Rotation.from_euler("xyz", found, degrees=True)
    assert (back.inv() * rotation).magnitude() < 1e-12


@pytest.mark.parametrize("stated_rpy", [(0.0, 0.0, 0.0), (0.0, 0.0, 90.0), (180.0, 0.0, 30.0)])
def test_the_found_rotation_turns_the_readings_about_the_axis_they_show(stated_rpy):
    """An IMU whose turns, put in the base frame by its stated rotation R0, turn about
    (-sin p, sin r cos p, cos r cos p) (the module's closed form: rolled r, pitched p
    beyond what R0 says): the rotation found turns the base's z into exactly that axis
    through R0, and keeps R0's yaw."""
    r, p = 0.8 * DEG, -1.3 * DEG
    stated = Rotation.from_euler("xyz", stated_rpy, degrees=True).as_matrix()
    found = GyroMounting(roll=r, pitch=p, stated_rotation=stated).found_rotation()
    assert found is not None
    # a reading of a turn about the base's z, in the IMU frame (found^T z), put in the
    # base frame by the stated rotation: the axis the turns show
    axis = stated @ found.T @ np.array([0.0, 0.0, 1.0])
    expected = [-math.sin(p), math.sin(r) * math.cos(p), math.cos(r) * math.cos(p)]
    np.testing.assert_allclose(axis, expected, atol=1e-12)
    # a level IMU (r = p = 0) is found where it is stated
    level = GyroMounting(roll=0.0, pitch=0.0, stated_rotation=stated).found_rotation()
    np.testing.assert_allclose(level, stated, atol=1e-12)


def test_without_a_stated_rotation_or_an_axis_nothing_is_found():
    assert GyroMounting(roll=0.1, pitch=0.1).found_rotation() is None
    assert GyroMounting(stated_rotation=np.eye(3)).found_rotation() is None
