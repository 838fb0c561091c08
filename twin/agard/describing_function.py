"""Describing functions at the excited frequencies of a periodic test signal (§5.3.1).

The describing function is the ratio of the Fourier coefficients of output and input at each
excited frequency over a window holding an integer number of periods (20 s for Table 5.2).
:func:`fit_lag_delay` fits the first-order lag plus delay of §5.5.1 (Table 5.5).

Examples
--------
>>> import numpy as np
>>> t = np.arange(0, 20, 0.001)
>>> u = np.sin(2 * np.pi * 1.0 * t)
>>> y = 0.5 * np.sin(2 * np.pi * 1.0 * (t - 0.035))
>>> h = describing_function(t, u, y, [1.0], (0.0, 20.0))
>>> round(float(np.abs(h[0])), 3), round(float(-np.angle(h[0], deg=True)), 1)  # 0.035 s * 360
(0.5, 12.6)

"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from twin.errors import SignalError

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


def fourier_coefficients(
    t: ArrayLike, x: ArrayLike, frequencies_hz: ArrayLike, window: tuple[float, float]
) -> ComplexArray:
    """Complex amplitudes of ``x`` at the given frequencies over ``window`` [t0, t1).

    Parameters
    ----------
    t : array_like, shape (n,)
        Uniform sample times [s].
    x : array_like, shape (n,) or (n, k)
        Signal(s).
    frequencies_hz : array_like, shape (m,)
        Frequencies [Hz]; each should fit an integer number of periods in the window.
    window : tuple of float
        Start (inclusive) and end (exclusive) [s].

    Returns
    -------
    ndarray, shape (m,) or (m, k)
        A sine of amplitude A and phase phi gives A e^{j phi} (relative to a sine).

    """
    tt = np.asarray(t, dtype=float)
    xx = np.asarray(x, dtype=float)
    sel = (tt >= window[0] - 1e-9) & (tt < window[1] - 1e-9)
    if sel.sum() < 4:
        raise SignalError(f"window {window} holds fewer than 4 samples of the signal")
    f = np.asarray(frequencies_hz, dtype=float)
    e = np.exp(-2j * np.pi * np.outer(f, tt[sel]))
    # sin(w t + phi) = Im(e^{j(w t + phi)}): its coefficient against e^{-j w t} is
    # -j/2 e^{j phi}; scale so that the result is A e^{j phi}
    return (e @ xx[sel]) * (2j / sel.sum())


def describing_function(
    t: ArrayLike, u: ArrayLike, y: ArrayLike, frequencies_hz: ArrayLike,
    window: tuple[float, float],
) -> ComplexArray:  # fmt: skip
    """Return Y(f) / U(f) at the excited frequencies (arguments as :func:`fourier_coefficients`).

    Raises
    ------
    SignalError
        If the input has no power at one of the frequencies.

    """
    U = fourier_coefficients(t, u, frequencies_hz, window)
    Y = fourier_coefficients(t, y, frequencies_hz, window)
    if np.any(np.abs(U) < 1e-15):
        raise SignalError("the input has no power at one of the describing-function frequencies")
    return Y / U


@dataclass(frozen=True)
class LagDelayFit:
    """First-order lag with delay, H = e^{-tau s} / (1 + t_m s), fitted to a response.

    Attributes
    ----------
    t_m : float
        Time constant [s] (Table 5.5).
    tau : float
        Delay [s].
    rms_error : float
        RMS of the relative complex residual |H / H_fit - 1|.

    """

    t_m: float
    tau: float
    rms_error: float

    @property
    def f_m(self) -> float:
        """Break frequency 1 / (2 pi t_m) [Hz] (Table 5.5)."""
        return 1.0 / (2 * np.pi * self.t_m) if self.t_m > 0 else float("inf")

    def response(self, f: ArrayLike) -> ComplexArray:
        """Return the fitted model at ``f`` [Hz]."""
        s = 2j * np.pi * np.asarray(f, dtype=float)
        return np.exp(-s * self.tau) / (1 + s * self.t_m)


def fit_lag_delay(frequencies_hz: ArrayLike, response: ArrayLike) -> LagDelayFit:
    """Fit H = e^{-tau s} / (1 + t_m s) to a describing function (§5.5.1).

    Gain and phase are fitted together (relative complex error), so the lag is separated from
    the delay by the gain it costs.

    Parameters
    ----------
    frequencies_hz : array_like, shape (m,)
        Frequencies [Hz].
    response : array_like, shape (m,)
        Complex describing function.

    """
    f = np.asarray(frequencies_hz, dtype=float)
    h = np.asarray(response, dtype=complex)
    s = 2j * np.pi * f

    def residual(x: FloatArray) -> FloatArray:
        r = h * (1 + s * x[0]) * np.exp(s * x[1]) - 1
        return np.concatenate([r.real, r.imag])

    phase = np.unwrap(np.angle(h))
    tau0 = max(float(np.polyfit(2 * np.pi * f, -phase, 1)[0]), 0.0)
    sol = least_squares(residual, x0=[0.5 * tau0, 0.5 * tau0], bounds=([0, -1], [10, 10]),
                        x_scale=[1e-3, 1e-3], xtol=1e-14, ftol=1e-14, gtol=1e-14)  # fmt: skip
    rms = float(np.sqrt(np.mean(np.abs(residual(sol.x)) ** 2) * 2))
    return LagDelayFit(float(sol.x[0]), float(sol.x[1]), rms)
