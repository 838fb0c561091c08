"""Wall time of a physical calibration of one 60 s run (goal <= 60 s on 2 cores).

The run: Table 5.2 signal 1 in pitch on the MPI, recorded on the full model with a cabin 1.6
times heavier (mass and inertia), the IMU alone. Timed apart: the physical calibration
(:func:`twin.diagnose.physical.calibrate`: the nominal and 25 screening simulations run
concurrently, the three best candidates refined, the IMU's alignment; MuJoCo's physics
releases the GIL, so the simulations share the cores) and the whole ``diagnose(...,
physics=True)`` (the chain's diagnosis on the full model first, then the calibration and the
chain's findings weighed on the same evidence). Also printed: the simulations run, and the time
of one full-model simulation of the run alone, for scale.
"""

import tempfile
import time
from pathlib import Path

from twin.chain.config import motion_system
from twin.chain.signals import describing_signal
from twin.chain.simulate import default_imu, prepare
from twin.core.threads import SIMULATION_THREADS, cpu_count
from twin.diagnose.data import nominal_imu
from twin.diagnose.diagnosis import diagnose
from twin.diagnose.hidden import record_runs
from twin.diagnose.physical import calibrate
from twin.formats.run_checks import read_plausible_run
from twin.measurement.measure import from_run
from twin.platform.payload import Payload
from twin.platform.platform_physics import PlatformPhysics


def main() -> None:
    work = tempfile.TemporaryDirectory()  # removed when this returns
    tmp = Path(work.name)
    mpi = motion_system("mpi")
    heavier = mpi.replace(physics=PlatformPhysics(payload=Payload.scaling("mpi", 1.6)))
    run = record_runs(heavier, mpi, "pitch", tmp, 5, "full", (1,), imu=default_imu("mpi"))[0]
    for name in ("actuators.csv", "forces.csv"):
        (run / name).unlink()
    sig = describing_signal(1, "pitch", settle_s=None)
    t0 = time.perf_counter()
    prepare(mpi, sig.commands, "full", 0).collect()
    one = time.perf_counter() - t0
    rec = read_plausible_run(run)
    t0 = time.perf_counter()
    result = calibrate(mpi, [(rec, from_run(rec))], nominal_imu(rec.meta, "mpi"))
    t_cal = time.perf_counter() - t0
    found = result.finding.extension.describe() if result.finding else "nothing"
    print(f"one full-model simulation of the {sig.commands.duration:.0f} s run: {one:.1f} s")
    print(
        f"physical calibration: {t_cal:.1f} s (goal <= 60 s), {result.simulations} "
        f"simulations, {min(SIMULATION_THREADS, cpu_count())} at once; found: {found}"
    )
    t0 = time.perf_counter()
    d = diagnose([run], physics=True)
    t_all = time.perf_counter() - t0
    named = ", ".join(f.extension.describe() for f in d.findings) or "none"
    print(
        f"diagnose --physics (chain on the full model + calibration): {t_all:.1f} s; named: {named}"
    )


if __name__ == "__main__":
    main()
