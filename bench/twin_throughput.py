"""Twin throughput and memory, measured in one run (the goals are listed below).

Prints, per platform:
- full twin throughput (chain + MuJoCo rollout + IMU, physics steps/s) / raw ``mj_step``
  throughput of the same model at rest in a C-side loop (goal >= 0.8), and / a raw rollout of
  the same model through the twin's own leg commands (the moving platform costs the solver
  more per step than the one at rest: this ratio is what the twin's Python costs);
- the full model's real-time factor at its 1 kHz physics rate;
- the reduced model's real-time factor on a 60 s run (goal >= 2000x) and on a 10 min run,
  whose ratio says whether the cost grows linearly with the duration (prepare included);
- peak memory of a 1 h simulated ``mpi`` run streamed to a twin-run/1 folder, against a 1 min
  run: memory must not grow with the run's length (the output is on disk).
Run with ``--quick`` for a 10 min "long" run instead of 1 h.
"""

import resource
import subprocess
import sys
import tempfile
import time
from collections import deque
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

from twin.chain.physics import FullPlatform
from twin.chain.signals import describing_signal
from twin.chain.simulate import default_imu, prepare
from twin.chain.trajectory import Trajectory
from twin.platform.facts import load_model

STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS


def raw_steps_per_s(platform, n=30000):
    model = load_model(platform)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    t0 = time.perf_counter()
    mujoco.mj_step(model, data, nstep=n)
    return n / (time.perf_counter() - t0)


def twin_steps_per_s(platform, model="full", commands=None):
    """Physics-rate samples per second of wall time for a whole run (prepare included)."""
    cmd = commands if commands is not None else describing_signal(2, "pitch").commands
    t0 = time.perf_counter()
    run = prepare(platform, cmd, model, seed=1)
    steps = sum(len(resp.t) for resp, _ in run.chunks())
    return steps / (time.perf_counter() - t0), steps


def same_motion_steps_per_s(platform):
    """Raw rollout throughput of the legs' own references in a twin run: one C-side call.

    The twin's physics moves the platform, which costs MuJoCo's constraint solver more per step
    than the model at rest of :func:`raw_steps_per_s`; this baseline steps the same model
    through the same leg commands (recorded from a twin run) with no Python in between.
    """
    recorded = []
    roll = FullPlatform._roll

    def recording(self, controls, phys):
        recorded.extend(c[0] for c in controls if c is not None)
        return roll(self, controls, phys)

    FullPlatform._roll = recording  # bench-only instrumentation
    try:
        twin_steps_per_s(platform, "full")
    finally:
        FullPlatform._roll = roll
    ctrl = np.concatenate(recorded)[None]
    model = load_model(platform)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    state = np.empty(mujoco.mj_stateSize(model, STATE))
    mujoco.mj_getState(model, data, state, STATE)
    t0 = time.perf_counter()
    rollout.rollout(model, data, state, ctrl)
    return ctrl.shape[1] / (time.perf_counter() - t0)


def long_commands(duration_s):
    t = np.arange(0, duration_s, 0.01)
    v = np.zeros((t.size, 6))
    v[:, 2] = -0.02 * np.sin(2 * np.pi * 0.3 * t)
    v[:, 4] = 0.02 * np.sin(2 * np.pi * 0.7 * t)
    return Trajectory(100.0, v)


def memory_case(duration_s, sink):
    """Run one reduced ``mpi`` run of ``duration_s`` into ``sink``; print peak RSS [MB]."""
    from twin.formats.runs import RunWriter

    cmd = long_commands(duration_s)
    run = prepare("mpi", cmd, "reduced", seed=1)
    meta = {"platform": "mpi", "platform_config": run.config.to_meta(), "command_rate_hz": 100.0,
            "imu": {"position_m": [0, 0, 0], "rate_hz": 819.2}}  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        recorder = None
        if sink == "rrd":
            from twin.viz.record import Recorder

            recorder = Recorder(run.platform.geometry, "bench", rrd=str(Path(tmp) / "r.rrd"))
        if sink == "none":
            deque(run.chunks(), maxlen=0)  # run it, keep nothing
        else:
            with RunWriter(Path(tmp) / "r", meta) as w:
                w.write("commands.csv", cmd.t, cmd.values)
                for resp, imu in run.chunks():
                    w.write("imu.csv", imu.t, np.hstack([imu.accel, imu.gyro]))
                    if recorder is not None:
                        recorder.log(resp, imu)
        if recorder is not None:
            recorder.close()
    print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)


def peak_rss_mb(duration_s, sink):
    """Peak resident memory [MB] of :func:`memory_case` in a fresh process."""
    out = subprocess.run(
        [sys.executable, __file__, "--memory-case", str(duration_s), sink],
        check=True, capture_output=True, text=True,
    )  # fmt: skip
    return float(out.stdout.split()[-1])


def main():
    if "--memory-case" in sys.argv:
        k = sys.argv.index("--memory-case")
        memory_case(float(sys.argv[k + 1]), sys.argv[k + 2])
        return
    quick = "--quick" in sys.argv
    for platform in ("mpi", "srs"):
        raw = max(raw_steps_per_s(platform) for _ in range(3))  # best of three, both
        full = max(twin_steps_per_s(platform, "full")[0] for _ in range(3))
        same = max(same_motion_steps_per_s(platform) for _ in range(3))
        print(f"{platform}: raw mj_step {raw:,.0f} steps/s; twin full {full:,.0f} steps/s "
              f"-> ratio {full / raw:.2f} (goal >= 0.8); raw rollout of the twin's own leg "
              f"commands {same:,.0f} steps/s (the moving platform's physics) -> ratio "
              f"{full / same:.2f} (1: no cost beyond the physics)")  # fmt: skip
        rate = default_imu(platform).rate_hz
        red = {s: max(twin_steps_per_s(platform, "reduced", long_commands(s))[0] for _ in range(3))
               / rate for s in (60.0, 600.0)}  # fmt: skip
        print(f"{platform}: real-time factor: full model {full / 1000:.0f}x (1 kHz physics); "
              f"reduced model {red[60.0]:.0f}x on a 60 s run (goal >= 2000x), {red[600.0]:.0f}x "
              f"on a 10 min run: time per simulated second 10 min / 60 s "
              f"{red[60.0] / red[600.0]:.2f} (1: linear in the duration)")  # fmt: skip
    long_s = 600.0 if quick else 3600.0
    label = f"{long_s / 60:.0f} min"
    short = peak_rss_mb(60.0, "folder")
    cases = {sink: peak_rss_mb(long_s, sink) for sink in ("none", "folder", "rrd")}
    print(f"peak RSS, reduced mpi run: 1 min to a run folder {short:.0f} MB; {label}: no sink "
          f"{cases['none']:.0f} MB, run folder {cases['folder']:.0f} MB, run folder + .rrd "
          f"{cases['rrd']:.0f} MB")  # fmt: skip
    print(f"  sink cost over no sink ({label}): run folder {cases['folder'] / cases['none']:.2f}, "
          f".rrd {cases['rrd'] / cases['none']:.2f} (goal: ~1, the sinks stream to disk); growth "
          f"1 min -> {label} {cases['folder'] - short:+.0f} MB (the 100 Hz commands, held whole: "
          f"{48 * 100 * (long_s - 60) / 1e6:.0f} MB; blocks, physics, noise and IMU are "
          "streamed)")  # fmt: skip


if __name__ == "__main__":
    main()
