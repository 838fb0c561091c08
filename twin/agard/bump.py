"""The turn-around bump test (AGARD-AR-144): smoothness of a velocity reversal.

One DOF moves at constant speed, reverses through zero speed at a constant acceleration to
the opposite speed, moves on, and reverses back, for each of a series of speeds (a motion
computer's bump schedule: 0.1, 0.05, 0.02, 0.01 and 0.005 m/s with reversal accelerations of
the same numbers in m/s^2, so that every reversal lasts 2 s). The profiles are the
piecewise-constant-jerk moves of :mod:`twin.chain.profiles`: every change of acceleration is a jerk
ramp of :data:`RAMP_S`.

At a reversal the commanded acceleration is constant, so a smooth platform's measured
acceleration is constant too; friction that flips sign with the speed, play or a servo that
hesitates shows as a *bump*: a short deviation of the measured acceleration from the expected
one. Every reversal is found from the commands (the instant the commanded speed crosses zero
at a constant acceleration), so that a bump series can be analysed inside a longer recorded
run. The platform should turn around later, where the *expected* speed crosses zero: the
commanded motion through the configuration's known dynamics (the platform filter of Eq 5.1,
whose double pole at w_b delays a ramp by 2 / w_b, 0.32 s on the MPI, and the delay), as
:mod:`twin.agard.threshold` compares them. The window runs from :data:`BEFORE_S` before that
time to :data:`AFTER_S` after it, cut to where the expected acceleration is within
:data:`STEADY_SHARE` of the commanded one (clear of the jerk ramps). In it this module
reports:

- the peak: the largest deviation of the measured acceleration from the expected one, signed,
  absolute and as a ratio of the commanded acceleration;
- the area: the deviation integrated over the window [m/s or rad/s], the speed lost (or
  gained) at the reversal;
- the noise: the rms deviation where the commanded acceleration has been zero for
  :data:`QUIET_S` (constant-speed stretches), for comparison;

and the trend of the bump with the reversal speed (the exponent of a power law fitted to the
mean absolute peak per speed).

What a bump looks like on the twin: a leg's Coulomb friction F flips sign with the leg's
speed. The legs' servo (Eq 5.9) feeds back the leg velocity with a gain K_d far above what
the cabin's mass asks (MPI: 73 500 N s/m a leg against 250 kg), so a friction flip does not
accelerate the cabin by 2 F_dof / M: the servo takes it up by a velocity error of
2 F_dof / C_dof (C_dof = K_d sum_j J_jk^2, the servo's damping in the DOF; F_dof = F sum_j
``|J_jk|``), and the platform *dwells*: its acceleration falls towards zero for about
2 F_dof / (C_dof a) seconds. The bump's area is that velocity error and its depth is at most
the commanded acceleration (tests/test_agard_bump.py checks both on the full model).

Examples
--------
>>> sig = bump_signal("heave", velocities=(0.1, 0.01))
>>> [round(t, 3) for t in sig.reversals_s]
[3.575, 7.675, 13.825, 17.925]

"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from twin.agard.segments import window_in
from twin.agard.session import Session
from twin.chain.filter import PlatformFilter
from twin.chain.profiles import JerkProfile, constant_acceleration, constant_speed
from twin.chain.trajectory import Trajectory
from twin.core.checks import number
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES, acceleration_unit, dof_index
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.results import frame
from twin.measurement.measure import Measurement, driven_dof

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]

#: The bump schedule's reversal speeds [m/s or rad/s]; the accelerations are the same numbers
#: [m/s^2 or rad/s^2] unless given.
VELOCITIES = (0.1, 0.05, 0.02, 0.01, 0.005)
#: Constant speed before each reversal [s].
CRUISE_S = 0.5
#: Length of every jerk ramp (acceleration change) [s].
RAMP_S = 0.05
#: Rest before the first series, between series and after the last [s].
REST_S = 1.0
#: Window around a reversal: from BEFORE_S before to AFTER_S after the time the platform
#: should turn around (the expected speed's zero crossing) [s].
BEFORE_S, AFTER_S = 0.25, 0.75
#: The window keeps to where the expected acceleration is within this share of the commanded.
STEADY_SHARE = 0.02
#: Time the commanded acceleration must have been zero for a sample to measure the noise [s].
QUIET_S = 0.5
#: Largest reversal speed [m/s or rad/s] and acceleration [m/s^2 or rad/s^2] accepted (the
#: platform's own limits are checked when the signal is run).
MAX_SPEED, MAX_ACCELERATION = 5.0, 50.0
#: A commanded speed below this share of the largest in the analysed span counts as zero.
SPEED_EPS = 1e-3


@dataclass(frozen=True, eq=False)
class BumpSignal:
    """The turn-around bump signal in one DOF.

    Attributes
    ----------
    commands : Trajectory
        Pose-offset commands (only ``dof`` moves); every series starts and ends at rest at
        neutral.
    dof : str
        Driven DOF.
    velocities, accelerations : tuple of float
        Reversal speed [m/s or rad/s] and acceleration [m/s^2 or rad/s^2] of each series.
    reversals_s : tuple of float
        Commanded reversal times [s] (two per series: + to - and - to +).
    cruise_s, ramp_s : float
        Constant speed before each reversal and jerk-ramp length [s].

    """

    commands: Trajectory
    dof: str
    velocities: tuple[float, ...]
    accelerations: tuple[float, ...]
    reversals_s: tuple[float, ...]
    cruise_s: float
    ramp_s: float

    def meta(self) -> dict[str, object]:
        """Return the ``signal`` entry of the run's ``meta.json``."""
        return {
            "kind": "bump",
            "dof": self.dof,
            "velocities": list(self.velocities),
            "accelerations": list(self.accelerations),
            "reversals_s": list(self.reversals_s),
            "cruise_s": self.cruise_s,
            "ramp_s": self.ramp_s,
        }


