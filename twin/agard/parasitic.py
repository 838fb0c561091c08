"""The parasitic-motion test (AGARD-AR-144; §3.3.1 "parasitic noise", §5.5).

One DOF is driven at a time; the motion the platform makes in the five undriven DOFs is its
parasitic motion: "the amount of interaction between the various degrees of freedom"
(§3.3.1). For every driven DOF and every measured DOF this module gives

* the standard deviation (rms, mean removed) and the peak of the acceleration over the
  measurement window (the thesis' "standard deviation and peak value of the parasitic
  acceleration"), with the channel's noise rms beside it as a reference: from a rest record
  when one is given, otherwise from the window's noise-only bins (those that are no multiple
  of the design's base frequency; for a single sine every bin between its harmonics), their
  mean power times the count of all bins;
* the coupling at the driven lines, the cross describing function's magnitude = undriven
  acceleration / commanded driven acceleration at the excited frequencies (Eq 3.6 applied to
  an undriven output, as :func:`twin.agard.df.analyse_df`'s ``cross``): the largest over the
  lines and the power-weighted mean ``sqrt(sum |Y|^2 / sum |U|^2)``, with the noise floor from the
  neighbouring non-excited bins (:func:`twin.measurement.describing_function.neighbour_noise`)
  on the same scale. A coupling less than :data:`ABOVE_NOISE_DB` above its floor is "at noise".

The diagonal holds the driven DOF's own rms, peak and describing-function gain.

Tilt. The measured translational accelerations are specific force (:mod:`twin.measurement.
measure`): a platform that rolls or pitches exactly as commanded reads g sin(angle) in sway or
surge and g (1 - cos(angle)) in heave. That is the driven motion seen through gravity, not an
interaction between DOFs, so by default it is removed before the analysis: the driven angle is
rebuilt over the window from the *measured* driven acceleration at the excited lines
(angle = -acceleration / omega^2 line by line), and the tilt of that angle subtracted. The
coupling the tilt alone would give is reported (``tilt``) so a reader sees what was removed.
Measurements are taken at (or transformed to) the upper gimbal point, as AGARD-AR-144 asks: an
IMU elsewhere reads a lever-arm acceleration that this module does not remove.

Coupling between a translational and a rotational DOF has units (m/s^2 per rad/s^2 = m/rad,
or rad/m); it is given in SI and in dB of that SI ratio.

Examples
--------
>>> from twin.agard.session import Session
>>> from twin.measurement.measure import Bench, configure
>>> r = run_parasitic(Session(Bench(configure("srs"), "reduced")), dofs=("surge",))
>>> r.cells["surge"]["sway"].above_noise
False

"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.agard.df import joined_sources
from twin.agard.session import Session
from twin.chain.signals import base_frequency, describing_signal, single_sine
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES, dof_index
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.results import frame
from twin.measurement.describing_function import fourier_coefficients, neighbour_noise
from twin.measurement.measure import Measurement, driven_dof
from twin.measurement.periodic import periodic_design

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
G = 9.81
#: A coupling at least this far above its noise floor stands above noise [dB]; 6 dB with 6
#: neighbouring bins would call about one cell of a 6 x 6 table "above noise" by chance.
ABOVE_NOISE_DB = 10.0
#: Non-excited bins on each side of a line for its noise floor (20 bins: a line of noise alone
#: stands 10 dB above their mean once in about 3000).
NEIGHBOUR_BINS = 10
#: Default driving signal: a single sine at 0.5 Hz as in the half-Hertz test (§3.3.1).
DEFAULT_FREQUENCY_HZ = 0.5
#: Default acceleration amplitude [m/s^2 or rad/s^2] (inside the MPI and SRS limits at 0.5 Hz).
DEFAULT_AMPLITUDE = 0.3
#: Default measurement window [s] (whole periods; 0.05 Hz resolution).
DEFAULT_WINDOW_S = 20.0
#: Signals :func:`run_parasitic` knows.
SIGNALS = ("sine", "multisine1", "multisine2", "multisine3")
#: Least noise-only bins for the off-harmonic noise estimate.
MIN_NOISE_BINS = 8
#: How far a frequency may be from a whole number of periods in its window [periods].
PERIOD_TOLERANCE = 0.01


@dataclass(frozen=True)
class Segment:
    """A stretch of a measurement in which one DOF is driven with known lines.

    Attributes
    ----------
    measurement : Measurement
        The run (may hold other DOFs' segments elsewhere in time).
    window : tuple of float
        Start (inclusive) and end (exclusive) of the analysed stretch [s]; it must hold a whole
        number of periods of every frequency.
    frequencies_hz : tuple of float
        Excited frequencies of the driven DOF in the window [Hz].

    """

    measurement: Measurement
    window: tuple[float, float]
    frequencies_hz: tuple[float, ...]


@dataclass(frozen=True)
class Cell:
    """What one measured DOF did while one DOF was driven.

    Attributes
    ----------
    rms, peak : float
        Standard deviation (mean removed) and largest absolute value of the acceleration over
        the windows, tilt removed [m/s^2 or rad/s^2].
    noise_rms : float
        The channel's noise rms (rest record or noise-only bins; see the module docstring).
    coupling_max : float
        Largest ``|Y / U|`` over the excited lines (SI ratio).
    coupling_max_hz : float
        Where it is [Hz].
    coupling_mean : float
        Power-weighted mean ``sqrt(sum |Y|^2 / sum |U|^2)`` over the lines.
    coupling_noise : float
        The noise floor of ``coupling_mean`` on the same scale (neighbouring bins).
    tilt : float
        Power-weighted coupling of the removed gravity tilt (0 where none was removed).

    """

    rms: float
    peak: float
    noise_rms: float
    coupling_max: float
    coupling_max_hz: float
    coupling_mean: float
    coupling_noise: float
    tilt: float = 0.0

    @property
    def snr_db(self) -> float:
        """How far ``coupling_mean`` stands above its noise floor [dB] (inf: no noise)."""
        if not self.coupling_noise > 0:
            return float("inf")
        if self.coupling_mean <= 0:
            return float("-inf")
        return float(20 * np.log10(self.coupling_mean / self.coupling_noise))

    @property
    def above_noise(self) -> bool:
        """Whether the coupling stands :data:`ABOVE_NOISE_DB` above its noise floor."""
        return self.snr_db >= ABOVE_NOISE_DB

    @property
    def rms_over_noise(self) -> float:
        """``rms / noise_rms`` (1: the channel moved no more than its noise)."""
        return self.rms / self.noise_rms if self.noise_rms > 0 else float("inf")

    def to_dict(self) -> dict[str, float | bool]:
        """JSON-ready (infinities as None-free floats: ``snr_db`` may be a large number)."""
        snr = self.snr_db
        return {
            "rms": self.rms,
            "peak": self.peak,
            "noise_rms": self.noise_rms,
            "coupling_max": self.coupling_max,
            "coupling_max_hz": self.coupling_max_hz,
            "coupling_mean": self.coupling_mean,
            "coupling_noise": self.coupling_noise,
            "snr_db": snr if np.isfinite(snr) else (999.0 if snr > 0 else -999.0),
            "above_noise": self.above_noise,
            "tilt": self.tilt,
        }


@dataclass(frozen=True, eq=False)
class ParasiticResult:
    """Parasitic motion of the driven DOFs: a 6 x 6 of :class:`Cell` (rows driven).

    Attributes
    ----------
    cells : dict of str to dict of str to Cell
        ``cells[driven][measured]``; the driven DOF's own cell is the diagonal.
    frequencies_hz : dict of str to ndarray
        Excited lines per driven DOF (all its segments).
    source : str
        What was measured.
    noise_basis : str
        Where the noise rms came from (``"rest record"`` or ``"noise-only bins"``).
    tilt_removed : bool
        Whether the gravity tilt of a driven roll or pitch was removed.

    """

    cells: dict[str, dict[str, Cell]]
    frequencies_hz: dict[str, FloatArray]
    source: str
    noise_basis: str
    tilt_removed: bool

    @property
    def dofs(self) -> tuple[str, ...]:
        """The driven DOFs, in the order of :data:`twin.core.frames.DOF_NAMES`."""
        return tuple(d for d in DOF_NAMES if d in self.cells)

    def matrix(self, name: str) -> FloatArray:
        """Return one field of the cells as a 6 x 6 array (rows driven; NaN: not driven).

        Parameters
        ----------
        name : str
            A :class:`Cell` attribute or property (``"coupling_mean"``, ``"rms"``,
            ``"snr_db"``, ...).

        """
        if name not in {*Cell.__dataclass_fields__, "snr_db", "rms_over_noise", "above_noise"}:
            raise SignalError(f"unknown cell field {name!r}; expected one of "
                              f"{', '.join(Cell.__dataclass_fields__)}, snr_db, "
                              "rms_over_noise, above_noise")  # fmt: skip
        out = np.full((6, 6), np.nan)
        for d, row in self.cells.items():
            for m, cell in row.items():
                out[dof_index(d), dof_index(m)] = float(getattr(cell, name))
        return out

    def worst(self) -> tuple[str, str, Cell]:
        """Return the off-diagonal cell of largest ``coupling_mean / coupling_noise``."""
        pairs = [(d, m, c) for d, row in self.cells.items() for m, c in row.items() if m != d]
        return max(pairs, key=lambda p: p[2].snr_db)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready result: per driven DOF, per measured DOF, the :class:`Cell` fields."""
        return {
            "test": "parasitic motion",
            "source": self.source,
            "noise_basis": self.noise_basis,
            "tilt_removed": self.tilt_removed,
            "above_noise_db": ABOVE_NOISE_DB,
            "frequencies_hz": {d: f.tolist() for d, f in self.frequencies_hz.items()},
            "cells": {d: {m: c.to_dict() for m, c in row.items()} for d, row in self.cells.items()},
        }

    def format_table(self) -> str:
        """Plain-text 6 x 6 tables (rows driven, columns measured): rms and coupling."""
        head = f"{'driven':>8} " + " ".join(f"{m:>11}" for m in DOF_NAMES)
        tilt = "gravity tilt removed" if self.tilt_removed else "gravity tilt included"
        lines = [
            f"parasitic motion ({self.source}; {tilt}; noise from {self.noise_basis})",
            "rms / noise rms [m/s^2 or rad/s^2] over the window:",
            head,
        ]
        for d in self.dofs:
            row = self.cells[d]
            lines.append(f"{d:>8} " + " ".join(
                f"{row[m].rms:.3f}/{row[m].noise_rms:.3f}".rjust(11) for m in DOF_NAMES
            ))  # fmt: skip
        lines += [
            "coupling at the driven lines, power-weighted |Y/U| [%, SI ratio]; diagonal the "
            f"describing-function gain; '~' within {ABOVE_NOISE_DB:g} dB of the noise floor:",
            head,
        ]
        for d in self.dofs:
            row = self.cells[d]
            cells = []
            for m in DOF_NAMES:
                c = row[m]
                mark = "" if c.above_noise or m == d else "~"
                cells.append(f"{mark}{100 * c.coupling_mean:.2f}".rjust(11))
            lines.append(f"{d:>8} " + " ".join(cells))
        d, m, c = self.worst()
        lines.append(
            f"most above noise: {d} -> {m}, {100 * c.coupling_mean:.2f} % "
            f"(max {100 * c.coupling_max:.2f} % "
            f"at {c.coupling_max_hz:g} Hz), {c.snr_db:.1f} dB above its noise floor "
            f"{100 * c.coupling_noise:.2f} %"
        )
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """One row per driven and measured DOF (:meth:`Cell.to_dict`)."""
        return frame({"driven": d, "measured": m, **c.to_dict()}
                     for d, row in self.cells.items() for m, c in row.items())  # fmt: skip

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Heat map of the coupling in dB (rows driven, columns measured), numbers in cells.

        Cells within :data:`ABOVE_NOISE_DB` of their noise floor are hatched and their
        number greyed; rows of undriven DOFs are blank; the diagonal is the driven DOF's
        describing-function gain. ``ax``: one Axes to draw on (its figure gets the colour
        bar; a new figure by default); ``path``: save the figure here.
        """
        from matplotlib.patches import Rectangle

        c = self.matrix("coupling_mean")
        with np.errstate(divide="ignore", invalid="ignore"):
            db = 20 * np.log10(c)
        off = db.copy()
        np.fill_diagonal(off, np.nan)
        finite = off[np.isfinite(off)]
        lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (-60.0, 0.0)
        fig, ax = subplots(ax, figsize=(6.8, 5.6))
        image = ax.imshow(np.ma.masked_invalid(off), cmap="viridis", vmin=min(lo, hi - 1),
                          vmax=hi)  # fmt: skip
        fig.colorbar(image, ax=ax, label="coupling |Y / U| [dB, SI ratio]")
        noisy = ~self.matrix("above_noise").astype(bool) & np.isfinite(c)
        for i in range(6):
            for j in range(6):
                if not np.isfinite(c[i, j]):
                    continue
                if i == j:
                    ax.add_patch(Rectangle((j - 0.5, i - 0.5), 1, 1, fc="white", ec="k"))
                    text, colour = f"{db[i, j]:.1f}\nDF gain", "k"
                else:
                    if noisy[i, j]:
                        ax.add_patch(Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False,
                                                   hatch="///", ec="w", lw=0))  # fmt: skip
                    text = f"{'~' if noisy[i, j] else ''}{db[i, j]:.1f}\n{100 * c[i, j]:.2g} %"
                    colour = "k" if image.norm(db[i, j]) > 0.5 else "w"
                ax.text(j, i, text, ha="center", va="center", fontsize=7, color=colour)
        ax.set_xticks(range(6), DOF_NAMES)
        ax.set_yticks(range(6), DOF_NAMES)
        ax.set_xlabel("measured DOF")
        ax.set_ylabel("driven DOF")
        ax.set_title(f"parasitic coupling (hatched: within {ABOVE_NOISE_DB:g} dB of noise)\n"
                     f"{self.source}", fontsize=9)  # fmt: skip
        return finish(fig, path)


def _check_dofs(dofs: Sequence[str]) -> tuple[str, ...]:
    """Return the DOFs as a tuple, refusing unknown, repeated or none."""
    if isinstance(dofs, str):
        dofs = (dofs,)
    out = tuple(dofs)
    if not out:
        raise SignalError(f"no DOF to drive; choose from {', '.join(DOF_NAMES)}")
    for d in out:
        if d not in DOF_NAMES:
            raise SignalError(f"unknown DOF {d!r}; expected one of {', '.join(DOF_NAMES)}")
    if len(set(out)) != len(out):
        raise SignalError(f"each DOF may be driven once; got {', '.join(out)}")
    return out


def _check_segment(seg: Segment, dof: str) -> tuple[FloatArray, tuple[float, float]]:
    """Return a segment's frequencies and window, refusing what cannot be analysed."""
    m = seg.measurement
    try:
        t0, t1 = (float(x) for x in seg.window)
    except (TypeError, ValueError):
        raise SignalError(f"{dof}: a window is (start_s, end_s); got {seg.window!r}") from None
    dt = float(m.t[1] - m.t[0])
    if not (np.isfinite(t0) and np.isfinite(t1) and t1 > t0):
        raise SignalError(f"{dof}: a window is (start_s, end_s) with start < end; got "
                          f"({t0:g}, {t1:g})")  # fmt: skip
    if t0 < m.t[0] - 1e-6 or t1 > m.t[-1] + dt + 1e-6:
        raise SignalError(
            f"{dof}: the window {t0:g}-{t1:g} s lies outside the run {m.source} "
            f"({m.t[0]:g}-{m.t[-1] + dt:g} s); a window must lie within the measurement"
        )
    f = np.atleast_1d(np.asarray(seg.frequencies_hz, dtype=float))
    nyquist = 0.5 / dt
    if f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0) or np.any(f >= nyquist):
        raise SignalError(f"{dof}: frequencies must be finite, between 0 and the Nyquist "
                          f"frequency {nyquist:g} Hz; got {f.tolist()}")  # fmt: skip
    periods = f * (t1 - t0)
    if np.any(np.abs(periods - np.round(periods)) > PERIOD_TOLERANCE) or np.any(periods < 0.99):
        raise SignalError(
            f"{dof}: the window {t0:g}-{t1:g} s ({t1 - t0:g} s) must hold a whole number of "
            f"periods of every frequency; {f.tolist()} Hz give {np.round(periods, 3).tolist()}"
        )
    return f, (t0, t1)


