"""Time bases of measured logs: jittery stamps, irregular sampling, gaps.

A logger's time column is rarely the uniform grid ``twin-run/1`` asks for. Two cases differ
and are told apart by the stamps themselves:

- a **uniform stream with jittery stamps** (samples taken by a clock, stamped by software):
  the stamps scatter about a straight line ``t0 + k dt`` (RMS below a fifth of a step); the
  samples are kept and the line is taken as their times (interpolating with the noisy
  stamps would add the jitter times the signal's slope as noise);
- **irregular sampling** (stamps right, samples not uniform, dropped samples): the samples
  are interpolated onto a uniform grid at the median step (cubic for the smooth commands,
  linear for the noisy IMU).

A step back in time, a repeated stamp or a gap of more than :data:`MAX_GAP_STEPS` steps is an
error naming the row: a run must be one continuous recording.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicSpline
from scipy.signal import butter, sosfiltfilt

from twin.chain.trajectory import interp_columns
from twin.core.errors import DataError

FloatArray = NDArray[np.float64]
#: The largest gap (in median steps) interpolated over.
MAX_GAP_STEPS = 10.0
#: Stamps whose RMS distance from a straight line is below this fraction of a step (and none
#: farther than a step) are jitter of a uniform stream; a dropped sample moves the line a
#: whole step and fails it.
JITTER_FRACTION = 0.2
#: A sample rate within this relative distance of a whole number of Hz (or of 819.2 Hz, the
#: ADIS16355's) is taken as that rate.
NICE_RATE_TOLERANCE = 2e-3


@dataclass(frozen=True, eq=False)
class Regular:
    """Samples on a uniform grid, and how they got there.

    Attributes
    ----------
    t0 : float
        Time of the first sample [s, the file's clock].
    rate_hz : float
        Sample rate [Hz].
    values : ndarray, shape (n, k)
        Samples.
    how : str
        ``uniform``, ``jittery stamps`` or ``interpolated``.
    jitter_rms_s : float
        RMS distance of the stamps from the straight line [s].
    median_step_s, max_gap_s : float
        Median and largest step of the stamps [s].

    """

    t0: float
    rate_hz: float
    values: FloatArray
    how: str
    jitter_rms_s: float
    median_step_s: float
    max_gap_s: float

    @property
    def t(self) -> FloatArray:
        """Sample times [s]."""
        return self.t0 + np.arange(len(self.values)) / self.rate_hz

    def to_dict(self) -> dict[str, object]:
        """Return what was done, for ``meta.json``."""
        return {"how": self.how, "rate_hz": self.rate_hz, "jitter_rms_s": self.jitter_rms_s,
                "median_step_s": self.median_step_s, "max_gap_s": self.max_gap_s}  # fmt: skip


def nice_rate(rate: float) -> float:
    """Round a measured rate to a whole number of Hz (or 819.2 Hz) when within 0.2 %."""
    for nice in (819.2, float(round(rate))):
        if nice > 0 and abs(rate / nice - 1) < NICE_RATE_TOLERANCE:
            return nice
    return float(rate)


def check_stamps(t: FloatArray, what: str) -> FloatArray:
    """Return the stamps as floats, or raise naming the first that is missing or out of order.

    Raises
    ------
    DataError
        Fewer than 16 samples, a stamp that is not finite, a step back or a repeated stamp.

    """
    t = np.asarray(t, dtype=float)
    if t.size < 16:
        raise DataError(f"{what}: needs at least 16 samples; got {t.size}")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise DataError(f"{what}: line {bad[0] + 2}: the time is not a number")
    d = np.diff(t)
    back = np.flatnonzero(d <= 0)
    if back.size:
        i = back[0] + 1
        word = "repeats" if d[back[0]] == 0 else "goes back"
        raise DataError(f"{what}: line {i + 2}: the time {word} ({t[i - 1]:.6g} -> {t[i]:.6g}); "
                        "stamps must increase strictly")  # fmt: skip
    return t


def decimate(reg: Regular, rate_hz: float) -> Regular:
    """Low-pass (zero phase, at a quarter of ``rate_hz``) and resample onto ``rate_hz``.

    A command log sampled far faster than its content (e.g. at the IMU's rate, with a
    limited number of decimals) would otherwise turn its rounding into accelerations.
    """
    sos = butter(4, rate_hz / 4, fs=reg.rate_hz, output="sos")
    smooth = sosfiltfilt(sos, reg.values, axis=0)
    t = reg.t
    grid = t[0] + np.arange(int(np.floor((t[-1] - t[0]) * rate_hz + 1e-9)) + 1) / rate_hz
    out = CubicSpline(t, smooth, axis=0)(grid)
    return replace(reg, rate_hz=rate_hz, values=out, how=f"{reg.how}, decimated")


def regularise(t: FloatArray, values: FloatArray, what: str, smooth: bool) -> Regular:
    """Put samples on a uniform grid (see module docstring).

    Parameters
    ----------
    t : ndarray, shape (n,)
        Stamps [s].
    values : ndarray, shape (n, k)
        Samples (finite).
    what : str
        Name of the file, for messages.
    smooth : bool
        Cubic interpolation (commands) rather than linear (IMU) where interpolation is needed.

    Raises
    ------
    DataError
        Fewer than 16 samples, a stamp that is not finite, a step back or a repeated stamp,
        a gap of more than :data:`MAX_GAP_STEPS` steps.

    """
    t = check_stamps(t, what)
    d = np.diff(t)
    step = float(np.median(d))
    gap = int(np.argmax(d))
    if d[gap] > MAX_GAP_STEPS * step:
        raise DataError(
            f"{what}: a gap of {d[gap]:.4g} s after t = {t[gap]:.6g} s (line {gap + 2}), "
            f"{d[gap] / step:.0f} samples; a run must be one continuous recording (at most "
            f"{MAX_GAP_STEPS:g} missing steps are interpolated)"
        )
    k = np.arange(t.size)
    slope, icpt = np.polyfit(k, t - t[0], 1)
    resid = t - t[0] - (icpt + slope * k)
    jitter = float(np.sqrt(np.mean(resid**2)))
    info = {"jitter_rms_s": jitter, "median_step_s": step, "max_gap_s": float(d[gap])}
    if jitter < JITTER_FRACTION * slope and np.max(np.abs(resid)) < slope:
        rate = nice_rate(1.0 / slope)
        if t.size * abs(1.0 / rate - slope) > 0.1 * slope:  # rounding would drift: keep it
            rate = 1.0 / slope
        how = "uniform" if np.max(np.abs(resid)) < 0.01 * slope else "jittery stamps"
        return Regular(float(t[0] + icpt), rate, np.asarray(values, float), how, **info)
    rate = nice_rate(1.0 / step)
    grid = t[0] + np.arange(int(np.floor((t[-1] - t[0]) * rate + 1e-9)) + 1) / rate
    if smooth:
        out = CubicSpline(t, values, axis=0)(grid)
    else:
        out = interp_columns(grid, t, values)
    return Regular(float(grid[0]), rate, out, "interpolated", **info)
