"""Chapter 6 with adaptive subjects and the MLE's honesty, measured in one run.

1. ``twin pilot experiment --pilot adaptive --subjects 6`` wall time on both cores (goal
   <= 60 s on this 2-core machine); over five seeded populations of nine subjects (the
   thesis' participants), how often each of the 30 main effects of Tables 6.4-6.6 agrees with
   the thesis (direction and p < 0.05 where it found an effect, p >= 0.05 where not).
2. The direction of the filter's effect on var(u) and the target crossover (the two the
   population does not reproduce) for the default subject over a grid of its priorities
   (control weight r, observation-noise ratio).
3. Closed-loop MLE coverage: 50 seeded runs of a known pilot (condition 8, 15 % remnant, the
   thesis' level) fitted one by one (two workers); per parameter the fraction within 2
   Cramer-Rao sd of the truth among the estimates where it counted as identifiable, and the
   fraction of all estimates whose likelihood-ratio interval (:mod:`twin.pilot.profile`)
   holds the truth (goal >= 90 %); once with one run per estimate, once with five
   repetitions averaged (the thesis' five per condition, §6.3.4).
"""

import time

import numpy as np

from twin.chain.config import motion_system
from twin.pilot.adapt import Task, adapt
from twin.pilot.experiment import pitch_remnant_scale
from twin.pilot.mle import PARAMETERS, fit_pitch_pilot
from twin.pilot.pitch import PitchPilot, simulate_pitch
from twin.pilot.population import run_population
from twin.tasks.engine import Engine

REPETITIONS, POPULATIONS = 5, 5


def main(runs: int = 50) -> None:
    t0 = time.perf_counter()
    run_population(6, 0, scheduler="local:2")
    wall = time.perf_counter() - t0
    print(f"adaptive experiment, 6 subjects, 2 workers: {wall:.1f} s (goal <= 60 s)")
    hits: dict[str, int] = {}
    for seed in range(POPULATIONS):
        for measure, by in run_population(9, seed, scheduler="local:2").agreement().items():
            for factor, ok in by.items():
                hits[f"{measure}/{factor}"] = hits.get(f"{measure}/{factor}", 0) + ok
    full = sum(v == POPULATIONS for v in hits.values())
    print(f"{POPULATIONS} populations of 9 subjects (the thesis' nine): {full} of {len(hits)} "
          f"main effects agree with Tables 6.4-6.6 in every population; the others:")  # fmt: skip
    for name, v in hits.items():
        if v < POPULATIONS:
            print(f"  {name:40s} agrees in {v} of {POPULATIONS}")
    print("filter effect (condition 5 / condition 1) on the default subject vs its priorities:")
    t1, t5 = Task.pitch("condition-1"), Task.pitch("condition-5")
    for r in (0.01, 0.03, 0.1):
        for ratio in (0.003, 0.01, 0.03):
            a1, a5 = adapt(t1, None, r, ratio), adapt(t5, None, r, ratio)
            print(f"  r {r:5.3f} noise ratio {ratio:5.3f}: var(u) x"
                  f"{a5.performance.var_u / a1.performance.var_u:5.3f}, target crossover "
                  f"{a1.loops.crossover_t:4.2f} -> {a5.loops.crossover_t:4.2f} rad/s "
                  f"(thesis: both down)")  # fmt: skip
    truth = PitchPilot(tau_v=0.275)  # visual + display delay on the 10 ms simulation grid
    cfg = motion_system("condition-8")
    scale = pitch_remnant_scale(truth, 0.15)
    for reps in (1, REPETITIONS):
        r = simulate_pitch(truth, cfg, runs * reps, seed=1, remnant_scale=scale)
        args = [(r.ft, r.fd, r.u[i * reps] if reps == 1 else r.u[i * reps : (i + 1) * reps])
                for i in range(runs)]  # fmt: skip
        t0 = time.perf_counter()
        with Engine("local:2") as engine:
            fits = engine.map(_fit, args, [{"run": i} for i in range(runs)], "fits").values()
        per_fit = 2 * (time.perf_counter() - t0) / runs
        what = "one run" if reps == 1 else f"{reps} repetitions averaged (as the thesis)"
        print(f"MLE coverage over {runs} estimates, each from {what} ({per_fit:.1f} s per fit "
              "with intervals); within 2 Cramer-Rao sd of the truth where identifiable, and "
              "within the likelihood-ratio interval (2 sd) for every estimate:")  # fmt: skip
        for n in PARAMETERS:
            ok = [f for f in fits if n not in f.unidentifiable]
            z = np.array([(getattr(f.pilot, n) - getattr(truth, n)) / f.crlb[n] for f in ok])
            crlb = f"{np.mean(np.abs(z) <= 2):4.0%}" if z.size else "  - "
            inside = np.mean([f.covers(n, getattr(truth, n)) for f in fits])
            sd = np.median([np.subtract(*f.intervals[n][::-1]) / 4 for f in fits])
            print(f"  {n:9s} CRLB {crlb} of {len(ok):2d} identifiable (goal >= 90 %); interval "
                  f"{inside:4.0%} of {runs} (goal >= 90 %), median width / 4 {sd:.3g}")  # fmt: skip


def _fit(ft, fd, u):
    """One MLE fit with likelihood-ratio intervals (a task of the engine)."""
    return fit_pitch_pilot(ft, fd, u, motion_system("condition-8"), intervals=True)


if __name__ == "__main__":
    main()
