"""One BLAS thread per twin process (twin.core.threads), the user's own choice kept."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from twin.core.threads import BLAS_THREAD_VARIABLES

#: Threads of the process once NumPy has loaded its BLAS (OpenBLAS starts its pool then).
COUNT = "import numpy, os; print(len(os.listdir('/proc/self/task')), os.environ['{var}'])"


def _run(code: str, **env: str) -> list[str]:
    clean = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES}
    out = subprocess.run([sys.executable, "-c", code], env={**clean, **env}, check=True,
                         capture_output=True, text=True)  # fmt: skip
    return out.stdout.split()


@pytest.mark.skipif(
    not Path("/proc/self/task").is_dir(),
    reason="the thread count is read from /proc (Linux); the setting itself is tested below",
)
def test_a_twin_command_process_has_no_blas_pool():
    """The CLI sets one thread before NumPy loads: the process has its main thread only."""
    threads, value = _run("import twin.cli.main; " + COUNT.format(var="OPENBLAS_NUM_THREADS"))
    assert value == "1"
    assert threads == "1"


def test_a_users_own_thread_count_is_kept():
    _, value = _run("import twin.cli; " + COUNT.format(var="OPENBLAS_NUM_THREADS"),
                    OPENBLAS_NUM_THREADS="2")  # fmt: skip
    assert value == "2"


def test_importing_the_library_leaves_blas_alone():
    """Only the command line decides for its process; ``import twin.chain`` does not."""
    code = "import twin.chain.simulate, os; print(os.environ.get('OPENBLAS_NUM_THREADS', '-'))"
    assert _run(code) == ["-"]


def test_concurrent_jobs_run_side_by_side_and_come_back_in_order():
    import threading

    from twin.core.threads import concurrently

    meet = threading.Barrier(2, timeout=30)  # two jobs that wait for each other: side by side
    jobs = [lambda: (meet.wait(), "a")[1], lambda: (meet.wait(), "b")[1], lambda: "c"]
    assert concurrently(jobs, workers=2) == ["a", "b", "c"]
    assert concurrently([lambda: threading.current_thread().name], workers=1) == ["MainThread"]


@pytest.mark.parametrize("workers", [1, 2])
def test_the_first_failing_job_in_order_raises_or_is_returned(workers):
    from twin.core.threads import concurrently

    ran = []

    def fail(k):
        ran.append(k)
        raise ValueError(f"job {k}")

    jobs = [lambda: 1, lambda: fail(1), lambda: fail(2)]
    with pytest.raises(ValueError, match="job 1"):
        concurrently(jobs, workers=workers)
    out = concurrently(jobs, workers=workers, return_exceptions=True)
    assert out[0] == 1 and [str(e) for e in out[1:]] == ["job 1", "job 2"]
