"""Recordings at URLs (``https://``, ``s3://``, ``gs://``, ``file://``, anything fsspec
knows): found, known again and copied through fsspec, at the edge of the package.

This is the one module of umbmark that imports fsspec (and aiohttp, fsspec's HTTP client);
``tests/test_architecture.py`` holds it. Both are optional (``umbmark[remote]``): without
them a URL is one line saying what to install.

- **Found**: :func:`expand` takes a URL to a recording, a folder or a glob (``*``, ``**``,
  ``[...]``; in ``http(s)://`` URLs ``?`` starts the query, elsewhere it is a wildcard),
  :func:`walk` searches a folder for recordings as the local search does: files named
  ``.bag`` or ``.mcap``, and folders holding a ``metadata.yaml`` (a ROS 2 bag's) taken
  whole. Listing needs a filesystem that lists: object stores and ``file://`` do, an HTTP
  server only where it answers a folder's URL with an index page of links (as ``python -m
  http.server`` and nginx's ``autoindex`` do). A URL named as a recording (``.bag``,
  ``.mcap``) is taken without a look: if it cannot be read, it fails as a recording.
- **Known again**: :func:`identity`, the URL redacted, the size and what the filesystem
  says of the version (ETag, last modification, generation, ...): what tells a recording
  seen before without reading its bytes.
- **Copied**: the bag readers read local files only, so :func:`fetched` streams a
  recording (a file, or a ROS 2 bag folder's files) into a private temporary folder in
  chunks of :data:`CHUNK` (never the whole file in memory), taking its SHA-256 on the way,
  bounded by :data:`MAX_BYTES` (checked against the size the filesystem gives before, and
  against the bytes while copying) and by the free space, and deletes the copy whatever
  happens. A ``file://`` URL is read in place. Reading waits at most
  :data:`CONNECT_TIMEOUT` for a connection and :data:`READ_TIMEOUT` for data (fsspec's own
  timeouts where the filesystem has them: HTTP, S3). Anything that goes wrong (404, a
  refused connection, a timeout, a missing backend such as s3fs) is an
  :class:`~umbmark.core.errors.InputError` of one line naming the URL.

Credentials and other settings of a filesystem come from fsspec's own configuration (its
environment variables ``FSSPEC_<PROTOCOL>_<OPTION>``, its config files) and the backend's
(``AWS_PROFILE``, ...), or from the URL itself: a user and password
(``https://user:password@host/...``) or a signed query (``?X-Amz-Signature=...``).

- **Redacted**: :func:`redacted` is the one place a URL's secrets are masked. The URL as
  given is what is read (the worker needs it); everything that is shown or kept (an error
  line, the outcome, the history, the page, the JSON, the command line on the page)
  carries its redacted form: the user and password as ``***@``, and as ``***`` the values
  of the query's secret parameters (the signature, the credential, a token, a key) and of
  those that change each time a URL is signed (its date, its expiry), so that a
  recording signed again tomorrow is known again by the same text (:func:`identity`).
"""

from __future__ import annotations

import hashlib
import json
import posixpath
import re
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path, PurePosixPath
from typing import Any
from urllib.parse import unquote, urlsplit

from umbmark.core.errors import InputError
from umbmark.sources.optiodom import is_session_listing

__all__ = [
    "CHUNK",
    "CONNECT_TIMEOUT",
    "MAX_BYTES",
    "READ_TIMEOUT",
    "REMOTE_MISSING",
    "expand",
    "fetched",
    "has_wildcard",
    "identity",
    "is_url",
    "redacted",
    "searched",
    "url_path",
    "walk",
]

