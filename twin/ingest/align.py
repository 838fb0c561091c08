"""Estimates an import needs from the data: the lag between two clocks, the IMU's mount.

:func:`lag_s` finds the shift between two recordings of related signals (band-limited
cross-correlation, up-sampled and refined by a parabola: well under a sample at 100 Hz).

:func:`estimate_mount` finds where on the cabin an accelerometer sits. On a rigid cabin an
accelerometer at ``r`` from the UGP reads ``f_ugp + omega_dot x r + omega x (omega x r)``
(:func:`twin.chain.imu.specific_force`); the terms in ``r`` are linear in ``r`` and built from
the *measured* gyros, so ``r`` is a least-squares fit of the measured specific force minus the
nominal twin's at the UGP. What the nominal twin gets wrong about the rotation (a gain, a
lag) reaches the accelerometers through gravity and would bias ``r``; nuisance regressors take
it: per axis the measured attitude (integrated gyros, the gravity terms) and the measured
rates (a small lag of them). Only rotation shows a mount: in runs that do not rotate the
mount is not identifiable, and does not matter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import signal

FloatArray = NDArray[np.float64]
#: A mount is only identifiable when the measured angular acceleration has at least this RMS
#: [rad/s^2] (about a 0.6 deg pitch multi-sine up to 2 Hz).
MIN_ANGULAR_ACCELERATION = 0.05
#: Length of the FIR that maps the nominal rotation onto the measured one [samples].
PROJECTION_TAPS = 21
#: A mount coordinate is kept when it is this many standard deviations from zero.
MOUNT_SIGNIFICANCE = 4.0


def lag_s(
    reference: FloatArray,
    delayed: FloatArray,
    rate_hz: float,
    max_lag_s: float,
    centre_s: float = 0.0,
    upsample: int = 16,
) -> tuple[float, float]:
    """Return the lag of ``delayed`` behind ``reference`` and the peak correlation.

    Parameters
    ----------
    reference, delayed : ndarray, shape (n, k) and (m, k)
        Related signals sampled at ``rate_hz`` from their own first sample (columns are
        compared pairwise; each is normalised, so units do not matter).
    rate_hz : float
        Sample rate of both [Hz].
    max_lag_s : float
        Lags within ``centre_s +- max_lag_s`` are searched.
    centre_s : float
        Centre of the search [s].
    upsample : int
        Interpolation factor of the cross-correlation before the parabolic refinement.

    Returns
    -------
    lag : float
        ``delayed[t + lag]`` matches ``reference[t]`` best [s].
    peak : float
        Normalised correlation at the lag (1: identical shapes).

    """
    x = np.atleast_2d(np.asarray(reference, float).T).T
    y = np.atleast_2d(np.asarray(delayed, float).T).T
    x = x - x.mean(axis=0)
    y = y - y.mean(axis=0)
    keep = (x.std(axis=0) > 0) & (y.std(axis=0) > 0)
    if not keep.any():
        return float("nan"), 0.0
    x, y = x[:, keep] / x[:, keep].std(axis=0), y[:, keep] / y[:, keep].std(axis=0)
    nfft = 1 << int(np.ceil(np.log2(len(x) + len(y))))
    cross = (np.conj(np.fft.rfft(x, nfft, axis=0)) * np.fft.rfft(y, nfft, axis=0)).sum(axis=1)
    cc = np.fft.irfft(cross, nfft * upsample) * upsample
    lags = np.arange(nfft * upsample, dtype=float)
    lags[lags >= nfft * upsample / 2] -= nfft * upsample
    lags /= rate_hz * upsample
    inside = np.flatnonzero(np.abs(lags - centre_s) <= max_lag_s)
    if inside.size < 3:
        return float("nan"), 0.0
    k = inside[np.argmax(cc[inside])]
    a, b, c = cc[k - 1], cc[k], cc[(k + 1) % cc.size]
    frac = 0.5 * (a - c) / (a - 2 * b + c) if a - 2 * b + c < 0 else 0.0
    peak = float(b / (min(len(x), len(y)) * x.shape[1]))
    return float(lags[k] + frac / (rate_hz * upsample)), peak


@dataclass(frozen=True)
class MountEstimate:
    """The IMU's position on the cabin as the data show it.

    Attributes
    ----------
    position_m : tuple of float
        Estimated (x, y, z) relative to the UGP, cabin axes [m] (NaN when not identifiable).
    std_m : tuple of float
        Standard deviations [m].
    identifiable : bool
        Whether the runs rotate enough to show a mount.
    angular_acceleration_rms : float
        RMS of the measured angular acceleration [rad/s^2].

    """

    position_m: tuple[float, float, float]
    std_m: tuple[float, float, float]
    identifiable: bool
    angular_acceleration_rms: float

    def significant(self) -> tuple[float, float, float]:
        """Return the position with coordinates within :data:`MOUNT_SIGNIFICANCE` sd set to 0."""
        if not self.identifiable:
            return (0.0, 0.0, 0.0)
        return tuple(  # type: ignore[return-value]
            p if abs(p) > MOUNT_SIGNIFICANCE * s else 0.0
            for p, s in zip(self.position_m, self.std_m, strict=True)
        )


def _skew(w: FloatArray) -> FloatArray:
    z = np.zeros(len(w))
    return np.stack(
        [np.stack([z, -w[:, 2], w[:, 1]], 1), np.stack([w[:, 2], z, -w[:, 0]], 1),
         np.stack([-w[:, 1], w[:, 0], z], 1)], 1)  # fmt: skip


def predictable(
    measured: FloatArray, predicted: FloatArray, taps: int = PROJECTION_TAPS
) -> FloatArray:
    """Return the part of ``measured`` a short centred FIR of ``predicted`` explains.

    The nominal twin's prediction is noise-free but may be wrong in gain, lag or bandwidth;
    a least-squares FIR of it (``taps`` samples, centred) follows the measured signal in all
    of these and leaves its noise out.
    """
    out = np.zeros_like(measured)
    half = taps // 2
    for k in range(measured.shape[1]):
        x = predicted[:, k]
        if not np.any(x):
            continue
        X = np.column_stack([np.roll(x, j) for j in range(-half, half + 1)])
        X[:half] = X[-half:] = 0.0  # no wrap-around at the ends
        coef, *_ = np.linalg.lstsq(X, measured[:, k], rcond=None)
        out[:, k] = X @ coef
    return out


def estimate_mount(
    t: FloatArray,
    residual: FloatArray,
    gyro: FloatArray,
    angular_acceleration: FloatArray,
    predicted_angular_acceleration: FloatArray,
    band_hz: tuple[float, float] = (0.05, 15.0),
) -> MountEstimate:
    """Least-squares IMU mount from accelerometer residuals (see module docstring).

    Parameters
    ----------
    t : ndarray, shape (n,)
        Uniform time grid [s].
    residual : ndarray, shape (n, 3)
        Measured specific force minus the nominal twin's at the UGP [m/s^2].
    gyro, angular_acceleration : ndarray, shape (n, 3)
        Measured angular rate [rad/s] and its derivative [rad/s^2].
    predicted_angular_acceleration : ndarray, shape (n, 3)
        The nominal twin's angular acceleration (noise-free) [rad/s^2]: the lever regressors
        use the measured rotation as :func:`predictable` from it (differentiated gyro noise
        in the regressors would bias the fit towards zero).
    band_hz : tuple of float
        Band the fit uses (zero-phase band-pass of every column).

    """
    fs = 1.0 / float(t[1] - t[0])
    rms = float(np.sqrt(np.mean(np.sum(predicted_angular_acceleration**2, axis=1))))
    if rms < MIN_ANGULAR_ACCELERATION:
        return MountEstimate((np.nan,) * 3, (np.nan,) * 3, False, rms)  # type: ignore[arg-type]
    w = gyro - gyro.mean(axis=0)
    attitude = signal.detrend(np.cumsum(w, axis=0) / fs, axis=0)
    wd_clean = predictable(angular_acceleration, predicted_angular_acceleration)
    w_clean = predictable(w, signal.detrend(np.cumsum(predicted_angular_acceleration, axis=0) / fs,
                                            axis=0))  # fmt: skip
    lever = _skew(wd_clean) + _skew(w_clean) @ _skew(w_clean)  # (n, 3, 3): f = lever @ r
    sos = signal.butter(2, [band_hz[0], min(band_hz[1], 0.45 * fs)], "bandpass", fs=fs,
                        output="sos")  # fmt: skip

    def band(x: FloatArray) -> FloatArray:
        return signal.sosfiltfilt(sos, x, axis=0)

    n = len(t)
    nuisance = band(np.hstack([attitude, w]))  # (n, 6), per axis
    rows = []
    for axis in range(3):
        block = np.zeros((n, 3 + 18))
        block[:, :3] = band(lever[:, axis, :])
        block[:, 3 + 6 * axis : 9 + 6 * axis] = nuisance
        rows.append(block)
    A = np.vstack(rows)
    b = band(residual).T.reshape(-1)
    coef, *_ = np.linalg.lstsq(A, b, rcond=None)
    e = b - A @ coef
    # the band-pass correlates neighbouring samples: the residual's variance counts
    # fs / (2 f_top) times (the sum of its autocorrelation), an independent sample per
    # half period of the band's top
    kappa = max(fs / (2 * min(band_hz[1], 0.45 * fs)), 1.0)
    sigma2 = float(e @ e) / max(len(e) - A.shape[1], 1)
    cov = sigma2 * kappa * np.linalg.pinv(A.T @ A)
    std = np.sqrt(np.clip(np.diag(cov)[:3], 0.0, None))
    seen = np.sqrt(np.sum(A[:, :3] ** 2, axis=0))  # a coordinate no rotation moves
    std[seen < 1e-9 * max(seen.max(), 1e-300)] = np.nan
    return MountEstimate(tuple(map(float, coef[:3])), tuple(map(float, std)), True, rms)  # type: ignore[arg-type]
