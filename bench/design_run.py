"""Wall time of ``twin design`` for ambiguous diagnoses (goal <= 30 s on 2 cores).

The first case: a 20 ms delay in the MPI's heave behind its 1 Hz filter, recorded with Table 5.2's
signal 2 alone; the diagnosis names it ambiguous (a platform lag, the delay, a gain with a
slower filter: three explanations, and the other single effects the diagnosis fitted as
rivals). Timed: :func:`twin.diagnose.design.design_from` (reading the runs, simulating the
nominal twin on them, the noise off the lines, every explanation refitted to the others at
every frequency of the band, the multisine scaled to the limits).

The second: two explanations with a backlash, the drawn case of seed 6008 (a 4.7 mrad play in
the MPI's roll, the platform filter's break moved by the nuisances; the diagnosis leaves the
moved filter and the play within the margin). Each pair with the play is simulated and
refitted at each amplitude tried (:mod:`twin.diagnose.simulated_evidence`).

Usage: ``python bench/design_run.py``
"""

import tempfile
import time
from pathlib import Path

from twin.chain.config import motion_system
from twin.chain.extensions import Extension
from twin.diagnose.design import design_from
from twin.diagnose.diagnosis import diagnose
from twin.diagnose.hidden import NUISANCE_RANGES, draw, record, record_runs
from twin.diagnose.report import write_report

GOAL_S = 30.0


def timed(name: str, runs: list[Path], seed: int, folder: Path) -> None:
    """Diagnose ``runs``, then time ``twin design`` on the diagnosis and print the ratio."""
    d = diagnose(runs, seed=seed)
    write_report(d, folder, figures=False)
    alternatives = len(d.findings[0].evidence.get("alternatives") or [])
    t0 = time.perf_counter()
    design = design_from(folder)
    wall = time.perf_counter() - t0
    print(f"{name}: explanations {1 + alternatives} ambiguous, {len(design.explanations)} weighed")
    print(*design.summary_lines()[:1], sep="\n")
    print(f"twin design: {wall:.1f} s (goal {GOAL_S:g} s: ratio {wall / GOAL_S:.2f})")


def main() -> None:
    work = tempfile.TemporaryDirectory()  # removed when this returns
    tmp = Path(work.name)
    mpi = motion_system("mpi")
    truth = mpi.replace(extensions=(Extension("delay", {"extra_delay_s": 0.020}, ("heave",)),))
    runs = record_runs(truth, mpi, "heave", tmp / "runs", 3, signals=(2,))
    timed("delay behind the MPI's filter", runs, 3, tmp / "diag")
    h = draw(6008, "backlash", max_redraws=400, nuisance=True, nuisance_ranges=NUISANCE_RANGES)
    timed("a play or a moved filter", record(h, tmp / "play"), h.seed, tmp / "diag-play")


if __name__ == "__main__":
    main()
