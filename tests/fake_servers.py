"""Servers on the loopback that are not Dask schedulers, for ``--scheduler`` tests.

Each is a context manager yielding its address ``tcp://127.0.0.1:PORT``; every one listens
on 127.0.0.1 only, on a free port, and stops when the block ends.
"""

from __future__ import annotations

import socket
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer

LOOPBACK = "127.0.0.1"


class _QuietHandler(SimpleHTTPRequestHandler):
    """An HTTP handler that logs nothing (the test's stderr stays clean)."""

    def log_message(self, format: str, *args: object) -> None:
        """Log nothing."""


@contextmanager
def http_server() -> Iterator[str]:
    """An HTTP server (Python's own, as ``python -m http.server`` runs it)."""
    server = ThreadingHTTPServer((LOOPBACK, 0), _QuietHandler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"tcp://{LOOPBACK}:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


@contextmanager
def silent_listener() -> Iterator[str]:
    """A port that accepts connections (the kernel does) and never says a word."""
    with socket.create_server((LOOPBACK, 0), backlog=64) as sock:
        yield f"tcp://{LOOPBACK}:{sock.getsockname()[1]}"


def closed_port() -> str:
    """An address where nothing listens (a free port, closed again)."""
    with socket.create_server((LOOPBACK, 0)) as sock:
        port = sock.getsockname()[1]
    return f"tcp://{LOOPBACK}:{port}"


@contextmanager
def tcp_server(talk: Callable[[socket.socket], None]) -> Iterator[str]:
    """A server that calls ``talk(connection)`` for each connection, then closes it."""
    sock = socket.create_server((LOOPBACK, 0), backlog=64)
    sock.settimeout(0.2)
    done = threading.Event()

    def serve() -> None:
        while not done.is_set():
            try:
                conn, _ = sock.accept()
            except OSError:  # the accept timed out, or the socket was closed
                continue
            with conn, suppress(OSError):
                conn.settimeout(10)
                talk(conn)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield f"tcp://{LOOPBACK}:{sock.getsockname()[1]}"
    finally:
        done.set()
        thread.join(timeout=5)
        sock.close()


def says(data: bytes, then_wait: bool = True) -> Callable[[socket.socket], None]:
    """A ``talk`` that sends ``data`` at once (a banner), then waits for the client to leave."""

    def talk(conn: socket.socket) -> None:
        conn.sendall(data)
        while then_wait and conn.recv(4096):
            pass

    return talk


def echoes(conn: socket.socket) -> None:
    """A ``talk`` that says nothing first, then sends back what it hears (an echo service)."""
    while chunk := conn.recv(4096):
        conn.sendall(chunk)
