"""A fleet's recordings: found in folders, globs and lists, each with its robot and day.

- **Found**: a source is a recording (a ROS 1 bag, a ROS 2 bag folder or its ``.db3`` /
  ``.mcap``, an MCAP file, an umbmark run log, an OptiOdom session), a folder searched
  for recordings (a folder that is a recording is not searched further), or a glob
  (``fleet/*/2026-11-*``). The search is bounded: :data:`MAX_DEPTH` folders deep,
  :data:`MAX_RECORDINGS` recordings.
  A source may be a URL (``https://``, ``s3://``, ``gs://``, ``file://``, anything fsspec
  knows) to a recording, a folder or a glob, found the same way through
  :mod:`umbmark.sources.remote` (a folder only where its filesystem lists: an HTTP server
  only with index pages).
- **Named**: ``robot_from``, a pattern of the recording's path (``{robot}/{date}/*.mcap``:
  ``{robot}`` and ``{date}`` stand for one path component each, or part of one, ``*`` for
  any part of one component, ``**`` for any components), gives the robot and the day;
  it is matched against the path relative to the folder searched, else against the end
  of the path (of a URL, its path: :func:`~umbmark.sources.remote.url_path`). ``{date}``
  takes ``YYYY-MM-DD`` or ``YYYYMMDD``. Without a pattern, or where it names no robot, the
  robot is None here and comes from the recording itself (its namespace or robot
  description) when it is read, or, where it cannot be read, from its path
  (:mod:`umbmark.fleets.naming`).
"""

from __future__ import annotations

import datetime as dt
import glob
import os
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from umbmark.core.errors import InputError, option
from umbmark.fleets.outcome import LOGGED

__all__ = [
    "MAX_DEPTH",
    "MAX_RECORDINGS",
    "FleetRecording",
    "find_recordings",
    "match_path",
    "path_pattern",
]

#: Deepest folder searched below a source.
MAX_DEPTH = 12
#: Most recordings one fleet run takes.
MAX_RECORDINGS = 100_000
#: Longest pattern.
MAX_PATTERN = 500
#: Files that are recordings by their name.
_RECORDING_SUFFIXES = (".bag", ".mcap")


@dataclass(frozen=True)
class FleetRecording:
    """One recording of the fleet.

    Attributes
    ----------
    path : str
        The recording (a file or a ROS 2 bag's / run log's folder), or its URL.
    robot : str or None
        Its robot, from the pattern; None: from the recording when it is read.
    day : datetime.date or None
        Its day, from the pattern's ``{date}``; None: from the recording's own clock.
    matched : bool
        The pattern matched its path (it may still name no robot: a pattern without
        ``{robot}``).
    parts : tuple of str
        Its path's components below the folder searched (all of them for a recording given
        itself): where a robot's name is looked for if it cannot be read
        (:func:`umbmark.fleets.naming.robot_in_path`).
    """

    path: str
    robot: str | None = None
    day: dt.date | None = None
    matched: bool = False
    parts: tuple[str, ...] = ()


def path_pattern(pattern: str) -> re.Pattern[str]:
    """The regular expression of a ``robot_from`` pattern (use ``fullmatch`` on a path
    relative to the folder searched, :func:`match_path` on any path).

    Raises
    ------
    InputError
        For a pattern that is empty, too long, names ``{robot}`` twice, or holds a field
        other than ``{robot}`` and ``{date}``.
    """
    named = option("robot_from", repr(pattern))
    if not pattern.strip() or len(pattern) > MAX_PATTERN:
        raise InputError(f"{named}: give a pattern such as '{{robot}}/{{date}}/*.mcap'")
    fields = re.findall(r"\{([^{}]*)\}", pattern)
    unknown = sorted({f for f in fields if f not in ("robot", "date")})
    if unknown:
        raise InputError(f"{named} holds {{{unknown[0]}}}: it takes {{robot}} and {{date}}")
    if fields.count("robot") > 1 or fields.count("date") > 1:
        raise InputError(f"{named} names a field twice")
    parts = re.split(r"(\{robot\}|\{date\}|\*\*/?|\*)", pattern.strip().replace(os.sep, "/"))
    regex = []
    for part in parts:
        if part == "{robot}":
            regex.append(r"(?P<robot>[^/]+?)")
        elif part == "{date}":
            regex.append(r"(?P<date>\d{4}-?\d{2}-?\d{2})")
        elif part.startswith("**"):
            regex.append(r"(?:.*/)?" if part.endswith("/") else r".*")
        elif part == "*":
            regex.append(r"[^/]*")
        else:
            regex.append(re.escape(part))
    return re.compile("".join(regex) + r"/?$")


def match_path(regex: re.Pattern[str], path: str, base: str | None) -> re.Match[str] | None:
    """The pattern matched against ``path`` relative to ``base`` (the folder searched),
    else against the end of ``path`` (the last components that match, so that
    ``{robot}`` is the robot's folder, not a folder above the fleet)."""
    text = Path(path).as_posix()
    if base is not None:
        try:
            rel = Path(path).relative_to(base).as_posix()
        except ValueError:
            rel = None
        if rel and rel != ".":
            found = regex.fullmatch(rel)
            if found is not None:
                return found
    parts = text.split("/")
    for k in range(len(parts) - 1, -1, -1):  # the shortest end of the path that matches
        found = regex.fullmatch("/".join(parts[k:]))
        if found is not None:
            return found
    return None


