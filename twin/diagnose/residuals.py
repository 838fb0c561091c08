"""Show what the nominal twin gets wrong: describing-function ratios, harmonics, residual noise.

Everything here compares a run's measured acceleration with the nominal twin's noise-free
prediction of it over the run's measurement window, against the nominal noise:

* **Describing-function ratio** measured / nominal at every excited line, with its standard
  deviation from the noise measured at the neighbouring non-excited bins (AGARD-AR-144's
  "noise" estimate). A line is significant when ``2 |R - 1|^2 / sd(R)^2`` exceeds the chi-square
  (2 degrees of freedom) quantile for ``ALPHA``; the smallest deviation the line could have
  shown is ``sqrt(q / 2) sd(R)``, given in dB and degrees.
* **Harmonic content and stochastic residue** (AGARD-AR-144's decomposition, §3.3.3): the
  power of measured - nominal at the 2nd-3rd harmonics of the lines, the 4th and higher, and
  at every other bin of the band, each against the power the nominal noise model expects
  there. Under the nominal model ``sum |Y_m - Y_n|^2 / S`` over n bins is Gamma(n, 1)
  distributed (each bin's periodogram is exponential with mean S): the p-value is two-sided.
* **Residual noise spectrum** in octave bands against the nominal noise spectrum (same test).

Spectra are periodograms of the segment with a Hann taper (``numpy.fft.rfft`` scaling): with
a rectangular window the jump between the segment's ends leaks the strong high-frequency IMU
noise (differentiated gyro noise rises as f^2) into the low bins, where it varied five-fold
between noise seeds. The nominal noise spectrum S is the mean periodogram of the simulated
noise realisations, smoothed over ``SMOOTH_BINS`` bins on each side. Tapered bins are
correlated (the periodograms of neighbours by 4/9, of next neighbours by 1/36), so the Whittle
log-likelihood, which treats bins as independent, is divided by ``TAPER_CORRELATION`` = 1 + 2
(4/9 + 1/36) to keep likelihood-ratio statistics calibrated.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy import signal, stats

from twin.diagnose.data import Channel
from twin.measurement.describing_function import fourier_coefficients, neighbour_noise

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
#: Significance level of every per-item test.
ALPHA = 0.01
#: Smoothing of the nominal noise periodogram [bins on each side].
SMOOTH_BINS = 2
#: Variance inflation of sums over Hann-tapered periodogram bins (see module docstring).
TAPER_CORRELATION = 1.0 + 2 * (4 / 9 + 1 / 36)
#: Width of the smoothing of the noise sources' spectra where their shapes matter [octaves].
SHAPE_OCTAVES = 1 / 3
#: Default analysis band [Hz]: up to the App. C.2.3 FIR cut-off.
MAX_HZ = 15.0


@dataclass(frozen=True, eq=False)
class Segment:
    """Spectra of one channel over one time segment, on the bins of the analysis band.

    Attributes
    ----------
    channel : Channel
        The channel.
    window : tuple of float
        Segment [s].
    mask : ndarray of bool, shape (n,)
        Samples in the segment.
    taper : ndarray
        Hann taper over the segment's samples.
    bins : ndarray of int
        rfft bin indices in the band.
    f : ndarray
        Their frequencies [Hz].
    measured : ndarray of complex
        rfft of the measured signal at ``bins``.
    source_psd : ndarray, shape (2, bins)
        Periodogram expectation of each nominal noise source (motion, IMU) at ``bins``.
    scales : tuple of float
        Power factors on the sources (1, 1: the nominal noise; fitted: the measured noise).

    """

    channel: Channel
    window: tuple[float, float]
    mask: NDArray[np.bool_]
    taper: FloatArray
    bins: NDArray[np.int_]
    f: FloatArray
    measured: ComplexArray
    source_psd: FloatArray
    scales: tuple[float, float] = (1.0, 1.0)

    @property
    def noise_psd(self) -> FloatArray:
        """Noise periodogram expectation at ``bins``: the sources times their scales."""
        return np.maximum(np.asarray(self.scales) @ self.source_psd, 1e-30)

    @property
    def shape_psd(self) -> FloatArray:
        """Source spectra smoothed over ``SHAPE_OCTAVES`` (for fits of the noise's *shape*).

        The 5-bin smoothing of :attr:`source_psd` leaves each bin's estimate about 35 %
        uncertain; that is fine for a noise *level*, but when two sources are told apart by
        their spectral shape the estimate's ripple reads as shape. The noise spectra here are
        those of filtered white noise (smooth in log frequency), so a fractional-octave mean
        keeps the shape and removes the ripple.
        """
        return np.array([octave_smooth(self.f, p, SHAPE_OCTAVES) for p in self.source_psd])

    def scaled(self, scales: tuple[float, float]) -> Segment:
        """Return the segment with other power factors on the noise sources."""
        return replace(self, scales=(float(scales[0]), float(scales[1])))

    def spectrum(self, x: FloatArray) -> ComplexArray:
        """Return the tapered rfft of a full-length signal over this segment, at the band's bins."""
        return np.fft.rfft(x[self.mask] * self.taper)[self.bins]

    def loglik(
        self, prediction: FloatArray | ComplexArray, psd_factor: FloatArray | float = 1.0
    ) -> float:
        """Whittle log-likelihood of the measured signal given a prediction.

        ``prediction`` is a full-length time signal or, already transformed, the spectrum at
        the band's bins; the noise spectrum is the nominal one times ``psd_factor``.
        """
        y = prediction if np.iscomplexobj(prediction) else self.spectrum(prediction)
        s = self.noise_psd * psd_factor
        return float(-np.sum(np.abs(self.measured - y) ** 2 / s + np.log(s)) / TAPER_CORRELATION)

    @property
    def size(self) -> int:
        """Number of bins (each two real observations)."""
        return int(self.bins.size)


def segment(
    ch: Channel, window: tuple[float, float] | None = None, max_hz: float = MAX_HZ
) -> Segment:
    """Spectra of ``ch`` over ``window`` (its measurement window by default).

    The band runs from half the lowest excited line (or two bins, whichever is higher: below
    it lie the IMU's bias and the fades) to ``max_hz``.
    """
    w = ch.window if window is None else window
    mask = (ch.t >= w[0] - 1e-9) & (ch.t < w[1] - 1e-9)
    n = int(mask.sum())
    f = np.fft.rfftfreq(n, 1.0 / ch.rate_hz)
    lo = max(0.5 * float(ch.lines_hz.min()), 2 * f[1])
    bins = np.flatnonzero((f >= lo) & (f <= max_hz))
    taper = signal.windows.hann(n, sym=False)
    measured = np.fft.rfft(ch.measured[mask] * taper)[bins]
    psd = np.array([_source_psd(x[:, mask] * taper, bins) for x in ch.sources])
    return Segment(ch, tuple(w), mask, taper, bins, f[bins], measured, psd)


def _source_psd(tapered: FloatArray, bins: NDArray[np.int_]) -> FloatArray:
    """Smoothed mean periodogram of noise realisations (rows), bias-corrected, at ``bins``."""
    mean = (np.abs(np.fft.rfft(tapered, axis=1)) ** 2).mean(axis=0)
    mean[0] = 0.0  # the DC bin holds the IMU's bias: keep it out of the smoothing
    weight = np.ones_like(mean)
    weight[0] = 0.0
    kernel = np.ones(2 * SMOOTH_BINS + 1)
    smooth = np.convolve(mean, kernel, "same") / np.convolve(weight, kernel, "same")
    # 1 / S-hat is biased high by m / (m - 1) for an average of m exponential periodograms
    # (m counted in independent bins): scale S-hat up so that E[|R|^2 / S-hat] = 1
    m = tapered.shape[0] * (2 * SMOOTH_BINS + 1) / TAPER_CORRELATION
    return smooth[bins] * m / (m - 1)


def octave_smooth(f: FloatArray, psd: FloatArray, octaves: float) -> FloatArray:
    """Mean of ``psd`` over ``octaves`` around each bin (at least the SMOOTH_BINS neighbours).

    Examples
    --------
    >>> f = np.linspace(0.1, 10.0, 100)
    >>> bool(np.allclose(octave_smooth(f, np.full(100, 2.0), 1 / 3), 2.0))
    True

    """
    c = np.concatenate([[0.0], np.cumsum(psd)])
    i = np.arange(f.size)
    lo = np.searchsorted(f, f * 2 ** (-octaves / 2))
    hi = np.searchsorted(f, f * 2 ** (octaves / 2), side="right")
    lo = np.clip(np.minimum(lo, i - SMOOTH_BINS), 0, f.size)
    hi = np.clip(np.maximum(hi, i + SMOOTH_BINS + 1), 0, f.size)
    return (c[hi] - c[lo]) / (hi - lo)


def line_bins(seg: Segment, f: FloatArray) -> NDArray[np.int_]:
    """Positions in ``seg.bins`` nearest to the frequencies ``f`` (-1 where outside the band)."""
    df = seg.f[1] - seg.f[0] if seg.size > 1 else 1.0
    k = np.round((np.asarray(f) - seg.f[0]) / df).astype(int)
    return np.where((k >= 0) & (k < seg.size), k, -1)


@dataclass(frozen=True, eq=False)
class LineRatios:
    """Describing-function ratio measured / nominal at the excited lines of one DOF.

    Attributes
    ----------
    dof : str
        DOF.
    f : ndarray
        Lines [Hz] (all runs, ascending).
    ratio : ndarray of complex
        Measured / nominal describing function.
    sd : ndarray
        Standard deviation of ``ratio`` (complex: ``E|dR|^2 = sd^2``) from neighbouring bins.
    statistic : ndarray
        ``2 |R - 1|^2 / sd^2`` (chi-square, 2 degrees of freedom, under the nominal model).
    significant : ndarray of bool
        ``statistic`` above its (1 - ALPHA) quantile.
    min_db, min_deg : ndarray
        The smallest magnitude [dB] / phase [deg] deviation each line could have revealed.

    """

    dof: str
    f: FloatArray
    ratio: ComplexArray
    sd: FloatArray
    statistic: FloatArray
    significant: NDArray[np.bool_]
    min_db: FloatArray
    min_deg: FloatArray

    @property
    def db(self) -> FloatArray:
        """Magnitude of the ratio [dB]."""
        return 20 * np.log10(np.abs(self.ratio))

    @property
    def deg(self) -> FloatArray:
        """Phase of the ratio [deg], in (-180, 180]."""
        return np.degrees(np.angle(self.ratio))

    def ci_db(self, z: float = 1.96) -> tuple[FloatArray, FloatArray]:
        """Confidence band of the magnitude [dB] (normal approximation, ``z`` sigmas)."""
        m = np.abs(self.ratio)
        lo = np.maximum(m - z * self.sd / np.sqrt(2), 1e-6 * m)
        return 20 * np.log10(lo), 20 * np.log10(m + z * self.sd / np.sqrt(2))

    def ci_deg(self, z: float = 1.96) -> FloatArray:
        """Half-width of the phase confidence band [deg]."""
        return np.degrees(np.minimum(z * self.sd / np.sqrt(2) / np.abs(self.ratio), np.pi))

    def to_json(self) -> dict[str, object]:
        """Per-line values."""
        lo, hi = self.ci_db()
        return {
            "frequency_hz": self.f.tolist(),
            "ratio_db": self.db.tolist(),
            "ratio_deg": self.deg.tolist(),
            "ci95_db": [lo.tolist(), hi.tolist()],
            "ci95_deg": self.ci_deg().tolist(),
            "statistic": "2|R-1|^2/sd^2 ~ chi2(2)",
            "value": self.statistic.tolist(),
            "significant": self.significant.tolist(),
            "smallest_detectable_db": self.min_db.tolist(),
            "smallest_detectable_deg": self.min_deg.tolist(),
        }


def line_ratios(
    channels: Sequence[Channel], prediction: Sequence[FloatArray] | None = None
) -> LineRatios:
    """Describing-function ratios of the measured signal over a prediction (nominal default)."""
    fs, rs, sds = [], [], []
    for i, ch in enumerate(channels):
        pred = ch.nominal if prediction is None else prediction[i]
        ym = fourier_coefficients(ch.t, ch.measured, ch.lines_hz, ch.window)
        yn = fourier_coefficients(ch.t, pred, ch.lines_hz, ch.window)
        noise = neighbour_noise(ch.t, ch.measured - pred, ch.lines_hz, ch.window, bins=4)
        fs.append(ch.lines_hz)
        rs.append(ym / yn)
        sds.append(noise / np.abs(yn))
    f, r, sd = (np.concatenate(x) for x in (fs, rs, sds))
    order = np.argsort(f)
    f, r, sd = f[order], r[order], sd[order]
    q = stats.chi2.ppf(1 - ALPHA, 2)
    stat = 2 * np.abs(r - 1) ** 2 / sd**2
    dev = np.sqrt(q / 2) * sd
    return LineRatios(
        channels[0].dof, f, r, sd, stat, stat > q,
        20 * np.log10(1 + dev), np.degrees(np.minimum(dev, np.pi)),
    )  # fmt: skip


@dataclass(frozen=True)
class PowerTest:
    """Measured - nominal power in a set of bins against the nominal noise.

    Attributes
    ----------
    name : str
        What the bins are.
    bins : int
        How many.
    ratio : float
        Residual power / expected noise power.
    p_value : float
        Two-sided; under the nominal model the statistic is Gamma distributed (bins divided
        by ``TAPER_CORRELATION`` degrees of freedom, moment-matched).
    significant : bool
        ``p_value < ALPHA``.

    """

    name: str
    bins: int
    ratio: float
    p_value: float
    significant: bool

    def to_json(self) -> dict[str, object]:
        """Values, with the statistic named."""
        return {
            "name": self.name, "bins": self.bins, "power_ratio": self.ratio,
            "p_value": self.p_value, "significant": self.significant,
            "statistic": "sum |Y_m - Y_n|^2 / S / c ~ Gamma(bins / c, 1), c = taper correlation",
        }  # fmt: skip


def power_test(name: str, resid: ComplexArray, psd: FloatArray) -> PowerTest:
    """Test the residual power in some bins against the nominal noise spectrum."""
    n = int(resid.size)
    if n == 0:
        return PowerTest(name, 0, float("nan"), 1.0, False)
    # the sum of n correlated exponential bins: Gamma with n / TAPER_CORRELATION degrees
    # of freedom and the same mean (moment matching)
    k = n / TAPER_CORRELATION
    stat = float(np.sum(np.abs(resid) ** 2 / psd)) / TAPER_CORRELATION
    p = float(2 * min(stats.gamma.sf(stat, k), stats.gamma.cdf(stat, k)))
    ratio = float(np.sum(np.abs(resid) ** 2) / np.sum(psd))
    return PowerTest(name, n, ratio, min(p, 1.0), p < ALPHA)


def decomposition(seg: Segment) -> list[PowerTest]:
    """AGARD-AR-144 partition of the residual: 2nd-3rd harmonics, 4th+, stochastic."""
    ch = seg.channel
    resid = seg.measured - seg.spectrum(ch.nominal)
    f_max = float(seg.f[-1])
    centre = line_bins(seg, ch.lines_hz)
    # the taper spreads each line over its two neighbouring bins
    lines = {int(k + j) for k in centre[centre >= 0] for j in (-1, 0, 1)}
    low = set(line_bins(seg, np.concatenate([2 * ch.lines_hz, 3 * ch.lines_hz])).tolist())
    low = low - lines - {-1}
    orders = [n * f for f in ch.lines_hz for n in range(4, int(f_max / f) + 1)]
    high = set(line_bins(seg, np.array(orders)).tolist()) - lines - low - {-1}
    rest = set(range(seg.size)) - lines - low - high
    low, high = low - lines, high - lines
    out = []
    for name, idx in (("harmonics 2-3", low), ("harmonics 4+", high), ("stochastic", rest)):
        k = np.array(sorted(idx), dtype=int)
        out.append(power_test(name, resid[k], seg.noise_psd[k]))
    return out


def residual_bands(seg: Segment, prediction: FloatArray | None = None) -> list[PowerTest]:
    """Residual power per octave band (excited lines left out) against the nominal noise."""
    ch = seg.channel
    resid = seg.measured - seg.spectrum(ch.nominal if prediction is None else prediction)
    keep = np.ones(seg.size, dtype=bool)
    k = line_bins(seg, ch.lines_hz)
    for j in (-1, 0, 1):  # a line and the two bins the taper spreads it over
        keep[np.clip(k[k >= 0] + j, 0, seg.size - 1)] = False
    out = []
    lo = float(seg.f[0])
    while lo < seg.f[-1]:
        hi = min(2 * lo, float(seg.f[-1]) + 1e-9)
        sel = keep & (seg.f >= lo) & (seg.f < hi if hi < seg.f[-1] else seg.f <= hi)
        out.append(power_test(f"{lo:.2g}-{hi:.2g} Hz", resid[sel], seg.noise_psd[sel]))
        lo = hi
    return out
