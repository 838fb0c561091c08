"""Wall time of a diagnosis: one 60 s run (target <= 10 s), two effects in two runs (<= 30 s).

The run: Table 5.2 signal 1 in pitch on the MPI (60 s), recorded from the twin with a hidden
30 ms extra delay, the nominal noise and an IMU twice as noisy as the data sheet. Timed:
``diagnose`` (nominal twin and 4 realisations of each noise source, residual analysis, every
effect and pair of effects fitted, the held-out gate, the noise judged, the smallest detectable
effects) and then the report folder (Markdown, JSON, figures, .rrd); also against the full
MuJoCo model, for comparison. Then both Table 5.2 runs in heave on the SRS with two hidden
effects (gain 0.9 and 25 ms), the case of the issue that asked for two effects at once.
"""

import tempfile
import time
from pathlib import Path

from twin.chain.config import motion_system
from twin.chain.extensions import Extension
from twin.chain.simulate import default_imu
from twin.diagnose.diagnosis import diagnose
from twin.diagnose.hidden import record_runs
from twin.diagnose.report import write_report
from twin.runs import read_run


def main():
    tmp = Path(tempfile.mkdtemp())
    mpi = motion_system("mpi")
    truth = mpi.replace(extensions=(Extension("delay", {"extra_delay_s": 0.03}, ("pitch",)),))
    noisy = default_imu("mpi").with_noise(2.0)
    run = record_runs(truth, mpi, "pitch", tmp, 5, signals=(1,), imu=noisy)
    duration = read_run(run[0]).commands.duration
    for model in ("reduced", "full"):
        d, t_diagnose = _timed(lambda m=model: diagnose(run, model=m))
        _, t_report = _timed(lambda m=model, d=d: write_report(d, tmp / f"report-{m}"))
        found = ", ".join(f.extension.describe() for f in d.findings) or "none"
        goal = " (goal <= 10 s)" if model == "reduced" else ""
        print(f"diagnose one {duration:.0f} s run, {model:7s} model: {t_diagnose:5.2f} s{goal}, "
              f"report {t_report:4.2f} s; found: {found}")  # fmt: skip
    srs = motion_system("srs")
    two = (Extension("gain", {"gain": 0.9}, ("heave",)),
           Extension("delay", {"extra_delay_s": 0.025}, ("heave",)))  # fmt: skip
    runs = record_runs(srs.replace(extensions=two), srs, "heave", tmp / "two", 6)
    total = sum(read_run(r).commands.duration for r in runs)
    d, t_two = _timed(lambda: diagnose(runs))
    found = ", ".join(f.extension.describe() for f in d.findings) or "none"
    print(f"diagnose two effects in two runs ({total:.0f} s), reduced model: {t_two:5.2f} s "
          f"(goal <= 30 s); found: {found}")  # fmt: skip


def _timed(job):
    """Return the job's result and its wall time [s]."""
    t0 = time.perf_counter()
    out = job()
    return out, time.perf_counter() - t0


if __name__ == "__main__":
    main()
