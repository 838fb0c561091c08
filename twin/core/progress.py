"""Progress of long work on stderr: one callable every library function accepts.

Library functions take ``progress=`` as a callable ``progress(message, done=None,
total=None)``: with ``done`` and ``total`` it is a step of a counted job (a bar with rate and
ETA, drawn by tqdm), without them a one-off message (shown beside the bar while a counted
job is under way). :class:`Progress` is the one the CLI
passes; it prints only when its stream is a terminal and ``--quiet`` was not given, so pipes,
logs and tests stay clean. Any other callable of that shape (a notebook's own, a GUI's) works.

Examples
--------
>>> import io
>>> class Tty(io.StringIO):
...     def isatty(self):
...         return True
>>> out = Tty()
>>> p = Progress(stream=out)
>>> for k in range(1, 4):
...     p("runs", k, 3)
>>> "3/3" in out.getvalue()
True
>>> Progress(quiet=True, stream=out).enabled
False

"""

from __future__ import annotations

import shutil
import sys
import threading
from typing import Protocol, TextIO


class ProgressFn(Protocol):
    """What ``progress=`` arguments are (see the module docstring)."""

    def __call__(self, message: str, done: float | None = None, total: float | None = None) -> None:
        """Report ``message``, or ``done`` of ``total`` steps of the job ``message``."""


#: tqdm's line: what, bar, done / total, elapsed < remaining (the ETA), rate.
BAR_FORMAT = (
    "  {desc}: {percentage:3.0f}%|{bar:20}| {n:.4g}/{total:.4g} [{elapsed}<{remaining}]{postfix}"
)


class Progress:
    """Progress on stderr (see the module docstring).

    Parameters
    ----------
    quiet : bool
        Print nothing.
    stream : file, optional
        Where to print (default ``sys.stderr``); nothing is printed unless it is a terminal.

    """

    def __init__(self, quiet: bool = False, stream: TextIO | None = None) -> None:
        self.stream = stream
        self.quiet = quiet
        self._bar = None  # the open tqdm bar, if any
        self._what: str | None = None
        self._finished: tuple[str, float] | None = None  # the last job whose bar was completed
        self._lock = threading.Lock()  # jobs may report from worker threads

    @property
    def enabled(self) -> bool:
        """Whether anything is printed (not quiet, and the stream is a terminal)."""
        stream = self.stream or sys.stderr
        return not self.quiet and bool(getattr(stream, "isatty", lambda: False)())

    def __call__(self, message: str, done: float | None = None, total: float | None = None) -> None:
        """Print a message, or advance the bar of ``message`` to ``done`` of ``total``."""
        if not self.enabled:
            return
        with self._lock:
            self._report(message, done, total)

    def _report(self, message: str, done: float | None, total: float | None) -> None:
        stream = self.stream or sys.stderr
        if done is None or total is None:
            if self._bar is not None:  # a step inside the counted job: shown beside its bar
                self._bar.set_postfix_str(message)
            else:
                print(f"  {message}", file=stream, flush=True)
            return
        from tqdm import tqdm

        bar = self._bar
        if bar is not None and self._what == message and bar.total == total and done < bar.n:
            return  # a late report from another worker thread
        if bar is None and self._finished == (message, total):
            return  # a late report after the job's bar was finished
        if bar is None or self._what != message or bar.total != total:
            self.close()
            width = shutil.get_terminal_size().columns  # a terminal may report 0: 80 then
            bar = self._bar = tqdm(total=total, desc=message, file=stream, bar_format=BAR_FORMAT,
                                   leave=True, ncols=width if width > 0 else 80)  # fmt: skip
            self._what = message
            self._finished = None
        bar.update(done - bar.n)
        if done >= total:
            self._finished = (message, total)
            self.close()

    def close(self) -> None:
        """Finish the open bar (a later message starts on a new line)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None
            self._what = None
