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
from scipy.optimize import least_squares, minimize_scalar

from twin.core.errors import SignalError

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


def phase_deg(h: ArrayLike) -> FloatArray:
    """Return the phase of a response [deg], unwrapped from its first element."""
    return np.degrees(np.unwrap(np.angle(np.asarray(h))))


class ResponseMixin:
    """``gain`` and ``phase_deg`` of a result holding a complex ``response``."""

    response: ComplexArray

    @property
    def gain(self) -> FloatArray:
        """``|H|`` (ratio)."""
        return np.abs(self.response)

    @property
    def phase_deg(self) -> FloatArray:
        """Phase of H [deg], unwrapped from the lowest frequency."""
        return phase_deg(self.response)


def dense_frequencies(f: FloatArray) -> FloatArray:
    """Return 400 log-spaced frequencies over the lines, at least 0.05-10 Hz (model curves)."""
    return np.geomspace(min(f.min(), 0.05), max(f.max(), 10.0), 400)


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
        RMS of the relative complex residual ``|H / H_fit - 1|``.

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


def neighbour_noise(
    t: ArrayLike,
    y: ArrayLike,
    frequencies_hz: ArrayLike,
    window: tuple[float, float],
    bins: int = 3,
) -> FloatArray:
    """RMS Fourier amplitude of ``y`` at the non-excited bins next to each excited frequency.

    The window's frequency resolution is 1 / T; the ``bins`` bins on each side of every
    excited frequency that are neither excited nor a 2nd or 3rd harmonic of an excited
    frequency carry only noise (and non-periodic distortion). Their RMS amplitude (same
    scaling as :func:`fourier_coefficients`) is the noise level at that frequency: the
    standard deviation of a describing function there is about this over the input amplitude.

    Parameters
    ----------
    t, y, frequencies_hz, window
        As :func:`fourier_coefficients` (``y`` one signal).
    bins : int
        Neighbours on each side.

    Returns
    -------
    ndarray, shape (m,)

    """
    out = np.full(np.size(frequencies_hz), np.nan)
    for i, fs in enumerate(neighbour_bins(frequencies_hz, window, bins)):
        if fs.size:
            out[i] = np.sqrt(np.mean(np.abs(fourier_coefficients(t, y, fs, window)) ** 2))
    return out


def neighbour_bins(
    frequencies_hz: ArrayLike, window: tuple[float, float], bins: int = 3
) -> list[FloatArray]:
    """Return the frequencies of the noise-only bins next to each excited frequency.

    Per frequency, up to ``2 bins`` bins of the window's resolution that are neither excited
    nor a 2nd or 3rd harmonic of an excited frequency (see :func:`neighbour_noise`).
    """
    f = np.asarray(frequencies_hz, dtype=float)
    df = 1.0 / (window[1] - window[0])
    taken = set(np.round(np.concatenate([f, 2 * f, 3 * f]) / df).astype(int).tolist())
    out = []
    for fi in f:
        k0 = round(fi / df)
        ks = [k0 + j for j in range(-bins, bins + 1) if j and k0 + j > 0 and k0 + j not in taken]
        out.append(np.array(ks, dtype=float) * df)
    return out


def fit_delay(
    frequencies_hz: ArrayLike,
    response: ArrayLike,
    model: ArrayLike | None = None,
    weights: ArrayLike | None = None,
    max_delay_s: float = 0.5,
) -> float:
    """Fit a pure delay to the phase of ``response / model`` (§3.4.3, §5.6.2.2) [s].

    Minimises sum w (1 - cos(phi + 2 pi f tau)) over tau, phi the phase of response / model:
    the circular form of a least-squares phase fit, so wrapped phases need no unwrapping.
    With equal weights this is the thesis' fit; with ``weights`` = signal-to-noise power at
    each frequency (see :func:`neighbour_noise`) frequencies where a filter leaves little
    signal stop dominating (with equal weights the thesis found 13 ms instead of about 19 ms
    behind the 1 Hz filter, Table 5.6).

    Parameters
    ----------
    frequencies_hz : array_like, shape (m,)
        Frequencies [Hz].
    response : array_like, shape (m,)
        Measured describing function.
    model : array_like, shape (m,), optional
        The known part of the dynamics (e.g. the platform filter, Eq 3.8); 1 if not given.
    weights : array_like, shape (m,), optional
        Weight of each frequency; equal if not given.
    max_delay_s : float
        Search range [-0.05 s, max_delay_s].

    Examples
    --------
    >>> import numpy as np
    >>> f = np.array([0.1, 0.5, 1.0, 2.0, 7.1])
    >>> round(fit_delay(f, np.exp(-2j * np.pi * f * 0.1)) * 1e3, 3)
    100.0

    """
    f = np.asarray(frequencies_hz, dtype=float)
    h = np.asarray(response, dtype=complex)
    h0 = np.ones_like(h) if model is None else np.asarray(model, dtype=complex)
    w = np.ones(f.size) if weights is None else np.asarray(weights, dtype=float)
    ok = np.isfinite(w) & (w > 0) & np.isfinite(h) & (np.abs(h0) > 0)
    if not ok.any():
        raise SignalError("no frequency with a usable phase to fit a delay to")
    f, w = f[ok], w[ok] / w[ok].max()
    phi = np.angle(h[ok] / h0[ok])

    def cost(tau: float | FloatArray) -> FloatArray:
        return (1 - np.cos(phi + 2 * np.pi * np.multiply.outer(tau, f))) @ w

    # grid finer than a quarter period of the highest frequency, then refine
    step = min(1e-3, 0.25 / (2 * np.pi * f.max()))
    grid = np.arange(-0.05, max_delay_s + step, step)
    best = float(grid[np.argmin(cost(grid))])
    sol = minimize_scalar(cost, bounds=(best - step, best + step), method="bounded",
                          options={"xatol": 1e-9})  # fmt: skip
    return float(sol.x)
