"""Every ``--scheduler`` address answers within seconds, naming what answered instead.

Before, an address where an HTTP server (or any port that accepts and says nothing) listened
hung the command for ever with no message. The servers here listen on 127.0.0.1 only
(:mod:`fake_servers`); ``make fuzz`` tries more kinds through the command line.
"""

from __future__ import annotations

import subprocess
import sys
import time

import pytest
from fake_servers import closed_port, echoes, http_server, says, silent_listener, tcp_server

from twin.cli.main import main
from twin.core.tasks.scheduler_probe import what_answers

#: A Dask scheduler's greeting, as one sends it on connecting (distributed 2026.8).
DASK_GREETING = (
    b":\x00\x00\x00\x00\x00\x00\x00\x01\x00\x00\x00\x00\x00\x00\x00*\x00\x00\x00\x00\x00\x00\x00"
    b"\x83\xabcompression\xc0\xa6python\x93\x03\x0b\x07\xafpickle-protocol\x05"
)


@pytest.mark.slow  # 8 s: the probe's own waits; the fast suite names the HTTP server in-process
def test_an_http_server_is_named_on_the_command_line_within_seconds(tmp_path):
    with http_server() as address:
        start = time.monotonic()
        done = subprocess.run(
            [sys.executable, "-m", "twin.cli", "pilot", "montecarlo", "--runs", "4",
             "--scheduler", address],
            cwd=tmp_path, capture_output=True, text=True, timeout=120,
        )  # fmt: skip
        took = time.monotonic() - start
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == (
        f"twin: error: no Dask scheduler at {address}: it answered, but is not a Dask scheduler "
        "(it speaks HTTP); start one with `dask scheduler` and workers with `dask worker "
        "ADDRESS`\n"
    )
    assert took < 60  # about 2.5 s and the start of Python; before: never


def test_a_silent_port_is_named_on_the_command_line(capsys, monkeypatch):
    monkeypatch.setattr("twin.core.tasks.engine.HANDSHAKE_TIMEOUT_S", 1.0)
    with silent_listener() as address:
        assert main(["pilot", "montecarlo", "--runs", "4", "--scheduler", address]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert f"{address}: it accepted the connection but said nothing within 1 s" in err


@pytest.mark.parametrize(
    ("server", "said"),
    [
        (lambda: http_server(), "it answered, but is not a Dask scheduler (it speaks HTTP)"),
        (lambda: silent_listener(), "it accepted the connection but said nothing within 1 s"),
        (lambda: tcp_server(says(b"SSH-2.0-OpenSSH_9.2\r\n")),
         "it answered, but is not a Dask scheduler (it said 'SSH-2.0-OpenSSH_9.2')"),
        (lambda: tcp_server(says(b"", then_wait=False)),
         "it accepted the connection and closed it without Dask's greeting"),
        (lambda: tcp_server(echoes),
         "it answered, but is not a Dask scheduler (it said 'HEAD / HTTP/1.0')"),
        (lambda: tcp_server(says(DASK_GREETING[:20] + b"\xff" * 60)),
         "it answered, but is not a Dask scheduler"),
    ],
    ids=["http", "silent", "banner", "closes", "echo", "almost-dask"],
)  # fmt: skip
def test_what_answers_instead_of_a_scheduler_is_named(server, said):
    with server() as address:
        start = time.monotonic()
        got = what_answers(address, timeout_s=1.0)
        took = time.monotonic() - start
    assert got is not None and got.startswith(said)
    assert took < 5


def test_nothing_listening_is_named_at_once():
    start = time.monotonic()
    assert what_answers(closed_port()) == "nothing listens there (connection refused)"
    assert time.monotonic() - start < 2


def test_a_dask_greeting_passes_and_nothing_is_sent_to_it():
    heard = []

    def greet_and_listen(conn):
        conn.sendall(DASK_GREETING)
        heard.append(conn.recv(4096))  # the probe closes: b""

    with tcp_server(greet_and_listen) as address:
        assert what_answers(address, timeout_s=1.0) is None
        deadline = time.monotonic() + 5
        while not heard and time.monotonic() < deadline:
            time.sleep(0.01)
    assert heard == [b""]
