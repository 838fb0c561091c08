"""Run a generator in a background thread, so its work overlaps with the consumer's.

NumPy and MuJoCo release the GIL in their heavy loops, so on a machine with two cores the
references of chunk k+1 are computed while chunk k is stepped or post-processed. Results are
identical to the plain generator: items are produced in order by one thread.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Iterable, Iterator
from typing import TypeVar

T = TypeVar("T")
_END = object()


class _Failure:
    """An exception raised by the producer, handed over to the consumer."""

    def __init__(self, error: BaseException) -> None:
        self.error = error


def prefetch(items: Iterable[T], depth: int = 2) -> Iterator[T]:
    """Yield the items of ``items``, produced up to ``depth`` ahead in a daemon thread.

    Parameters
    ----------
    items : iterable
        Produced in the background thread (e.g. a generator doing NumPy work).
    depth : int
        How many items may wait for the consumer; bounds the extra memory.

    Raises
    ------
    Exception
        Whatever the producer raised, re-raised in the consumer at the item where it occurred.

    Examples
    --------
    >>> list(prefetch(x * x for x in range(4)))
    [0, 1, 4, 9]

    """
    if depth < 1:
        raise ValueError(f"depth must be >= 1; got {depth}")
    box: queue.Queue[object] = queue.Queue(depth)
    stop = threading.Event()

    def put(item: object) -> bool:
        while not stop.is_set():
            try:
                box.put(item, timeout=0.05)
                return True
            except queue.Full:
                continue
        return False

    def produce() -> None:
        try:
            for item in items:
                if not put(item):
                    return
            put(_END)
        except BaseException as error:
            put(_Failure(error))

    worker = threading.Thread(target=produce, name="twin-prefetch", daemon=True)
    worker.start()
    try:
        while True:
            item = box.get()
            if item is _END:
                return
            if isinstance(item, _Failure):
                raise item.error
            yield item  # type: ignore[misc]
    finally:
        stop.set()
        worker.join(timeout=1.0)