#: Bytes read and written at a time when copying a recording.
CHUNK = 8 << 20
#: Most bytes one recording may have to be copied (64 GiB).
MAX_BYTES = 64 << 30
#: Seconds to wait for a connection.
CONNECT_TIMEOUT = 30.0
#: Seconds to wait for data on an open connection.
READ_TIMEOUT = 120.0
#: Deepest folder copied inside a recording's folder.
FOLDER_DEPTH = 4
#: What to install when fsspec (or its HTTP client) is missing.
REMOTE_MISSING = (
    "a URL is read through fsspec, which is not installed: python -m pip install "
    "'fsspec[http]' (s3:// also needs s3fs, gs:// gcsfs; in umbmark's checkout, "
    "python -m pip install '.[remote]')"
)
#: Files that are recordings by their name.
_RECORDING_SUFFIXES = (".bag", ".mcap")
#: A ROS 2 bag's (or a run log's) folder holds this file.
_FOLDER_MARK = "metadata.yaml"
#: What the filesystems' ``info()`` say of a file's version, in the order taken.
_VERSION_KEYS = (
    "etag", "content-md5", "md5hash", "crc32c", "digest", "checksum", "generation",
    "versionid", "version_id", "last-modified", "lastmodified", "last_modified", "updated",
    "mtime", "modify",
)  # fmt: skip
_SCHEME = re.compile(r"^([A-Za-z][A-Za-z0-9+.-]*)://")
#: A URL inside a text (an error line, a command line): up to a space or a quote.
_URL_IN_TEXT = re.compile(r"[A-Za-z][A-Za-z0-9+.-]*://[^\s'\"<>]+")
#: What masks a secret.
MASK = "***"
#: Query parameters (by their name, any case) whose values are masked: secrets (a
#: signature, a key, a token, a password) and the parts of a signed URL that change each
#: time it is signed (S3's and CloudFront's, Google Cloud Storage's V2, generic ones).
_SECRET_NAMES = frozenset({
    "sig", "signature", "token", "access_token", "id_token", "refresh_token", "auth",
    "authorization", "password", "passwd", "pwd", "pass", "secret", "client_secret", "key",
    "apikey", "api_key", "access_key", "accesskey", "credential", "credentials", "session",
    "sessiontoken", "code", "policy", "expires", "googleaccessid", "awsaccesskeyid",
    "key-pair-id",
})  # fmt: skip
#: Query parameters whose names hold one of these are masked too.
_SECRET_PARTS = ("signature", "token", "secret", "password", "credential")
#: Prefixes of signing parameters, all masked (AWS Signature V4, Google's V4).
_SIGNING_PREFIXES = ("x-amz-", "x-goog-")
#: An Azure shared access signature's parameters that change each time it is signed (its
#: start, expiry and signing key's), masked where the query has its ``sig``.
_AZURE_SIGNED = frozenset({
    "se", "st", "skoid", "sktid", "skt", "ske", "sks", "skv", "saoid", "suoid", "scid",
    "sduoid",
})  # fmt: skip


def is_url(text: str) -> bool:
    """Whether ``text`` is a URL (``scheme://...``) rather than a local path."""
    return _SCHEME.match(text) is not None


def redacted(text: str) -> str:
    """``text`` (a URL, or any text holding URLs: an error line, a command line) with every
    URL's credentials masked: its user and password (``https://***@host/...``) and the
    values of its query's secret and signing parameters (``?X-Amz-Signature=***``,
    ``sig=***``, ``token=***``: the module says which). Anything else is kept as written;
    a text without a URL (a local path) is itself.

    The one function that masks a URL's secrets: what is read is the URL as given, what is
    shown or kept is this."""
    if "://" not in text:
        return text
    return _URL_IN_TEXT.sub(lambda found: _redacted_url(found[0]), text)


def _redacted_url(url: str) -> str:
    scheme, rest = url.split("://", 1)
    host = _after_user(rest)
    if host:
        rest = f"{MASK}@{rest[host:]}"
    before, hash_, fragment = rest.partition("#")
    path, question, query = before.partition("?")
    if question:
        path += "?" + _redacted_query(query)
    if hash_:
        path += "#" + _redacted_query(fragment)
    return f"{scheme}://{path}"


def _after_user(rest: str) -> int:
    """Where the host starts in a URL after its ``scheme://``: after the last "@" before
    the path (a password holding "?" or "#" unescaped counts as one, where a parser would
    have taken it for the host); 0 without a user."""
    slash = rest.find("/")
    authority = rest if slash < 0 else rest[:slash]
    return authority.rindex("@") + 1 if "@" in authority else 0


def _redacted_query(query: str) -> str:
    """A query (or a fragment) with the values of its secret and signing parameters
    masked; its other parts as written."""
    parts = query.split("&")
    names = [unquote(p.partition("=")[0]).lower() for p in parts]
    azure = "sig" in names
    out = []
    for part, name in zip(parts, names, strict=True):
        key, equals, _ = part.partition("=")
        secret = (
            name in _SECRET_NAMES
            or name.startswith(_SIGNING_PREFIXES)
            or any(word in name for word in _SECRET_PARTS)
            or (azure and name in _AZURE_SIGNED)
        )
        out.append(f"{key}={MASK}" if equals and secret else part)
    return "&".join(out)


