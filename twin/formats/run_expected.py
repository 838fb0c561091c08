"""What a recorded run's IMU should read, given its commands: the yardstick of its checks.

The nominal configuration of a run's ``meta.json`` (its linear blocks: platform filter, delay,
resonance, lead, gain and sensor filter; no noise, no backlash, no platform dynamics) moves
the cabin as the commands ask, and an ideal IMU at the run's mount reads that motion: specific
force with gravity and angular rate, thesis cabin axes (x forward, y right, z down; at rest
(0, 0, -9.81) m/s^2), as :func:`twin.chain.imu.specific_force`, through its axes' rotation
where the configuration has an ``imu_alignment``. Both that reading and the
recorded IMU (without single-sample glitches) are band-limited alike (:data:`BAND_HZ`, zero
phase) onto one grid of :data:`GRID_HZ`, the recorded one :data:`SEARCH_S` beyond the
commands on either side, so that they can be cross-correlated over lags
(:class:`Comparison`). What is compared is cheap: no simulation, a few FFTs and filters per
run.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage, signal

from twin.chain.config import MotionSystem
from twin.chain.imu import rotate_readings
from twin.chain.response import GRAVITY_BASE
from twin.chain.trajectory import Trajectory, interp_columns
from twin.core.frames import angular_motion, rotation_matrix

if TYPE_CHECKING:
    from twin.formats.runs import RecordedRun

FloatArray = NDArray[np.float64]
#: Rate of the grid commands and IMU are compared on [Hz] (the App. C.2.3 analysis grid).
GRID_HZ = 100.0
#: Both are low-passed here [Hz] (the App. C.2.3 FIR's cutoff): what the analyses look at.
BAND_HZ = 15.0
#: Order of the zero-phase Butterworth low-pass (applied forwards and backwards).
BAND_ORDER = 4
#: Lags searched on either side of the commands' clock [s]: a clock offset of a few tenths of
#: a second to seconds (a logger started late, stamps of another epoch) shows within it.
SEARCH_S = 2.0
#: The recorded IMU goes through a running median of this many samples first: a single-sample
#: glitch (a logger's spike of 12 g) would otherwise dominate the band-limited signal and its
#: correlations; any motion within the band passes it nearly unchanged.
DESPIKE_SAMPLES = 3
#: Least time commands and IMU must cover for their motion to be compared [s].
MIN_COMPARED_S = 2.0


def nominal_pose(commands: Trajectory, config: MotionSystem) -> Trajectory:
    """Return the pose the configuration's linear blocks make of the commands.

    The blocks' frequency response (:meth:`~twin.chain.config.MotionSystem.response_at_hz`)
    applied by a zero-padded FFT to the commands' offsets from their first sample (held
    before it, as the chain starts in steady state).
    """
    x = commands.values - commands.values[0]
    nfft = 1 << int(np.ceil(np.log2(2 * commands.n)))
    f = np.fft.rfftfreq(nfft, 1.0 / commands.rate_hz)
    y = np.fft.irfft(np.fft.rfft(x, nfft, axis=0) * config.response_at_hz(f), nfft, axis=0)
    return commands.replace(y[: commands.n] + commands.values[0])


def ideal_imu(pose: Trajectory, mount: ArrayLike, t: FloatArray) -> FloatArray:
    """Return what an ideal IMU at ``mount`` reads at times ``t`` on a cabin following ``pose``.

    Returns
    -------
    ndarray, shape (len(t), 6)
        Specific force ax, ay, az [m/s^2] (gravity included) and rates p, q, r [rad/s],
        cabin axes.

    """
    p, v, a = pose.derivatives(t, 2)
    angles = p[:, 3:]
    T = rotation_matrix(angles)
    omega_b, omega_dot_b = angular_motion(angles, v[:, 3:], a[:, 3:])
    omega = np.einsum("nji,nj->ni", T, omega_b)
    omega_dot = np.einsum("nji,nj->ni", T, omega_dot_b)
    r = np.broadcast_to(np.asarray(mount, dtype=float), omega.shape)
    force = (np.einsum("nji,nj->ni", T, a[:, :3] - GRAVITY_BASE) + np.cross(omega_dot, r)
             + np.cross(omega, np.cross(omega, r)))  # fmt: skip
    return np.hstack([force, omega])


def band_limited(x: FloatArray, rate_hz: float) -> FloatArray:
    """Low-pass the columns of ``x`` (sampled at ``rate_hz``) to :data:`BAND_HZ`, zero phase."""
    sos = signal.butter(BAND_ORDER, BAND_HZ, fs=rate_hz, output="sos")
    centre = np.median(x, axis=0)
    return signal.sosfiltfilt(sos, x - centre, axis=0) + centre


@dataclass(frozen=True, eq=False)
class Comparison:
    """A run's IMU beside the nominal twin's ideal reading of its commands, on one grid.

    Attributes
    ----------
    expected : ndarray, shape (n, 6)
        The nominal twin's ideal IMU reading over the commands (band-limited).
    measured : ndarray, shape (n + 2 k, 6)
        The recorded IMU (band-limited) from ``k`` grid steps before the commands to ``k``
        after them; NaN where it was not recorded.
    lags_s : ndarray, shape (2 k + 1,)
        The lags the correlations are computed at [s] (positive: the IMU later).

    """

    expected: FloatArray
    measured: FloatArray
    lags_s: FloatArray

    @property
    def aligned(self) -> FloatArray:
        """The recorded IMU over the commands' own times (lag zero), NaN where not recorded."""
        k = (len(self.lags_s) - 1) // 2
        return self.measured[k : k + len(self.expected)]

    def correlation(self, channels: list[int]) -> Correlation:
        """Correlate the given channels at every lag (each scaled by the expected's sd)."""
        n = len(self.expected)
        recorded = np.isfinite(self.measured[:, 0]).astype(float)
        k = len(self.lags_s)
        num, dp, dm = (np.empty((k, len(channels))) for _ in range(3))
        ones = np.ones(n)
        for j, c in enumerate(channels):
            e = self.expected[:, c] - self.expected[:, c].mean()
            sd = e.std()
            e = e / sd
            m = np.where(recorded > 0, self.measured[:, c], 0.0)
            m = np.where(recorded > 0, m - m[recorded > 0].mean(), 0.0) / sd
            num[:, j] = signal.correlate(m, e, mode="valid")
            dp[:, j] = signal.correlate(recorded, e**2, mode="valid")
            dm[:, j] = signal.correlate(m**2, ones, mode="valid")
        covered = signal.correlate(recorded, ones, mode="valid")
        return Correlation(self.lags_s, num, dp, dm, covered / GRID_HZ)