def _tilt(t: FloatArray, f: FloatArray, acc: ComplexArray, k: int) -> FloatArray:
    """Specific force of the tilt of a driven roll (k = 3) or pitch (k = 4), shape (n, 3).

    The angle is rebuilt from the measured angular acceleration's coefficients at the lines
    (angle = -acc / omega^2); pitch reads (g sin, 0, g (1 - cos)), roll (0, -g sin, g (1 - cos))
    (R^T (0, 0, -g) + (0, 0, g), R the cabin attitude, z down).
    """
    out = np.zeros((t.size, 3))
    if k not in (3, 4):
        return out
    w = 2 * np.pi * f
    angle = np.imag(np.exp(1j * np.outer(t, w)) @ (-acc / w**2))
    out[:, 0 if k == 4 else 1] = (1.0 if k == 4 else -1.0) * G * np.sin(angle)
    out[:, 2] = G * (1 - np.cos(angle))
    return out


def _off_harmonic_power(y: FloatArray, dt: float, f: FloatArray) -> tuple[float, int]:
    """Noise variance of ``y`` from its noise-only bins, and their count (0: too few).

    The noise-only bins are the window's bins that are no multiple of the design's base
    frequency (where a periodic response has nothing); their mean power times the count of
    all bins between DC and Nyquist estimates the noise variance over the band.
    """
    n = y.size
    power = 2 * np.abs(np.fft.rfft(y)) ** 2 / n**2
    k = np.arange(power.size)
    band = (k > 0) & (k < n / 2)
    period = n * dt
    fb = base_frequency(f, resolution_hz=1e-4)
    ratio = k * (1 / period) / fb
    periodic = np.abs(ratio - np.round(ratio)) < 1e-3
    noise = band & ~periodic
    if noise.sum() < MIN_NOISE_BINS:
        return float("nan"), 0
    return float(power[noise].mean() * band.sum()), int(noise.sum())


