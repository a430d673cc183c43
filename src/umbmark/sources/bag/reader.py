"""Opening bags with rosbags, listing their topics and iterating raw messages.

Everything that touches rosbags' reader lives here, and every failure of it becomes an
:class:`umbmark.core.errors.InputError` of one line naming the bag: a path that is not a bag,
a missing rosbags (:func:`missing_rosbags`), a bag that cannot be opened, a topic
that is absent or of the wrong type (the message lists the topics present), a storage
error while reading messages, or a message that cannot be deserialized.

rosbags is imported only when a bag is opened, so importing :mod:`umbmark.sources.bag`
works without it. :func:`messages` counts the messages it yields for the progress of the
read under way (:mod:`umbmark.sources.progress`).
"""

from __future__ import annotations

from collections.abc import Generator, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from umbmark.core.errors import InputError
from umbmark.sources.progress import current_tracker

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

__all__ = [
    "deserialize",
    "listing",
    "message_count",
    "messages",
    "missing_rosbags",
    "missing_topic",
    "one_line",
    "open_bag",
    "raw_messages",
    "reader_windows",
    "time_windows",
    "topic_connections",
    "topic_types",
    "windowed",
]

_LISTED = 25  # names listed in an error message at most


def listing(items: Sequence[str]) -> str:
    """``items`` separated by ``", "``, the first 25 of them and how many more there are."""
    shown = ", ".join(items[:_LISTED])
    more = len(items) - _LISTED
    return f"{shown}, and {more} more" if more > 0 else shown


def one_line(err: BaseException) -> str:
    """An exception's text on one line (its type's name if it has none)."""
    text = " ".join(str(err).split())
    return text or type(err).__name__


def _bag_location(path: Path, src: str) -> Path:
    """The path to give rosbags: a ``.bag`` file, a ROS 2 folder or a storage file."""
    if not path.exists():
        raise InputError("no such bag: the file or folder does not exist", source=src)
    if path.is_dir():
        if (path / "metadata.yaml").is_file():
            return path
        raise InputError("not a bag: a ROS 2 bag folder needs a metadata.yaml", source=src)
    if path.suffix == ".bag":
        return path
    if path.suffix in (".db3", ".mcap"):
        return path.parent if (path.parent / "metadata.yaml").is_file() else path
    if path.name == "metadata.yaml":
        return path.parent
    try:
        with path.open("rb") as file:
            magic = file.read(13)
    except OSError as err:
        raise InputError(f"cannot read the bag: {one_line(err)}", source=src) from None
    if magic.startswith(b"#ROSBAG"):
        raise InputError(
            "this looks like a ROS 1 bag, but it must be named *.bag to be read", source=src
        )
    raise InputError(
        "not a bag: expected a ROS 1 .bag file, a ROS 2 bag folder, or its .db3/.mcap file",
        source=src,
    )


def missing_rosbags(src: str, doing: str = "reading") -> InputError:
    """The one line for a bag without rosbags installed (``doing``: reading or writing).

    umbmark is installed from its checkout, not from an index, so the line names the
    index's package (as umbmark's ``ros`` extra requires it) and the extra for a checkout.
    """
    return InputError(
        f"{doing} bags needs rosbags, which is not installed: python -m pip install "
        f"'{rosbags_requirement()}' (or, in umbmark's checkout, python -m pip install '.[ros]')",
        source=src,
    )


def rosbags_requirement() -> str:
    """rosbags as umbmark's ``ros`` extra requires it (``rosbags>=0.11``), from the
    installed package's metadata (pyproject.toml says it once); ``rosbags`` without it."""
    from importlib.metadata import PackageNotFoundError, requires

    try:
        required = requires("umbmark") or []
    except PackageNotFoundError:  # pragma: no cover - a source tree on the path
        required = []
    for line in required:
        name, _, marker = line.partition(";")
        if name.strip().startswith("rosbags") and "ros" in marker:
            return name.strip().replace(" ", "")
    return "rosbags"


#: Topics published once and latched: read whole even through a window.
LATCHED = ("/tf_static", "/robot_description")


