"""The ``twin`` command in a process group of its own, sent Ctrl-C as a terminal sends it.

A terminal's Ctrl-C is one SIGINT to every process of the foreground process group: the
``twin`` process and the worker processes of its local Dask cluster. :func:`start` runs the
command as a program (``python -m twin.cli``, :data:`AS_IN_A_TERMINAL`) in a new session,
with ``TMPDIR`` its own ``tmp`` folder and its ``work`` folder as the current one;
:func:`ctrl_c` sends SIGINT to the group; :func:`left_behind` lists what a command left in
those folders.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import suppress
from pathlib import Path

#: Longest wait for a command to get to work, or to end [s] (a loaded 2-core machine).
PATIENCE_S = 180.0
#: ``python -m twin.cli`` as a terminal's foreground job runs it, with SIGINT not ignored even
#: where the tests run with it ignored (in the background of a script: a process inherits it).
AS_IN_A_TERMINAL = (
    "import runpy, signal; signal.signal(signal.SIGINT, signal.default_int_handler); "
    "runpy.run_module('twin.cli', run_name='__main__', alter_sys=True)"
)
#: Dask's own scratch folder in ``TMPDIR``: lock files, shared and reused by every run.
DASK_SCRATCH = "dask-scratch-space"


def start(argv: list[str], root: Path) -> subprocess.Popen:
    """Start ``twin argv`` in a new session (its own process group) under ``root``."""
    for name in ("tmp", "work"):
        (root / name).mkdir(exist_ok=True)
    env = {**os.environ, "TMPDIR": str(root / "tmp")}
    env.pop("TWIN_DEBUG", None)
    with (root / "stdout").open("w") as out, (root / "stderr").open("w") as err:
        return subprocess.Popen(
            [sys.executable, "-c", AS_IN_A_TERMINAL, *argv],
            cwd=root / "work",
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=out,
            stderr=err,
            start_new_session=True,
        )


def writing_a_run(root: Path) -> bool:
    """Whether some run under ``root`` has physics written (a non-empty ``actuators.csv``)."""
    for p in root.rglob("actuators.csv"):
        try:
            if p.stat().st_size:
                return True
        except OSError:  # removed meanwhile
            continue
    return False


def wait_until(ready: Callable[[], bool], proc: subprocess.Popen, root: Path) -> None:
    """Poll until ``ready()``; fail if the command ends first or takes :data:`PATIENCE_S`."""
    deadline = time.monotonic() + PATIENCE_S
    while not ready():
        assert proc.poll() is None, f"ended first ({proc.returncode}): {stderr(root)}"
        assert time.monotonic() < deadline, "never got to work"
        time.sleep(0.02)


def starting_processes(proc: subprocess.Popen) -> bool:
    """Whether the command has started a process (a local cluster is about to start)."""
    return any(fields[1] == str(proc.pid) for fields in _processes())


def ctrl_c(proc: subprocess.Popen, times: int = 1, gap_s: float = 0.3) -> None:
    """Send SIGINT to the command's process group ``times`` times, ``gap_s`` apart."""
    for k in range(times):
        if k:
            time.sleep(gap_s)
        with suppress(ProcessLookupError):  # the whole group has ended already
            os.killpg(proc.pid, signal.SIGINT)


def finish(proc: subprocess.Popen, root: Path) -> tuple[int, str]:
    """Wait for the command (and every process of its group) to end; return code and stderr."""
    try:
        code = proc.wait(timeout=PATIENCE_S)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        raise AssertionError(f"no end within {PATIENCE_S:g} s: {stderr(root)}") from None
    deadline = time.monotonic() + 30  # the workers write to stderr too: wait for them
    while _group_alive(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    return code, stderr(root)


def _processes() -> Iterator[list[str]]:
    """The state, parent and process group (and more) of every process (``/proc/PID/stat``)."""
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            yield stat.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):  # ended meanwhile
            continue


def _group_alive(pgid: int) -> bool:
    """Whether a process of the group is still running (a zombie is not: it may never be reaped
    where the container's first process does not reap orphans)."""
    return any(f[2] == str(pgid) and f[0] != "Z" for f in _processes())


def stderr(root: Path) -> str:
    """What the command wrote to stderr."""
    return (root / "stderr").read_text()


def left_behind(root: Path, *expected: str) -> list[str]:
    """Paths left in ``tmp`` and ``work`` but Dask's scratch folder and ``expected`` names."""
    keep = {DASK_SCRATCH, *expected}
    return sorted(
        str(p.relative_to(root))
        for where in ("tmp", "work")
        for p in (root / where).iterdir()
        if p.name not in keep
    )
