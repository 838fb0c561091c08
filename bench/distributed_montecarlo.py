"""Chapter 2 Monte-Carlo on a Dask cluster against one process, measured in one run.

10,000 closed-loop runs of the roll task (batches of 500: 20 tasks), each identified with FC
and ARX, run (1) in this process, one batch after another, and (2) on a local Dask cluster of
two worker processes (this machine's two cores). Prints both wall times, the ratio, the
cluster's start-up, whether the two results are bit-identical, and an estimate, from the
measured per-task cost, of a 1,000,000-run study on N workers (and the memory its results
would take where they are gathered). Pass a number to run fewer (e.g. ``2000``).
"""

import sys
import time

import numpy as np

from twin.core.tasks.engine import Engine
from twin.pilot.studies.montecarlo import monte_carlo

BATCH = 500


def main():
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 10_000
    tasks = -(-runs // BATCH)
    t0 = time.perf_counter()
    alone = monte_carlo(runs, seed=0, batch=BATCH)
    wall_1 = time.perf_counter() - t0
    # the part every study pays once in the client: remnant scale, ARX structure (FPE)
    t0 = time.perf_counter()
    monte_carlo(2, seed=0, batch=BATCH)
    fixed = time.perf_counter() - t0
    with Engine("local:2") as engine:
        t0 = time.perf_counter()
        engine.client()
        startup = time.perf_counter() - t0
        t0 = time.perf_counter()
        spread = monte_carlo(runs, seed=0, batch=BATCH, scheduler=engine)
        wall_2 = time.perf_counter() - t0
    same = all(
        np.array_equal(getattr(alone, m)[r], getattr(spread, m)[r])
        for m in ("fc", "arx")
        for r in ("pe", "px")
    )
    print(f"Ch 2 Monte-Carlo, {runs} runs in {tasks} tasks of {BATCH}:")
    print(f"  one process:                  {wall_1:6.1f} s  ({runs / wall_1:5.0f} runs/s)")
    print(
        f"  local cluster, 2 workers:     {wall_2:6.1f} s  ({runs / wall_2:5.0f} runs/s), "
        f"plus {startup:.1f} s to start it"
    )
    print(
        f"  ratio one process / cluster:  {wall_1 / wall_2:6.2f}x "
        f"(with start-up {wall_1 / (wall_2 + startup):.2f}x); results bit-identical: {same}"
    )
    task_1 = (wall_1 - fixed) / tasks  # one batch on a core of its own
    task_2 = 2 * (wall_2 - fixed) / tasks  # one batch on a cluster worker, overhead included
    per_run_bytes = (
        sum(getattr(alone, m)[r].nbytes for m in ("fc", "arx") for r in ("pe", "px")) / runs
    )
    big = 1_000_000
    big_tasks = -(-big // BATCH)
    print(
        f"  measured: {fixed:.1f} s fixed (client), {task_1:.2f} s per task alone, "
        f"{task_2:.2f} s per task and worker on the cluster ({task_2 / task_1:.2f}x: two "
        "workers share this machine's memory bandwidth and the scheduler)"
    )
    print(f"estimate, {big:,} runs ({big_tasks} tasks), from the cluster's per-task cost:")
    for n in (1, 2, 8, 32, 128):
        hours = (fixed + -(-big_tasks // n) * task_2) / 3600
        print(f"  {n:4d} workers: {hours:7.2f} h")
    print(
        f"  results gathered in the client: {per_run_bytes * big / 1e9:.1f} GB "
        f"({per_run_bytes:.0f} B per run: FC and ARX responses at "
        f"{alone.omega_rad_s.size} lines)"
    )


if __name__ == "__main__":
    main()
