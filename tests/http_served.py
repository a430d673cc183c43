"""Folders served over HTTP by real servers started as separate processes on a free port of
this machine, for the tests of recordings at URLs; ended by their PIDs.

- :class:`Served`: Python's own ``python -m http.server`` (index pages for folders,
  ``Content-Length`` and ``Last-Modified`` for files, no range requests).
- :class:`Unsized`: a server that answers every path with one file's bytes and no
  ``Content-Length`` (the size is known only once it is read).
- :class:`Guarded`: Python's own server of a folder behind HTTP basic authentication (a
  user and password; 401 without them).
"""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from pathlib import Path

#: A server that sends a file's bytes without saying their length (HTTP/1.0, closed at the
#: end), to every GET and HEAD.
_UNSIZED = """
import sys
from http.server import BaseHTTPRequestHandler, HTTPServer

data = open(sys.argv[2], "rb").read()


class Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.0"

    def do_HEAD(self):
        self.send_response(200)
        self.send_header("Content-Type", "application/octet-stream")
        self.end_headers()

    def do_GET(self):
        self.do_HEAD()
        self.wfile.write(data)

    def log_message(self, *args):
        pass

HTTPServer(("127.0.0.1", int(sys.argv[1])), Handler).serve_forever()
"""

#: ``python -m http.server``'s handler (index pages, files) behind HTTP basic
#: authentication: 401 to any request without the user and password given.
_GUARDED = """
import base64, functools, sys
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer

expected = "Basic " + base64.b64encode(sys.argv[3].encode()).decode()


class Handler(SimpleHTTPRequestHandler):
    def allowed(self):
        if self.headers.get("Authorization") == expected:
            return True
        self.send_response(401)
        self.send_header("WWW-Authenticate", 'Basic realm="fleet"')
        self.send_header("Content-Length", "0")
        self.end_headers()
        return False

    def do_GET(self):
        if self.allowed():
            super().do_GET()

    def do_HEAD(self):
        if self.allowed():
            super().do_HEAD()


handler = functools.partial(Handler, directory=sys.argv[2])
ThreadingHTTPServer(("127.0.0.1", int(sys.argv[1])), handler).serve_forever()
"""


#: The start of a Python script in which fsspec cannot be imported (an import hook that
#: finds it nowhere, as where it is not installed).
WITHOUT_FSSPEC = (
    "import sys\n"
    "class Nowhere:\n"
    "    def find_spec(self, name, path, target=None):\n"
    "        if name.split('.')[0] == 'fsspec':\n"
    "            raise ModuleNotFoundError(f'No module named {name!r}', name=name)\n"
    "sys.meta_path.insert(0, Nowhere())\n"
)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class _Server:
    """A server process on ``127.0.0.1:port``, ended by its PID."""

    def __init__(self, args: list[str], port: int, log: Path) -> None:
        self.port = port
        self.url = f"http://127.0.0.1:{port}"
        self._log = open(log, "wb")  # noqa: SIM115 (closed by close)
        self.proc = subprocess.Popen(args, stdout=self._log, stderr=self._log)
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise AssertionError(f"the server ended: {log.read_text()}")
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", port)) == 0:
                    return
            time.sleep(0.05)
        self.close()
        raise AssertionError("the server did not start")

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._log.close()

    def __enter__(self) -> _Server:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class Served(_Server):
    """``python -m http.server --bind 127.0.0.1 PORT --directory folder``."""

    def __init__(self, folder: Path, log: Path) -> None:
        port = free_port()
        args = [sys.executable, "-m", "http.server", "--bind", "127.0.0.1", str(port),
                "--directory", str(folder)]  # fmt: skip
        super().__init__(args, port, log)


class Unsized(_Server):
    """Every path answered with ``file``'s bytes, no ``Content-Length``."""

    def __init__(self, file: Path, log: Path) -> None:
        port = free_port()
        super().__init__([sys.executable, "-c", _UNSIZED, str(port), str(file)], port, log)


class Guarded(_Server):
    """``folder`` served as :class:`Served` serves it, to ``user:password`` only (HTTP basic
    authentication); :attr:`url` is without them."""

    def __init__(self, folder: Path, log: Path, user: str, password: str) -> None:
        port = free_port()
        args = [sys.executable, "-c", _GUARDED, str(port), str(folder), f"{user}:{password}"]
        super().__init__(args, port, log)