def _scheme(url: str) -> str:
    found = _SCHEME.match(url)
    return "" if found is None else found[1].lower()


def _http(url: str) -> bool:
    return _scheme(url) in ("http", "https")


def has_wildcard(url: str) -> bool:
    """Whether a URL is a glob: ``*`` or ``[`` in its path, or ``?`` outside HTTP (where
    it starts the query)."""
    if _http(url):
        path = urlsplit(url).path
        return "*" in path or "[" in path
    return any(ch in url.split("://", 1)[1] for ch in "*?[")


def url_path(url: str) -> str:
    """The path of a URL, as ``robot_from`` patterns are matched against it: the URL's path
    for HTTP (``/fleet/amr1/2026-11-02/drive.mcap``), else everything after ``scheme://``
    (``s3://bucket/amr1/...``: ``/bucket/amr1/...``; ``file:///data/x``: ``/data/x``); never
    its user or password."""
    if _http(url):
        return unquote(urlsplit(url).path) or "/"
    rest = url.split("://", 1)[1]
    return "/" + unquote(rest[_after_user(rest) :]).lstrip("/")


def searched(url: str) -> str:
    """The path (:func:`url_path`) of the folder a URL is searched from: a glob's folder
    before its first wildcard, else the URL's own."""
    if not has_wildcard(url):
        return url_path(url)
    scheme, rest = url.split("://", 1)
    head = re.split(r"[*\[]" if _http(url) else r"[*?\[]", rest, maxsplit=1)[0]
    return url_path(f"{scheme}://{posixpath.dirname(head)}")


def _name(path: str) -> str:
    return unquote(path.rstrip("/").rsplit("/", 1)[-1].split("?", 1)[0])


def _is_recording_name(path: str) -> bool:
    return _name(path).lower().endswith(_RECORDING_SUFFIXES)


def _why(exc: BaseException) -> str:
    """What went wrong, in a few words: an HTTP status, a timeout, else the outermost
    message that says more than the path."""
    chain: list[BaseException] = []
    seen: BaseException | None = exc
    while seen is not None and len(chain) < 12:
        chain.append(seen)
        seen = seen.__cause__ or seen.__context__
    for e in chain:
        status = getattr(e, "status", None)
        if isinstance(status, int) and status >= 400:
            said = str(getattr(e, "message", "") or "").strip()
            return f"HTTP {status}" + (f" {said}" if said else "")
    for e in chain:
        if isinstance(e, TimeoutError) or "timeout" in type(e).__name__.lower():
            return f"timed out ({e})" if str(e).strip() else "timed out"
    for e in chain:
        text = redacted(" ".join(str(e).split()))  # masked before it is cut short
        if not text or (isinstance(e, FileNotFoundError) and " " not in text):
            continue  # fsspec's FileNotFoundError(path): the path alone says nothing
        return text if len(text) < 300 else text[:297] + "..."
    if any(isinstance(e, FileNotFoundError) for e in chain):
        return "not found"
    return type(exc).__name__


def _refused(url: str, exc: BaseException) -> InputError:
    """The one line of a URL that cannot be read, its credentials masked (in the URL, and
    in any URL the reason repeats)."""
    return InputError(redacted(f"cannot be read ({_why(exc)})"), source=redacted(url))


def _options(url: str, read_timeout: float) -> dict[str, Any]:
    """fsspec's own timeouts for the filesystems that take them, under what fsspec's
    configuration gives the same option (the user's settings win)."""
    from fsspec.config import conf

    scheme = _scheme(url)
    ours: dict[str, Any]
    if scheme in ("http", "https"):
        import aiohttp

        timeout = aiohttp.ClientTimeout(
            total=None, sock_connect=CONNECT_TIMEOUT, sock_read=read_timeout
        )
        key, ours = "client_kwargs", {"timeout": timeout}
    elif scheme in ("s3", "s3a"):
        key = "config_kwargs"
        ours = {"connect_timeout": CONNECT_TIMEOUT, "read_timeout": read_timeout}
    else:
        return {}
    configured = dict(conf.get(scheme) or {}).get(key)
    return {key: {**ours, **(configured if isinstance(configured, dict) else {})}}


