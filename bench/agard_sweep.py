"""Wall time of the Table 5.2 describing-function sweep (target <= 5 s), measured in one run.

Two multi-sine runs (signals 1 and 2, with the Eq 3.3 pre-measurement) in pitch and in heave,
four runs and 200 s of simulated time, IMU post-processing and analysis included. Prints the
wall time and the ratio to real time for the full MuJoCo model (goal <= 5 s on this 2-core
machine) and the reduced model, with the runs on both cores and on one.
"""

import time

from twin.agard.df import sweep
from twin.chain.signals import describing_signal
from twin.measurement.measure import Bench, configure


def main():
    simulated = 2 * sum(describing_signal(n, "pitch", settle_s=None).commands.duration
                        for n in (1, 2))  # fmt: skip
    for model in ("full", "reduced"):
        for workers in (2, 1):
            bench = Bench(configure("mpi"), model)
            t0 = time.perf_counter()
            sweep(bench, ("pitch", "heave"), workers=workers)
            wall = time.perf_counter() - t0
            goal = " (goal <= 5 s)" if model == "full" else ""
            print(
                f"DF sweep, mpi {model:7s} {workers} thread(s): {wall:5.2f} s wall for "
                f"{simulated:.0f} s simulated = {simulated / wall:6.0f}x real time{goal}"
            )


if __name__ == "__main__":
    main()