@dataclass
class _Acc:
    """Accumulates one driven DOF's segments."""

    sq: FloatArray  # sum of squares (mean removed) per channel
    n: int
    peak: FloatArray
    noise_sq: FloatArray  # noise variance times samples, per channel
    noise_n: int
    Y: list[ComplexArray]  # (m, 6) per segment
    U: list[ComplexArray]
    N: list[FloatArray]  # neighbour noise amplitude, (m, 6)
    T: list[ComplexArray]  # tilt coefficients, (m, 6)
    f: list[FloatArray]


def _segment(acc: _Acc, seg: Segment, k: int, dof: str, remove_tilt: bool, rest: bool) -> None:
    """Add one segment to a driven DOF's sums."""
    m = seg.measurement
    f, window = _check_segment(seg, dof)
    sel = (m.t >= window[0] - 1e-9) & (m.t < window[1] - 1e-9)
    if sel.sum() < 16:
        raise SignalError(f"{dof}: the window {window[0]:g}-{window[1]:g} s holds fewer than 16 "
                          f"samples of {m.source}")  # fmt: skip
    t = m.t[sel]
    U = fourier_coefficients(m.t, m.commanded[:, k], f, window)
    scale = max(float(np.abs(m.commanded[sel, k]).max()), 1e-300)
    if np.any(np.abs(U) < 1e-6 * scale) or not np.any(m.commanded[sel, k]):
        raise SignalError(f"{dof}: the {dof} commands of {m.source} do not excite every line "
                          f"{f.tolist()} Hz in {window[0]:g}-{window[1]:g} s")  # fmt: skip
    raw = m.measured[sel]
    Y_raw = fourier_coefficients(t, raw, f, window)
    tilt = np.zeros_like(raw)
    if remove_tilt:
        tilt[:, :3] = _tilt(t, f, Y_raw[:, k], k)
    y = raw - tilt
    Y = fourier_coefficients(t, y, f, window)
    Y[:, k] = Y_raw[:, k]
    yc = y - y.mean(axis=0)
    acc.sq += np.sum(yc**2, axis=0)
    acc.n += t.size
    acc.peak = np.maximum(acc.peak, np.abs(yc).max(axis=0))
    if not rest:
        dt = float(m.t[1] - m.t[0])
        for j in range(6):
            var, bins = _off_harmonic_power(yc[:, j], dt, f)
            if bins == 0:
                raise SignalError(
                    f"{dof}: the window {window[0]:g}-{window[1]:g} s of {m.source} has no bins "
                    f"free of the lines' base frequency ({f.tolist()} Hz) to measure the noise "
                    "in; give a rest record (rest=...) or a single sine"
                )
            acc.noise_sq[j] += var * t.size
        acc.noise_n += t.size
    acc.N.append(
        np.column_stack([neighbour_noise(t, y[:, j], f, window, NEIGHBOUR_BINS) for j in range(6)])
    )
    acc.Y.append(Y)
    acc.U.append(U)
    acc.T.append(fourier_coefficients(t, tilt, f, window))
    acc.f.append(f)