def series_profiles(v: float, a: float, cruise_s: float, ramp_s: float) -> list[JerkProfile]:
    """Return one series' moves: to +v, cruise, reverse to -v, cruise, reverse to +v, stop.

    The constant speed after the first reversal lasts ``2 cruise_s + v / a + ramp_s`` so that
    the series ends where it started; the excursion is about +/- v (v / a + ramp + cruise).
    """
    t_speed = v / a + ramp_s  # 0 -> v at a, ramps included
    t_rev = 2 * v / a + ramp_s  # v -> -v
    return [
        constant_acceleration(a, 0.0, v, t_speed),
        constant_speed(v, cruise_s),
        constant_acceleration(-a, v, -v, t_rev),
        constant_speed(-v, 2 * cruise_s + t_speed),
        constant_acceleration(a, -v, v, t_rev),
        constant_speed(v, cruise_s),
        constant_acceleration(-a, v, 0.0, t_speed),
    ]


def bump_signal(
    dof: str,
    velocities: Sequence[float] | None = None,
    accelerations: Sequence[float] | None = None,
    cruise_s: float = CRUISE_S,
    ramp_s: float = RAMP_S,
    rest_s: float = REST_S,
    rate_hz: float = 100.0,
) -> BumpSignal:
    """Build the turn-around bump signal (see the module docstring).

    Parameters
    ----------
    dof : str
        One of :data:`twin.core.frames.DOF_NAMES`.
    velocities : sequence of float, optional
        Reversal speeds, > 0 and at most :data:`MAX_SPEED` (default :data:`VELOCITIES`).
    accelerations : sequence of float, optional
        Reversal accelerations, one per speed, > 0 and at most :data:`MAX_ACCELERATION`
        (default: the speeds' numbers).
    cruise_s : float
        Constant speed before each reversal [s] (> 0).
    ramp_s : float
        Jerk-ramp length [s], > 0 and at most v / a of every series.
    rest_s : float
        Rest before, between and after the series [s] (>= 0).
    rate_hz : float
        Command rate [Hz].

    Raises
    ------
    SignalError
        For an unknown DOF, an empty or mismatched list, or a value outside its range.

    """
    if dof not in DOF_NAMES:
        raise SignalError(f"unknown DOF {dof!r}; expected one of {', '.join(DOF_NAMES)}")
    v = _values(VELOCITIES if velocities is None else velocities, "bump velocities", MAX_SPEED)
    a = v if accelerations is None else _values(accelerations, "bump accelerations",
                                                MAX_ACCELERATION)  # fmt: skip
    if len(a) != len(v):
        raise SignalError(f"give one bump acceleration per velocity; got {len(a)} accelerations "
                          f"for {len(v)} velocities")  # fmt: skip
    number(cruise_s, "bump cruise time [s]", lo=0, lo_open=True, hi=60, error=SignalError)
    number(rest_s, "bump rest time [s]", lo=0, hi=60, error=SignalError)
    shortest = min(vi / ai for vi, ai in zip(v, a, strict=True))
    number(ramp_s, f"bump jerk ramp [s] (at most the shortest v / a, {shortest:g} s)",
           lo=0, lo_open=True, hi=shortest, error=SignalError)  # fmt: skip
    number(rate_hz, "command rate [Hz]", lo=10, hi=10000, error=SignalError)
    pieces: list[tuple[float, JerkProfile]] = []
    reversals = []
    t = rest_s
    for vi, ai in zip(v, a, strict=True):
        parts = series_profiles(vi, ai, cruise_s, ramp_s)
        for k, p in enumerate(parts):
            if k in (2, 4):  # the reversals: mid-way through their constant acceleration
                reversals.append(t + p.duration / 2)
            pieces.append((t, p))
            t += p.duration
        t += rest_s
    n = round(t * rate_hz) + 1
    tt = np.arange(n) / rate_hz
    x = np.zeros(n)
    s0 = 0.0
    for start, p in pieces:
        sel = (tt >= start) & (tt < start + p.duration)
        x[sel] = s0 + p.at(tt[sel] - start)[0]
        s0 += p.end[0]
        x[tt >= start + p.duration] = s0
    values = np.zeros((n, 6))
    values[:, dof_index(dof)] = x
    times = tuple(float(r) for r in reversals)
    return BumpSignal(Trajectory(rate_hz, values), dof, v, a, times, float(cruise_s),
                      float(ramp_s))  # fmt: skip


