"""The design of a periodic run: its excited lines and a window of whole periods.

Every analysis of a periodic run (the describing functions of :mod:`twin.agard.df`, the
parasitic motion, the OMCT and noise-level points, the diagnosis of :mod:`twin.diagnose`)
needs the frequencies the commands excite and a window holding whole periods of them. A run the
twin wrote names both in its ``meta.json`` (``signal.frequencies_hz``, ``signal.window_s``);
for another they are inferred from the commands (:func:`inferred_design`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy import signal

from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES
from twin.measurement.describing_function import fourier_coefficients
from twin.measurement.measure import Measurement

FloatArray = NDArray[np.float64]
#: Least share of the commanded power an inferred design's lines must explain.
MIN_EXPLAINED = 0.95
#: Share from which a base frequency is taken without trying smaller ones.
GOOD_EXPLAINED = 0.999
#: Most base frequencies tried for an inferred design, and the longest FFT it takes.
MAX_BASES, MAX_PAD = 256, 2**22
#: Least spectral peak, relative to the largest, taken as an excited line.
LINE_REL = 1e-4


def periodic_design(m: Measurement, k: int) -> tuple[FloatArray, tuple[float, float]]:
    """Excited frequencies and measurement window of a periodic run.

    From the run's ``meta["signal"]`` when the twin wrote it; otherwise inferred from the
    commands (:func:`inferred_design`) and refused unless its lines explain at least
    :data:`MIN_EXPLAINED` of the commanded speed's power over the window.

    Raises
    ------
    SignalError
        No periodic signal in the commands, the run too short for a period, or lines that do
        not explain the commands (not a multisine over whole periods, or a run cut short).

    """
    sig = m.meta.get("signal", {})
    if "frequencies_hz" in sig and "window_s" in sig:
        return np.asarray(sig["frequencies_hz"], dtype=float), tuple(sig["window_s"])
    share, f, window = inferred_design(m, k)
    if share < MIN_EXPLAINED:
        raise SignalError(
            f"{m.source}: the lines found in the {DOF_NAMES[k]} commands "
            f"({', '.join(f'{x:.3g}' for x in f[:8])}{' ...' if f.size > 8 else ''} Hz) explain "
            f"only {100 * share:.0f} % of their speed's power over {window[0]:.2f}-"
            f"{window[1]:.2f} s: not a multisine over whole periods (or one in much noise); "
            "give the design in meta.json (signal.frequencies_hz and signal.window_s)"
        )
    return f, window


def inferred_design(m: Measurement, k: int) -> tuple[float, FloatArray, tuple[float, float]]:
    """Share explained, excited frequencies and window of a run without a design in its meta.

    The lines are the spectral peaks of the commanded speed (the pose command samples at
    their own rate, differenced: no interpolation images, no quantisation amplified twice,
    and neither the low lines of an equal-amplitude design nor the high ones of an
    equal-acceleration one are weighted away)
    in the middle half of the time both the commands and the IMU cover: above
    :data:`LINE_REL` of the largest and ten times the spectrum's median (its floor). The
    frequencies are then taken as multiples of a base frequency (§3.2.3.3); the window is
    the longest whole number of base periods between the fades of Eq 3.1 (1 / f_min long)
    at both ends, ending where the fade-out starts. The share is :func:`explained`'s, of the
    speed over the window.
    """
    c = m.commands
    rows = np.flatnonzero((c.t >= m.t[0] - 1e-9) & (c.t <= m.t[-1] + 1e-9))
    v = np.diff(c.values[rows, k]) * c.rate_hz
    tv = c.t[rows[:-1]] + 0.5 / c.rate_hz  # the differences' times
    n = v.size
    mid = v[n // 4 : 3 * n // 4]
    if mid.size < 64 or not np.any(mid):
        raise SignalError(f"{m.source}: the {DOF_NAMES[k]} commands hold no periodic signal "
                          "to analyse")  # fmt: skip
    pad = min(16 * mid.size, MAX_PAD)
    spec = np.abs(np.fft.rfft(mid * signal.windows.blackmanharris(mid.size), pad))
    freqs = np.fft.rfftfreq(pad, 1.0 / c.rate_hz)
    floor = max(LINE_REL * spec.max(), 10 * float(np.median(spec)))
    nyquist = 0.5 / (m.t[1] - m.t[0])  # of the analysis grid
    peak = (spec[1:-1] > spec[:-2]) & (spec[1:-1] >= spec[2:]) & (spec[1:-1] > floor)
    idx = np.flatnonzero(peak & (freqs[1:-1] < nyquist)) + 1
    if idx.size == 0:
        raise SignalError(f"{m.source}: no excited frequency found in the commands")
    # parabolic interpolation of the log spectrum around each peak
    a, b, cc = (np.log(spec[idx + j] + 1e-300) for j in (-1, 0, 1))
    curve = a - 2 * b + cc
    found = freqs[idx] + 0.5 * (a - cc) / np.where(curve < 0, curve, -1.0) * freqs[1]
    # the frequencies are multiples of a base frequency (§3.2.3.3). Candidates divide the
    # highest line (the best known relative to its own frequency: a low line of few periods
    # in the middle half is pulled by its negative-frequency image), each refined by least
    # squares on all lines; of those that fit every line within a third of a bin, the
    # largest whose lines explain the speed over whole periods (GOOD_EXPLAINED), else the
    # largest that explains enough (MIN_EXPLAINED: a smaller base that explains a hair more,
    # with fades longer than assumed in the window, is a worse fit of the lines), else the
    # one that explains most; at most MAX_BASES tried (a chirp's one peak fits every divisor)
    tol = 0.3 * c.rate_hz / mid.size
    best: tuple[float, FloatArray, tuple[float, float]] | None = None
    enough: tuple[float, FloatArray, tuple[float, float]] | None = None
    tried = 0
    for k_div in range(1, int(found.max() / tol) + 2):
        harmonic = np.maximum(np.round(found / (found.max() / k_div)), 1)
        fb = float(harmonic @ found / (harmonic @ harmonic))
        if not np.all(np.abs(found - harmonic * fb) < tol):
            continue
        f = np.unique(harmonic * fb)
        window = _whole_periods(m, f, fb)
        if window is None or tried == MAX_BASES:
            break  # smaller bases have longer periods still
        tried += 1
        share = explained(tv, v, f, window)
        if share >= GOOD_EXPLAINED:
            return share, f, window
        if enough is None and share >= MIN_EXPLAINED:
            enough = (share, f, window)
        if best is None or share > best[0]:
            best = (share, f, window)
    if enough is not None:
        return enough
    if best is None:
        raise SignalError(f"{m.source}: the run is too short for one period of its lines "
                          f"({', '.join(f'{x:.3g}' for x in found[:8])} Hz)")  # fmt: skip
    return best


def _whole_periods(m: Measurement, f: FloatArray, fb: float) -> tuple[float, float] | None:
    """Return the longest whole number of base periods between the fades (None: none fits)."""
    period = 1.0 / fb
    start, end = m.t[0] + 1.0 / f.min(), m.t[-1] - 1.0 / f.min()
    count = int(np.floor((end - start) / period + 1e-9))
    return (end - count * period, end) if count >= 1 else None


def explained(t: FloatArray, v: FloatArray, f: FloatArray, window: tuple[float, float]) -> float:
    """Share of ``v``'s power over ``window`` (mean removed) at the lines ``f``."""
    sel = (t >= window[0] - 1e-9) & (t < window[1] - 1e-9)
    power = np.sum(np.abs(fourier_coefficients(t, v, f, window)) ** 2) / 2
    return float(power / max(float(np.var(v[sel])), 1e-300))
