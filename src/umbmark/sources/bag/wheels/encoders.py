"""Wheel encoders: cumulative counts on ``std_msgs`` topics, or two fields of any message.

The readers behind :class:`~umbmark.sources.bag.bag_options.BagOptions`' ``left_ticks_topic``
/ ``right_ticks_topic`` (:func:`read_ticks`) and ``left_field`` / ``right_field``
(:func:`read_fields`); the module docstring of :mod:`umbmark.sources.bag.bag_options` says
what they read.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from umbmark.core.arrays import FloatArray, IntArray
from umbmark.core.errors import InputError, option
from umbmark.model.recording import WheelSeries
from umbmark.sources.bag import custom
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.fastpath import POSITION, Sample, fast_layout
from umbmark.sources.bag.fieldpath import getter, row_getter
from umbmark.sources.bag.msgtypes import TICK_TYPES, Number
from umbmark.sources.bag.samples import clean, on_left_times, read_topic, time_ns

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader

    from umbmark.sources.bag.bag_options import BagOptions

__all__ = ["read_fields", "read_ticks", "unwrap"]


def _read_counts(
    reader: AnyReader, topics: dict[str, str], topic: str, side: str, src: str
) -> tuple[IntArray, FloatArray]:
    """Time [ns] and unwrapped cumulative counts, each shape (k,), of a ticks topic."""
    conns, msgtype = bag_reader.topic_connections(
        reader, topics, topic, tuple(TICK_TYPES), f"{side} wheel ticks", src
    )
    bits = TICK_TYPES[msgtype][1]

    def decode(msg: Number) -> list[Sample]:
        return [(0, 0, (float(msg.data),), POSITION)]

    layout_of = fast_layout(msgtype)
    scan = read_topic(
        reader, conns, msgtype, topic, src, width=1, decode=decode, layout_of=layout_of
    )
    times, _, counts = clean(time_ns(scan, False), scan.values, f"topic {topic}", src, header=False)
    return times, unwrap(counts[:, 0], bits)


def unwrap(counts: FloatArray, bits: int | None) -> FloatArray:
    """Counts of a ``bits``-bit counter that wraps around, shape (k,), made continuous.

    A jump of more than half the counter's range between two samples is taken as a wrap.
    ``bits`` None: the counts are returned as they are.
    """
    if bits is None:
        return counts
    span = float(2**bits)
    step = np.diff(counts)
    step = step - span * (step > span / 2) + span * (step < -span / 2)
    return np.asarray(counts[0] + np.concatenate([[0.0], np.cumsum(step)]))


def read_ticks(
    reader: AnyReader,
    topics: dict[str, str],
    left_topic: str,
    right_topic: str,
    ticks_per_revolution: float,
    src: str,
) -> WheelSeries:
    time, counts = on_left_times(
        _read_counts(reader, topics, left_topic, "left", src),
        _read_counts(reader, topics, right_topic, "right", src),
        f"the ticks topics {left_topic} and {right_topic} overlap in time in fewer than"
        " 2 samples of the left wheel",
        src,
    )
    return WheelSeries(time=time, angles=counts * (2.0 * math.pi / ticks_per_revolution))


def read_fields(
    reader: AnyReader, topics: dict[str, str], options: BagOptions, src: str
) -> WheelSeries:
    """Wheel rotation from two fields of the messages of ``wheel_topic``, of any type.

    The type's definition comes from the bag or ``msg_dir``
    (:func:`umbmark.sources.bag.custom.add_definitions`); every message is deserialized
    by rosbags and its two values collected into lists, turned into arrays once. Times
    are ``header.stamp`` if the type has a ``std_msgs/Header header`` and the time source
    is ``"header"``, else the bag time.
    """
    assert options.left_field is not None  # the caller checked
    assert options.right_field is not None
    topic = options.wheel_topic
    if topic in topics and ", " in topics[topic]:
        raise InputError(
            f"topic {topic} has messages of several types ({topics[topic]}); wheel fields "
            "are read from one",
            source=src,
        )
    conns, msgtype = bag_reader.topic_connections(
        reader, topics, topic, (topics.get(topic, ""),), "wheel data", src
    )
    custom.add_definitions(reader, msgtype, options.msg_dir, topic, src)
    fielddefs = reader.typestore.fielddefs
    fields = []
    for what, text in (("left field", options.left_field), ("right field", options.right_field)):
        try:
            fields.append(custom.resolve_field(fielddefs, msgtype, text, what, of=topic))
        except InputError as err:
            raise InputError(err.problem, source=src) from None
    left, right = fields
    tpr = options.ticks_per_rev
    if tpr is None:
        for field in fields:
            if field.integer:
                raise InputError(
                    f"field {field.text} of {msgtype} is an integer ({field.base}): encoder "
                    f"counts need {option('ticks_per_rev')} (counts per wheel revolution); "
                    "without it the fields are read as angles [rad]",
                    source=src,
                )
    header = options.time_source == "header" and custom.has_header(fielddefs, msgtype)
    paths = [left.steps, right.steps]
    if header:
        paths += [("header", "stamp", "sec"), ("header", "stamp", "nanosec")]
    row = row_getter(paths)
    store = reader.typestore
    deserialize = store.deserialize_cdr if reader.is2 else store.deserialize_ros1
    rows: list[tuple[Any, ...]] = []
    bag_ns: list[int] = []
    add_row, add_ns = rows.append, bag_ns.append
    for ns, raw in bag_reader.messages(reader, conns, topic, src):
        try:
            msg = deserialize(raw, msgtype)
        except Exception as err:  # malformed message bytes, a definition that does not fit
            raise InputError(
                f"a message of {topic} cannot be decoded as {msgtype}: {bag_reader.one_line(err)}",
                source=src,
            ) from None
        try:
            add_row(row(msg))
        except AttributeError as err:  # a message class unlike its definition
            raise InputError(
                f"a message of {topic} lacks a field of {msgtype}: {bag_reader.one_line(err)}",
                source=src,
            ) from None
        except IndexError:
            raise InputError(
                f"a message of {topic} (bag time {ns * 1e-9:.9f} s) has too few entries "
                f"for the field {_short_field(msg, left, right)}",
                source=src,
            ) from None
        add_ns(ns)
    if not rows:
        raise InputError(f"topic {topic} has no messages", source=src)
    # one conversion; float64 holds the stamps' seconds and nanoseconds exactly
    table = np.array(rows, np.float64).reshape(len(rows), len(paths))
    if header:
        time_ns = table[:, 2].astype(np.int64) * 1_000_000_000 + table[:, 3].astype(np.int64)
    else:
        time_ns = np.array(bag_ns, np.int64)
    _, time, values = clean(time_ns, table[:, :2], f"topic {topic}", src, header=header)
    if tpr is None:
        return WheelSeries(time=time, angles=values)
    counts = np.column_stack(
        [unwrap(values[:, 0], left.wrap_bits), unwrap(values[:, 1], right.wrap_bits)]
    )
    return WheelSeries(time=time, angles=counts * (2.0 * math.pi / tpr))


def _short_field(msg: object, *fields: custom.Field) -> str:
    """The first of ``fields`` that ``msg`` is too short for."""
    for field in fields:
        try:
            getter(field.steps)(msg)
        except IndexError:
            return field.text
    return fields[0].text
