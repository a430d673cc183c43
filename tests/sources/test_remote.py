"""Recordings at URLs through fsspec, against real servers (``python -m http.server`` and a
server that keeps the size to itself, started as processes), ``file://`` and ``memory://``:
folders listed as the local search lists them, globs, each copy streamed chunk by chunk
into a private folder with the digest the local file has, bounded in size and deleted
whatever happens, every read error one line naming the URL, and the identity that tells a
recording seen before; a URL's credentials masked (``redacted``), on URLs written by hand
(a user and password, signed queries as S3, Google Cloud Storage, CloudFront and Azure
sign them, tokens), each expected form written out, and the identity of a URL signed
again."""

from __future__ import annotations

import hashlib
import os
import socket
import subprocess
import sys
import time
import tracemalloc
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("fsspec", reason="the remote extra: pip install '.[remote]'")
pytest.importorskip("aiohttp", reason="the remote extra: pip install '.[remote]'")

from umbmark.core.digest import path_sha256
from umbmark.core.errors import InputError
from umbmark.sources.remote import (
    CHUNK,
    REMOTE_MISSING,
    expand,
    fetched,
    has_wildcard,
    identity,
    is_url,
    redacted,
    searched,
    url_path,
    walk,
)

from helpers import ROOT
from http_served import WITHOUT_FSSPEC, Served, Unsized, free_port

#: The recordings of the tree below, by their path under ``fleet/``.
RECORDINGS = ["amr1/2026-11-01/a.mcap", "amr1/2026-11-02/b.bag", "amr2/20261102/session"]


