"""Objects whose output is complete only when closed: a ``with`` block closes or aborts them.

:class:`CloseOrAbort` gives a class with ``close()`` (finish: rename the output into place)
and ``abort()`` (remove the partial output) its context-manager methods, so that leaving the
block by an exception leaves nothing half-written.
"""

from __future__ import annotations

from typing import Self


class CloseOrAbort:
    """Mixin: ``with obj:`` calls ``obj.close()``, or ``obj.abort()`` on an exception."""

    def close(self) -> None:
        """Finish the output (subclass)."""
        raise NotImplementedError

    def abort(self) -> None:
        """Remove the partial output (subclass)."""
        raise NotImplementedError

    def __enter__(self) -> Self:
        """Enter the context."""
        return self

    def __exit__(self, kind: object, exc: object, tb: object) -> None:
        """Close, or abort on an exception."""
        if kind is None:
            self.close()
        else:
            self.abort()