def _values(values: Sequence[float], what: str, hi: float) -> tuple[float, ...]:
    """Return a non-empty list of numbers in (0, hi] as a tuple, else raise SignalError."""
    if isinstance(values, str) or not isinstance(values, Sequence | np.ndarray):
        raise SignalError(f"{what} must be a list of numbers in (0, {hi:g}]; got {values!r}")
    if len(values) == 0:
        raise SignalError(f"{what} must hold at least one number in (0, {hi:g}]")
    return tuple(number(x, f"{what}[{k}]", lo=0, lo_open=True, hi=hi, error=SignalError)
                 for k, x in enumerate(values))  # fmt: skip


@dataclass(frozen=True)
class Reversal:
    """One velocity reversal and its bump.

    Attributes
    ----------
    t_s : float
        Time the commanded speed crosses zero [s].
    t_platform_s : float
        Time the expected speed (through the filter and delay) crosses zero [s]: where the
        platform should turn around; the window is centred here.
    speed : float
        Commanded speed the reversal goes to [m/s or rad/s].
    acceleration : float
        Commanded acceleration at the reversal (signed) [m/s^2 or rad/s^2].
    peak : float
        Largest deviation of the measured from the expected acceleration in the window,
        signed [m/s^2 or rad/s^2].
    t_peak_s : float
        Its time from ``t_platform_s`` [s].
    area : float
        The deviation integrated over the window [m/s or rad/s].
    window_s : tuple of float
        The window, from and to [s] (absolute times).

    """

    t_s: float
    t_platform_s: float
    speed: float
    acceleration: float
    peak: float
    t_peak_s: float
    area: float
    window_s: tuple[float, float]

    @property
    def ratio(self) -> float:
        """``|peak|`` over the commanded acceleration's magnitude."""
        return abs(self.peak) / abs(self.acceleration)

    def to_dict(self) -> dict[str, float | list[float]]:
        """JSON-ready."""
        return {"t_s": self.t_s, "t_platform_s": self.t_platform_s, "speed": self.speed,
                "acceleration": self.acceleration, "peak": self.peak,
                "peak_abs": abs(self.peak), "ratio": self.ratio, "t_peak_s": self.t_peak_s,
                "area": self.area, "window_s": list(self.window_s)}  # fmt: skip


