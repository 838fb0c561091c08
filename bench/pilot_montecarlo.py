"""Chapter 2 Monte-Carlo throughput (target: 10,000 runs in <= 60 s), measured in one run.

10,000 closed-loop runs of the roll task with fresh remnant, each identified with the FC
method and a MISO ARX model (structure chosen once by FPE): wall time (goal <= 60 s on this
2-core machine) and runs per second. Pass a number to run fewer (e.g. ``1000``). Then one 90 s
pitch-task run with the full MuJoCo platform in the loop, and with the reduced one: real-time
factors.
"""

import sys
import time

from twin.pilot.models.pitch import PitchPilot, simulate_pitch
from twin.pilot.studies.montecarlo import monte_carlo


def main():
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 10_000
    t0 = time.perf_counter()
    r = monte_carlo(runs, seed=0, batch=500)
    wall = time.perf_counter() - t0
    goal = " (goal <= 60 s for 10,000)" if runs == 10_000 else ""
    print(
        f"Ch 2 Monte-Carlo: {runs} runs + FC + ARX {r.orders} in {wall:.1f} s{goal}; "
        f"{runs / wall:.0f} runs/s"
    )
    for model in ("full", "reduced"):
        t0 = time.perf_counter()
        simulate_pitch(PitchPilot(), "condition-8", 1, 0, model=model)
        wall = time.perf_counter() - t0
        print(
            f"one 90 s pitch-task run, {model} platform in the loop: {wall:.2f} s, "
            f"real-time factor {90.0 / wall:.0f}x"
        )


if __name__ == "__main__":
    main()
