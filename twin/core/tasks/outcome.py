"""What a batch of tasks gave back: each task's result in input order, and what failed.

A task that fails (an exception in it, or its worker lost more often than the scheduler
allows) does not cost the others their results: :class:`Outcome` keeps every result it got and
a :class:`Failure` per failed task naming the task's inputs, so a sweep can write the points
that worked and say which did not and why.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from twin.core.errors import TwinError


class TaskError(TwinError, RuntimeError):
    """One or more tasks of a batch failed (the message names their inputs)."""

    def __init__(self, what: str, failures: list[Failure]) -> None:
        self.failures = failures
        shown = "; ".join(f.describe() for f in failures[:3])
        more = f" (and {len(failures) - 3} more)" if len(failures) > 3 else ""
        super().__init__(f"{len(failures)} of the {what} failed: {shown}{more}")


@dataclass(frozen=True)
class Failure:
    """A task that failed.

    Attributes
    ----------
    index : int
        Its place in the batch.
    inputs : dict
        What the task was given (configuration, seed, grid point, run folders, ...).
    error : str
        The exception's type and message (``KilledWorker: ...`` when its worker died too often).
    traceback : str
        Where it was raised (empty when not known).

    """

    index: int
    inputs: Mapping[str, Any]
    error: str
    traceback: str = ""

    def describe(self) -> str:
        """One line: the inputs and the error."""
        shown = ", ".join(f"{k}={v}" for k, v in self.inputs.items())
        return f"task {self.index} ({shown}): {self.error}"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "index": self.index,
            "inputs": {k: _plain(v) for k, v in self.inputs.items()},
            "error": self.error,
            "traceback": self.traceback,
        }


def _plain(v: object) -> object:
    return v if isinstance(v, (str, int, float, bool, type(None))) else str(v)


@dataclass
class Outcome:
    """Results of a batch of tasks, in the order the tasks were given.

    Attributes
    ----------
    what : str
        What the tasks were (for messages), e.g. ``"Monte-Carlo batches"``.
    results : list
        Each task's result; None where it failed.
    failures : list of Failure
        The failed tasks, in input order.

    """

    what: str
    results: list[Any]
    failures: list[Failure] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """Whether every task gave a result."""
        return not self.failures

    def values(self) -> list[Any]:
        """Return every result; raise :class:`TaskError` if any task failed.

        For the callers that need all of them (a Monte-Carlo study, an ANOVA over subjects).
        """
        if self.failures:
            raise TaskError(self.what, self.failures)
        return self.results
