"""Outputs complete only when closed: a ``with`` block closes or aborts them.

:class:`CloseOrAbort` gives a class with ``close()`` (finish: rename the output into place)
and ``abort()`` (remove the partial output) its context-manager methods, so that leaving the
block by an exception leaves nothing half-written; :func:`staging_dir` is the hidden folder
such an output is written into before it is renamed into place.
"""

from __future__ import annotations

import os
import tempfile
from abc import ABC, abstractmethod
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
