"""The AGARD-AR-144 hysteresis test: output position against input position at very low frequency.

A position sine of very low frequency drives one DOF at a large and at a small amplitude
(AR-144's D schedules: about 0.006 Hz at 0.5 m and 0.005 m; the defaults here are 0.05 Hz and
the largest of 0.5, 0.2, 0.1, ... m or rad that stays within the platform limits, and a
hundredth of it, so that a run lasts a minute). Over a window of whole periods the output
position is drawn against the commanded (input) position; its loop's width is the hysteresis.

Width, as defined here (all in m or rad, and in % of the amplitude):

* ``width`` - at zero input: the mean output where the input crosses its centre falling,
  minus the mean output where it crosses rising (interpolated between samples). Play of
  total width p in the DOF gives p; Coulomb friction against a servo of stiffness K gives
  2 F / K.
* ``width_max`` - the largest difference between the falling and rising branches at equal
  input, over the middle :data:`INNER` of the input range (the branches averaged over the
  periods; the turning points are left out, where both branches meet).

A delay opens a loop too: at low frequency a lag tau turns the output y(t) = x(t - tau), an
ellipse of width 2 A sin(2 pi f tau) at zero input. Both widths are therefore taken after the
output has been advanced by the configuration's lag at the test frequency (its delay plus the
platform filter's phase, -arg H(f) / (2 pi f), :meth:`~twin.chain.config.MotionSystem.
response_at_hz`; or a lag the user gives, e.g. the describing function's fitted delay).
The raw width (output not advanced) and the lag's own width 2 A sin(2 pi f tau) are reported
beside them, so that a pure delay is not called hysteresis.

The output position is the platform's pose: for a simulation the pose of the simulated
response; for a recorded run the measured leg lengths (``actuators.csv``) through forward
kinematics (:func:`twin.platform.kinematics.forward`). A run without leg lengths has no
position record: its accelerations cannot be integrated twice over minutes, and it is refused.

Examples
--------
>>> from twin.agard.session import Session
>>> from twin.measurement.measure import Bench, configure
>>> s = Session(Bench(configure("mpi", break_hz=0, noise=False), "full"))
>>> r = run_hysteresis(s, "heave", frequency_hz=0.1, amplitudes=[0.05])
>>> bool(abs(r.loops[0].width) < 1e-4)  # the 35 ms delay's 2.2 mm removed
True

"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from twin.agard.df import joined_sources
from twin.agard.positions import PositionRecord
from twin.agard.segments import AMPLITUDE_TOLERANCE, checked_window
from twin.agard.session import Session
from twin.chain.config import MotionSystem
from twin.chain.signals import DescribingSignal, MultiSine, check_signal, periodic_signal
from twin.core.checks import number
from twin.core.errors import SignalError, SignalLimitError
from twin.core.frames import DOF_NAMES, dof_index
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.results import frame

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]

#: Default test frequency [Hz] (AR-144 D: about 0.006 Hz; 0.05 Hz keeps a run near a minute).
DEFAULT_FREQUENCY_HZ = 0.05
#: Largest default amplitude (AR-144 D: 0.5 m) and the smaller ones tried where it breaks a
#: platform limit [m or rad].
DEFAULT_TOPS = (0.5, 0.2, 0.1, 0.05, 0.02, 0.01, 0.005, 0.002, 0.001)
#: The small amplitude relative to the large one (AR-144 D: 0.005 m against 0.5 m).
SMALL_RATIO = 0.01
#: Share of the input range (about its centre) over which ``width_max`` is sought.
INNER = 0.9
#: Input levels at which the branches are compared for ``width_max``.
LEVELS = 181
#: Lowest and highest test frequency [Hz].
MIN_FREQUENCY_HZ, MAX_FREQUENCY_HZ = 1e-3, 1.0


def position_unit(dof: str) -> str:
    """Return the position unit of a DOF: ``m`` or ``rad``."""
    return "rad" if dof_index(dof) >= 3 else "m"


@dataclass(frozen=True)
class HysteresisSegment:
    """One loop to analyse: a window of whole periods of a position record.

    Attributes
    ----------
    record : PositionRecord
        The run (may hold other signals outside the window).
    start_s, end_s : float
        The window [s]: whole periods of the sine, after its fade-in.
    frequency_hz : float
        The sine's frequency [Hz].
    amplitude : float
        Its commanded position amplitude [m or rad].

    """

    record: PositionRecord
    start_s: float
    end_s: float
    frequency_hz: float
    amplitude: float


@dataclass(frozen=True, eq=False)
class HysteresisLoop:
    """The loop of one amplitude.

    Attributes
    ----------
    dof : str
        Driven DOF.
    frequency_hz, amplitude : float
        The sine [Hz, m or rad].
    lag_s : float
        Lag the output was advanced by before measuring the widths [s].
    width, width_max : float
        Width at zero input and largest width at equal input, beyond the lag [m or rad].
    raw_width : float
        Width at zero input of the output as measured (lag included).
    lag_width : float
        A pure lag's width at zero input, 2 A sin(2 pi f lag_s).
    period_widths : ndarray
        ``width`` of each period of the window.
    input, output : ndarray
        The window's input and advanced output (for the plot).
    source : str
        What was measured.

    """

    dof: str
    frequency_hz: float
    amplitude: float
    lag_s: float
    width: float
    width_max: float
    raw_width: float
    lag_width: float
    period_widths: FloatArray
    input: FloatArray
    output: FloatArray
    source: str

    @property
    def width_pct(self) -> float:
        """``width`` in % of the amplitude."""
        return 100.0 * self.width / self.amplitude

    @property
    def width_max_pct(self) -> float:
        """``width_max`` in % of the amplitude."""
        return 100.0 * self.width_max / self.amplitude

    def to_dict(self) -> dict[str, object]:
        """JSON-ready (no samples)."""
        return {
            "frequency_hz": self.frequency_hz,
            "amplitude": self.amplitude,
            "lag_ms": self.lag_s * 1e3,
            "width": self.width,
            "width_pct": self.width_pct,
            "width_max": self.width_max,
            "width_max_pct": self.width_max_pct,
            "raw_width": self.raw_width,
            "lag_width": self.lag_width,
            "period_widths": self.period_widths.tolist(),
            "source": self.source,
        }


@dataclass(frozen=True, eq=False)
class HysteresisResult:
    """The hysteresis test of one DOF: a loop per amplitude.

    Attributes
    ----------
    dof : str
        Driven DOF.
    loops : tuple of HysteresisLoop
        One per amplitude, largest first.
    skipped : dict of float to str
        Amplitudes not run, with the platform limit they would break.

    """

    dof: str
    loops: tuple[HysteresisLoop, ...]
    skipped: dict[float, str]

    @property
    def source(self) -> str:
        """What was measured."""
        return joined_sources([lp.source for lp in self.loops])

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: ``loops`` (widths in m or rad and %), ``skipped``."""
        return {
            "test": "hysteresis",
            "dof": self.dof,
            "unit": position_unit(self.dof),
            "source": self.source,
            "loops": [lp.to_dict() for lp in self.loops],
            "skipped": {str(a): why for a, why in self.skipped.items()},
        }

    def format_table(self) -> str:
        """Plain-text table: per amplitude the widths beyond the lag, the raw and lag widths."""
        u = position_unit(self.dof)
        lines = [
            f"hysteresis, {self.dof} ({self.source}); widths with the output advanced by the lag",
            f"{'f [Hz]':>7} {'A [' + u + ']':>10} {'width [' + u + ']':>12} {'%':>7} "
            f"{'max [' + u + ']':>12} {'%':>7} {'raw':>10} {'lag':>10} {'lag ms':>7}",
        ]
        for lp in self.loops:
            lines.append(
                f"{lp.frequency_hz:7.3g} {lp.amplitude:10.4g} {lp.width:12.3e} "
                f"{lp.width_pct:7.3f} {lp.width_max:12.3e} {lp.width_max_pct:7.3f} "
                f"{lp.raw_width:10.3e} {lp.lag_width:10.3e} {lp.lag_s * 1e3:7.1f}"
            )
        for a, why in self.skipped.items():
            lines.append(f"{'':7} {a:10.4g} skipped: {why}")
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """One row per amplitude's loop (:meth:`HysteresisLoop.to_dict`)."""
        return frame(lp.to_dict() for lp in self.loops)

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Plot output against input per amplitude, and output minus input below it.

        The output is advanced by the lag; the lower panels open the loop up.

        Parameters
        ----------
        ax : sequence of 2 x n Axes, optional
            Where to draw: the loops (first row) and output minus input (second row),
            one column per amplitude, in row order; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        n = max(1, len(self.loops))
        fig, axes = subplots(ax, 2, n, figsize=(4.2 * n, 6.5), squeeze=False, sharex="col")
        u = position_unit(self.dof)
        for c, lp in enumerate(self.loops):
            top, bottom = axes[0, c], axes[1, c]
            top.plot(lp.input, lp.output, lw=0.8, label=f"advanced {lp.lag_s * 1e3:.1f} ms")
            top.plot(lp.input, lp.input, "k:", lw=0.6, label="output = input")
            bottom.plot(lp.input, lp.output - lp.input, lw=0.8)
            top.set_ylabel(f"output {self.dof} [{u}]")
            bottom.set_ylabel(f"output - input [{u}]")
            bottom.set_xlabel(f"input {self.dof} [{u}]")
            top.set_title(f"A {lp.amplitude:g} {u}, {lp.frequency_hz:g} Hz: width "
                          f"{lp.width:.3g} {u} ({lp.width_pct:.2f} %)", fontsize=8)  # fmt: skip
            top.legend(fontsize=7)
            for ax in (top, bottom):
                ax.grid(True, alpha=0.4)
        fig.suptitle(f"hysteresis, {self.dof}: {self.source}", fontsize=9)
        return finish(fig, path)