class _Windowed:
    """An open reader whose messages are those of one time window: what a reader of the
    whole bag gets, cut to the window, so that every reader in the package reads one
    window of a long recording unchanged. Latched topics (:data:`LATCHED`: published once,
    at the start) are read whole."""

    def __init__(self, reader: AnyReader, window: tuple[int, int]) -> None:
        self._reader = reader
        self._window = window

    def __getattr__(self, name: str) -> Any:  # noqa: ANN401 (the reader's own attributes)
        return getattr(self._reader, name)

    def messages(
        self,
        connections: Sequence[Connection] = (),
        start: int | None = None,
        stop: int | None = None,
    ) -> Iterator[tuple[Connection, int, bytes]]:
        if connections and all(c.topic in LATCHED for c in connections):
            return self._reader.messages(connections=connections, start=start, stop=stop)
        first, end = self._window
        start = first if start is None else max(start, first)
        stop = end if stop is None else min(stop, end)
        return self._reader.messages(connections=connections, start=start, stop=stop)


@contextmanager
def open_bag(path: Path, src: str, window: tuple[int, int] | None = None) -> Iterator[AnyReader]:
    """An open ``AnyReader``; every failure to open becomes an :class:`InputError`.

    Parameters
    ----------
    path : Path
        A ROS 1 ``.bag`` file, a ROS 2 bag folder, or its ``.db3``/``.mcap`` file or
        ``metadata.yaml``.
    src : str
        The path as the user gave it, for error messages.
    window : (int, int), optional
        Bag times [ns], from and before: its messages are only those of this window
        (:data:`LATCHED` topics whole), so that a long recording is read one window at a
        time with every reader unchanged.
    """
    location = _bag_location(path, src)
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise missing_rosbags(src) from None
    try:
        reader = AnyReader([location], default_typestore=get_typestore(Stores.LATEST))
        reader.open()
    except Exception as err:  # rosbags, sqlite, mcap, yaml, decompression: all bad input
        problem = f"cannot read the bag: {one_line(err)}"
        if isinstance(err, AssertionError):  # rosbags' checks of a ROS 1 bag's records
            problem += ": its records' counts or lengths are inconsistent, a damaged index"
        if location.suffix == ".bag" and "index" in problem.lower():
            problem += " (a recording that was cut short needs `rosbag reindex` first)"
        raise InputError(problem, source=src) from None
    try:
        yield windowed(reader, window)
    finally:
        reader.close()


def time_windows(path: Path, src: str, seconds: float) -> list[tuple[int, int] | None]:
    """The bag's time cut into windows of ``seconds`` (:func:`reader_windows`), the bag
    opened for it.

    Raises
    ------
    ValueError
        ``seconds`` is not a positive time.
    InputError
        The bag cannot be opened.
    """
    if not seconds > 0.0:
        raise ValueError("a window must be a positive time")
    with open_bag(path, src) as reader:
        return reader_windows(reader, seconds)


def reader_windows(reader: AnyReader, seconds: float) -> list[tuple[int, int] | None]:
    """The open bag's time cut into windows of ``seconds`` [ns, from and before], the
    windows every reader of a long recording reads one at a time (:func:`open_bag`,
    :func:`windowed`): one, None, for a bag no longer than that.

    Raises
    ------
    ValueError
        ``seconds`` is not a positive time.
    """
    if not seconds > 0.0:
        raise ValueError("a window must be a positive time")
    first, last = int(reader.start_time), int(reader.end_time)
    step = int(seconds * 1e9)
    if last - first <= step:
        return [None]
    return [(a, min(a + step, last + 1)) for a in range(first, last + 1, step)]


def windowed(reader: AnyReader, window: tuple[int, int] | None) -> AnyReader:
    """The open bag as a reader of the messages of ``window`` only (bag times [ns], from
    and before; :data:`LATCHED` topics whole), as :func:`open_bag` gives it: several
    windows of one bag read without opening it again (opening a long bag reads its index:
    0.3 s for half an hour of 200 Hz). None: the whole bag."""
    return reader if window is None else cast("AnyReader", _Windowed(reader, window))


def topic_types(reader: AnyReader) -> dict[str, str]:
    """Topic name to message type, sorted by topic; several types joined by ``", "``."""
    out: dict[str, str] = {}
    for topic, info in sorted(reader.topics.items()):
        if info.msgtype is not None:
            out[topic] = info.msgtype
        else:
            out[topic] = ", ".join(sorted({c.msgtype for c in info.connections}))
    return out