@pytest.fixture(scope="module")
def tree(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("remote")
    fleet = root / "fleet"
    for rel, data in (("amr1/2026-11-01/a.mcap", os.urandom(3000)),
                      ("amr1/2026-11-02/b.bag", os.urandom(5000)),
                      ("amr1/notes.txt", b"not a recording\n"),
                      ("amr2/20261102/session/metadata.yaml",
                       b"rosbag2_bagfile_information:\n  version: 5\n"),
                      ("amr2/20261102/session/session_0.db3", os.urandom(7000)),
                      ("deep/1/2/3/x.mcap", b"x")):  # fmt: skip
        (fleet / rel).parent.mkdir(parents=True, exist_ok=True)
        (fleet / rel).write_bytes(data)
    (root / "big.mcap").write_bytes(os.urandom(8 * CHUNK))
    (root / "changing.mcap").write_bytes(os.urandom(3000))
    return root


@pytest.fixture(scope="module")
def served(tree: Path, tmp_path_factory) -> Iterator[str]:
    with Served(tree, tmp_path_factory.mktemp("log") / "http.log") as server:
        yield server.url


def _left(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("umbmark-remote-"))


def test_urls_are_told_from_paths_and_globs():
    assert [is_url(t) for t in ("s3://b/k", "https://h/x", "file:///d", "/d/x", "C:\\d", "a:b")] \
        == [True, True, True, False, False, False]  # fmt: skip
    # In HTTP a '?' starts the query; elsewhere it is a wildcard.
    assert [has_wildcard(u) for u in ("https://h/x.mcap?sig=1", "https://h/*/x", "s3://b/day?",
                                      "gs://b/[ab]/x", "s3://b/k")] \
        == [False, True, True, True, False]  # fmt: skip
    assert url_path("https://h:8/fleet/amr%201/x.mcap?sig=1") == "/fleet/amr 1/x.mcap"
    assert url_path("s3://bucket/amr1/x.mcap") == "/bucket/amr1/x.mcap"
    assert url_path("file:///data/x") == "/data/x"
    assert searched("https://h/fleet/*/2026-*/x.mcap?sig=1") == "/fleet"
    assert searched("s3://bucket/fleet/**/*.mcap") == "/bucket/fleet"
    assert searched("https://h/fleet/") == "/fleet/"


def test_a_served_folder_is_listed_as_the_local_search_lists_it(served: str, tree: Path):
    """An index page of links is a folder; a ROS 2 bag's folder is one recording; the
    search stops ``max_depth`` folders deep, as the local one does."""
    found = list(walk(f"{served}/fleet/", 12))
    assert [u.removeprefix(f"{served}/fleet/").rstrip("/") for u in found] == [
        *RECORDINGS,
        "deep/1/2/3/x.mcap",
    ]
    assert "deep/1/2/3/x.mcap" not in [
        u.rsplit("fleet/", 1)[1] for u in walk(f"{served}/fleet/", 3)
    ]
    on_disk = list(walk(f"file://{tree}/fleet", 12))
    assert [u.removeprefix(f"file://{tree}/fleet/") for u in on_disk] == [
        *RECORDINGS,
        "deep/1/2/3/x.mcap",
    ]


def test_globs_and_single_recordings(served: str):
    matched = expand(f"{served}/fleet/amr*/2026*", 12)
    assert [u.removeprefix(f"{served}/fleet/").rstrip("/") for u in matched] == [
        "amr1/2026-11-01",
        "amr1/2026-11-02",
        "amr2/20261102",
    ]
    with pytest.raises(InputError, match="matches no file or folder"):
        expand(f"{served}/fleet/*/1999-*", 12)
    # A recording's URL is taken without a look (it fails as a recording if it cannot be
    # read); a folder's is looked at.
    assert expand(f"{served}/fleet/gone.mcap", 12) == [f"{served}/fleet/gone.mcap"]
    with pytest.raises(InputError, match="HTTP 404") as raised:
        expand(f"{served}/nothing/", 12)
    assert str(raised.value).startswith(f"{served}/nothing/: cannot be read")


def test_a_copy_is_streamed_chunk_by_chunk_and_deleted(served: str, tree: Path, tmp_path: Path):
    """Eight chunks copied while no more than four are held in memory (fsspec's HTTP stream
    and the copy's); the digest taken on the way is the file's; the copy is gone after, and
    after an error in the body too."""
    data = (tree / "big.mcap").read_bytes()
    tracemalloc.start()
    try:
        with fetched(f"{served}/big.mcap", folder=tmp_path) as (local, digest):
            _, peak = tracemalloc.get_traced_memory()
            assert local.read_bytes() == data
            assert local.name == "big.mcap"
            assert local.parent.parent == tmp_path
            assert _left(tmp_path) == [local.parent.name]
    finally:
        tracemalloc.stop()
    assert peak < 4 * CHUNK < len(data)
    assert digest == hashlib.sha256(data).hexdigest()
    assert _left(tmp_path) == []
    a_mcap = f"{served}/fleet/amr1/2026-11-01/a.mcap"
    with (  # noqa: PT012
        pytest.raises(RuntimeError, match="the calibration broke"),
        fetched(a_mcap, folder=tmp_path) as (local, _),
    ):
        assert local.exists()
        raise RuntimeError("the calibration broke")
    assert _left(tmp_path) == []


def test_a_bag_folder_is_copied_whole_with_its_local_digest(
    served: str, tree: Path, tmp_path: Path
):
    original = tree / "fleet" / "amr2" / "20261102" / "session"
    with fetched(f"{served}/fleet/amr2/20261102/session/", folder=tmp_path) as (local, digest):
        assert local.name == "session"
        assert sorted(p.name for p in local.iterdir()) == ["metadata.yaml", "session_0.db3"]
        for p in local.iterdir():
            assert p.read_bytes() == (original / p.name).read_bytes()
    assert digest == path_sha256(original)
    assert _left(tmp_path) == []


def test_file_urls_are_read_in_place(tree: Path, tmp_path: Path):
    path = tree / "fleet" / "amr1" / "2026-11-01" / "a.mcap"
    with fetched(f"file://{path}", folder=tmp_path) as (local, digest):
        assert (local, digest) == (path, None)
        assert _left(tmp_path) == []


def test_the_size_is_bounded_before_and_while_copying(served: str, tree: Path, tmp_path: Path):
    url = f"{served}/fleet/amr1/2026-11-02/b.bag"  # 5000 bytes
    too_large = "is 5000 bytes, more than the 4999 bytes a recording may have to be copied"
    with pytest.raises(InputError, match=too_large), fetched(url, limit=4999, folder=tmp_path):
        pass
    with fetched(url, limit=5000, folder=tmp_path) as (local, _):
        assert local.stat().st_size == 5000
    # A server that does not say the size: stopped while copying.
    log = tmp_path / "unsized.log"
    with Unsized(tree / "fleet" / "amr1" / "2026-11-02" / "b.bag", log) as server:
        unsized = f"{server.url}/b.bag"
        with (
            pytest.raises(InputError, match="is more than the 4999 bytes a recording may have"),
            fetched(unsized, limit=4999, folder=tmp_path),
        ):
            pass
        with fetched(f"{server.url}/b.bag", limit=5000, folder=tmp_path) as (local, digest):
            assert digest == path_sha256(tree / "fleet" / "amr1" / "2026-11-02" / "b.bag")
    assert _left(tmp_path) == []


def _one_line(url: str, **kwargs) -> str:  # type: ignore[no-untyped-def]
    with pytest.raises(InputError) as raised, fetched(url, **kwargs):
        pass
    text = str(raised.value)
    assert "\n" not in text
    assert text.startswith(f"{url}: cannot be read (")
    return text


def test_read_errors_are_one_line_naming_the_url(served: str, tmp_path: Path):
    assert "HTTP 404" in _one_line(f"{served}/fleet/gone.mcap", folder=tmp_path)
    closed = free_port()
    assert "Cannot connect to host" in _one_line(f"http://127.0.0.1:{closed}/x.mcap")
    # A server that takes the connection and never answers: fsspec's read timeout.
    with socket.socket() as silent:
        silent.bind(("127.0.0.1", 0))
        silent.listen(8)
        url = f"http://127.0.0.1:{silent.getsockname()[1]}/x.mcap"
        start = time.monotonic()
        assert "timed out" in _one_line(url, read_timeout=0.5, folder=tmp_path)
        assert time.monotonic() - start < 10
    assert _one_line("memory:///umbmark-gone.mcap", folder=tmp_path).endswith("(not found)")
    assert _left(tmp_path) == []


def test_the_identity_follows_size_and_version(served: str, tree: Path, tmp_path: Path):
    """The URL, the size and the server's Last-Modified: the same file gives the same
    identity; rewritten with other bytes of the same size and a new time, another."""
    url = f"{served}/changing.mcap"
    first = identity(url)
    assert first.startswith(f"{url}|3000|")
    assert identity(url) == first
    path = tree / "changing.mcap"
    stat = path.stat()
    path.write_bytes(os.urandom(3000))
    os.utime(path, (stat.st_atime, stat.st_mtime + 60))
    assert identity(url).startswith(f"{url}|3000|")
    assert identity(url) != first
    folder = identity(f"{served}/fleet/amr2/20261102/session/")
    meta = len(b"rosbag2_bagfile_information:\n  version: 5\n")
    assert folder.split("|")[1] == str(7000 + meta)
    on_disk = f"file://{path}"
    assert identity(on_disk).startswith(f"{on_disk}|3000|")
    assert identity(on_disk) != identity(f"file://{tree / 'fleet/amr1/2026-11-02/b.bag'}")
    with pytest.raises(InputError, match="HTTP 404"):
        identity(f"{served}/fleet/gone.mcap")


def test_memory_urls_are_found_known_and_copied(tmp_path: Path):
    import fsspec

    memory = fsspec.filesystem("memory")
    memory.pipe("/umbmark-test/r1/2026-11-01/x.mcap", b"abc" * 1000)
    memory.pipe("/umbmark-test/r1/notes.txt", b"no")
    try:
        found = list(walk("memory://umbmark-test", 12))
        assert found == ["memory:///umbmark-test/r1/2026-11-01/x.mcap"]
        assert identity(found[0]).startswith(f"{found[0]}|3000|")
        with fetched(found[0], folder=tmp_path) as (local, digest):
            assert local.read_bytes() == b"abc" * 1000
        assert digest == hashlib.sha256(b"abc" * 1000).hexdigest()
        assert _left(tmp_path) == []
    finally:
        memory.rm("/umbmark-test", recursive=True)


def test_without_fsspec_a_url_is_one_line_saying_what_to_install():
    """fsspec made unimportable in a Python of its own (an import hook that finds it
    nowhere, as where it is not installed): the URL, and what to install."""
    code = (
        WITHOUT_FSSPEC + "from umbmark.core.errors import InputError\n"
        "from umbmark.sources.remote import expand\n"
        "try:\n    expand('https://example.invalid/fleet/', 12)\n"
        "except InputError as exc:\n    print(exc)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, check=False, timeout=60)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == f"https://example.invalid/fleet/: {REMOTE_MISSING}\n"


def test_a_link_back_up_is_not_followed(tmp_path: Path):
    """A folder linked into itself (``file://``): searched once, as the local search does."""
    (tmp_path / "fleet" / "amr1").mkdir(parents=True)
    (tmp_path / "fleet" / "amr1" / "a.mcap").write_bytes(b"x")
    (tmp_path / "fleet" / "amr1" / "again").symlink_to(tmp_path / "fleet")
    found = list(walk(f"file://{tmp_path}/fleet", 12))
    assert found == [f"file://{tmp_path}/fleet/amr1/a.mcap"]


#: An S3 GET URL presigned with Signature V4 (the shape boto3 gives), on two nights.
S3_NIGHT_1 = (
    "https://fleet-bags.s3.eu-west-1.amazonaws.com/amr1/2026-11-02/drive.mcap"
    "?X-Amz-Algorithm=AWS4-HMAC-SHA256"
    "&X-Amz-Credential=AKIAIOSFODNN7EXAMPLE%2F20261102%2Feu-west-1%2Fs3%2Faws4_request"
    "&X-Amz-Date=20261102T020000Z&X-Amz-Expires=3600&X-Amz-SignedHeaders=host"
    "&X-Amz-Security-Token=IQoJb3JpZ2luX2VjEXAMPLE"
    "&X-Amz-Signature=fe5f80f77d5fa3beca038a248ff027d0445342fe2855ddc963176630326f1024"
)
S3_NIGHT_2 = (
    "https://fleet-bags.s3.eu-west-1.amazonaws.com/amr1/2026-11-02/drive.mcap"
    "?X-Amz-Algorithm=AWS4-HMAC-SHA256"
    "&X-Amz-Credential=AKIAIOSFODNN7EXAMPLE%2F20261103%2Feu-west-1%2Fs3%2Faws4_request"
    "&X-Amz-Date=20261103T020000Z&X-Amz-Expires=7200&X-Amz-SignedHeaders=host"
    "&X-Amz-Security-Token=IQoJb3JpZ2luX2VjOTHER"
    "&X-Amz-Signature=0a1b2c3d4e5f60718293a4b5c6d7e8f90a1b2c3d4e5f60718293a4b5c6d7e8f9"
)
S3_SHOWN = (
    "https://fleet-bags.s3.eu-west-1.amazonaws.com/amr1/2026-11-02/drive.mcap"
    "?X-Amz-Algorithm=***&X-Amz-Credential=***&X-Amz-Date=***&X-Amz-Expires=***"
    "&X-Amz-SignedHeaders=***&X-Amz-Security-Token=***&X-Amz-Signature=***"
)


@pytest.mark.parametrize(
    ("url", "shown"),
    [
        ("http://user:password@host/fleet/a.mcap", "http://***@host/fleet/a.mcap"),
        ("https://reader:s3cr%40t@bags.example.com:8443/fleet/",
         "https://***@bags.example.com:8443/fleet/"),
        ("https://ghp_token123@host/x.bag", "https://***@host/x.bag"),
        # A password with an unescaped "?" or "#": masked up to the last "@" before the path.
        ("https://u:pa?ss#w@host/x.mcap", "https://***@host/x.mcap"),
        ("s3://AKIAEXAMPLE:wJalrXUtnFEMI@fleet-bags/amr1/x.mcap",
         "s3://***@fleet-bags/amr1/x.mcap"),
        (S3_NIGHT_1, S3_SHOWN),
        # Signature V2 (S3), and Google Cloud Storage's V2: the key id, expiry, signature.
        ("https://b.s3.amazonaws.com/x.bag?AWSAccessKeyId=AKIAEX&Expires=1793000000"
         "&Signature=vjbyPxybdZaNmGa%2ByT272YEAiv4%3D",
         "https://b.s3.amazonaws.com/x.bag?AWSAccessKeyId=***&Expires=***&Signature=***"),
        ("https://storage.googleapis.com/b/x.mcap?GoogleAccessId=sa@p.iam.gserviceaccount.com"
         "&Expires=1793000000&Signature=BCl2Zz%2F",
         "https://storage.googleapis.com/b/x.mcap?GoogleAccessId=***&Expires=***"
         "&Signature=***"),
        # Google Cloud Storage V4, lower case as gsutil gives it.
        ("https://storage.googleapis.com/b/x.mcap?x-goog-algorithm=GOOG4-RSA-SHA256"
         "&x-goog-credential=sa%40p.iam.gserviceaccount.com%2F20261102%2Fauto%2Fstorage"
         "%2Fgoog4_request&x-goog-date=20261102T020000Z&x-goog-expires=3600"
         "&x-goog-signedheaders=host&x-goog-signature=7a4b",
         "https://storage.googleapis.com/b/x.mcap?x-goog-algorithm=***&x-goog-credential=***"
         "&x-goog-date=***&x-goog-expires=***&x-goog-signedheaders=***&x-goog-signature=***"),
        # CloudFront: Policy, Signature, Key-Pair-Id.
        ("https://d111111abcdef8.cloudfront.net/x.mcap?Policy=eyJTdGF0ZW1lbnQi"
         "&Signature=Nql641NHEUkUaXQH&Key-Pair-Id=K2JCJMDEHXQW5F",
         "https://d111111abcdef8.cloudfront.net/x.mcap?Policy=***&Signature=***"
         "&Key-Pair-Id=***"),
        # Azure: the signature, and its start and expiry (which change each time it is
        # signed); what it grants (sp, sr, sv, spr) kept.
        ("https://acct.blob.core.windows.net/fleet/x.mcap?sv=2022-11-02&sp=r"
         "&st=2026-11-02T02:00:00Z&se=2026-11-02T08:00:00Z&spr=https&sr=b"
         "&sig=Z%2FRHIX5Xcg0Mq2rqI3OlWTjEg2tYkboXr1P9ZUXDtkk%3D",
         "https://acct.blob.core.windows.net/fleet/x.mcap?sv=2022-11-02&sp=r&st=***&se=***"
         "&spr=https&sr=b&sig=***"),
        # Generic tokens and keys, in the query or the fragment; other parameters kept.
        ("https://host/x.mcap?versionId=3&token=abc123&part=2",
         "https://host/x.mcap?versionId=3&token=***&part=2"),
        ("https://host/x.mcap?access_token=a&api_key=b&apiKey=c&signature=d&password=e",
         "https://host/x.mcap?access_token=***&api_key=***&apiKey=***&signature=***"
         "&password=***"),
        ("https://host/x.mcap?my-upload-token=q&client_secret=w",
         "https://host/x.mcap?my-upload-token=***&client_secret=***"),
        ("https://host/x.mcap#access_token=zz&x=1", "https://host/x.mcap#access_token=***&x=1"),
    ],
)  # fmt: skip
def test_credentials_are_masked(url: str, shown: str):
    assert redacted(url) == shown


@pytest.mark.parametrize(
    "text",
    [
        "https://host/fleet/amr1/2026-11-02/drive.mcap",
        "https://host/x.mcap?versionId=7&sp=r&st=2026",  # Azure's st only with its sig
        "https://host/fleet/?page=2",
        "s3://bucket/amr?/2026-11-0[12]/*.mcap",  # a glob's "?" and "[", no parameter
        "https://host/x.mcap?X-Amz-Signature",  # a name alone: no value to mask
        "file:///data/fleet/a.mcap",
        "/data/fleet/amr1/2026-11-02/drive.mcap",
        "recordings/amr1: no usable recording (neither a laser scan nor a reference)",
        "",
    ],
)
def test_what_holds_no_secret_is_kept_as_written(text: str):
    assert redacted(text) == text


def test_urls_inside_a_text_are_masked_and_the_rest_kept():
    line = (
        "failed: http://u:pw@h:8000/fleet/x.mcap: cannot be read (Cannot connect to host "
        "h:8000 ssl:default [see 'http://u:pw@h:8000/fleet/x.mcap'])"
    )
    assert redacted(line) == (
        "failed: http://***@h:8000/fleet/x.mcap: cannot be read (Cannot connect to host "
        "h:8000 ssl:default [see 'http://***@h:8000/fleet/x.mcap'])"
    )
    command = (
        "umbmark fleet 'https://reader:hunter2@bags.example.com/fleet/' "
        "https://h/one.mcap?sig=AbC --robot-from '{robot}/{date}/*' --history h.sqlite3"
    )
    assert redacted(command) == (
        "umbmark fleet 'https://***@bags.example.com/fleet/' "
        "https://h/one.mcap?sig=*** --robot-from '{robot}/{date}/*' --history h.sqlite3"
    )


def test_a_url_signed_again_is_redacted_alike_and_its_path_holds_no_user():
    """What a recording is known again by holds no secret and does not change when its
    URL is signed again the next night (another signature, credential date and expiry)."""
    assert S3_NIGHT_1 != S3_NIGHT_2
    assert redacted(S3_NIGHT_1) == redacted(S3_NIGHT_2) == S3_SHOWN
    # The path a --robot-from pattern is matched against: never the user or password.
    assert url_path("s3://KEY:SECRET@bucket/amr1/x.mcap") == "/bucket/amr1/x.mcap"
    assert url_path("https://u:p@h/fleet/amr1/x.mcap?sig=1") == "/fleet/amr1/x.mcap"


def test_a_served_recording_is_known_and_refused_without_its_credentials(served: str):
    """Against a real server (which ignores the query and any user): the identity of a
    URL holding a user and password, or signed on two nights, holds neither and is the
    same each night; a read error names the URL redacted."""
    host = served.removeprefix("http://")
    plain = identity(f"{served}/changing.mcap")
    with_user = identity(f"http://reader:hunter2@{host}/changing.mcap")
    assert with_user == plain.replace(served, f"http://***@{host}")
    nights = [
        identity(f"{served}/changing.mcap?X-Amz-Date=2026110{n}T020000Z&X-Amz-Signature=s{n}x")
        for n in (2, 3)
    ]
    assert nights[0] == nights[1]
    assert nights[0].startswith(f"{served}/changing.mcap?X-Amz-Date=***&X-Amz-Signature=***|")
    with pytest.raises(InputError) as raised:
        expand(f"http://reader:hunter2@{host}/nothing/", 12)
    assert (
        str(raised.value) == f"http://***@{host}/nothing/: cannot be read (HTTP 404 File not found)"
    )
