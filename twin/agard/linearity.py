"""The AGARD-AR-144 linearity test: the describing function at several amplitudes.

A single sine (Eq 3.4) drives one DOF at each of a few frequencies and, per frequency, at
several acceleration amplitudes (AR-144's A schedules: three a decade apart, e.g. 3, 0.3 and
0.03 m/s^2 or rad/s^2 at mid frequencies). At each point the describing function is the ratio
of the Fourier coefficients of the measured and the commanded acceleration at the driving
frequency over a window of whole periods (Eq 3.6, as :mod:`twin.agard.df`). A linear system
has the same describing function at every amplitude; the test reports, per frequency, how
gain and phase change with amplitude relative to the largest amplitude run there, with
confidence intervals from the noise at the neighbouring non-excited bins
(:func:`twin.measurement.describing_function.neighbour_noise`).

Confidence intervals: the neighbouring bins' RMS Fourier amplitude, over the commanded
amplitude, is the total standard deviation ``s`` of the complex describing function; its
component along the response (the gain's) and across it (the gain times the phase's, in
radians) each have sd ``s / sqrt(2)`` (as :meth:`twin.agard.df.DfResult.bounds_95`). A change
relative to the reference amplitude has the two points' variances added (independent noise);
the half-width is ``z`` times its sd, ``z`` the normal quantile of the level (1.96 at 95 %).

The analysis (:func:`analyse_linearity`) works on :class:`LinearitySegment` s: a measurement,
a window of whole periods in it, the frequency and the amplitude. A lab that runs its whole
schedule as one long run gives one segment per sine, all windows in the same measurement.

Examples
--------
>>> from twin.agard.session import Session
>>> from twin.measurement.measure import Bench, configure
>>> s = Session(Bench(configure("srs", noise=False), "reduced"))
>>> r = run_linearity(s, "heave", frequencies_hz=[1.0], amplitudes=[1.0, 0.1])
>>> bool(abs(r.gain_change[0]) < 0.01)
True

"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy.stats import norm

from twin.agard.df import joined_sources
from twin.agard.segments import AMPLITUDE_TOLERANCE, checked_window
from twin.agard.session import Session
from twin.chain.signals import check_signal, single_sine
from twin.core.checks import number
from twin.core.errors import SignalError, SignalLimitError
from twin.core.frames import DOF_NAMES, acceleration_unit
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.results import frame
from twin.measurement.describing_function import fourier_coefficients, neighbour_noise
from twin.measurement.measure import Measurement, driven_dof

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: Default frequencies [Hz]: a handful across 0.2-5 Hz.
DEFAULT_FREQUENCIES_HZ = (0.2, 0.5, 1.0, 2.0, 5.0)
#: Default amplitudes relative to the largest one at a frequency: three a decade apart.
DEFAULT_LADDER = (1.0, 0.1, 0.01)
#: Largest default amplitude, and the smaller ones tried (1-2-5 steps) where it breaks a
#: platform limit [m/s^2 or rad/s^2].
DEFAULT_TOPS = (3.0, 2.0, 1.0, 0.5, 0.2, 0.1, 0.05, 0.02, 0.01, 0.005, 0.002, 0.001)
#: Shortest measurement window of a run [s] (whole periods, rounded up).
WINDOW_S = 10.0
#: Default confidence level of the intervals.
LEVEL = 0.95


@dataclass(frozen=True)
class LinearitySegment:
    """One point of the linearity test: a window of a measurement driven by one sine.

    Attributes
    ----------
    measurement : Measurement
        The run (may hold other sines outside the window).
    start_s, end_s : float
        The window [s], on the measurement's clock: whole periods of the sine, after its
        fade-in and settling.
    frequency_hz : float
        The sine's frequency [Hz].
    amplitude : float
        Its commanded acceleration amplitude [m/s^2 or rad/s^2].

    """

    measurement: Measurement
    start_s: float
    end_s: float
    frequency_hz: float
    amplitude: float


@dataclass(frozen=True)
class SkippedPoint:
    """A point that was not run, and why (the platform limit it would break)."""

    frequency_hz: float
    amplitude: float
    reason: str


@dataclass(frozen=True, eq=False)
class LinearityResult:
    """Describing functions of one DOF at several amplitudes per frequency.

    Points are sorted by frequency, then by amplitude, largest first.

    Attributes
    ----------
    dof : str
        Driven DOF.
    frequencies_hz, amplitudes : ndarray, shape (p,)
        Each measured point's frequency [Hz] and acceleration amplitude.
    response : ndarray of complex, shape (p,)
        Describing function (measured / commanded acceleration) at each point.
    noise : ndarray, shape (p,)
        Total standard deviation of ``response`` from the neighbouring bins.
    skipped : tuple of SkippedPoint
        Points not run.
    source : str
        What was measured.
    level : float
        Confidence level of the intervals (0.95: 95 %).

    """

    dof: str
    frequencies_hz: FloatArray
    amplitudes: FloatArray
    response: ComplexArray
    noise: FloatArray
    skipped: tuple[SkippedPoint, ...]
    source: str
    level: float = LEVEL

    @property
    def gain(self) -> FloatArray:
        """``|H|`` at each point (ratio)."""
        return np.abs(self.response)

    @property
    def phase_deg(self) -> FloatArray:
        """Phase of H at each point [deg], in (-180, 180]."""
        return np.degrees(np.angle(self.response))

    @property
    def z(self) -> float:
        """Normal quantile of :attr:`level` (1.96 at 95 %)."""
        return float(norm.ppf(0.5 + self.level / 2))

    @property
    def reference(self) -> NDArray[np.int64]:
        """Index of each point's reference: the largest amplitude measured at its frequency."""
        out = np.empty(self.frequencies_hz.size, dtype=np.int64)
        for f in np.unique(self.frequencies_hz):
            at = np.flatnonzero(self.frequencies_hz == f)
            out[at] = at[np.argmax(self.amplitudes[at])]
        return out

    def _relative_sd(self) -> FloatArray:
        """Each point's component sd over its gain (= its phase sd in radians)."""
        return self.noise / np.sqrt(2) / self.gain

    @property
    def gain_change(self) -> FloatArray:
        """Gain relative to the reference amplitude's, minus 1 (0: linear)."""
        return self.gain / self.gain[self.reference] - 1.0

    @property
    def phase_change_deg(self) -> FloatArray:
        """Phase minus the reference amplitude's [deg] (0: linear)."""
        return np.degrees(np.angle(self.response / self.response[self.reference]))

    def _change_sd(self) -> FloatArray:
        """Relative sd of a point's change from its reference (0 for the reference itself)."""
        r, ref = self._relative_sd(), self.reference
        own = np.arange(ref.size) == ref
        return np.where(own, 0.0, np.hypot(r, r[ref]))

    @property
    def gain_change_ci(self) -> FloatArray:
        """Half-width of :attr:`gain_change`'s confidence interval at :attr:`level`."""
        return self.z * (self.gain_change + 1.0) * self._change_sd()

    @property
    def phase_change_ci_deg(self) -> FloatArray:
        """Half-width of :attr:`phase_change_deg`'s confidence interval [deg]."""
        return np.degrees(self.z * self._change_sd())

    @property
    def gain_ci(self) -> FloatArray:
        """Half-width of each gain's own confidence interval."""
        return self.z * self.noise / np.sqrt(2)

    @property
    def phase_ci_deg(self) -> FloatArray:
        """Half-width of each phase's own confidence interval [deg] (90: noise reaches the gain)."""
        return np.degrees(np.arcsin(np.clip(self.z * self._relative_sd(), 0.0, 1.0)))

    @property
    def linear(self) -> NDArray[np.bool_]:
        """Whether each point's gain and phase change lie within their confidence intervals.

        A reference point is linear by definition (its change is zero, to rounding).
        """
        is_reference = self.reference == np.arange(self.frequencies_hz.size)
        return is_reference | (
            (np.abs(self.gain_change) <= self.gain_change_ci)
            & (np.abs(self.phase_change_deg) <= self.phase_change_ci_deg)
        )

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: ``points`` (gain, phase, their changes and intervals) and ``skipped``."""
        cols = {
            "frequency_hz": self.frequencies_hz,
            "amplitude": self.amplitudes,
            "gain": self.gain,
            "gain_ci": self.gain_ci,
            "phase_deg": self.phase_deg,
            "phase_ci_deg": self.phase_ci_deg,
            "gain_change": self.gain_change,
            "gain_change_ci": self.gain_change_ci,
            "phase_change_deg": self.phase_change_deg,
            "phase_change_ci_deg": self.phase_change_ci_deg,
            "gain_sd": self.noise,
        }
        points = [
            {k: _finite(v[i]) for k, v in cols.items()}
            | {
                "reference_amplitude": float(self.amplitudes[self.reference[i]]),
                "linear": bool(self.linear[i]),
            }
            for i in range(self.frequencies_hz.size)
        ]
        return {
            "test": "linearity",
            "dof": self.dof,
            "source": self.source,
            "amplitude_unit": acceleration_unit(self.dof),
            "confidence_level": self.level,
            "points": points,
            "skipped": [
                {"frequency_hz": s.frequency_hz, "amplitude": s.amplitude, "reason": s.reason}
                for s in self.skipped
            ],
        }

    def format_table(self) -> str:
        """Plain-text table: per point gain, phase and their change from the reference."""
        pct = f"{100 * self.level:g} %"
        lines = [
            f"linearity, {self.dof} ({self.source}); changes relative to the largest "
            f"amplitude at each frequency, +- {pct} interval",
            f"{'f [Hz]':>7} {'A [' + acceleration_unit(self.dof) + ']':>12} {'gain':>7} "
            f"{'phase':>7} {'gain change %':>17} {'phase change deg':>18}",
        ]
        for i in range(self.frequencies_hz.size):
            ref = self.reference[i] == i
            change = (
                f"{'reference':>17} {'':>18}"
                if ref
                else f"{100 * self.gain_change[i]:+8.2f} +-{100 * self.gain_change_ci[i]:6.2f} "
                f"{self.phase_change_deg[i]:+8.2f} +-{self.phase_change_ci_deg[i]:6.2f}"
            )
            lines.append(
                f"{self.frequencies_hz[i]:7.3g} {self.amplitudes[i]:12.4g} {self.gain[i]:7.4f} "
                f"{self.phase_deg[i]:7.1f} {change}"
            )
        for s in self.skipped:
            lines.append(f"{s.frequency_hz:7.3g} {s.amplitude:12.4g} skipped: {s.reason}")
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """One row per frequency and amplitude: the ``points`` of :meth:`to_dict`."""
        return frame(self.to_dict()["points"])  # type: ignore[arg-type]

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Gain and phase against amplitude, one line per frequency, with error bars.

        Parameters
        ----------
        ax : sequence of two Axes, optional
            Where to draw: gain and phase; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        fig, (ax_g, ax_p) = subplots(ax, 2, 1, figsize=(6.5, 6), sharex=True)
        for c, f in enumerate(np.unique(self.frequencies_hz)):
            at = np.flatnonzero(self.frequencies_hz == f)
            at = at[np.argsort(self.amplitudes[at])]
            a, colour = self.amplitudes[at], f"C{c % 10}"
            ax_g.errorbar(a, self.gain[at], yerr=self.gain_ci[at], fmt="o-", color=colour,
                          capsize=2, ms=4, label=f"{f:g} Hz")  # fmt: skip
            ax_p.errorbar(a, self.phase_deg[at], yerr=self.phase_ci_deg[at], fmt="o-",
                          color=colour, capsize=2, ms=4)  # fmt: skip
        ax_g.set_xscale("log")
        ax_g.set_ylabel("gain [-]")
        ax_p.set_ylabel("phase [deg]")
        ax_p.set_xlabel(f"amplitude [{acceleration_unit(self.dof)}]")
        for ax in (ax_g, ax_p):
            ax.grid(True, which="major", alpha=0.5)
            ax.grid(True, which="minor", alpha=0.2)
        if self.frequencies_hz.size:
            ax_g.legend(fontsize=8)
        ax_g.set_title(f"linearity, {self.dof} ({100 * self.level:g} % intervals): "
                       f"{self.source}", fontsize=9)  # fmt: skip
        return finish(fig, path)


def _finite(x: float) -> float | None:
    """Return a float for JSON (None for a non-finite value)."""
    return float(x) if np.isfinite(x) else None


def check_segment(seg: LinearitySegment, k: int) -> None:
    """Raise :class:`SignalError` for a segment that cannot be analysed.

    The window must lie in the measurement and hold a whole number of periods
    (:func:`~twin.agard.segments.checked_window`); the commanded acceleration's amplitude at
    the frequency over the window must be the stated one within
    :data:`~twin.agard.segments.AMPLITUDE_TOLERANCE`.
    """
    m = seg.measurement
    where = f"{m.source}: segment {seg.frequency_hz:g} Hz, {seg.amplitude:g}"
    span = (float(m.t[0]), float(m.t[-1]))
    f, start, end = checked_window(
        where, seg.frequency_hz, seg.amplitude, (seg.start_s, seg.end_s), span
    )
    got = abs(fourier_coefficients(m.t, m.commanded[:, k], [f], (start, end))[0])
    if abs(got / seg.amplitude - 1) > AMPLITUDE_TOLERANCE:
        raise SignalError(
            f"{where}: the commanded {DOF_NAMES[k]} acceleration over the window has amplitude "
            f"{got:.4g} at {f:g} Hz, not the stated {seg.amplitude:g} (within "
            f"{100 * AMPLITUDE_TOLERANCE:g} %); a window from another part of the run?"
        )


def analyse_point(seg: LinearitySegment, k: int) -> tuple[complex, float]:
    """Return the describing function and its total noise sd of one checked segment."""
    m, f, window = seg.measurement, [seg.frequency_hz], (seg.start_s, seg.end_s)
    U = fourier_coefficients(m.t, m.commanded[:, k], f, window)[0]
    Y = fourier_coefficients(m.t, m.measured[:, k], f, window)[0]
    noise = neighbour_noise(m.t, m.measured[:, k], f, window)[0] / abs(U)
    return complex(Y / U), float(noise)


def analyse_linearity(
    segments: Sequence[LinearitySegment],
    dof: str | None = None,
    skipped: Sequence[SkippedPoint] = (),
    level: float = LEVEL,
) -> LinearityResult:
    """Return the linearity test of measured segments (one sine each).

    Parameters
    ----------
    segments : sequence of LinearitySegment
        One per point; windows of whole periods, possibly of one long run.
    dof : str, optional
        Driven DOF; else each measurement's (its ``meta`` or the DOF its commands move most),
        which must be the same for all.
    skipped : sequence of SkippedPoint
        Points that were not run, reported as such.
    level : float
        Confidence level of the intervals, in (0, 1).

    Raises
    ------
    SignalError
        For no segment, segments of different DOFs, two at the same frequency and amplitude,
        a bad level, or a segment :func:`check_segment` refuses.

    """
    number(level, "confidence level", lo=0, hi=1, lo_open=True, hi_open=True, error=SignalError)
    if not segments:
        raise SignalError("the linearity test needs at least one segment (a measured sine)")
    ks = {driven_dof(s.measurement, dof) for s in segments}
    if len(ks) != 1:
        raise SignalError("all linearity segments must drive the same DOF; got "
                          f"{', '.join(DOF_NAMES[k] for k in sorted(ks))}")  # fmt: skip
    k = ks.pop()
    keys = [(float(s.frequency_hz), float(s.amplitude)) for s in segments]
    if len(set(keys)) != len(keys):
        raise SignalError("two linearity segments have the same frequency and amplitude; give "
                          "each point once")  # fmt: skip
    for s in segments:
        check_segment(s, k)
    order = sorted(range(len(segments)), key=lambda i: (keys[i][0], -keys[i][1]))
    points = [analyse_point(segments[i], k) for i in order]
    return LinearityResult(
        DOF_NAMES[k],
        np.array([keys[i][0] for i in order]),
        np.array([keys[i][1] for i in order]),
        np.array([h for h, _ in points], dtype=complex),
        np.array([n for _, n in points]),
        tuple(skipped),
        joined_sources([segments[i].measurement.source for i in order]),
        float(level),
    )


def fitting_amplitude(
    platform: str, dof: str, frequency_hz: float, tops: Sequence[float] = DEFAULT_TOPS
) -> float | str:
    """Return the first of ``tops`` whose sine stays within the platform limits (or why none).

    The limit check is :func:`twin.chain.signals.check_signal`'s, the one a session runs.
    """
    reason = ""
    for a in tops:
        try:
            check_signal(single_sine(dof, frequency_hz, a, window_s=WINDOW_S).commands, platform)
        except SignalLimitError as e:
            reason = str(e)
            continue
        return float(a)
    return reason


def schedule(
    platform: str,
    dof: str,
    frequencies_hz: Sequence[float] | None = None,
    amplitudes: Sequence[float] | None = None,
) -> tuple[list[tuple[float, float]], list[SkippedPoint]]:
    """Return the (frequency, amplitude) points to run and those skipped beforehand.

    With ``amplitudes`` given every frequency gets them as they are (a point that breaks a
    limit is skipped when run); by default each frequency gets :data:`DEFAULT_LADDER` times
    the largest of :data:`DEFAULT_TOPS` whose sine stays within the limits.

    Raises
    ------
    SignalError
        For an unknown DOF, or a frequency or amplitude that is not a positive number.

    """
    if dof not in DOF_NAMES:
        raise SignalError(f"unknown DOF {dof!r}; expected one of {', '.join(DOF_NAMES)}")
    freqs = DEFAULT_FREQUENCIES_HZ if frequencies_hz is None else frequencies_hz
    if len(freqs) == 0 or (amplitudes is not None and len(amplitudes) == 0):
        raise SignalError("the linearity test needs at least one frequency and one amplitude")
    fs = sorted({number(f, "linearity frequency [Hz]", lo=0, lo_open=True, hi=50.0,
                        error=SignalError) for f in freqs})  # fmt: skip
    points, skipped = [], []
    for f in fs:
        if amplitudes is not None:
            amps = sorted({number(a, f"linearity amplitude [{acceleration_unit(dof)}]", lo=0,
                                  lo_open=True, hi=100.0, error=SignalError)
                           for a in amplitudes}, reverse=True)  # fmt: skip
            points += [(f, a) for a in amps]
            continue
        top = fitting_amplitude(platform, dof, f)
        if isinstance(top, str):
            skipped.append(SkippedPoint(f, DEFAULT_TOPS[-1], top))
        else:
            points += [(f, top * r) for r in DEFAULT_LADDER]
    return points, skipped


def run_linearity(
    session: Session,
    dof: str,
    frequencies_hz: Sequence[float] | None = None,
    amplitudes: Sequence[float] | None = None,
    window_s: float = WINDOW_S,
) -> LinearityResult:
    """Run single sines at several amplitudes per frequency in ``dof`` and analyse them.

    Parameters
    ----------
    session : Session
        The bench and its sinks.
    dof : str
        Driven DOF.
    frequencies_hz : sequence of float, optional
        Default :data:`DEFAULT_FREQUENCIES_HZ`.
    amplitudes : sequence of float, optional
        Acceleration amplitudes run at every frequency [m/s^2 or rad/s^2]; by default three
        a decade apart per frequency, the largest scaled down to stay within the platform
        limits (:func:`schedule`).
    window_s : float
        Shortest measurement window of each run [s] (whole periods).

    """
    points, skipped = schedule(session.bench.config.platform, dof, frequencies_hz, amplitudes)
    session.expect(len(points), f"linearity {dof}")
    segments = []
    for f, a in points:
        m = session.measure_sine(dof, f, a, window_s, f"sine-{dof}-{f:g}Hz-{a:g}")
        if isinstance(m, str):
            skipped.append(SkippedPoint(f, a, m))
        else:
            start, end = m.meta["signal"]["window_s"]
            segments.append(LinearitySegment(m, start, end, f, a))
    if not segments:
        raise SignalLimitError(f"no linearity point of {dof} could be run: "
                          + "; ".join(s.reason for s in skipped))  # fmt: skip
    return analyse_linearity(segments, dof, skipped)
