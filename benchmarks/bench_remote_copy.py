"""A recording at a URL copied by a fleet's worker: its memory against the file's size,
and its rate against a plain read of the same file from disk.

A file of random bytes (``--mib``, 256 by default) is served by ``python -m http.server``
on this machine's loopback and copied by :func:`umbmark.sources.remote.fetched` (in
chunks of ``CHUNK``, its SHA-256 taken on the way) into a private temporary folder, after
a first, small copy has imported fsspec and aiohttp. Printed side by side, from the same
run: Python's peak memory during the copy (tracemalloc) against the file's size, and the
copy's rate against reading the file whole from disk in the same chunks.

Run: python benchmarks/bench_remote_copy.py [--mib 256]
"""

from __future__ import annotations

import argparse
import os
import socket
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

from umbmark.sources.remote import CHUNK, fetched


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _read_rate(path: Path) -> float:
    """Reading ``path`` from disk in chunks of ``CHUNK`` [MiB/s]."""
    start = time.perf_counter()
    with path.open("rb") as f:
        while f.read(CHUNK):
            pass
    return path.stat().st_size / (1 << 20) / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mib", type=int, default=256, help="the file's size [MiB]")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-remote-") as folder:
        served = Path(folder)
        big = served / "big.bin"
        with big.open("wb") as f:
            for _ in range(args.mib):
                f.write(os.urandom(1 << 20))
        (served / "small.bin").write_bytes(os.urandom(1000))
        port = _free_port()
        server = subprocess.Popen(
            [sys.executable, "-m", "http.server", str(port), "--bind", "127.0.0.1", "-d", folder],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            url = f"http://127.0.0.1:{port}"
            deadline = time.monotonic() + 30
            while True:
                try:
                    with fetched(f"{url}/small.bin"):  # its libraries imported here
                        break
                except Exception:
                    if time.monotonic() > deadline:
                        raise
                    time.sleep(0.2)
            tracemalloc.start()
            start = time.perf_counter()
            with fetched(f"{url}/big.bin") as (local, _):
                seconds = time.perf_counter() - start
                size = local.stat().st_size / (1 << 20)
            peak = tracemalloc.get_traced_memory()[1] / (1 << 20)
            tracemalloc.stop()
        finally:
            server.terminate()
            server.wait()
        disk = _read_rate(big)
    rate = size / seconds
    print(f"file: {size:.0f} MiB over HTTP on loopback, chunks of {CHUNK >> 20} MiB")
    print(f"Python's peak memory copying it: {peak:.1f} MiB ({peak / size:.3f} of the file)")
    print(f"copy: {rate:.0f} MiB/s; reading it from disk: {disk:.0f} MiB/s ({rate / disk:.2f}x)")


if __name__ == "__main__":
    main()