@dataclass(frozen=True, eq=False)
class BumpResult:
    """The turn-around bump test of one DOF.

    Attributes
    ----------
    dof : str
        Driven DOF.
    reversals : tuple of Reversal
        In time order.
    noise_rms : float
        RMS deviation of measured from expected acceleration where the commanded acceleration
        has been zero for :data:`QUIET_S` (nan if the span has no such stretch).
    traces : tuple of (ndarray, ndarray, ndarray)
        Per reversal: time from the reversal [s], measured and expected acceleration over
        the window widened by :data:`BEFORE_S` on each side (for the plot).
    source : str
        What was measured.

    """

    dof: str
    reversals: tuple[Reversal, ...]
    noise_rms: float
    traces: tuple[tuple[FloatArray, FloatArray, FloatArray], ...]
    source: str

    def per_speed(self) -> list[dict[str, float]]:
        """Mean absolute peak, ratio and area per reversal speed, fastest first."""
        speeds = sorted({_rounded(r.speed) for r in self.reversals}, reverse=True)
        out = []
        for s in speeds:
            rs = [r for r in self.reversals if _rounded(r.speed) == s]
            out.append({"speed": s, "acceleration": float(np.mean([abs(r.acceleration)
                                                                   for r in rs])),
                        "peak_abs": float(np.mean([abs(r.peak) for r in rs])),
                        "ratio": float(np.mean([r.ratio for r in rs])),
                        "area_abs": float(np.mean([abs(r.area) for r in rs])),
                        "reversals": len(rs)})  # fmt: skip
        return out

    @property
    def trend_exponent(self) -> float:
        """Exponent p of ``|peak| ~ speed^p`` fitted over the speeds (nan with fewer than two)."""
        rows = self.per_speed()
        if len(rows) < 2 or any(r["peak_abs"] <= 0 for r in rows):
            return float("nan")
        x = np.log([r["speed"] for r in rows])
        y = np.log([r["peak_abs"] for r in rows])
        return float(np.polyfit(x, y, 1)[0])

    def to_dict(self) -> dict[str, object]:
        """JSON-ready (every reversal, the per-speed means, noise and trend)."""
        return {
            "test": "turn-around bump",
            "dof": self.dof,
            "window": {"before_s": BEFORE_S, "after_s": AFTER_S, "steady_share": STEADY_SHARE},
            "reversals": [r.to_dict() for r in self.reversals],
            "per_speed": self.per_speed(),
            "noise_rms": _jsonable(self.noise_rms),
            "trend_exponent": _jsonable(self.trend_exponent),
            "source": self.source,
        }

    def format_table(self) -> str:
        """Plain-text summary: one row per reversal, then the trend."""
        unit = acceleration_unit(self.dof)
        speed_unit = unit.replace("/s^2", "/s")
        lines = [
            f"turn-around bump, {self.dof} ({self.source}); peak = largest deviation of measured "
            f"from expected acceleration, {BEFORE_S:g} s before to {AFTER_S:g} s after the "
            "platform's expected turn-around",
            f"{'t [s]':>8}{'turn [s]':>9}{'speed':>10}{'accel':>10}{'peak':>11}{'ratio':>8}"
            f"{'at [s]':>8}{'area':>11}",
        ]
        for r in self.reversals:
            lines.append(f"{r.t_s:8.2f}{r.t_platform_s:9.2f}{r.speed:10.4g}{r.acceleration:+10.4g}{r.peak:+11.3e}"
                         f"{r.ratio:8.2f}{r.t_peak_s:+8.3f}{r.area:+11.3e}")  # fmt: skip
        lines.append(f"units: speed {speed_unit}, acceleration and peak {unit}, area {speed_unit}")
        lines.append(f"noise (rms deviation at constant speed): {self.noise_rms:.3e} {unit}")
        lines.append(f"trend: |peak| ~ speed^{self.trend_exponent:.2f}")
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """One row per velocity reversal (:meth:`Reversal.to_dict`)."""
        return frame(r.to_dict() for r in self.reversals)

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Acceleration around each reversal (over ``|commanded|``), and ``|peak|`` vs speed.

        Parameters
        ----------
        ax : sequence of two Axes, optional
            Where to draw: the accelerations around the reversals and ``|peak|`` against
            speed; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        fig, (ax_t, ax_v) = subplots(ax, 1, 2, figsize=(10, 4))
        speeds = sorted({_rounded(r.speed) for r in self.reversals}, reverse=True)
        colours = {s: f"C{k % 10}" for k, s in enumerate(speeds)}
        labelled = set()
        for r, (tr, meas, ref) in zip(self.reversals, self.traces, strict=True):
            s, scale = _rounded(r.speed), abs(r.acceleration)
            label = None if s in labelled else f"{s:g}"
            labelled.add(s)
            ax_t.plot(tr, meas / scale, "-", color=colours[s], lw=0.8, label=label)
            ax_t.plot(tr, ref / scale, ":", color=colours[s], lw=0.8)
        ax_t.set_xlabel("time from the expected turn-around [s]")
        ax_t.set_ylabel("acceleration / |commanded| (dotted: expected)")
        ax_t.legend(title="speed", fontsize=7)
        ax_t.grid(True, alpha=0.4)
        rows = self.per_speed()
        unit = acceleration_unit(self.dof)
        ax_v.loglog([r["speed"] for r in rows], [r["peak_abs"] for r in rows], "o-",
                    label="|peak|")  # fmt: skip
        ax_v.loglog([r["speed"] for r in rows], [r["acceleration"] for r in rows], "k--", lw=0.8,
                    label="commanded acceleration")  # fmt: skip
        if np.isfinite(self.noise_rms) and self.noise_rms > 0:
            ax_v.axhline(3 * self.noise_rms, color="grey", lw=0.8, label="3 x noise rms")
        ax_v.set_xlabel(f"reversal speed [{unit.replace('/s^2', '/s')}]")
        ax_v.set_ylabel(f"bump [{unit}]")
        ax_v.legend(fontsize=7)
        ax_v.grid(True, which="both", alpha=0.3)
        fig.suptitle(f"turn-around bump, {self.dof}: {self.source}", fontsize=9)
        return finish(fig, path)


