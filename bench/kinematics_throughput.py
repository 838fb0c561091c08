"""Throughput of the kinematics and of the full MuJoCo model, measured in one run.

Prints samples per second for inverse kinematics, Jacobian and forward kinematics on a 10 s,
1 kHz trajectory, the ratio of vectorised IK to a per-sample Python loop, and the full model's
raw `mj_step` real-time factor at its 1 kHz physics rate (the baseline the twin's
throughput is measured against).
"""

import time

import mujoco
import numpy as np

from twin.platform.facts import load_model
from twin.platform.geometry import load_geometry
from twin.platform.kinematics import forward, inverse, jacobian


def timed(fn, repeat=5):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def bench_platform(platform):
    """Print the throughput figures of one platform."""
    geo = load_geometry(platform)
    t = np.arange(0, 10, 0.001)
    pose = np.column_stack([0.1 * np.sin(t), 0.1 * np.cos(t), 0.05 * np.sin(2 * t),
                            0.1 * np.sin(3 * t), 0.1 * np.cos(t), 0.2 * np.sin(t)])  # fmt: skip
    n = len(t)
    lengths = inverse(geo, pose)
    t_ik = timed(lambda: inverse(geo, pose))
    t_loop = timed(lambda: [inverse(geo, p) for p in pose[:1000]], repeat=2) * n / 1000
    t_j = timed(lambda: jacobian(geo, pose))
    t_fk = timed(lambda: forward(geo, lengths), repeat=2)
    fk = forward(geo, lengths)
    model = load_model(platform)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    steps = 5000
    t_step = timed(lambda: mujoco.mj_step(model, data, nstep=steps), repeat=3)
    print(f"[{platform}] {n} samples")
    print(f"  inverse kinematics : {n / t_ik:12.0f} samples/s "
          f"(vectorised / per-sample loop = {t_loop / t_ik:.0f}x)")  # fmt: skip
    print(f"  Jacobian           : {n / t_j:12.0f} samples/s")
    print(f"  forward kinematics : {n / t_fk:12.0f} samples/s "
          f"({fk.iterations} Newton iterations max)")  # fmt: skip
    rtf = steps * model.opt.timestep / t_step
    print(f"  raw mj_step        : {steps / t_step:12.0f} steps/s = real-time factor "
          f"{rtf:.1f} at {1 / model.opt.timestep:.0f} Hz")  # fmt: skip


if __name__ == "__main__":
    for name in ("mpi", "srs"):
        bench_platform(name)
