"""Ctrl-C in a twin process: one interrupt ends a command, and nothing cuts its clean-up short.

Ctrl-C sends SIGINT to the terminal's whole foreground process group: the ``twin`` process
and, with a local Dask cluster, its worker processes. So:

* the ``twin`` command (:func:`twin.cli.main.main`) turns the first Ctrl-C into one
  :class:`KeyboardInterrupt` (:func:`handling_ctrl_c`); a further Ctrl-C within
  :data:`GRACE_S` is ignored while the command cleans up (partial outputs removed, the cluster
  shut down), and once the command has ended Ctrl-C is ignored for the rest of the process:
  Python then waits for MuJoCo's rollout threads before it exits, and a second Ctrl-C in that
  wait would tear the interpreter down under them (a segmentation fault, exit 139). A
  Ctrl-C after the grace time raises again (should library code have swallowed the first);
* worker processes ignore SIGINT: a local cluster starts inside :func:`deferred` (a process
  inherits an ignored signal) and its workers load :mod:`twin.core.tasks.worker_setup`; the
  ``twin`` process shuts them down, so no worker prints a traceback;
* :func:`deferred` holds a Ctrl-C back while something must not be cut in the middle (a
  cluster starting or closing) and delivers it when the block ends.
"""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

#: How long after a Ctrl-C a further one is ignored (the command is cleaning up) [s].
GRACE_S = 5.0


def _in_main_thread() -> bool:
    """Whether this is the main thread (the only one that may set signal handlers)."""
    return threading.current_thread() is threading.main_thread()


class CtrlC:
    """The SIGINT handler of the ``twin`` command (see the module docstring).

    Attributes
    ----------
    first : float or None
        When the last interrupt that was raised came (``time.monotonic``), None before one.

    """

    def __init__(self) -> None:
        self.first: float | None = None

    @property
    def interrupted(self) -> bool:
        """Whether a Ctrl-C came: whatever the command then raised, the Ctrl-C ended it.

        (An import that Ctrl-C cuts short can raise an ``ImportError`` that no longer
        names the interrupt, and library code may swallow it.)
        """
        return self.first is not None

    def __call__(self, signum: int, frame: FrameType | None) -> None:
        """Raise :class:`KeyboardInterrupt`, unless the last one came less than GRACE_S ago."""
        now = time.monotonic()
        if self.first is not None and now - self.first < GRACE_S:
            return  # the clean-up of the first is under way
        self.first = now
        raise KeyboardInterrupt


@contextmanager
def handling_ctrl_c(process: bool) -> Iterator[CtrlC]:
    """Handle Ctrl-C as the ``twin`` command does within the block (see the module docstring).

    Only in the main thread, and only where SIGINT has Python's default handler: a command
    started with SIGINT ignored (in the background by a script, under ``nohup``) keeps
    ignoring it, and a caller's own handler is kept.

    Parameters
    ----------
    process : bool
        The block is the whole process's work (the ``twin`` command run as a program): when
        the block ends, interrupted or not, SIGINT stays ignored, as Python waits for the
        threads still running (MuJoCo's) and exits: a Ctrl-C in that wait would kill the
        process by the signal, with no line and no exit code of its own. Otherwise (a caller
        running a command in its own process) the default handler is restored.

    Yields
    ------
    CtrlC
        The handler, which tells whether a Ctrl-C came (never, where it was not installed).

    """
    handler = CtrlC()
    if not _in_main_thread() or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield handler
        return
    signal.signal(signal.SIGINT, handler)
    try:
        yield handler
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN if process else signal.default_int_handler)


@contextmanager
def deferred() -> Iterator[None]:
    """Hold Ctrl-C back within the block; a Ctrl-C that came meanwhile is raised at its end.

    Within the block SIGINT is ignored as well as blocked (Linux keeps a blocked signal
    pending even while it is ignored): processes started in the block inherit the ignored
    SIGINT for good. Only in the main thread, and where signals can be blocked (POSIX).
    """
    if not _in_main_thread() or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    previous = signal.getsignal(signal.SIGINT)
    if previous is not None:  # None: a handler not set from Python, which cannot be put back
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)  # a pending Ctrl-C is handled here