def _rounded(x: float) -> float:
    """``x`` to four significant digits (groups reversals by speed)."""
    return float(f"{x:.4g}")


def _jsonable(x: float) -> float | None:
    return None if not np.isfinite(x) else float(x)


def expected_motion(m: Measurement, k: int) -> tuple[FloatArray, FloatArray]:
    """Commanded speed and acceleration of DOF ``k`` through the configuration's filter and delay.

    What the platform should do (the known dynamics of :mod:`twin.agard.threshold`'s analytic
    model): the platform filter of Eq 5.1 where the configuration has one, then the delay.
    """
    t = m.t
    rows = np.column_stack([m.commands.at(t, 1)[:, k], m.commanded[:, k]])
    fb = m.config.breaks_hz[k]
    if fb is not None:
        filt = PlatformFilter(float(fb))
        both = Trajectory(1.0 / (t[1] - t[0]), np.tile(rows, (1, 3)), float(t[0]))
        rows = filt(both).values[:, [0, 1]]
    delay = float(m.config.delays_s[k])
    return tuple(np.interp(t - delay, t, rows[:, c], left=rows[0, c]) for c in (0, 1))


def settle_s(m: Measurement, k: int) -> float:
    """Time the expected motion takes to settle after an acceleration change [s].

    The delay plus, with a platform filter (Eq 5.1, a double pole at w_b), 5 / w_b (its step
    response is within 5 % by then).
    """
    fb = m.config.breaks_hz[k]
    return float(m.config.delays_s[k]) + (5.0 / (2 * np.pi * fb) if fb is not None else 0.0)