def configured_lag(config: MotionSystem, dof: str, frequency_hz: float) -> float:
    """Return the configuration's lag at ``frequency_hz``: -arg H(f) / (2 pi f) [s].

    H is the reduced model (:meth:`MotionSystem.response_at_hz`: filter, delay,
    resonance); at the hysteresis test's low frequencies the filter's phase is a lag too.
    """
    h = config.response_at_hz([frequency_hz])[0, dof_index(dof)]
    return float(-np.angle(h) / (2 * np.pi * frequency_hz))


def _check_segment(seg: HysteresisSegment, k: int) -> tuple[float, float]:
    """Raise :class:`SignalError` for a segment that cannot be analysed; return its window."""
    r = seg.record
    where = f"{r.source}: segment {seg.frequency_hz:g} Hz, {seg.amplitude:g}"
    _, start, end = checked_window(where, seg.frequency_hz, seg.amplitude,
                                   (seg.start_s, seg.end_s), (float(r.t[0]), float(r.t[-1])),
                                   (MIN_FREQUENCY_HZ, MAX_FREQUENCY_HZ))  # fmt: skip
    sel = (r.t >= start - 1e-9) & (r.t < end - 1e-9)
    got = 0.5 * float(np.ptp(r.commanded[sel, k]))
    if abs(got / seg.amplitude - 1) > AMPLITUDE_TOLERANCE:
        raise SignalError(f"{where}: the commanded {DOF_NAMES[k]} over the window has amplitude "
                          f"{got:.4g}, not the stated {seg.amplitude:g} (within "
                          f"{100 * AMPLITUDE_TOLERANCE:g} %); a window from another part of "
                          "the run?")  # fmt: skip
    return start, end


