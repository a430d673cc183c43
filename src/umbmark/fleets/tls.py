"""An existing Dask scheduler over TLS (``tls://HOST:PORT``), as this client meets it: the
certificates Dask's configuration gives the client checked before it connects, and one TLS
handshake tried first, so that a cluster that lets no one in says so in one line, naming
whose certificate was refused and the setting that names it, instead of Dask's retries and
a line about a scheduler that does not answer.

This module knows nothing of Dask: :mod:`umbmark.fleets.cluster` (the one module that
imports it) reads Dask's own security settings (its ``Security``: the configuration's
``distributed.comm.tls.*`` keys, from its YAML files or the ``DASK_DISTRIBUTED__COMM__TLS__*``
environment variables) and hands the files and the SSL context Dask made of them here.
There are no umbmark options for the certificates: the scheduler, the workers and this
client read the same settings in the same place.

- :func:`check_files`: a ``tls://`` address with no CA or no client certificate set, or a
  file set that cannot be read, is one line naming the setting and its environment
  variable.
- :func:`unusable`: files that OpenSSL refuses (a key that is not the certificate's, a
  file that is no PEM).
- :func:`handshake`: the scheduler's certificate not signed by the CA this client trusts,
  this client's certificate refused by the scheduler, or a scheduler that does not speak
  TLS, each one line; a scheduler that is not there is left to Dask's own connect, which
  waits for one that is starting.
- :func:`unencrypted`: the warning where certificates are set and the address is
  ``tcp://``.
"""

from __future__ import annotations

import socket
import ssl
from collections.abc import Mapping

from umbmark.core.errors import InputError

__all__ = [
    "ANSWER_WAIT",
    "CA_FILE",
    "CLIENT_CERT",
    "CLIENT_KEY",
    "REQUIRE_ENCRYPTION",
    "check_files",
    "environment_variable",
    "handshake",
    "unencrypted",
    "unusable",
]

#: Dask's configuration keys of this client's TLS files.
CA_FILE = "distributed.comm.tls.ca-file"
CLIENT_CERT = "distributed.comm.tls.client.cert"
CLIENT_KEY = "distributed.comm.tls.client.key"
#: Dask's key that makes every connection off this machine take TLS.
REQUIRE_ENCRYPTION = "distributed.comm.require-encryption"
#: Most seconds to wait, after the handshake, for the scheduler's first bytes (a scheduler
#: that took this client's certificate speaks first; one that refused it says so at once).
ANSWER_WAIT = 5.0
#: OpenSSL's reasons for bytes that are not TLS (a plain ``tcp://`` scheduler answering).
_NOT_TLS = ("WRONG_VERSION_NUMBER", "RECORD_LAYER_FAILURE", "PACKET_LENGTH_TOO_LONG",
            "UNKNOWN_PROTOCOL", "HTTP_REQUEST")  # fmt: skip


def environment_variable(key: str) -> str:
    """Dask's environment variable of a configuration key
    (``distributed.comm.tls.ca-file``: ``DASK_DISTRIBUTED__COMM__TLS__CA_FILE``)."""
    return "DASK_" + "__".join(part.upper().replace("-", "_") for part in key.split("."))


def check_files(address: str, files: Mapping[str, str | None]) -> None:
    """Refuse, in one line, a ``tls://`` address for which Dask's configuration gives
    this client no CA or no certificate, or names a file that cannot be read.

    Parameters
    ----------
    address : str
        The scheduler's address.
    files : mapping
        Each key of :data:`CA_FILE`, :data:`CLIENT_CERT`, :data:`CLIENT_KEY` and the path
        (or the PEM text itself) it is set to; None where it is not set (the key may be
        in the certificate's file).

    Raises
    ------
    InputError
    """
    unset = [key for key in (CA_FILE, CLIENT_CERT) if not files.get(key)]
    if unset:
        keys = (CA_FILE, CLIENT_CERT, CLIENT_KEY)
        raise InputError(
            f"the scheduler takes TLS, and Dask's configuration gives this client no "
            f"certificate ({' and '.join(unset)} not set): set {', '.join(keys)} in a Dask "
            f"configuration file or as {', '.join(environment_variable(k) for k in keys)} "
            "(docs/fleet.md)",
            source=address,
        )
    for key, value in files.items():
        if not value or "\n" in value:  # not set, or the PEM text itself
            continue
        try:
            with open(value, "rb") as f:
                f.read(1)
        except OSError as exc:
            raise InputError(
                f"{value} ({key}) cannot be read: {exc.strerror or exc}", source=address
            ) from None


