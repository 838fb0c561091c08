"""Speed work must not change a single bit: seeded runs against stored figures.

Each case below runs a seeded piece of the twin (open-loop runs on both platforms, with every
block and extension; the pilot in the loop of Chapter 6 and the loop of Chapter 2; a
describing-function sweep) and reduces its outputs to SHA-256 digests of the float64 bytes,
stored in ``tests/data/stored_figures.json`` together with a few values of every array. A
change that is only about speed must leave every digest as it is.

Bit-identity holds for one numerical environment: the stored file names the NumPy, SciPy and
MuJoCo versions, the machine and NumPy's CPU features it was made with. Elsewhere (another
SIMD path of ``sin``, another MuJoCo) the digests may differ in the last bits, so there the
stored values are compared within 1e-9 of each array's scale instead: still a test of the
results, and it says which of the two checks ran.

A change that is meant to change results re-stores the figures, and says why in its commit::

    python tests/test_stored_figures.py --store
"""

from __future__ import annotations

import hashlib
import json
import platform
import sys
from collections.abc import Callable
from pathlib import Path

import mujoco
import numpy as np
import pytest
import scipy
from configurations import everything

STORE = Path(__file__).parent / "data" / "stored_figures.json"
#: Values of each array kept (evenly spaced) for the comparison off the stored environment.
VALUES = 48
#: Relative tolerance off the stored environment (of each array's largest magnitude).
RTOL = 1e-9


def _commands(seconds: float, rate: float = 100.0):
    """Smooth surge, heave and pitch multi-sines with a fade-in."""
    from twin.chain.trajectory import Trajectory

    t = np.arange(round(seconds * rate) + 1) / rate
    fade = np.clip(t / 1.5, 0, 1)
    v = np.zeros((t.size, 6))
    v[:, 0] = fade * 0.01 * np.sin(2 * np.pi * 0.8 * t)
    v[:, 2] = fade * (0.02 * np.sin(2 * np.pi * 0.35 * t) + 0.004 * np.sin(2 * np.pi * 2.15 * t))
    v[:, 3] = fade * 0.01 * np.sin(2 * np.pi * 0.45 * t)
    v[:, 4] = fade * (0.03 * np.sin(2 * np.pi * 0.55 * t) + 0.005 * np.sin(2 * np.pi * 3.35 * t))
    v[:, 5] = fade * 0.01 * np.sin(2 * np.pi * 0.25 * t)
    return Trajectory(rate, v)


def _open_loop(config, seconds: float, model: str, seed: int) -> dict[str, np.ndarray]:
    from twin.chain.simulate import simulate

    sim = simulate(config, _commands(seconds), model, seed=seed)
    r = sim.response
    counts = np.array([*sim.limits.samples.values(), sim.imu.saturated], dtype=float)
    return {"imu.accel": sim.imu.accel, "imu.gyro": sim.imu.gyro, "imu.t": sim.imu.t,
            "pose": r.pose, "command": r.command, "omega_dot": r.omega_dot, "legs": r.legs,
            "limits": counts}  # fmt: skip


def _pilot() -> dict[str, np.ndarray]:
    from twin.pilot.models.pitch import PitchPilot, simulate_pitch

    runs = simulate_pitch(PitchPilot(), "condition-8", runs=2, seed=3, remnant_scale=1.0)
    return {"e": runs.e, "u": runs.u, "theta": runs.theta, "theta_felt": runs.theta_felt}


def _chapter_2() -> dict[str, np.ndarray]:
    from twin.pilot.models.forcing import roll_task
    from twin.pilot.models.loop import remnant_scale_for, simulate_loop
    from twin.pilot.models.model import RollPilot

    fd, ft = roll_task()
    scale = remnant_scale_for(RollPilot(), fd, ft, 0.1)
    loop = simulate_loop(RollPilot(), fd, ft, runs=3, seed=5, remnant_scale=scale)
    return {"scale": np.array([scale]), "e": loop.e, "u": loop.u, "x": loop.x, "n": loop.n}


def _describing_function() -> dict[str, np.ndarray]:
    from twin.agard.df import sweep
    from twin.measurement.measure import Bench, configure

    res = sweep(Bench(configure("mpi"), "reduced", seed=2), ("heave",), signals=(1, 2))["heave"]
    return {"f": res.frequencies_hz, "h.real": res.response.real, "h.imag": res.response.imag,
            "noise": res.noise, "delay": np.array([res.delay_s])}  # fmt: skip