def zero_crossing_widths(x: FloatArray, y: FloatArray) -> FloatArray:
    """Return, per period, the output falling minus rising where ``x`` crosses its centre.

    ``x`` is a sine over whole periods; its centre is the midpoint of its range. The output
    is interpolated linearly between the samples around each crossing.
    """
    xc = x - 0.5 * (x.max() + x.min())
    i = np.flatnonzero(np.sign(xc[:-1]) != np.sign(xc[1:]))
    i = i[xc[i] != xc[i + 1]]
    s = xc[i] / (xc[i] - xc[i + 1])
    yc = y[i] + s * (y[i + 1] - y[i])
    rising = xc[i + 1] > xc[i]
    up, down = yc[rising], yc[~rising]
    n = min(up.size, down.size)
    if n == 0:
        raise SignalError("the input does not cross its centre both ways in the window")
    return down[:n] - up[:n]


def branch_width(x: FloatArray, y: FloatArray, inner: float = INNER) -> float:
    """Largest falling-minus-rising output at equal input over the middle of the input range.

    Each branch (the samples where ``x`` rises, and where it falls) is interpolated onto
    :data:`LEVELS` input levels over the middle ``inner`` of the range and averaged over its
    half periods.
    """
    mid, half = 0.5 * (x.max() + x.min()), 0.5 * np.ptp(x)
    levels = mid + inner * half * np.linspace(-1, 1, LEVELS)
    dx = np.diff(x)
    sign = np.sign(dx)
    edges = np.flatnonzero(sign[:-1] != sign[1:]) + 1
    branches: dict[bool, list[FloatArray]] = {True: [], False: []}
    for lo, hi in zip(np.r_[0, edges], np.r_[edges, dx.size], strict=True):
        xs, ys = x[lo : hi + 1], y[lo : hi + 1]
        if xs.size < 3:
            continue
        rising = xs[-1] > xs[0]
        order = slice(None) if rising else slice(None, None, -1)
        inside = (levels >= xs.min()) & (levels <= xs.max())
        row = np.full(LEVELS, np.nan)
        row[inside] = np.interp(levels[inside], xs[order], ys[order])
        branches[rising].append(row)
    if not branches[True] or not branches[False]:
        raise SignalError("the input neither rises nor falls through the window's middle")
    up, down = _mean_rows(branches[True]), _mean_rows(branches[False])
    diff = down - up
    finite = np.isfinite(diff)
    if not finite.any():
        raise SignalError("the rising and falling branches share no input level")
    return float(diff[finite].max())