def _parts(text: str, base: str) -> tuple[str, ...]:
    """The components of ``text`` below ``base``; all of them where it is not below."""
    try:
        rel = Path(text).relative_to(base).as_posix()
    except ValueError:
        rel = "."
    if rel == ".":
        rel = Path(text).as_posix()
    return tuple(part for part in rel.split("/") if part)


def _base(source: str) -> str:
    """The folder a source is searched from: a glob's folder before its first wildcard."""
    if not any(ch in source for ch in "*?["):
        return source
    head = re.split(r"[*?\[]", source, maxsplit=1)[0]
    return os.path.dirname(head) or "."


def _day(text: str, path: str) -> dt.date:
    digits = text.replace("-", "")
    try:
        return dt.date(int(digits[:4]), int(digits[4:6]), int(digits[6:8]))
    except ValueError:
        raise InputError(f"{text!r} is no date (YYYY-MM-DD)", source=path) from None


def _is_recording(path: Path) -> bool:
    from umbmark.runs.load import detect_format

    if path.is_file():
        return path.suffix.lower() in _RECORDING_SUFFIXES
    if not path.is_dir():
        return False
    try:
        return detect_format(path) in ("bag", *LOGGED)
    except InputError:
        return False


def _walk(root: Path, depth: int) -> Iterator[Path]:
    if _is_recording(root):
        yield root
        return
    if not root.is_dir() or depth >= MAX_DEPTH:
        return
    try:
        children = sorted(root.iterdir(), key=lambda p: p.name)
    except OSError as exc:
        raise InputError(f"cannot be read ({exc.strerror or exc})", source=root) from None
    for child in children:
        if child.is_symlink() and child.is_dir():
            continue  # a link back up would loop
        yield from _walk(child, depth + 1)


def _expand(source: str) -> list[Path]:
    if any(ch in source for ch in "*?["):
        found = sorted(Path(p) for p in glob.glob(source, recursive=True))
        if not found:
            raise InputError("matches no file or folder", source=source)
        return found
    path = Path(source)
    if not path.exists():
        raise InputError("no such file or folder", source=source)
    return [path]


def _found(source: str) -> Iterator[tuple[str, str, str, str]]:
    """Each recording of a source: its path (or URL), the key it is known by once, the path
    the pattern is matched against, and the folder searched."""
    from umbmark.sources.remote import expand, is_url, searched, url_path, walk

    if is_url(source):
        base = searched(source)
        for top in expand(source, MAX_DEPTH):
            for url in walk(top, MAX_DEPTH):
                yield url, url.rstrip("/"), url_path(url), base
        return
    base = _base(source)
    for root in _expand(source):
        for path in _walk(root, 0):
            yield str(path), str(path.resolve()), path.as_posix(), base


def _shown(path: str) -> str:
    """A path as it is shown: a URL redacted (no user, password or signature)."""
    from umbmark.sources.remote import redacted

    return redacted(path)


def find_recordings(
    sources: Sequence[str | os.PathLike[str]], robot_from: str | None = None
) -> list[FleetRecording]:
    """Every recording under ``sources``, with its robot and day where the pattern says.

    Parameters
    ----------
    sources : sequence of path, glob or URL
        Recordings, folders to search, or globs; local or URLs.
    robot_from : str, optional
        A pattern of the recordings' paths naming the robot and the day (see the module).

    Returns
    -------
    list of FleetRecording
        In the order found (sources in order, each folder's entries by name), each once;
        a URL as given, to be read (show it redacted:
        :func:`umbmark.sources.remote.redacted`).

    Raises
    ------
    InputError
        For a source that does not exist or matches nothing, no recording found, more
        than :data:`MAX_RECORDINGS`, a bad pattern, or a URL without fsspec installed or
        whose folder cannot be listed.
    """
    if not sources:
        raise InputError("give the fleet's recordings: folders, globs or files")
    regex = path_pattern(robot_from) if robot_from is not None else None
    seen: set[str] = set()
    found: list[FleetRecording] = []
    for source in sources:
        for path, key, text, base in _found(os.fspath(source)):
            if key in seen:
                continue
            seen.add(key)
            if len(found) >= MAX_RECORDINGS:
                raise InputError(f"more than {MAX_RECORDINGS} recordings",
                                 source=_shown(os.fspath(source)))  # fmt: skip
            robot, day = None, None
            match = match_path(regex, text, base) if regex is not None else None
            if match is not None:
                groups = match.groupdict()
                robot = groups.get("robot")
                if groups.get("date"):
                    day = _day(groups["date"], _shown(path))
            parts = _parts(text, base)
            found.append(FleetRecording(path, robot, day, match is not None, parts))
    if not found:
        names = ", ".join(_shown(os.fspath(s)) for s in sources)
        raise InputError(f"no recording (ROS bag, MCAP, run log) found in {names}")
    return found