def _rest_noise(rest: Sequence[tuple[Measurement, tuple[float, float]]]) -> FloatArray:
    """Noise rms per channel from rest records (each window's mean removed, pooled)."""
    sq, n = np.zeros(6), 0
    for m, window in rest:
        seg = Segment(m, window, (1.0 / (window[1] - window[0]),))
        _check_segment(seg, "rest")
        sel = (m.t >= window[0] - 1e-9) & (m.t < window[1] - 1e-9)
        x = m.measured[sel] - m.measured[sel].mean(axis=0)
        sq += np.sum(x**2, axis=0)
        n += int(sel.sum())
    if n < 16:
        raise SignalError("the rest record holds fewer than 16 samples")
    return np.sqrt(sq / n)


def analyse_segments(
    segments: Mapping[str, Sequence[Segment]],
    rest: Sequence[tuple[Measurement, tuple[float, float]]] | None = None,
    remove_tilt: bool = True,
) -> ParasiticResult:
    """Return the parasitic motion from segments of one or more runs.

    Parameters
    ----------
    segments : mapping of str to sequence of Segment
        Per driven DOF, the stretches in which it alone was driven (e.g. the single sines of
        an AGARD-AR-144 schedule inside one long run, each with its own window and lines).
    rest : sequence of (Measurement, (start_s, end_s)), optional
        Stretches at rest (the platform holding neutral): the noise rms of every channel.
        Without them the noise rms comes from each window's noise-only bins.
    remove_tilt : bool
        Remove the gravity tilt of a driven roll or pitch (see the module docstring).

    Raises
    ------
    SignalError
        An unknown DOF, a DOF without segments, a window outside its run or without whole
        periods, lines the commands do not excite, or a window without noise-only bins and
        no rest record.

    """
    dofs = _check_dofs(tuple(segments))
    noise = _rest_noise(rest) if rest else None
    cells: dict[str, dict[str, Cell]] = {}
    freqs: dict[str, FloatArray] = {}
    sources = []
    for dof in dofs:
        segs = list(segments[dof])
        if not segs:
            raise SignalError(f"{dof}: no segment given; each driven DOF needs at least one")
        k = dof_index(dof)
        acc = _Acc(np.zeros(6), 0, np.zeros(6), np.zeros(6), 0, [], [], [], [], [])
        for seg in segs:
            if not isinstance(seg, Segment):
                raise SignalError(f"{dof}: segments are Segment(measurement, window, "
                                  f"frequencies_hz); got {type(seg).__name__}")  # fmt: skip
            _segment(acc, seg, k, dof, remove_tilt, noise is not None)
            sources.append(seg.measurement.source)
        Y, U, N, T = (np.concatenate(x) for x in (acc.Y, acc.U, acc.N, acc.T))
        f = np.concatenate(acc.f)
        u2 = float(np.sum(np.abs(U) ** 2))
        rms = np.sqrt(acc.sq / acc.n)
        noise_rms = noise if noise is not None else np.sqrt(acc.noise_sq / acc.noise_n)
        row = {}
        for j, name in enumerate(DOF_NAMES):
            c = np.abs(Y[:, j] / U)
            i = int(np.argmax(c))
            row[name] = Cell(
                rms=float(rms[j]),
                peak=float(acc.peak[j]),
                noise_rms=float(noise_rms[j]),
                coupling_max=float(c[i]),
                coupling_max_hz=float(f[i]),
                coupling_mean=float(np.sqrt(np.sum(np.abs(Y[:, j]) ** 2) / u2)),
                coupling_noise=float(np.sqrt(np.nansum(N[:, j] ** 2) / u2)),
                tilt=float(np.sqrt(np.sum(np.abs(T[:, j]) ** 2) / u2)),
            )
        cells[dof] = row
        freqs[dof] = f
    basis = "rest record" if noise is not None else "noise-only bins"
    source = joined_sources(sources)
    return ParasiticResult(cells, freqs, source, basis, remove_tilt)