def unusable(address: str, files: Mapping[str, str | None], exc: BaseException) -> InputError:
    """The line for TLS files OpenSSL refuses (a key that is not the certificate's, a file
    that is no PEM certificate)."""
    named = ", ".join(f"{key} {value}" for key, value in files.items() if value)
    return InputError(
        f"the TLS files of Dask's configuration cannot be used ({_said(exc)}): {named}",
        source=address,
    )


def unencrypted(address: str, cert: str) -> str:
    """The warning for a ``tcp://`` scheduler while Dask's configuration gives this client
    a certificate."""
    return (
        f"Dask's configuration gives this client a TLS certificate ({CLIENT_CERT}: {cert}), "
        f"but the scheduler's address {address} is tcp://: the connection is not encrypted "
        "(the recordings' URLs and their results cross the network as they are); where the "
        "scheduler takes TLS, give its tls:// address"
    )


def handshake(
    address: str,
    host: str,
    port: int,
    context: ssl.SSLContext,
    files: Mapping[str, str | None],
    timeout: float,
) -> None:
    """One TLS handshake with the scheduler, as Dask's client makes it (``context`` is the
    one Dask made), and its first bytes awaited: a refusal either way is one line.

    A scheduler that does not take the connection (none there, or still starting) is left
    to Dask's own connect, which waits for it; one that takes it and stays silent for
    :data:`ANSWER_WAIT` seconds is taken as having accepted.

    Raises
    ------
    InputError
        The scheduler's certificate not signed by the CA this client trusts; this
        client's certificate refused by the scheduler; a scheduler that does not speak TLS;
        no TCP connection within ``timeout`` seconds.
    """
    try:
        raw = socket.create_connection((host, port), timeout=timeout)
    except TimeoutError:
        raise InputError(
            f"no Dask scheduler answers at {address} (no connection within {timeout:g} s)",
            source=address,
        ) from None
    except OSError:
        return  # refused or unreachable: Dask's connect waits for a scheduler starting
    with raw:
        try:
            conn = context.wrap_socket(raw, server_hostname=host)
        except ssl.SSLCertVerificationError as exc:
            raise InputError(
                f"the scheduler's certificate is not signed by the CA this client trusts "
                f"({CA_FILE}: {files.get(CA_FILE)}): {exc.verify_message}",
                source=address,
            ) from None
        except (ssl.SSLEOFError, ConnectionResetError) as exc:
            raise InputError(
                f"the scheduler closed the connection in the TLS handshake ({_said(exc)}): "
                "it refuses this client's certificate, or it does not speak TLS",
                source=address,
            ) from None
        except ssl.SSLError as exc:
            if exc.reason in _NOT_TLS:
                raise InputError(
                    f"the scheduler answers, but not with TLS ({_said(exc)}): is it a "
                    "tcp:// scheduler?",
                    source=address,
                ) from None
            raise _refused(address, files, exc) from None
        except TimeoutError:
            raise InputError(
                f"the scheduler took the connection but gave no TLS handshake within {timeout:g} s",
                source=address,
            ) from None
        except OSError as exc:  # closed mid-handshake
            raise _refused(address, files, exc) from None
        with conn:
            _answer(address, conn, files, min(timeout, ANSWER_WAIT))


def _answer(address: str, conn: ssl.SSLSocket, files: Mapping[str, str | None],
            wait: float) -> None:  # fmt: skip
    """The scheduler's first bytes after the handshake: with TLS 1.3 a scheduler that
    refuses this client's certificate says so only now."""
    conn.settimeout(wait)
    try:
        first = conn.recv(1)
    except TimeoutError:
        return  # silent, not refused
    except OSError as exc:  # an alert (unknown CA, bad certificate), or the door closed
        raise _refused(address, files, exc) from None
    if not first:
        raise _refused(address, files, ConnectionResetError("closed without a word"))


def _refused(address: str, files: Mapping[str, str | None], exc: BaseException) -> InputError:
    return InputError(
        f"the scheduler refused this client's certificate ({_said(exc)}; {CLIENT_CERT}: "
        f"{files.get(CLIENT_CERT)}): it takes certificates signed by the CA it was started "
        "with (its --tls-ca-file)",
        source=address,
    )


def _said(exc: BaseException) -> str:
    """What OpenSSL said, in its words: ``tlsv1 alert unknown ca`` (without its code's
    brackets and file)."""
    text = str(getattr(exc, "strerror", None) or exc)
    if text.startswith("[") and "] " in text:
        text = text.split("] ", 1)[1]
    return text.split(" (_ssl.c:", 1)[0].strip() or type(exc).__name__