@dataclass(frozen=True, eq=False)
class Correlation:
    """Sums of products of expected and recorded channels at each lag (see :class:`Comparison`).

    Attributes
    ----------
    lags_s : ndarray, shape (k,)
        Lags [s].
    products, expected_power, measured_power : ndarray, shape (k, channels)
        Per lag and channel: sum of expected x recorded, of expected^2 and of recorded^2 over
        the samples both cover.
    covered_s : ndarray, shape (k,)
        Time both cover at each lag [s].

    """

    lags_s: FloatArray
    products: FloatArray
    expected_power: FloatArray
    measured_power: FloatArray
    covered_s: FloatArray

    def total(self) -> FloatArray:
        """Correlation coefficient of all channels together at each lag (NaN: too little)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            rho = self.products.sum(1) / np.sqrt(
                self.expected_power.sum(1) * self.measured_power.sum(1)
            )
        return np.where(self.covered_s >= MIN_COMPARED_S, rho, np.nan)

    def per_channel(self) -> FloatArray:
        """Correlation coefficient of each channel at each lag, shape (k, channels)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            rho = self.products / np.sqrt(self.expected_power * self.measured_power)
        return np.where((self.covered_s >= MIN_COMPARED_S)[:, None], rho, np.nan)


def compare(run: RecordedRun, config: MotionSystem) -> Comparison | None:
    """Put a run's IMU beside the nominal twin's ideal reading of its commands.

    Returns None when commands or IMU cover less than :data:`MIN_COMPARED_S`, alone or
    within :data:`SEARCH_S` of each other: there is too little to compare.
    """
    c = run.commands
    t_imu, imu = run.imu_t, run.imu
    if c.duration < MIN_COMPARED_S or t_imu[-1] - t_imu[0] < MIN_COMPARED_S:
        return None
    n = int(np.floor(c.duration * GRID_HZ + 1e-9)) + 1
    search = round(min(SEARCH_S, c.duration / 3) * GRID_HZ)
    t = c.t0 + np.arange(n) / GRID_HZ
    ideal = ideal_imu(nominal_pose(c, config), run.meta["imu"]["position_m"], t)
    expected = band_limited(rotate_readings(ideal, config.imu_rotation), GRID_HZ)
    grid = c.t0 + np.arange(-search, n + search) / GRID_HZ
    rate = (len(t_imu) - 1) / (t_imu[-1] - t_imu[0])
    inside = (grid >= t_imu[0]) & (grid <= t_imu[-1])
    if inside.sum() < MIN_COMPARED_S * GRID_HZ:
        return None
    measured = np.full((grid.size, 6), np.nan)
    despiked = ndimage.median_filter(imu, size=(DESPIKE_SAMPLES, 1), mode="nearest")
    measured[inside] = interp_columns(grid[inside], t_imu, band_limited(despiked, rate))
    return Comparison(expected, measured, np.arange(-search, search + 1) / GRID_HZ)
