"""Twin throughput and memory, measured in one run (issue 3 targets).

Prints, per platform:
- full twin throughput (chain + MuJoCo rollout + IMU, physics steps/s) / raw ``mj_step``
  throughput of the same model in a C-side loop (goal >= 0.8);
- the full model's real-time factor at its 1 kHz physics rate;
- the reduced model's real-time factor (goal >= 1000x);
- peak memory of a 1 h simulated ``mpi`` run streamed to a twin-run/1 folder, against a 1 min
  run: memory must not grow with the run's length (the output is on disk).
Run with ``--quick`` for a 10 min "long" run instead of 1 h.
"""

import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import mujoco
import numpy as np

from twin.chain.simulate import prepare
from twin.platforms import load_model
from twin.signals import describing_signal
from twin.trajectory import Trajectory


def raw_steps_per_s(platform, n=30000):
    model = load_model(platform)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    t0 = time.perf_counter()
    mujoco.mj_step(model, data, nstep=n)
    return n / (time.perf_counter() - t0)


def twin_steps_per_s(platform, model="full"):
    cmd = describing_signal(2, "pitch").commands
    run = prepare(platform, cmd, model, seed=1)
    t0 = time.perf_counter()
    steps = sum(len(resp.t) for resp, _ in run.chunks())
    return steps / (time.perf_counter() - t0), steps


def long_commands(duration_s):
    t = np.arange(0, duration_s, 0.01)
    v = np.zeros((t.size, 6))
    v[:, 2] = -0.02 * np.sin(2 * np.pi * 0.3 * t)
    v[:, 4] = 0.02 * np.sin(2 * np.pi * 0.7 * t)
    return Trajectory(100.0, v)


def peak_mb_streaming(duration_s, model="reduced"):
    """Peak traced memory [MB] of a run streamed to disk chunk by chunk."""
    from twin.runs import RunWriter

    cmd = long_commands(duration_s)
    tracemalloc.start()
    run = prepare("mpi", cmd, model, seed=1)
    meta = {"platform": "mpi", "platform_config": run.config.to_meta(), "command_rate_hz": 100.0,
            "imu": {"position_m": [0, 0, 0], "rate_hz": 819.2}}  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp, RunWriter(Path(tmp) / "r", meta) as w:
        w.write("commands.csv", cmd.t, cmd.values)
        for _resp, imu in run.chunks():
            w.write("imu.csv", imu.t, np.hstack([imu.accel, imu.gyro]))
    peak = tracemalloc.get_traced_memory()[1] / 1e6
    tracemalloc.stop()
    return peak


def main():
    quick = "--quick" in sys.argv
    for platform in ("mpi", "srs"):
        raw = raw_steps_per_s(platform)
        full, _ = twin_steps_per_s(platform, "full")
        red, _ = twin_steps_per_s(platform, "reduced")
        print(f"{platform}: raw mj_step {raw:,.0f} steps/s; twin full {full:,.0f} steps/s "
              f"-> ratio {full / raw:.2f} (goal >= 0.8)")  # fmt: skip
        print(f"{platform}: full model real-time factor {full / 1000:.0f}x at 1 kHz physics; "
              f"reduced model {red / 1000:.0f}x (goal >= 1000x)")  # fmt: skip
    long_s = 600.0 if quick else 3600.0
    short = peak_mb_streaming(60.0)
    long = peak_mb_streaming(long_s)
    print(f"peak memory, reduced mpi run streamed to disk: 1 min {short:.0f} MB, "
          f"{long_s / 60:.0f} min {long:.0f} MB (ratio {long / short:.2f}; the noise realisation "
          "and the 100 Hz commands are the only parts that grow)")  # fmt: skip


if __name__ == "__main__":
    main()