def find_reversals(
    t: FloatArray, speed: FloatArray, acc: FloatArray
) -> list[tuple[float, int, int]]:
    """Return (time, first, last index) of every reversal of the commanded speed.

    A reversal is a change of sign between two stretches where ``|speed|`` is above
    :data:`SPEED_EPS` of its largest, the commanded acceleration between them (inclusive)
    keeping at least half its value at the crossing: passing through zero, not stopping and
    starting again. The time is the zero crossing interpolated linearly.
    """
    top = float(np.abs(speed).max()) if speed.size else 0.0
    if top == 0:
        return []
    sgn = np.where(np.abs(speed) > SPEED_EPS * top, np.sign(speed), 0.0)
    moving = np.flatnonzero(sgn)
    out = []
    for i, j in pairwise(moving):
        if sgn[i] == sgn[j]:
            continue
        seg = np.arange(i, j + 1)
        z = i + int(np.flatnonzero(np.sign(speed[seg[1:]]) != np.sign(speed[i]))[0])
        t0 = t[z] - speed[z] * (t[z + 1] - t[z]) / (speed[z + 1] - speed[z])
        a0 = np.interp(t0, t[seg], acc[seg])
        if a0 != 0 and np.all(np.abs(acc[seg]) >= 0.5 * abs(a0)) and np.sign(a0) == sgn[j]:
            out.append((float(t0), int(i), int(j)))
    return out