def _mean_rows(rows: list[FloatArray]) -> FloatArray:
    """Column means over the finite entries of the rows (NaN where a column has none)."""
    a = np.array(rows)
    ok = np.isfinite(a)
    count = ok.sum(axis=0)
    total = np.where(ok, a, 0.0).sum(axis=0)
    return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def analyse_segment(seg: HysteresisSegment, k: int, lag_s: float | None = None) -> HysteresisLoop:
    """Return the loop of one segment (see the module docstring for the widths)."""
    start, end = _check_segment(seg, k)
    r, f, a = seg.record, float(seg.frequency_hz), float(seg.amplitude)
    dof = DOF_NAMES[k]
    lag = configured_lag(r.config, dof, f) if lag_s is None else float(lag_s)
    sel = (r.t >= start - 1e-9) & (r.t < end - 1e-9)
    t, x = r.t[sel], r.commanded[sel, k]
    raw = r.output[sel, k]
    advanced = np.interp(t + lag, r.t, r.output[:, k])
    widths = zero_crossing_widths(x, advanced)
    return HysteresisLoop(
        dof,
        f,
        a,
        lag,
        float(widths.mean()),
        branch_width(x, advanced),
        float(zero_crossing_widths(x, raw).mean()),
        float(2 * a * np.sin(2 * np.pi * f * lag)),
        widths,
        x,
        advanced,
        r.source,
    )


def analyse_hysteresis(
    segments: Sequence[HysteresisSegment],
    dof: str | None = None,
    lag_s: float | None = None,
    skipped: dict[float, str] | None = None,
) -> HysteresisResult:
    """Return the hysteresis test of measured segments (one sine each).

    Parameters
    ----------
    segments : sequence of HysteresisSegment
        One per amplitude; windows of whole periods, possibly of one long run
        (:meth:`PositionRecord.from_run` reads a recorded run's).
    dof : str, optional
        Driven DOF; by default the one the first segment's commands move most in its window.
    lag_s : float, optional
        Lag to advance the output by [s], in [0, 1]; by default the configuration's at each
        segment's frequency (:func:`configured_lag`).
    skipped : dict of float to str, optional
        Amplitudes not run, and why.

    Raises
    ------
    SignalError
        For no segment, an unknown DOF, a lag out of range, or a segment whose window is not
        whole periods of the stated sine within the record.

    """
    if not segments:
        raise SignalError("the hysteresis test needs at least one segment (a measured sine)")
    if lag_s is not None:
        number(lag_s, "hysteresis lag [s]", lo=0, hi=1, error=SignalError)
    if dof is None:
        s0 = segments[0]
        sel = (s0.record.t >= s0.start_s) & (s0.record.t < s0.end_s)
        k = int(np.argmax(np.ptp(s0.record.commanded[sel], axis=0))) if sel.any() else 0
    elif dof in DOF_NAMES:
        k = dof_index(dof)
    else:
        raise SignalError(f"unknown DOF {dof!r}; expected one of {', '.join(DOF_NAMES)}")
    loops = sorted((analyse_segment(s, k, lag_s) for s in segments), key=lambda lp: -lp.amplitude)
    return HysteresisResult(DOF_NAMES[k], tuple(loops), dict(skipped or {}))


