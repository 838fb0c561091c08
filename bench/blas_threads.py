"""BLAS threads per process: counted in each kind of process the twin starts, and timed.

Prints:
- the threads of a process after NumPy has loaded its BLAS: a bare ``python`` (OpenBLAS's
  pool, one thread per core), a ``twin`` command process, and a Dask worker started by the
  twin's engine (goal: no BLAS pool beside the main thread in the twin's processes);
- the wall time of two full-model runs side by side (the test suite's or a two-worker
  cluster's situation) with the default BLAS pool against one BLAS thread per process.

Run: ``python bench/blas_threads.py``
"""

import os
import subprocess
import sys
import time

from twin.core.threads import BLAS_THREAD_VARIABLES

#: Counts the threads of the process once NumPy has loaded (OpenBLAS starts its pool then).
COUNT = "import numpy, os; print(len(os.listdir('/proc/self/task')))"
#: One full-model run of 20 s on the MPI platform.
RUN = (
    "import numpy as np; from twin.chain.simulate import simulate; "
    "from twin.chain.trajectory import Trajectory; t = np.arange(2001) / 100.0; "
    "v = np.zeros((t.size, 6)); v[:, 2] = -0.02 * np.sin(2 * np.pi * 0.3 * t); "
    "v[:, 4] = 0.02 * np.sin(2 * np.pi * 0.7 * t); "
    "simulate('mpi', Trajectory(100.0, v), 'full', seed=1)"
)


def _env(blas: str | None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES}
    if blas is not None:
        env["OPENBLAS_NUM_THREADS"] = blas
    return env


def threads(code: str, blas: str | None = None) -> int:
    out = subprocess.run([sys.executable, "-c", code], env=_env(blas), check=True,
                         capture_output=True, text=True)  # fmt: skip
    return int(out.stdout.split()[-1])


def worker_blas_setting() -> str:
    """OPENBLAS_NUM_THREADS inside a worker of the twin's local Dask cluster."""
    from twin.core.tasks.engine import Engine

    with Engine("local:1") as engine:
        return next(iter(engine.client().run(os.environ.get, "OPENBLAS_NUM_THREADS").values()))


def side_by_side(blas: str | None, repeats: int = 3) -> float:
    """Best wall time [s] of two full-model runs in two processes at once."""
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        procs = [subprocess.Popen([sys.executable, "-c", RUN], env=_env(blas)) for _ in range(2)]
        if any(p.wait() for p in procs):
            raise SystemExit("a run failed")
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    if os.path.isdir("/proc/self/task"):
        bare = threads(COUNT)
        cli = threads("import twin.cli.main; " + COUNT)
        print(f"threads after NumPy loads: bare python {bare}, twin command {cli} "
              f"(goal: 1, the main thread; cores {os.cpu_count()})")  # fmt: skip
    else:
        print("threads after NumPy loads: not counted (no /proc/self/task on this system)")
    print(f"Dask worker of the twin's local cluster: OPENBLAS_NUM_THREADS={worker_blas_setting()}")
    default, single = side_by_side(None), side_by_side("1")
    print(f"two 20 s full-model runs side by side: default BLAS pool {default:.2f} s, one BLAS "
          f"thread per process {single:.2f} s -> {default / single:.2f}x")  # fmt: skip


if __name__ == "__main__":
    main()