def analyse_bump(
    m: Measurement, dof: str | None = None, window: tuple[float, float] | None = None
) -> BumpResult:
    """Analyse the turn-around bumps of a measurement (or of a window of a longer run).

    Parameters
    ----------
    m : Measurement
        Commanded and measured accelerations.
    dof : str, optional
        The DOF (default: the run's signal's, or the one the commands move most).
    window : (float, float), optional
        Analyse only the reversals in this time span [s] of the run (a bump series inside a
        longer schedule); default the whole run.

    Raises
    ------
    SignalError
        For a window that is not an increasing pair inside the run, or a span whose commands
        hold no velocity reversal at constant acceleration.

    """
    k = driven_dof(m, dof)
    t = m.t
    lo, hi = window_in(window, (float(t[0]), float(t[-1])), "bump")
    span = (t >= lo - 1e-9) & (t <= hi + 1e-9)
    ts = t[span]
    speed = m.commands.at(ts, 1)[:, k]
    acc = m.commanded[span, k]
    found = find_reversals(ts, speed, acc)
    if not found:
        raise SignalError(f"{m.source}: the {DOF_NAMES[k]} commands between {lo:.2f} and "
                          f"{hi:.2f} s hold no velocity reversal (a speed that changes sign at "
                          "a constant acceleration); the bump test needs one")  # fmt: skip
    exp_speed, expected = expected_motion(m, k)
    dev = m.measured[:, k] - expected
    reversals, traces = [], []
    windows = []
    for t0, _, j in found:
        a0 = float(m.commands.at([t0], 2)[0, k])
        # the speed the reversal goes to: where the commanded acceleration has ramped out
        last = j
        while last < ts.size - 1 and abs(acc[last + 1] - a0) <= 0.01 * abs(a0):
            last += 1
        ramp_end = np.flatnonzero(np.abs(acc[last:]) < 0.01 * abs(a0))
        after = float(abs(speed[last + ramp_end[0]]) if ramp_end.size else
                      np.abs(speed[last:]).max())  # fmt: skip
        # where the platform should reverse: the expected speed's zero crossing
        near = np.flatnonzero((t >= t0 - 1e-9) & (t <= t0 + settle_s(m, k) + AFTER_S))
        cross = near[:-1][np.sign(exp_speed[near[:-1]]) != np.sign(exp_speed[near[1:]])]
        te = t0 + float(m.config.delays_s[k])
        if cross.size:
            c = int(cross[0])
            te = float(t[c] - exp_speed[c] * (t[c + 1] - t[c]) / (exp_speed[c + 1] - exp_speed[c]))
        # the window: around it, where the expected acceleration is the commanded one
        steady = np.abs(expected - a0) <= STEADY_SHARE * abs(a0)
        ce = int(np.clip(np.searchsorted(t, te), 0, t.size - 1))
        if not steady[ce]:
            continue  # the reversal is too short for the platform to reach its acceleration
        first, last_e = ce, ce
        while first > 0 and steady[first - 1]:
            first -= 1
        while last_e < t.size - 1 and steady[last_e + 1]:
            last_e += 1
        w0 = max(te - BEFORE_S, t[first], lo)
        w1 = min(te + AFTER_S, t[last_e], hi)
        sel = (t >= w0 - 1e-9) & (t <= w1 + 1e-9)
        if sel.sum() < 3:
            continue  # too close to the span's ends to measure
        peak_i = int(np.argmax(np.abs(dev[sel])))
        tw = t[sel]
        reversals.append(Reversal(t0, te, after, a0, float(dev[sel][peak_i]),
                                  float(tw[peak_i] - te), float(np.trapezoid(dev[sel], tw)),
                                  (float(tw[0]), float(tw[-1]))))  # fmt: skip
        windows.append((w0, w1))
        wide = (t >= w0 - BEFORE_S) & (t <= w1 + BEFORE_S)
        traces.append((t[wide] - te, m.measured[wide, k].copy(), expected[wide].copy()))
    if not reversals:
        raise SignalError(f"{m.source}: the reversals between {lo:.2f} and {hi:.2f} s leave no "
                          "window to measure (too close to the ends or too short)")  # fmt: skip
    quiet = _quiet(t, m.commanded[:, k], settle_s(m, k)) & (t >= lo) & (t <= hi)
    for w0, w1 in windows:
        quiet &= (t < w0) | (t > w1)
    noise = float(np.sqrt(np.mean(dev[quiet] ** 2))) if quiet.sum() > 10 else float("nan")
    return BumpResult(DOF_NAMES[k], tuple(reversals), noise, tuple(traces), m.source)


def _quiet(t: FloatArray, acc: FloatArray, settle: float) -> NDArray[np.bool_]:
    """Return where the commanded acceleration was zero over the last QUIET_S + settle s."""
    top = float(np.abs(acc).max()) or 1.0
    busy = np.abs(acc) > 1e-6 * top
    n = max(1, round((QUIET_S + settle) / (t[1] - t[0])))
    recent = np.convolve(busy.astype(float), np.ones(n), mode="full")[: t.size]
    return recent == 0


def run_bump(
    session: Session,
    dof: str,
    velocities: Sequence[float] | None = None,
    accelerations: Sequence[float] | None = None,
    cruise_s: float = CRUISE_S,
) -> BumpResult:
    """Run the turn-around bump schedule in ``dof`` on a session's bench and analyse it.

    Parameters
    ----------
    session : Session
        Where to run (its bench, sinks and run numbering).
    dof : str
        Driven DOF.
    velocities, accelerations : sequence of float, optional
        Reversal speeds and accelerations (defaults: :data:`VELOCITIES`, the same numbers).
    cruise_s : float
        Constant speed before each reversal [s].

    """
    sig = bump_signal(dof, velocities, accelerations, cruise_s)
    m = session.measure(sig, f"bump-{dof}")
    return analyse_bump(m, dof)