def hysteresis_signal(
    dof: str, frequency_hz: float, amplitude: float, periods: int = 1, rate_hz: float = 100.0
) -> DescribingSignal:
    """Return a position sine of ``amplitude`` [m or rad]: fade-in, ``periods``, fade-out.

    The phases of §3.2.3 without pre-measurement: the fade (Eq 3.1, one period long) brings
    the play to its working side before the window.
    """
    if dof not in DOF_NAMES:
        raise SignalError(f"unknown DOF {dof!r}; expected one of {', '.join(DOF_NAMES)}")
    f = number(frequency_hz, "hysteresis frequency [Hz]", lo=MIN_FREQUENCY_HZ,
               hi=MAX_FREQUENCY_HZ, error=SignalError)  # fmt: skip
    a = number(amplitude, f"hysteresis amplitude [{position_unit(dof)}]", lo=0, lo_open=True,
               hi=1.0, error=SignalError)  # fmt: skip
    if not isinstance(periods, int) or not 1 <= periods <= 100:
        raise SignalError(f"periods must be an integer from 1 to 100; got {periods!r}")
    ms = MultiSine(np.array([f]), np.array([a * (2 * np.pi * f) ** 2]))
    u = position_unit(dof)
    label = f"hysteresis sine {f:g} Hz, {a:g} {u}"
    return periodic_signal(ms, dof, rate_hz, 0.0, periods / f, label)


def fitting_amplitude(platform: str, dof: str, frequency_hz: float) -> float | str:
    """Return the first of :data:`DEFAULT_TOPS` within the platform limits (or why none)."""
    reason = ""
    for a in DEFAULT_TOPS:
        try:
            check_signal(hysteresis_signal(dof, frequency_hz, a).commands, platform)
        except SignalLimitError as e:
            reason = str(e)
            continue
        return a
    return reason


def simulate_positions(
    session: Session, sig: DescribingSignal, name: str
) -> tuple[PositionRecord, DescribingSignal]:
    """Run ``sig`` on the session and return the pose record (a Measurement holds no pose).

    Raises
    ------
    SignalLimitError
        If the signal would break a platform limit (the run still counts).

    """
    session.measure(sig, name)
    return PositionRecord.from_simulation(session.simulation), sig  # type: ignore[arg-type]


def run_hysteresis(
    session: Session,
    dof: str,
    frequency_hz: float | None = None,
    amplitudes: Sequence[float] | None = None,
    periods: int = 1,
    lag_s: float | None = None,
) -> HysteresisResult:
    """Run the very-low-frequency position sines in ``dof`` and measure their loops.

    Parameters
    ----------
    session : Session
        The bench (full or reduced model) and its sinks.
    dof : str
        Driven DOF.
    frequency_hz : float, optional
        Default :data:`DEFAULT_FREQUENCY_HZ`.
    amplitudes : sequence of float, optional
        Position amplitudes [m or rad]; by default the largest of :data:`DEFAULT_TOPS` within
        the platform limits and :data:`SMALL_RATIO` of it. An amplitude that would break a
        limit is skipped and reported.
    periods : int
        Periods in each window.
    lag_s : float, optional
        Lag to advance the output by (see :func:`analyse_hysteresis`).

    """
    f = DEFAULT_FREQUENCY_HZ if frequency_hz is None else frequency_hz
    if dof not in DOF_NAMES:
        raise SignalError(f"unknown DOF {dof!r}; expected one of {', '.join(DOF_NAMES)}")
    skipped: dict[float, str] = {}
    if amplitudes is None:
        top = fitting_amplitude(session.bench.config.platform, dof, f)
        if isinstance(top, str):
            raise SignalLimitError(f"no hysteresis amplitude of {dof} fits: {top}")
        amplitudes = (top, top * SMALL_RATIO)
    if len(amplitudes) == 0:
        raise SignalError("the hysteresis test needs at least one amplitude")
    sigs = [hysteresis_signal(dof, f, a, periods) for a in amplitudes]
    session.expect(len(sigs), f"hysteresis {dof}")
    segments = []
    for a, sig in zip(amplitudes, sigs, strict=True):
        try:
            record, _ = simulate_positions(session, sig, f"hysteresis-{dof}-{f:g}Hz-{a:g}")
        except SignalLimitError as e:
            skipped[float(a)] = str(e)
            continue
        segments.append(HysteresisSegment(record, *sig.window, f, float(a)))
    if not segments:
        raise SignalLimitError(f"no hysteresis amplitude of {dof} could be run: "
                               + "; ".join(skipped.values()))  # fmt: skip
    return analyse_hysteresis(segments, dof, lag_s, skipped)