def missing_topic(topic: str, what: str, topics: Mapping[str, str], src: str) -> InputError:
    """The error for ``topic`` (``what`` it is for) not in the bag at ``src``, listing the
    ``topics`` present (name to message type)."""
    present = [f"{name} ({typ})" for name, typ in topics.items()]
    listed = f"topics present: {listing(present)}" if present else "the bag has no topics"
    return InputError(f"no topic {topic} ({what}) in the bag; {listed}", source=src)


def topic_connections(
    reader: AnyReader,
    topics: dict[str, str],
    topic: str,
    allowed: Sequence[str],
    what: str,
    src: str,
) -> tuple[list[Connection], str]:
    """The connections of ``topic`` and its message type, checked against ``allowed``.

    Parameters
    ----------
    reader : AnyReader
        The open bag.
    topics : dict
        Its :func:`topic_types`.
    topic : str
        The topic wanted.
    allowed : sequence of str
        The message types it may have.
    what : str
        What the topic is for (``"wheel joint states"``), for error messages.
    src : str
        The bag's path, for error messages.

    Raises
    ------
    InputError
        The topic is not in the bag (the message lists the topics present), or has a
        type not in ``allowed``.
    """
    if topic not in topics:
        raise missing_topic(topic, what, topics, src)
    msgtype = topics[topic]
    if msgtype not in allowed:
        raise InputError(
            f"topic {topic} has messages of type {msgtype}; {what} must be " + " or ".join(allowed),
            source=src,
        )
    return [c for c in reader.connections if c.topic == topic], msgtype


def message_count(conns: Sequence[Connection]) -> int:
    """How many messages ``conns`` hold, as the bag's index or metadata says."""
    return sum(int(getattr(conn, "msgcount", 0) or 0) for conn in conns)


def messages(
    reader: AnyReader,
    conns: Sequence[Connection],
    topic: str,
    src: str,
    window: tuple[int, int] | None = None,
) -> Iterator[tuple[int, bytes]]:
    """``(bag time [ns], raw message)`` of ``conns`` (within ``window``, bag times [ns] from
    and before, if given); read errors become InputError.

    Inside a read that reports progress (:func:`umbmark.sources.progress.tracking`), the
    messages yielded are counted and reported every
    :data:`~umbmark.sources.progress.REPORT_EVERY` messages.
    """
    tracker = current_tracker()
    start, stop = (None, None) if window is None else window
    if tracker is None:
        yield from raw_messages(reader, conns, topic, src, start, stop)
        return
    tracker.begin(topic, message_count(conns))
    every = max(1, tracker.every)
    pending = 0
    try:
        for item in raw_messages(reader, conns, topic, src, start, stop):
            yield item
            pending += 1
            if pending == every:
                tracker.advance(pending)
                pending = 0
    finally:
        if pending:
            tracker.advance(pending)


def raw_messages(
    reader: AnyReader,
    conns: Sequence[Connection],
    topic: str,
    src: str,
    start: int | None = None,
    stop: int | None = None,
) -> Generator[tuple[int, bytes], None, None]:
    """``(bag time [ns], raw message)`` of ``conns`` (from ``start`` [ns] on and before
    ``stop``, if given), uncounted; read errors become InputError. The stream is closed
    when left early (and the generator's ``close()`` closes it at once)."""
    stream = reader.messages(connections=conns, start=start, stop=stop)
    try:
        while True:
            try:
                _, timestamp, raw = next(stream)
            except StopIteration:
                return
            except Exception as err:  # corrupt storage, truncated chunk, bad compression
                raise InputError(
                    f"cannot read the messages of {topic}: {one_line(err)}", source=src
                ) from None
            yield timestamp, raw
    finally:
        close = getattr(stream, "close", None)
        if close is not None:
            close()


def deserialize(reader: AnyReader, raw: bytes, msgtype: str, topic: str, src: str) -> object:
    """The message ``raw`` of ``topic`` deserialized by rosbags; failures become InputError."""
    try:
        return reader.deserialize(raw, msgtype)
    except Exception as err:  # malformed message bytes
        raise InputError(
            f"a message of {topic} cannot be decoded: {one_line(err)}", source=src
        ) from None