def _filesystem(url: str, read_timeout: float = READ_TIMEOUT) -> tuple[Any, str]:
    """The filesystem of a URL and the path on it.

    Raises
    ------
    InputError
        fsspec (or the filesystem's backend) is not installed, or the URL is not one.
    """
    try:
        from fsspec.core import url_to_fs

        fs, path = url_to_fs(url, **_options(url, read_timeout))
        return fs, str(path)
    except ImportError as exc:
        if (exc.name or "").split(".")[0] in ("fsspec", "aiohttp"):
            raise InputError(REMOTE_MISSING, source=redacted(url)) from None
        raise _refused(url, exc) from None
    except Exception as exc:  # an unknown protocol, a bad option: fsspec's own errors
        raise _refused(url, exc) from None


def _local(fs: Any) -> bool:  # noqa: ANN401 (an fsspec filesystem)
    return "file" in (fs.protocol if isinstance(fs.protocol, tuple) else (fs.protocol,))


def expand(source: str, max_depth: int) -> list[str]:
    """The URLs a source stands for: a glob's matches (at most ``max_depth`` deep), else
    the URL itself (looked at, unless its name is a recording's).

    Raises
    ------
    InputError
        For a glob that matches nothing, a URL that does not exist or cannot be read.
    """
    fs, path = _filesystem(source)
    if has_wildcard(source):
        try:
            found = sorted(fs.glob(path, maxdepth=max_depth))
        except Exception as exc:
            raise _refused(source, exc) from None
        if not found:
            raise InputError("matches no file or folder", source=redacted(source))
        return [fs.unstrip_protocol(p) for p in found]
    if _is_recording_name(source):
        return [source]  # read by the worker: if it cannot be, it fails as a recording
    try:
        fs.info(path)
    except Exception as exc:
        raise _refused(source, exc) from None
    return [source]


def walk(url: str, max_depth: int) -> Iterator[str]:
    """The recordings at or under ``url``: a file named ``.bag`` / ``.mcap``, or a folder
    holding ``metadata.yaml`` (a ROS 2 bag, a run log) or an OptiOdom session's files
    (taken whole), each folder's entries by name, at most ``max_depth`` folders deep.

    Raises
    ------
    InputError
        For a folder that cannot be listed.
    """
    fs, path = _filesystem(url)
    yield from _walk(fs, path, 0, None, max_depth)


def _walk(fs: Any, path: str, depth: int, folder: bool | None, deepest: int) -> Iterator[str]:  # noqa: ANN401
    if not folder and _is_recording_name(path):
        yield fs.unstrip_protocol(path)
        return
    try:
        if folder is None:
            folder = bool(fs.isdir(path))
        if not folder:
            return
        entries = [e for e in fs.ls(path, detail=True) if e["name"].rstrip("/") != path.rstrip("/")]
    except Exception as exc:
        raise _refused(fs.unstrip_protocol(path), exc) from None
    entries.sort(key=lambda e: _name(e["name"]))
    names = [_name(e["name"]) for e in entries if e.get("type") != "directory"]
    if _FOLDER_MARK in names or is_session_listing(names):
        yield fs.unstrip_protocol(path)  # a ROS 2 bag's, run log's or session's folder
        return
    if depth >= deepest:
        return
    for entry in entries:
        folder = entry.get("type") == "directory"
        if folder and entry.get("islink"):
            continue  # a link back up would loop (the local search skips them too)
        yield from _walk(fs, entry["name"], depth + 1, folder, deepest)


def _files(fs: Any, path: str) -> list[tuple[str, PurePosixPath | None, dict[str, Any]]]:  # noqa: ANN401
    """A recording's files: ``(path, name inside the folder or None, info)``, a folder's
    in the order :func:`umbmark.core.digest.path_sha256` reads them."""
    if _is_recording_name(path) or not fs.isdir(path):
        return [(path, None, fs.info(path))]
    root = path.rstrip("/")
    found = fs.find(path, maxdepth=FOLDER_DEPTH, detail=True)
    files = []
    for name, info in found.items():
        if info.get("type") == "directory" or name.endswith("/"):
            continue
        rel = PurePosixPath(unquote(name[len(root) :].lstrip("/")))
        if not name.startswith(root + "/") or any(p in ("", ".", "..") for p in rel.parts):
            continue  # a link out of the folder
        files.append((name, rel, info if info.get("size") is not None else fs.info(name)))
    return sorted(files, key=lambda f: f[1].parts if f[1] is not None else ())