def analyse_parasitic(
    m: Measurement, dof: str | None = None, remove_tilt: bool = True
) -> ParasiticResult:
    """Return the parasitic motion of one single-DOF periodic run (e.g. a run folder's).

    The design (lines and window) comes from the run's ``meta.json`` or is inferred from the
    commands (:func:`twin.measurement.periodic.periodic_design`).

    Parameters
    ----------
    m : Measurement
        The run (:func:`twin.measurement.measure.from_run` for a recorded folder).
    dof : str, optional
        The driven DOF; by default the one the run's signal names or the commands move most.
    remove_tilt : bool
        See :func:`analyse_segments`.

    """
    k = driven_dof(m, dof)
    f, window = periodic_design(m, k)
    seg = Segment(m, window, tuple(float(x) for x in f))
    return analyse_segments({DOF_NAMES[k]: [seg]}, remove_tilt=remove_tilt)


def run_parasitic(
    session: Session,
    dofs: Sequence[str] = DOF_NAMES,
    signal: str = "sine",
    frequency_hz: float = DEFAULT_FREQUENCY_HZ,
    amplitude: float | ArrayLike = DEFAULT_AMPLITUDE,
    window_s: float = DEFAULT_WINDOW_S,
    remove_tilt: bool = True,
) -> ParasiticResult:
    """Drive each DOF in turn on a session's bench and analyse the parasitic motion.

    Parameters
    ----------
    session : Session
        The bench and its sinks; one run per driven DOF.
    dofs : sequence of str
        The DOFs to drive (all six by default).
    signal : str
        ``"sine"`` (default: one sine of ``frequency_hz`` and ``amplitude``, as the thesis'
        parasitic noise at 0.5 Hz, §3.3.1: every bin between its harmonics is noise only,
        so the noise reference comes from the same run) or ``"multisine1"`` ...
        ``"multisine3"`` (Table 5.2: coupling over 0.1-7 Hz, but every bin of its 20 s
        window is a multiple of its base frequency, so intermodulation can reach the noise
        estimate and the analysis refuses it without a rest record: use
        :func:`analyse_segments` with ``rest``).
    frequency_hz, amplitude, window_s : float
        The sine's frequency [Hz], acceleration amplitude [m/s^2 or rad/s^2] (one, or one
        per entry of ``dofs``) and shortest window [s].
    remove_tilt : bool
        See :func:`analyse_segments`.

    """
    dofs = _check_dofs(dofs)
    if signal not in SIGNALS:
        raise SignalError(f"unknown parasitic signal {signal!r}; expected one of "
                          f"{', '.join(SIGNALS)}")  # fmt: skip
    try:
        amps = np.array(amplitude, dtype=float, ndmin=1)
    except (TypeError, ValueError):
        raise SignalError(f"amplitude must be one positive number or one per DOF; got "
                          f"{amplitude!r}") from None  # fmt: skip
    if amps.size == 1:
        amps = np.full(len(dofs), amps[0])
    if amps.shape != (len(dofs),) or not np.all(np.isfinite(amps) & (amps > 0)):
        raise SignalError(f"amplitude must be one positive number or one per DOF "
                          f"({len(dofs)}); got {amplitude!r}")  # fmt: skip
    segments = {}
    session.expect(len(dofs), "parasitic motion")
    for dof, a in zip(dofs, amps, strict=True):
        if signal == "sine":
            sig = single_sine(dof, frequency_hz, float(a), window_s=window_s)
            name = f"parasitic-sine-{dof}-{frequency_hz:g}Hz-{a:g}"
        else:
            sig = describing_signal(int(signal[-1]), dof, settle_s=None)
            name = f"parasitic-{signal}-{dof}"
        m = session.measure(sig, name)
        segments[dof] = [Segment(m, sig.window, tuple(float(x) for x in sig.frequencies_hz))]
    return analyse_segments(segments, remove_tilt=remove_tilt)


__all__ = [
    "ABOVE_NOISE_DB",
    "Cell",
    "ParasiticResult",
    "Segment",
    "analyse_parasitic",
    "analyse_segments",
    "run_parasitic",
]
