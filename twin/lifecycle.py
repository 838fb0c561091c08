"""Outputs complete only when closed: a ``with`` block closes or aborts them.

:class:`CloseOrAbort` gives a class with ``close()`` (finish: rename the output into place)
and ``abort()`` (remove the partial output) its context-manager methods, so that leaving the
block by an exception leaves nothing half-written; :func:`staging_dir` is the hidden folder
such an output is written into before it is renamed into place, and :func:`replacing_dir`
the ``with`` block that writes a report folder that way.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from abc import ABC, abstractmethod
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Self


def staging_dir(final: Path) -> Path:
    """Return a new hidden folder beside ``final`` to write into before renaming it there.

    Made with the permissions a folder made by ``mkdir`` would have (``mkdtemp``'s private
    0700 would otherwise stay on the finished folder).
    """
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.", dir=final.parent))
    mask = os.umask(0)
    os.umask(mask)
    tmp.chmod(0o777 & ~mask)
    return tmp


@contextmanager
def replacing_dir(final: str | Path) -> Iterator[Path]:
    """Yield a staging folder that replaces ``final`` when the block ends without an error.

    An existing ``final`` is removed only then; on an error the staging folder is removed and
    ``final`` is left as it was.
    """
    final = Path(final)
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
