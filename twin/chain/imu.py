"""Virtual IMU (ADIS16355 of App. C.1.2) and the thesis' post-processing (App. C.2.3).

:func:`specific_force` gives what an ideal accelerometer at a mount point reads (lever arm
included); :class:`VirtualImu` samples it and the angular rate at 819.2 Hz from the platform's
physics-rate response (linear interpolation: 819.2 Hz does not divide 1 kHz), reads it with
axes rotated on the cabin where the mount is misaligned (:func:`rotate_readings`), adds seeded
bias and white noise and saturates like the ADIS16355; :func:`postprocess` applies the
thesis' FIR and Savitzky-Golay filters and resamples to 100 Hz.

Sensor-noise defaults are ADIS16355 data-sheet figures (output noise without averaging:
accelerometers 35 mg rms, gyros 0.60 deg/s rms; bias in-run stability: 0.7 mg and
0.015 deg/s); the thesis gives no numbers for them. Set them to zero for an ideal IMU.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal

from twin.chain import kernels
from twin.chain.response import GRAVITY_BASE, PlatformResponse
from twin.chain.trajectory import interp_columns
from twin.core.errors import SignalError
from twin.core.frames import rotation_matrix

FloatArray = NDArray[np.float64]
G = 9.81


def specific_force(response: PlatformResponse, mount: ArrayLike) -> FloatArray:
    """Specific force at a point fixed to the cabin, in cabin axes [m/s^2].

    f = T^T (a - g) + omega_dot x r + omega x (omega x r), with T the cabin attitude (Eq A.2),
    a the UGP acceleration and g = (0, 0, 9.81) in the z-down base frame; a cabin at rest
    reads (0, 0, -9.81).

    Parameters
    ----------
    response : PlatformResponse
        Cabin motion.
    mount : array_like, shape (3,)
        Position of the sensor in the cabin frame, relative to the UGP [m].

    """
    return _truth(response, mount)[:, :3]


def _truth(
    response: PlatformResponse, mount: ArrayLike, out: FloatArray | None = None
) -> FloatArray:
    """Return what an ideal IMU at ``mount`` reads: specific force and rate, shape (n, 6)."""
    T = response.rotation
    if T is None:
        T = rotation_matrix(response.pose[:, 3:])
    r = np.asarray(mount, dtype=float)
    if r.shape != (3,):
        raise SignalError(f"an IMU mount is one point, shape (3,) [m]; got shape {r.shape}")
    if out is None:
        out = np.empty((len(response.t), 6))
    kernels.specific_force(T, response.acceleration, response.omega, response.omega_dot,
                           r, GRAVITY_BASE, out)  # fmt: skip
    return out


@dataclass(frozen=True)
class ImuSpec:
    """An IMU: where it sits, how fast it samples, how it errs.

    Attributes
    ----------
    position_m : tuple of float
        Mount in the cabin frame relative to the UGP [m].
    rate_hz : float
        Sample rate [Hz] (819.2 for the ADIS16355).
    accel_range, gyro_range : float
        Saturation [m/s^2, rad/s].
    accel_noise_sd, gyro_noise_sd : float
        White-noise standard deviation per sample [m/s^2, rad/s].
    accel_bias_sd, gyro_bias_sd : float
        Standard deviation of the constant per-run bias [m/s^2, rad/s].

    """

    position_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rate_hz: float = 819.2
    accel_range: float = 10.0 * G
    gyro_range: float = float(np.radians(300.0))
    accel_noise_sd: float = 0.035 * G
    gyro_noise_sd: float = float(np.radians(0.60))
    accel_bias_sd: float = 0.0007 * G
    gyro_bias_sd: float = float(np.radians(0.015))

    def __post_init__(self) -> None:
        """Check the values."""
        if len(self.position_m) != 3 or not np.all(np.isfinite(self.position_m)):
            raise SignalError(f"IMU position must be 3 finite numbers [m]; got {self.position_m}")
        for name in ("rate_hz", "accel_range", "gyro_range"):
            v = getattr(self, name)
            if not np.isfinite(v) or v <= 0:
                raise SignalError(f"IMU {name} must be > 0; got {v}")
        for name in ("accel_noise_sd", "gyro_noise_sd", "accel_bias_sd", "gyro_bias_sd"):
            v = getattr(self, name)
            if not np.isfinite(v) or v < 0:
                raise SignalError(f"IMU {name} must be >= 0; got {v}")

    def ideal(self) -> ImuSpec:
        """Return the same IMU without noise and bias."""
        return self.with_noise(0.0)

    def with_noise(self, scale: float) -> ImuSpec:
        """Return the same IMU with its noise and bias standard deviations times ``scale``.

        A better (``scale`` < 1) or a worse unit than the data sheet's.
        """
        k = float(scale)
        if not np.isfinite(k) or k < 0:
            raise SignalError(f"IMU noise scale must be a finite number >= 0; got {scale!r}")
        return ImuSpec(self.position_m, self.rate_hz, self.accel_range, self.gyro_range,
                       self.accel_noise_sd * k, self.gyro_noise_sd * k,
                       self.accel_bias_sd * k, self.gyro_bias_sd * k)  # fmt: skip


@dataclass(frozen=True, eq=False)
class ImuRecord:
    """IMU samples.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s].
    accel : ndarray, shape (n, 3)
        Specific force (ax, ay, az) [m/s^2], cabin axes.
    gyro : ndarray, shape (n, 3)
        Angular rate (p, q, r) [rad/s], cabin axes.
    saturated : int
        Samples in which any channel hit its range.

    """

    t: FloatArray
    accel: FloatArray
    gyro: FloatArray
    saturated: int = 0

    @property
    def rate_hz(self) -> float:
        """Sample rate [Hz]."""
        return (len(self.t) - 1) / float(self.t[-1] - self.t[0])


def rotate_readings(values: FloatArray, rotation: ArrayLike | None) -> FloatArray:
    """Return what an IMU whose axes are rotated by ``rotation`` reads of ``values``.

    Parameters
    ----------
    values : ndarray, shape (n, 6)
        Specific force (ax, ay, az) and angular rate (p, q, r) in cabin axes.
    rotation : array_like, shape (3, 3), or None
        R, taking the IMU's axes to the cabin's
        (:func:`~twin.chain.extensions.imu_rotation`); None: a well-mounted IMU.

    Returns
    -------
    ndarray, shape (n, 6)
        Each triad as R^T v, a new array; ``values`` itself where ``rotation`` is None.

    Examples
    --------
    >>> import numpy as np
    >>> R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # yawed 90 deg
    >>> rotate_readings(np.array([[1.0, 0.0, 0.0, 0.0, 2.0, 0.0]]), R)  # x reads as -y
    array([[ 0., -1.,  0.,  2.,  0.,  0.]])

    """
    if rotation is None:
        return values
    R = np.asarray(rotation, dtype=float)
    if R.shape != (3, 3):
        raise SignalError(f"an IMU rotation is a 3 x 3 matrix; got shape {R.shape}")
    out = np.empty_like(values)
    out[:, :3] = values[:, :3] @ R  # rows: (R^T v)^T = v^T R
    out[:, 3:] = values[:, 3:] @ R
    return out


class VirtualImu:
    """Sample a platform response like the ADIS16355, chunk by chunk.

    Parameters
    ----------
    spec : ImuSpec
        The sensor.
    seed : int or numpy.random.Generator or None
        Seed for bias and noise (same seed, same bits).
    rotation : array_like, shape (3, 3), optional
        The IMU's axes rotated on the cabin (an ``imu_alignment``,
        :func:`~twin.chain.extensions.imu_rotation`): the sensing elements read the rotated
        motion, and their bias, noise and saturation act in their own axes after it. The
        random draws are the same with or without it (same seed: the same noise). None: a
        well-mounted IMU.

    """

    def __init__(
        self,
        spec: ImuSpec,
        seed: int | np.random.Generator | None = 0,
        rotation: ArrayLike | None = None,
    ) -> None:
        self.spec = spec
        self.rotation = None if rotation is None else np.asarray(rotation, dtype=float)
        rotate_readings(np.zeros((0, 6)), self.rotation)  # a malformed one is refused here
        self._rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        self._bias = np.concatenate(
            [self._rng.normal(0, spec.accel_bias_sd, 3), self._rng.normal(0, spec.gyro_bias_sd, 3)]
        )
        self._next = 0  # index of the next IMU sample
        self._carry: tuple[FloatArray, FloatArray] | None = None  # last platform sample

    def feed(self, response: PlatformResponse) -> ImuRecord:
        """Return the IMU samples that fall within this chunk (and the gap before it)."""
        t, carried = response.t, int(self._carry is not None)
        truth = np.empty((carried + t.size, 6))  # the last chunk's last sample first
        if self._carry is not None:
            t = np.concatenate([self._carry[0], t])
            truth[0] = self._carry[1]
        _truth(response, self.spec.position_m, truth[carried:])
        if self._next == 0 and self._carry is None:
            self._t0 = float(t[0])
        last = int(np.floor((t[-1] - self._t0) * self.spec.rate_hz + 1e-9))
        idx = np.arange(self._next, last + 1)
        ti = self._t0 + idx / self.spec.rate_hz
        values = interp_columns(ti, t, truth)
        self._next = last + 1
        self._carry = (t[-1:].copy(), truth[-1].copy())
        values = np.ascontiguousarray(values)  # a fresh array: the errors go in place
        values = rotate_readings(values, self.rotation)  # the truth as the rotated axes read it
        sd = np.repeat([self.spec.accel_noise_sd, self.spec.gyro_noise_sd], 3)
        noise = self._rng.standard_normal(values.shape)
        rng = np.repeat([self.spec.accel_range, self.spec.gyro_range], 3)
        hit = kernels.sensor_errors(values, self._bias, noise, sd, rng)
        return ImuRecord(ti, values[:, :3], values[:, 3:], hit)

    @staticmethod
    def concatenate(parts: list[ImuRecord]) -> ImuRecord:
        """Join consecutive chunks."""
        return ImuRecord(
            np.concatenate([p.t for p in parts]),
            np.concatenate([p.accel for p in parts]),
            np.concatenate([p.gyro for p in parts]),
            sum(p.saturated for p in parts),
        )


#: App. C.2.3 filter settings.
FIR_TAPS, FIR_CUTOFF_HZ, FIR_CHEBWIN_DB = 201, 15.0, 70.0
SG_ORDER, SG_POINTS = 9, 69


@dataclass(frozen=True, eq=False)
class ProcessedImu:
    """IMU data after App. C.2.3: filtered, differentiated, at the output rate.

    Attributes
    ----------
    t : ndarray, shape (m,)
        Time [s].
    accel : ndarray, shape (m, 3)
        FIR-filtered specific force [m/s^2].
    gyro : ndarray, shape (m, 3)
        FIR-filtered angular rate [rad/s].
    angular_acceleration : ndarray, shape (m, 3)
        Savitzky-Golay derivative of the rates, FIR-filtered [rad/s^2].

    """

    t: FloatArray
    accel: FloatArray
    gyro: FloatArray
    angular_acceleration: FloatArray


def fir_filter(rate_hz: float) -> FloatArray:
    """Return the App. C.2.3 FIR: 201 taps, 15 Hz, Chebyshev window with 70 dB sidelobes."""
    return signal.firwin(FIR_TAPS, FIR_CUTOFF_HZ, window=("chebwin", FIR_CHEBWIN_DB), fs=rate_hz)


def _zero_phase(taps: FloatArray, x: FloatArray) -> FloatArray:
    """Apply a linear-phase FIR with its delay removed (edges padded with the end values)."""
    half = len(taps) // 2
    padded = np.concatenate([np.repeat(x[:1], half, 0), x, np.repeat(x[-1:], half, 0)])
    return signal.fftconvolve(padded, taps[:, None], mode="valid", axes=0)


def postprocess(record: ImuRecord, rate_hz: float = 100.0) -> ProcessedImu:
    """Apply the thesis' post-processing (App. C.2.3) and resample.

    Accelerations and rates: the 201-tap FIR (no phase shift: its 100-sample delay is
    removed). Angular acceleration: Savitzky-Golay differentiator (order 9, 69 points) on
    the rates, then the FIR. All are then sampled at ``rate_hz`` from the first IMU sample.

    Parameters
    ----------
    record : ImuRecord
        Raw IMU samples.
    rate_hz : float
        Output rate [Hz] (100 Hz in the thesis).

    """
    if len(record.t) < SG_POINTS:
        raise SignalError(f"post-processing needs at least {SG_POINTS} IMU samples")
    fs = record.rate_hz
    taps = fir_filter(fs)
    acc = _zero_phase(taps, record.accel)
    gyro = _zero_phase(taps, record.gyro)
    dgyro = signal.savgol_filter(record.gyro, SG_POINTS, SG_ORDER, deriv=1, delta=1 / fs, axis=0)
    alpha = _zero_phase(taps, dgyro)
    t_out = np.arange(record.t[0], record.t[-1] + 1e-12, 1.0 / rate_hz)

    def at(x: FloatArray) -> FloatArray:
        return interp_columns(t_out, record.t, x)

    return ProcessedImu(t_out, at(acc), at(gyro), at(alpha))
