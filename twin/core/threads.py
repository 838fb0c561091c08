"""One BLAS thread per process: the twin's processes do not fight over the cores.

The twin's numerical work is MuJoCo's physics (one thread per run) and NumPy on arrays of a
few thousand samples: BLAS threads gain nothing there, and where several processes run at
once (the two workers of the test suite, a Dask cluster's workers, two commands side by side)
each process's BLAS pool competes with the others' physics threads. So every process the twin
starts uses one BLAS thread, set where the process starts, before NumPy loads its BLAS:

* the ``twin`` command (:mod:`twin.cli`);
* Dask's worker processes (``distributed``'s nanny sets ``OPENBLAS_NUM_THREADS``,
  ``OMP_NUM_THREADS`` and ``MKL_NUM_THREADS`` to 1 before it starts a worker; the workers of a
  remote scheduler are set up by whoever starts them);
* the test suite's workers (``conftest.py``).

A value the user has set already is kept (``OPENBLAS_NUM_THREADS=4 twin ...``). In a notebook,
set the variables before the first ``import numpy``, or use ``threadpoolctl``. An open-loop
run's chunks (:func:`twin.chain.stepping.overlapped`, where the full model's physics rolls in
a thread of its own) keep BLAS to one thread with ``threadpoolctl`` whatever the process set,
and restore it after.
``bench/blas_threads.py`` counts the threads of each kind of process and times a run both ways.

Independent simulations (a diagnosis' noise realisations, the plays of a backlash search) run
side by side with :func:`concurrently`: MuJoCo releases the GIL while it rolls, so two full
model runs take about the time of one on two cores.
"""

from __future__ import annotations

import functools
import os
import sys
import threading
from collections.abc import Callable, Sequence
from contextlib import AbstractContextManager
from typing import Any, TypeVar

#: The variables OpenBLAS, OpenMP and MKL read when they load.
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
#: Simulations :func:`concurrently` runs at once at most (fewer on fewer cores): each full
#: model run keeps about one core busy (its physics thread, its Python work overlapping it).
SIMULATION_THREADS = 2
T = TypeVar("T")


def single_blas_thread() -> bool:
    """Ask for one BLAS thread in this process, unless the user has chosen a number.

    Returns
    -------
    bool
        True if the setting can still take effect (NumPy not imported yet); False if NumPy
        has loaded its BLAS already, so that the setting applies only to child processes.

    """
    for name in BLAS_THREAD_VARIABLES:
        os.environ.setdefault(name, "1")
    return "numpy" not in sys.modules


@functools.cache
def _controller() -> Any:
    """Return the process's thread pools, found once (finding them costs about 3 ms a time)."""
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


def one_blas_thread() -> AbstractContextManager[object]:
    """Keep BLAS to one thread within a ``with`` block, whatever the process set; restore after.

    The pools are found at the first call (NumPy's and SciPy's BLAS are loaded by then, as the
    chain imports both), so a BLAS library loaded later is not limited.
    """
    return _controller().limit(limits=1, user_api="blas")


def cpu_count() -> int:
    """Return the CPU cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def concurrently(
    jobs: Sequence[Callable[[], T]], workers: int | None = None, return_exceptions: bool = False
) -> list[Any]:
    """Run independent jobs in threads; return their results in the jobs' order.

    For simulations (MuJoCo releases the GIL while it rolls): each result is the one the job
    gives on its own, whatever ran beside it. BLAS keeps to one thread meanwhile
    (:func:`one_blas_thread`, restored after). The threads are no daemons and are waited for
    by events, never by ``Thread.join`` (a join cut short by Ctrl-C marks a running thread
    ended, bpo-45274): on an interrupt no further job starts, the running ones finish in the
    background and Python waits for them at exit, not tearing down under MuJoCo.

    Parameters
    ----------
    jobs : sequence of callable
        Calls without arguments.
    workers : int, optional
        Threads; :data:`SIMULATION_THREADS`, at most the cores, by default. With one (or one
        job) the jobs run in this thread, one after the other.
    return_exceptions : bool
        Return a job's exception in place of its result (else the first job's exception, in
        the jobs' order, is raised once every started job has ended).

    Returns
    -------
    list
        The jobs' results (or exceptions), in order.

    """
    n = len(jobs)
    workers = min(workers or min(SIMULATION_THREADS, cpu_count()), n)
    outcomes: list[tuple[bool, Any]] = [(False, None)] * n
    if workers <= 1:
        for i, job in enumerate(jobs):
            try:
                outcomes[i] = (True, job())
            except Exception as exc:
                if not return_exceptions:
                    raise
                outcomes[i] = (False, exc)
        return [value for _, value in outcomes]
    lock, done = threading.Lock(), threading.Semaphore(0)
    queue = iter(range(n))
    stop = threading.Event()

    def work() -> None:
        while not stop.is_set():
            with lock:
                i = next(queue, None)
            if i is None:
                break
            try:
                outcomes[i] = (True, jobs[i]())
            except BaseException as exc:  # handed to the caller
                outcomes[i] = (False, exc)
            finally:
                done.release()

    with one_blas_thread():
        threads = [threading.Thread(target=work, name=f"twin-job-{k}") for k in range(workers)]
        for t in threads:
            t.start()
        try:
            for _ in range(n):
                done.acquire()
        except BaseException:
            stop.set()  # no further job starts; the running ones end in the background
            raise
    for ok, value in outcomes:
        if not ok and not (return_exceptions and isinstance(value, Exception)):
            raise value
    return [value for _, value in outcomes]