def identity(url: str) -> str:
    """The URL redacted (:func:`redacted`), its size and what its filesystem says of its
    version (ETag, last modification, generation, ...; a folder's: of its files) as one
    text: what tells a recording seen before without reading its bytes. It holds no
    secret, and a URL signed again (another signature, date and expiry) gives the same.

    Raises
    ------
    InputError
        For a URL that cannot be read.
    """
    fs, path = _filesystem(url)
    try:
        files = _files(fs, path)
    except Exception as exc:
        raise _refused(url, exc) from None
    size, facts = 0, []
    for _, rel, info in files:
        size += int(info.get("size") or 0)
        keys = {str(k).lower(): v for k, v in info.items()}
        said = {k: str(keys[k]) for k in _VERSION_KEYS if k in keys}
        if not said and "created" in keys:
            said = {"created": str(keys["created"])}
        facts.append([str(rel or ""), said])
    version = hashlib.sha256(json.dumps(facts, sort_keys=True).encode()).hexdigest()[:16]
    return f"{redacted(url)}|{size}|{version}"


@contextmanager
def fetched(
    url: str,
    *,
    limit: int = MAX_BYTES,
    folder: str | Path | None = None,
    read_timeout: float = READ_TIMEOUT,
) -> Iterator[tuple[Path, str | None]]:
    """The recording at ``url`` as a local path for as long as the ``with`` lasts: a copy
    in a private temporary folder (in ``folder``, default the system's), deleted whatever
    happens, and its SHA-256 taken while copying; a ``file://`` URL is its own path (its
    digest None: not read here). ``read_timeout``: seconds to wait for data.

    Raises
    ------
    InputError
        For a URL that cannot be read, a recording over ``limit`` bytes, or one larger
        than the free space.
    """
    fs, path = _filesystem(url, read_timeout)
    if _local(fs):
        yield Path(path), None
        return
    try:
        files = _files(fs, path)
    except Exception as exc:
        raise _refused(url, exc) from None
    known = sum(int(info.get("size") or 0) for _, _, info in files)
    if known > limit:
        raise InputError(
            f"is {_size(known)}, more than the {_size(limit)} a recording may have to be copied",
            source=redacted(url),
        )
    with tempfile.TemporaryDirectory(prefix="umbmark-remote-", dir=folder) as scratch:
        free = shutil.disk_usage(scratch).free
        if known > free:
            raise InputError(
                f"is {_size(known)}; the temporary folder {scratch} has {_size(free)} free",
                source=redacted(url),
            )
        local = Path(scratch) / (_name(path) or "recording")
        digest = _copy(fs, url, files, local, limit)
        yield local, digest


def _size(n: int) -> str:
    if n >= 1 << 30:
        return f"{n / (1 << 30):.1f} GiB"
    return f"{n / (1 << 20):.1f} MiB" if n >= 1 << 20 else f"{n} bytes"


def _copy(
    fs: Any,  # noqa: ANN401 (an fsspec filesystem)
    url: str,
    files: list[tuple[str, PurePosixPath | None, dict[str, Any]]],
    local: Path,
    limit: int,
) -> str:
    """Stream ``files`` into ``local`` (a file, or a folder of them), chunk by chunk, and
    return their SHA-256 as :func:`umbmark.core.digest.path_sha256` takes it."""
    digest = hashlib.sha256()
    copied = 0
    for remote, rel, _ in files:
        target = local if rel is None else local.joinpath(*rel.parts)
        target.parent.mkdir(parents=True, exist_ok=True)
        if rel is not None:
            digest.update(rel.as_posix().encode() + b"\0")
        try:
            # block_size 0: HTTP as one streamed GET, no range requests the server may refuse
            options = {"block_size": 0} if _http(url) else {"block_size": CHUNK}
            with fs.open(remote, "rb", **options) as source, target.open("wb") as out:
                while True:
                    chunk = source.read(CHUNK)
                    if not chunk:
                        break
                    copied += len(chunk)
                    if copied > limit:
                        raise InputError(
                            f"is more than the {_size(limit)} a recording may have to be copied",
                            source=redacted(url),
                        )
                    digest.update(chunk)
                    out.write(chunk)
                    del chunk  # not held while the next one is read
        except InputError:
            raise
        except Exception as exc:
            raise _refused(url, exc) from None
    return digest.hexdigest()
