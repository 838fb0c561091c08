"""Wall time of diagnosing one 60 s run against the reduced model (target: <= 10 s).

The run: Table 5.2 signal 1 in pitch on the MPI (60 s), recorded from the twin with a hidden
30 ms extra delay and the nominal noise. Timed: ``diagnose`` (nominal twin and 8 noise
realisations, residual analysis, every candidate fitted, the gain on held-out halves, the
smallest detectable effects) and then the report folder (Markdown, JSON, figures, .rrd).
Also timed against the full MuJoCo model, for comparison.
"""

import tempfile
import time
from pathlib import Path

from twin.chain.config import motion_system
from twin.chain.extensions import Extension
from twin.diagnose.diagnosis import diagnose
from twin.diagnose.hidden import record_runs
from twin.diagnose.report import write_report
from twin.runs import read_run


def main():
    tmp = Path(tempfile.mkdtemp())
    mpi = motion_system("mpi")
    truth = mpi.replace(extensions=(Extension("delay", {"extra_delay_s": 0.03}, ("pitch",)),))
    run = record_runs(truth, mpi, "pitch", tmp, 5, signals=(1,))
    duration = read_run(run[0]).commands.duration
    for model in ("reduced", "full"):
        d, t_diagnose = _timed(lambda m=model: diagnose(run, model=m))
        _, t_report = _timed(lambda m=model, d=d: write_report(d, tmp / f"report-{m}"))
        found = ", ".join(f.extension.describe() for f in d.findings) or "none"
        goal = " (goal <= 10 s)" if model == "reduced" else ""
        print(f"diagnose one {duration:.0f} s run, {model:7s} model: {t_diagnose:5.2f} s{goal}, "
              f"report {t_report:4.2f} s; found: {found}")  # fmt: skip


def _timed(job):
    """Return the job's result and its wall time [s]."""
    t0 = time.perf_counter()
    out = job()
    return out, time.perf_counter() - t0


if __name__ == "__main__":
    main()
