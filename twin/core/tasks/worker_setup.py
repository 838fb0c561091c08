"""Set-up of each worker process of a local cluster (a Dask preload, by module name).

The same set-up is the initializer of the standard library's process pool a core install
(without Dask) uses instead (:func:`process_setup`).

A local cluster's workers share the terminal's process group with the ``twin`` process, so
Ctrl-C reaches them too; the ``twin`` process shuts them down (:mod:`twin.core.interrupts`), so a
worker ignores SIGINT instead of dying with a traceback. The first workers inherit the
ignored signal from the start of the cluster; this preload covers the ones the nanny starts
again later (after a worker was killed). A local cluster runs one worker process per core
(one task thread each), so a worker runs its simulations one after the other
(:data:`twin.core.threads.SIMULATION_THREADS` set to 1), as it keeps BLAS to one thread.
"""

from __future__ import annotations

import signal
from typing import Any

import twin.core.threads


def dask_setup(worker: Any) -> None:
    """Ignore SIGINT, simulate one run at a time (Dask calls this as the worker starts).

    Parameters
    ----------
    worker : distributed.Worker
        The worker being started (unused).

    """
    process_setup()


def process_setup() -> None:
    """Ignore SIGINT and simulate one run at a time: any local worker process's set-up."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    twin.core.threads.SIMULATION_THREADS = 1
