"""A bag opened through a time window (``open_bag(..., window)``): what every reader in the
package gets is the whole bag's messages cut to the window, latched topics whole, so that
a long recording is read one window at a time."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")

from robot_bags import TB3, drive, turtlebot3_bag
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.recording import read_recording

JOINTS = BagOptions(left_joint="wheel_left_joint", right_joint="wheel_right_joint")


@pytest.fixture(scope="module", params=["mcap", "ros1"])
def bag(request, tmp_path_factory) -> Path:
    motion = drive(TB3, 1.0, 1.0, directions=("cw",))
    return turtlebot3_bag(tmp_path_factory.mktemp("tb3") / "tb3", request.param, motion)


def _times(path: Path, window: tuple[int, int] | None) -> dict[str, list[int]]:
    """Each topic's bag times [ns], as read through the window."""
    out: dict[str, list[int]] = {}
    with bag_reader.open_bag(path, str(path), window) as reader:
        for topic in bag_reader.topic_types(reader):
            conns = [c for c in reader.connections if c.topic == topic]
            out[topic] = [t for t, _ in bag_reader.messages(reader, conns, topic, str(path))]
    return out


def test_a_window_cuts_every_topic_but_the_latched_ones(bag: Path):
    whole = _times(bag, None)
    first = min(t[0] for t in whole.values() if t)
    last = max(t[-1] for t in whole.values() if t)
    a = first + (last - first) // 3
    b = first + 2 * (last - first) // 3
    cut = _times(bag, (a, b))
    assert set(cut) == set(whole)
    for topic, times in whole.items():
        if topic in ("/tf_static", "/robot_description"):
            assert cut[topic] == times
            assert times
        else:
            assert cut[topic] == [t for t in times if a <= t < b], topic
    assert 0 < len(cut["/joint_states"]) < len(whole["/joint_states"])


def test_the_wheels_of_a_window_are_the_whole_reads_samples_in_it(bag: Path):
    whole = read_recording(bag, JOINTS).wheels
    t0, t1 = whole.time[0], whole.time[-1]
    a, b = t0 + 0.25 * (t1 - t0), t0 + 0.5 * (t1 - t0)
    # The writer stamps each message with its bag time: the window in seconds is the same.
    part = read_recording(bag, JOINTS, window=(int(a * 1e9), int(b * 1e9))).wheels
    inside = (whole.time >= a - 1e-6) & (whole.time < b + 1e-6)
    assert part.time.size == np.count_nonzero(inside) > 10
    np.testing.assert_array_equal(part.time, whole.time[inside])
    np.testing.assert_array_equal(part.angles, whole.angles[inside])
