"""What answers at a scheduler address: found with a plain socket within seconds.

Dask's client retries a refused connection until its timeout, then waits without a limit for
a handshake the other end may never complete; so ``--scheduler`` pointing at an HTTP server,
or at a port that accepts and says nothing, hung a command for ever. :func:`what_answers`
looks first, within :data:`HANDSHAKE_TIMEOUT_S`:

1. a TCP connection (refused: nothing listens; no answer: no such machine, or a firewall);
2. for ``tcp://``, Dask's greeting: a Dask scheduler speaks first, at once, with its
   handshake (a frame of a few dozen bytes: ``uint64`` total length, ``uint64`` frame count,
   one ``uint64`` length per frame, the frames). Anything else is named by what it said; a
   server still silent after half the time (HTTP waits for its client) is asked for
   ``HEAD /`` and named by its answer. Nothing is sent to a server that greets.

``tls://`` and ``ws(s)://`` addresses are checked for the connection only (their client
speaks first); other protocols (``inproc``, ``ucx``) are left to Dask's client.
"""

from __future__ import annotations

import socket
import struct
import time

#: Longest wait for a connection and Dask's greeting [s].
HANDSHAKE_TIMEOUT_S = 5.0
#: Protocols whose connection can be checked with a plain TCP socket.
_TCP_BASED = ("tcp", "tls", "ws", "wss")
#: Most frames a greeting is taken to have (a Dask handshake has one).
_MAX_FRAMES = 64
#: Most bytes a greeting is taken to have (a Dask handshake has a few dozen).
_MAX_GREETING = 1 << 16
#: Sent to a server that stays silent, to hear what it speaks (an HTTP server answers).
_HTTP_PROBE = b"HEAD / HTTP/1.0\r\n\r\n"


def _split(address: str) -> tuple[str, str, int]:
    """Return the protocol, host and port of ``[proto://]host:port``."""
    scheme, _, rest = address.rpartition("://")
    host, _, port = rest.rpartition(":")
    return scheme or "tcp", host.strip("[]"), int(port)


def _dask_greeting(data: bytes) -> bool | None:
    """Whether ``data`` is a whole Dask handshake (None: too short to tell yet)."""
    if len(data) < 16:
        return None
    total, count = struct.unpack("<QQ", data[:16])
    if not 1 <= count <= _MAX_FRAMES or not 8 * (1 + count) <= total <= _MAX_GREETING:
        return False
    if len(data) < 16 + 8 * count:
        return None
    lengths = struct.unpack(f"<{count}Q", data[16 : 16 + 8 * count])
    if total != 8 * (1 + count) + sum(lengths):
        return False
    return True if len(data) >= 8 + total else None


def _said(data: bytes) -> str:
    """Name a non-Dask answer: its protocol if known, else its first line."""
    if data.startswith(b"HTTP/"):
        return "it speaks HTTP"
    line = data.split(b"\n", 1)[0].strip().decode("ascii", "replace")
    return f"it said {line[:40]!r}"


def _read(sock: socket.socket, data: bytes, until: float) -> tuple[bytes, bool]:
    """Read until the answer is a Dask greeting or is not one, ``until`` or end of stream.

    Returns the bytes read and whether the stream ended.
    """
    while _dask_greeting(data) is None:
        left = until - time.monotonic()
        if left <= 0:
            return data, False
        sock.settimeout(left)
        try:
            chunk = sock.recv(4096)
        except TimeoutError:
            return data, False
        if not chunk:
            return data, True
        data += chunk
    return data, False


def _listen_to(sock: socket.socket, start: float, timeout_s: float) -> str | None:
    """Return what is wrong with the server on ``sock`` (None: it greets as Dask does)."""
    data, ended = _read(sock, b"", start + timeout_s / 2)
    if not data and not ended:  # silent: perhaps a server waiting for its client
        sock.sendall(_HTTP_PROBE)
        data, ended = _read(sock, data, start + timeout_s)
    if _dask_greeting(data):
        return None
    if data:
        return f"it answered, but is not a Dask scheduler ({_said(data)})"
    if ended:
        return "it accepted the connection and closed it without Dask's greeting"
    return (f"it accepted the connection but said nothing within {timeout_s:g} s (a Dask "
            "scheduler greets at once)")  # fmt: skip


def what_answers(address: str, timeout_s: float = HANDSHAKE_TIMEOUT_S) -> str | None:
    """Say what is wrong at a scheduler ``address``, within about ``timeout_s``.

    Parameters
    ----------
    address : str
        ``proto://host:port`` (as :func:`twin.core.tasks.engine.parse_scheduler` returns it).
    timeout_s : float
        Longest wait for the connection and for the greeting [s].

    Returns
    -------
    str or None
        What answered instead of a Dask scheduler, e.g. ``"nothing listens there
        (connection refused)"`` or ``"it answered, but is not a Dask scheduler (it speaks
        HTTP)"``; None if a Dask scheduler greeted (or the protocol cannot be checked here).

    """
    scheme, host, port = _split(address)
    if scheme not in _TCP_BASED:
        return None
    start = time.monotonic()
    try:
        sock = socket.create_connection((host, port), timeout=timeout_s)
    except ConnectionRefusedError:
        return "nothing listens there (connection refused)"
    except TimeoutError:
        return f"no answer within {timeout_s:g} s (no connection: no such machine, or a firewall)"
    except socket.gaierror as e:
        return f"unknown host {host!r} ({e.strerror})"
    except OSError as e:
        return f"cannot be reached ({e.strerror or e})"
    with sock:
        if scheme != "tcp":
            return None
        try:
            return _listen_to(sock, start, timeout_s)
        except OSError as e:  # reset by the other end
            return f"the connection failed before Dask's greeting ({e.strerror or e})"
