"""Forcing functions of the tracking tasks: sums of sines on the measurement time's grid.

Chapter 2's roll task (Table 2.2: twelve sines each for the disturbance and the target, on
multiples k of the base frequency 1 / 81.92 s, no phase) and Chapter 6's pitch task (Table 6.2:
ten sines each with phases, Eq 6.4). A run lasts 90 s at 100 Hz: 8.08 s run-in, then the
81.92 s measurement window (§6.3.4).

Examples
--------
>>> fd, ft = roll_task()
>>> fd.omega_rad_s.size, round(float(fd.omega_rad_s[0]), 4)
(12, 0.3835)

"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]

#: Measurement time [s] (2^13 samples at 100 Hz) and run-in [s] (§6.3.4).
MEASUREMENT_S = 81.92
RUN_IN_S = 8.08
RATE_HZ = 100.0

#: Table 2.2: k, amplitude [rad] of the disturbance (1) and target (2) forcing functions.
TABLE_2_2 = {
    "disturbance": (
        (5, 8, 11, 17, 28, 46, 59, 82, 106, 137, 178, 211),
        (
            0.0020,
            0.0046,
            0.0074,
            0.0125,
            0.0184,
            0.0235,
            0.0264,
            0.0316,
            0.0382,
            0.0489,
            0.0669,
            0.0848,
        ),
    ),
    "target": (
        (6, 9, 13, 19, 29, 47, 61, 83, 107, 139, 179, 213),
        (
            0.0568,
            0.0495,
            0.0397,
            0.0278,
            0.0162,
            0.0078,
            0.0052,
            0.0034,
            0.0024,
            0.0019,
            0.0015,
            0.0014,
        ),
    ),
}

#: Table 6.2: frequency [rad/s], amplitude [deg], phase [rad].
TABLE_6_2 = {
    "disturbance": (
        (0.383, 0.844, 1.764, 2.838, 3.912, 5.446, 7.747, 10.508, 13.116, 17.334),
        (0.344, 0.452, 0.275, 0.180, 0.190, 0.235, 0.315, 0.432, 0.568, 0.848),
        (-1.731, 4.016, -1.194, 4.938, 5.442, 2.274, 1.636, 2.973, 3.429, 3.486),
    ),
    "target": (
        (0.460, 0.997, 2.071, 3.145, 4.065, 5.599, 7.900, 10.661, 14.880, 17.564),
        (0.698, 0.488, 0.220, 0.119, 0.080, 0.049, 0.031, 0.023, 0.018, 0.016),
        (1.288, 6.089, 5.507, 1.734, 2.019, 0.441, 5.175, 3.415, 1.066, 3.479),
    ),
}


@dataclass(frozen=True)
class ForcingFunction:
    """A sum of sines, Eq 6.4: f(t) = sum A_k sin(w_k t + phi_k).

    Attributes
    ----------
    omega_rad_s, amplitude, phase_rad : ndarray
        Frequencies [rad/s], amplitudes and phases [rad].
    name : str
        ``disturbance`` or ``target``.

    """

    omega_rad_s: FloatArray
    amplitude: FloatArray
    phase_rad: FloatArray
    name: str = ""

    def __call__(self, t: ArrayLike) -> FloatArray:
        """Evaluate at times ``t`` [s] (t = 0 at the start of the run)."""
        tt = np.asarray(t, dtype=float)
        return np.sin(np.multiply.outer(tt, self.omega_rad_s) + self.phase_rad) @ self.amplitude

    def bins(self, measurement_s: float = MEASUREMENT_S) -> NDArray[np.int64]:
        """FFT bins of the lines over a window of ``measurement_s`` (integer periods)."""
        return np.round(self.omega_rad_s * measurement_s / (2 * np.pi)).astype(np.int64)

    @property
    def variance(self) -> float:
        """Variance of the signal [units^2]."""
        return float(np.sum(self.amplitude**2) / 2)


def _on_grid(k: ArrayLike) -> FloatArray:
    return 2 * np.pi * np.asarray(k, dtype=float) / MEASUREMENT_S


def roll_task() -> tuple[ForcingFunction, ForcingFunction]:
    """Chapter 2's disturbance and target forcing functions (Table 2.2), in rad."""
    out = []
    for name in ("disturbance", "target"):
        k, a = TABLE_2_2[name]
        out.append(ForcingFunction(_on_grid(k), np.array(a), np.zeros(len(k)), name))
    return out[0], out[1]


def pitch_task() -> tuple[ForcingFunction, ForcingFunction]:
    """Chapter 6's disturbance and target forcing functions (Table 6.2), in rad.

    The frequencies of Table 6.2 are printed to three decimals; they are put on the nearest
    multiple of the base frequency 1 / 81.92 s so that the window holds whole periods.
    """
    out = []
    for name in ("disturbance", "target"):
        w, a, phi = TABLE_6_2[name]
        k = np.round(np.asarray(w) * MEASUREMENT_S / (2 * np.pi))
        out.append(ForcingFunction(_on_grid(k), np.radians(a), np.array(phi), name))
    return out[0], out[1]


def run_times(rate_hz: float = RATE_HZ) -> FloatArray:
    """Sample times of one run: run-in plus measurement, [0, 90) s."""
    return np.arange(round((RUN_IN_S + MEASUREMENT_S) * rate_hz)) / rate_hz
