"""Outputs complete only when closed: a ``with`` block closes or aborts them.

:class:`CloseOrAbort` gives a class with ``close()`` (finish: rename the output into place)
and ``abort()`` (remove the partial output) its context-manager methods, so that leaving the
block by an exception leaves nothing half-written; :func:`staging_dir` is the hidden folder
such an output is written into before it is renamed into place, :func:`replacing_dir`
the ``with`` block that writes a report folder that way and :func:`replacing_file` the one
for a single file. :func:`check_output_file`, :func:`check_output_dir` and
:func:`check_writable` refuse an output path before any work (the command line calls them
while parsing, :mod:`twin.cli.common`).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from abc import ABC, abstractmethod
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Self

from twin.errors import UsageError


def staging_dir(final: Path) -> Path:
    """Return a new hidden folder beside ``final`` to write into before renaming it there.

    Made with the permissions a folder made by ``mkdir`` would have (``mkdtemp``'s private
    0700 would otherwise stay on the finished folder).
    """
    try:
        final.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.", dir=final.parent))
    except OSError as e:
        raise UsageError(f"{final}: cannot be written there ({e.strerror})") from None
    mask = os.umask(0)
    os.umask(mask)
    tmp.chmod(0o777 & ~mask)
    return tmp


def check_writable(final: str | Path) -> Path:
    """Refuse an output path that cannot be created: under a file, or in a folder not writable.

    Looks at the nearest folder that exists (the others are made when the output is written).

    Raises
    ------
    UsageError
        Naming the path and why (a file on the way, permission denied, read-only file system).

    """
    final = Path(final)
    there = next((p for p in final.absolute().parents if p.exists()), None)
    if there is not None and not there.is_dir():
        raise UsageError(f"{final}: {there} is a file, not a folder")
    if there is not None and not os.access(there, os.W_OK | os.X_OK):
        raise UsageError(f"{final}: cannot write in {there} (permission denied or a read-only "
                         "file system)")  # fmt: skip
    return final


def check_output_file(path: str | Path, suffixes: tuple[str, ...] = ()) -> Path:
    """Refuse an output file that cannot be written: a folder, a bad suffix, no way to write.

    Parameters
    ----------
    path : str or Path
        The file to be written.
    suffixes : tuple of str
        Allowed suffixes (lower case, with the dot), e.g. the figure formats; empty: any.

    Raises
    ------
    UsageError
        Naming the path and what is allowed.

    """
    final = Path(path)
    if final.is_dir() or not final.name or str(path).endswith(os.sep):
        raise UsageError(f"{final}: is a folder; give a file name")
    if suffixes and final.suffix.lower() not in suffixes:
        raise UsageError(f"{final}: unknown file type {final.suffix or '(none)'!r}; use one of "
                         f"{', '.join(suffixes)}")  # fmt: skip
    return check_writable(final)


@contextmanager
def replacing_file(final: str | Path) -> Iterator[Path]:
    """Yield a hidden name beside ``final`` (same suffix) that becomes ``final`` on success.

    The file appears under its name only when complete; on an exception the partial file is
    removed. Missing parent folders are made.
    """
    final = check_output_file(final)
    tmp = final.with_name(f".{final.stem}.partial{final.suffix}")
    try:
        final.parent.mkdir(parents=True, exist_ok=True)
        yield tmp
        tmp.replace(final)
    except OSError as e:  # named by the user's path, not the hidden one
        with suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise UsageError(f"{final}: cannot be written ({e.strerror or e})") from None
    except BaseException:
        with suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise


def check_output_dir(final: str | Path, marker: str) -> None:
    """Refuse an output folder :func:`replacing_dir` must not replace (see there).

    Commands call it before their work, so a bad ``--out`` costs nothing.
    """
    final = check_writable(final)
    if final.is_symlink():
        raise UsageError(f"output folder {final} is a symbolic link; give the folder itself")
    here = Path.cwd().resolve()
    where = final.resolve()
    if where == here or where in here.parents:
        raise UsageError(f"output folder {final} is the current folder or above it; give a new "
                         "folder")  # fmt: skip
    if final.exists() and not final.is_dir():
        raise UsageError(f"output folder {final} is a file; give a folder")
    if final.is_dir() and any(final.iterdir()) and not (final / marker).is_file():
        raise UsageError(f"output folder {final} exists and is not an earlier output (no "
                         f"{marker}); give a new folder or remove it")  # fmt: skip


@contextmanager
def replacing_dir(final: str | Path, marker: str) -> Iterator[Path]:
    """Yield a staging folder that replaces ``final`` when the block ends without an error.

    Parameters
    ----------
    final : str or Path
        The output folder.
    marker : str
        A file every output of this kind holds (e.g. ``report.json``): an existing ``final``
        is replaced only if it is empty or holds it (an earlier output of the same kind), so
        a user's own folder, the current folder or one holding the inputs is never removed.

    Raises
    ------
    UsageError
        Before anything is written, for a ``final`` that is a file, the current folder or one
        above it, or a non-empty folder that is not an earlier output of this kind.

    """
    final = Path(final)
    check_output_dir(final, marker)
    tmp = staging_dir(final)
    try:
        yield tmp
        if final.exists():
            shutil.rmtree(final)
        tmp.replace(final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


class CloseOrAbort(ABC):
    """Base: ``with obj:`` calls ``obj.close()``, or ``obj.abort()`` on an exception."""

    @abstractmethod
    def close(self) -> None:
        """Finish the output."""

    @abstractmethod
    def abort(self) -> None:
        """Remove the partial output."""

    def __enter__(self) -> Self:
        """Enter the context."""
        return self

    def __exit__(self, kind: object, exc: object, tb: object) -> None:
        """Close, or abort on an exception."""
        if kind is None:
            self.close()
        else:
            self.abort()