#: name -> the seeded run, its outputs by name (about 3 s for all of them).
CASES: dict[str, Callable[[], dict[str, np.ndarray]]] = {
    "reduced-mpi-60s": lambda: _open_loop("mpi", 60.0, "reduced", 1),
    "reduced-everything-srs-20s": lambda: _open_loop(everything(), 20.0, "reduced", 4),
    "full-mpi-3s": lambda: _open_loop("mpi", 3.0, "full", 2),
    "full-everything-srs-3s": lambda: _open_loop(everything(), 3.0, "full", 4),
    "pilot-condition-8": _pilot,
    "chapter-2-loop": _chapter_2,
    "df-mpi-heave-reduced": _describing_function,
}


def environment() -> dict[str, object]:
    """What bit-identity depends on: library versions, BLAS, machine, CPU and its features.

    OpenBLAS picks its kernels by the CPU at run time, so the CPU model is part of it.
    """
    from numpy._core._multiarray_umath import __cpu_features__

    blas = np.show_config(mode="dicts")["Build Dependencies"]["blas"]
    return {"numpy": np.__version__, "scipy": scipy.__version__, "mujoco": mujoco.__version__,
            "blas": f"{blas.get('name')} {blas.get('version')}", "machine": platform.machine(),
            "cpu": _cpu_model(),
            "cpu_features": sorted(k for k, on in __cpu_features__.items() if on)}  # fmt: skip


def _cpu_model() -> str:
    """The CPU's model name (Linux), or the platform's processor string."""
    info = Path("/proc/cpuinfo")
    lines = info.read_text().splitlines() if info.is_file() else []
    names = [line.split(":", 1)[1].strip() for line in lines if line.startswith("model name")]
    return names[0] if names else platform.processor()


def digest(a: np.ndarray) -> str:
    """SHA-256 of an array's float64 values (C order, little-endian) and its shape."""
    x = np.ascontiguousarray(a, dtype="<f8")
    return hashlib.sha256(repr(x.shape).encode() + x.tobytes()).hexdigest()


def values(a: np.ndarray) -> list[float]:
    """About :data:`VALUES` evenly spaced values of an array, flattened (all of a short one)."""
    x = np.ravel(np.asarray(a, dtype=float))
    idx = np.unique(np.linspace(0, x.size - 1, min(VALUES, x.size)).round().astype(int))
    return x[idx].tolist()


def figures(name: str) -> dict[str, dict[str, object]]:
    """Run one case; return digest, shape and some values of each output."""
    out = CASES[name]()
    return {k: {"sha256": digest(v), "shape": list(np.shape(v)), "values": values(v)}
            for k, v in out.items()}  # fmt: skip


def store() -> None:
    """Run every case and write :data:`STORE`."""
    data = {"environment": environment(), "cases": {name: figures(name) for name in CASES}}
    STORE.parent.mkdir(exist_ok=True)
    STORE.write_text(json.dumps(data, indent=1) + "\n")
    print(f"stored {len(CASES)} cases in {STORE}")


def _stored() -> dict:
    return json.loads(STORE.read_text())


@pytest.mark.parametrize("name", list(CASES))
def test_results_equal_the_stored_figures(name):
    """Same seed, same bits as the stored figures (within 1e-9 on another environment)."""
    stored = _stored()
    want = stored["cases"][name]
    got = figures(name)
    assert sorted(got) == sorted(want), f"{name}: outputs {sorted(got)} != {sorted(want)}"
    exact = stored["environment"] == environment()
    for key, w in want.items():
        g = got[key]
        assert g["shape"] == w["shape"], f"{name}/{key}: shape {g['shape']} != {w['shape']}"
        if exact:
            if g["sha256"] != w["sha256"]:
                diff = np.abs(np.subtract(g["values"], w["values"])).max()
                pytest.fail(f"{name}/{key}: not bit-identical to the stored figures (largest "
                            f"difference over the stored values {diff:.3g})")  # fmt: skip
        else:
            a, b = np.asarray(g["values"]), np.asarray(w["values"])
            scale = max(float(np.abs(b).max()), 1e-300)
            assert np.abs(a - b).max() <= RTOL * scale, (
                f"{name}/{key}: differs from the stored figures by more than {RTOL:g} of its "
                f"scale (another numerical environment than the stored one, so not bit-compared)"
            )


def test_the_stored_environment_is_named():
    """The stored file says what its bits depend on (so a mismatch can be explained)."""
    env = _stored()["environment"]
    assert set(env) == set(environment())
    assert env["cpu_features"], "the stored environment lists NumPy's CPU features"


if __name__ == "__main__":
    if sys.argv[1:] != ["--store"]:
        sys.exit("usage: python tests/test_stored_figures.py --store")
    store()
