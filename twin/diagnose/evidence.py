"""The linear evidence of a diagnosis: the excited lines, with the measurement's own noise.

A dynamic cause (delay, gain, filter, resonance, lead, sensor filter, backlash) shows where the
run put power: at its excited lines. Per channel and window, :class:`Lines` holds the complex
amplitude of the measured signal at every line (Y), the nominal twin's noise-free prediction
of it (P) and the standard deviation of Y, from the *measured* residual (measured - nominal)
at the non-excited bins next to each line, as AGARD-AR-144 estimates the noise of a describing
function. The nominal noise model plays no part: a quieter or louder IMU than the data sheet's,
or more motion noise, changes the uncertainty of the evidence, never the evidence, so no
dynamic cause can be named for a noise difference (that is judged on its own, in
:mod:`twin.diagnose.nuisance`).

Under a model that predicts Yhat at the lines, Y - Yhat is complex Gaussian with
``E|Y - Yhat|^2 = sd^2``, so the log-likelihood is -chi2 with ``chi2 = sum |Y - Yhat|^2 / sd^2`` (a
constant dropped). The variance estimate from M neighbouring bins (2 M real degrees of
freedom) is scaled by 2M / (2M - 2), which makes ``E[|Y - Yhat|^2 / sd^2] = 1`` under the true
model (1 / chi-square bias).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from twin.core.errors import SignalError
from twin.diagnose.data import Channel
from twin.measurement.describing_function import fourier_coefficients, neighbour_bins

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
#: Non-excited bins on each side of a line used for its noise.
NEIGHBOURS = 5


def line_amplitudes(
    t: FloatArray, y: FloatArray, f: FloatArray, window: tuple[float, float]
) -> ComplexArray:
    """Least-squares complex amplitudes of sines at ``f`` over ``window`` (any length).

    Over whole periods of every line this equals
    :func:`~twin.measurement.describing_function.fourier_coefficients`; over part of the
    measurement window (the held-out halves) the lines are fitted jointly, with a constant.
    """
    sel = in_window(t, window)
    c, *_ = np.linalg.lstsq(line_design(t[sel], f), y[sel], rcond=None)
    m = f.size
    return c[:m] + 1j * c[m : 2 * m]


def in_window(t: FloatArray, window: tuple[float, float]) -> NDArray[np.bool_]:
    """Return the samples of ``t`` in ``window`` [start, end)."""
    return (t >= window[0] - 1e-9) & (t < window[1] - 1e-9)


def line_design(t: FloatArray, f: FloatArray) -> FloatArray:
    """Return the least-squares design of sines and cosines at ``f`` and a constant at ``t``.

    Columns: sin(2 pi f_i t) for every line, then cos(2 pi f_i t), then 1; the fitted
    coefficients c give the lines' complex amplitudes c[:m] + j c[m:2m].
    """
    return np.hstack([np.sin(2 * np.pi * np.outer(t, f)), np.cos(2 * np.pi * np.outer(t, f)),
                      np.ones((t.size, 1))])  # fmt: skip


@dataclass(frozen=True, eq=False)
class Lines:
    """The excited lines of one channel over one window.

    Attributes
    ----------
    channel : Channel
        The channel.
    window : tuple of float
        Window [s].
    f : ndarray
        Lines [Hz].
    measured : ndarray of complex
        Measured amplitudes Y.
    nominal : ndarray of complex
        The nominal twin's noise-free amplitudes P.
    sd : ndarray
        Standard deviation of Y (complex: ``E|dY|^2 = sd^2``) from the measurement's own noise.

    """

    channel: Channel
    window: tuple[float, float]
    f: FloatArray
    measured: ComplexArray
    nominal: ComplexArray
    sd: FloatArray

    @property
    def size(self) -> int:
        """Number of lines (each two real observations)."""
        return int(self.f.size)

    def amplitudes(self, x: FloatArray) -> ComplexArray:
        """Amplitudes of a full-length signal of the channel at the lines, over the window."""
        return line_amplitudes(self.channel.t, x, self.f, self.window)

    def chi2(self, predicted: ComplexArray) -> float:
        """Return ``sum |Y - Yhat|^2 / sd^2`` (minus the log-likelihood)."""
        return float(np.sum(np.abs(self.measured - predicted) ** 2 / self.sd**2))

    def residuals(self, predicted: ComplexArray) -> FloatArray:
        """Standardised real residuals (real and imaginary parts; their squares sum to chi2)."""
        r = (self.measured - predicted) / self.sd
        return np.concatenate([r.real, r.imag])


def measured_line_sd(ch: Channel, prediction: FloatArray | None = None) -> FloatArray:
    """Return the standard deviation of the line amplitudes over the measurement window.

    From the measured residual at the neighbouring non-excited bins (bias-corrected, see the
    module docstring).
    """
    resid = ch.measured - (ch.nominal if prediction is None else prediction)
    return neighbour_sd(ch.t, resid[:, None], ch.lines_hz, ch.window)[:, 0]


def neighbour_sd(
    t: FloatArray, resid: FloatArray, f: FloatArray, window: tuple[float, float]
) -> FloatArray:
    """Return each line amplitude's standard deviation per column of ``resid`` (n, k).

    From the residual's power at the :data:`NEIGHBOURS` non-excited bins on each side of the
    line, bias-corrected (see the module docstring); NaN for a line with fewer than two.
    """
    out = np.full((f.size, resid.shape[1]), np.nan)
    for i, fs in enumerate(neighbour_bins(f, window, NEIGHBOURS)):
        if fs.size >= 2:
            c = fourier_coefficients(t, resid, fs, window)
            power = np.mean(np.abs(c) ** 2, axis=0)
            out[i] = np.sqrt(power * (2 * fs.size) / (2 * fs.size - 2))
    return out


def nominal_line_sd(ch: Channel, scales: Sequence[float] = (1.0, 1.0)) -> FloatArray:
    """Return the standard deviation of the line amplitudes the nominal noise model expects.

    The sources are taken times ``scales`` (power); the result is the mean power of the noise
    realisations at the lines' neighbours.
    """
    noise = np.tensordot(np.sqrt(np.asarray(scales, dtype=float)), ch.sources, axes=1)
    out = np.empty(ch.lines_hz.size)
    for i, fs in enumerate(neighbour_bins(ch.lines_hz, ch.window, NEIGHBOURS)):
        c = fourier_coefficients(ch.t, noise.T, fs, ch.window)
        out[i] = np.sqrt(np.mean(np.abs(c) ** 2))
    return out


def lines(
    ch: Channel,
    window: tuple[float, float] | None = None,
    sd: FloatArray | None = None,
    max_hz: float = np.inf,
) -> Lines:
    """Return the line evidence of ``ch`` over ``window`` (its measurement window by default).

    ``sd`` overrides the measured standard deviation (e.g. the nominal noise model's, to
    predict what a run could show); over part of the window the full window's is scaled by
    sqrt(full / part). Lines above ``max_hz`` are left out.
    """
    w = ch.window if window is None else tuple(window)
    base = measured_line_sd(ch) if sd is None else np.asarray(sd, dtype=float)
    part = np.sqrt((ch.window[1] - ch.window[0]) / (w[1] - w[0]))
    if not np.all(np.isfinite(base) & (base > 0)):
        bad = ch.lines_hz[~(np.isfinite(base) & (base > 0))]
        raise SignalError(
            f"{ch.run}: no noise estimate at the line(s) {', '.join(f'{f:g}' for f in bad)} Hz "
            "(no non-excited bin beside them, or a noise-free recording); the diagnosis needs "
            "the measurement's own noise next to every excited line"
        )
    y = line_amplitudes(ch.t, ch.measured, ch.lines_hz, w)
    p = line_amplitudes(ch.t, ch.nominal, ch.lines_hz, w)
    keep = ch.lines_hz <= max_hz
    return Lines(ch, w, ch.lines_hz[keep], y[keep], p[keep], (base * part)[keep])
