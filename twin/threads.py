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
"""

from __future__ import annotations

import functools
import os
import sys
from contextlib import AbstractContextManager
from typing import Any

#: The variables OpenBLAS, OpenMP and MKL read when they load.
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


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
