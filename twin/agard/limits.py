"""System limits measured, not computed (AGARD-AR-144): what a DOF reaches, and what stops it.

A platform's limits are usually quoted from its design: the stroke-limited excursion of each
DOF (``twin workspace``), and the actuators' velocity and acceleration limits (Table 5.1).
This test measures them: one DOF is driven by jerk-limited point-to-point moves
(:func:`twin.chain.profiles.point_to_point`) of increasing size, speed, acceleration and jerk (one
run per level: out to +d, back to neutral, out to -d, back, holding :data:`HOLD_S` at every
end), and the response is measured: the excursion and speed reached (from the platform's pose:
simulated, or solved from a recorded run's leg lengths by forward kinematics), the
acceleration and jerk reached (from the IMU, post-processed as App. C.2.3).

What stopped a level:

- simulated: the actuator limiter's counts of the run (:mod:`twin.chain.limits`: samples of
  the leg references beyond the stroke, the velocity or the acceleration limit; samples at a
  force limit), in ``limit`` mode, so that commands beyond the limits are run, limited;
- recorded (no counts): the shortfall of what was reached against what was expected (the
  commands through the configuration's platform filter and delay): an excursion short by
  more than :data:`SHORTFALL` ``["stroke"]``, a speed short by more than
  :data:`SHORTFALL` ``["velocity"]``, an acceleration short by more than
  :data:`SHORTFALL` ``["acceleration"]`` (which cannot tell an acceleration limit from a force
  limit).

The limits computed from the design are reported beside (:func:`dof_limits`): the workspace's
excursion, and the legs' velocity and acceleration limits through the Jacobian at neutral
(the DOF's speed at which the fastest leg reaches its limit).

Examples
--------
>>> lim = dof_limits("mpi", "heave")
>>> round(lim.excursion_max, 4), round(lim.velocity, 4)
(0.2555, 0.3326)

"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_filter

from twin.agard.df import joined_sources
from twin.agard.positions import PositionRecord
from twin.agard.segments import window_in
from twin.agard.session import Session
from twin.chain.filter import PlatformFilter
from twin.chain.profiles import point_to_point
from twin.chain.trajectory import Trajectory
from twin.core.checks import number
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES, acceleration_unit, dof_index
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.results import frame
from twin.formats.runs import RecordedRun
from twin.measurement.measure import Measurement, driven_dof

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]

#: Default levels: each a share of the stroke-limited excursion (the move's size) and of the
#: top speed, acceleration and jerk.
LEVELS = (0.25, 0.5, 0.75, 1.0, 1.2)
#: Default top speed and acceleration over the DOF's computed limits (at level 1).
OVER = 1.5
#: Default jerk ramp of the top level [s] (jerk = acceleration / ramp).
JERK_RAMP_S = 0.1
#: Hold at every end of a move, and rest before and after a level [s].
HOLD_S, REST_S = 1.0, 1.0
#: Shortfall of reached against expected above which a recorded run counts a limit.
SHORTFALL = {"stroke": 0.02, "velocity": 0.05, "acceleration": 0.15}
#: Share of a design limit (:func:`dof_limits`; the least over the excursion) the expected
#: motion must reach before a shortfall is put down to that limit.
NEAR = 0.8
#: Savitzky-Golay window for the speed from the pose and the jerk from the IMU [s].
DIFF_WINDOW_S = 0.11
#: Time at the start and end of a run left out (the post-processing's transients) [s].
EDGE_S = 0.3
#: The limiter's kinds of count.
KINDS = ("stroke", "velocity", "acceleration", "force")
#: Largest level accepted (a share of the workspace; beyond it the commands are not a test).
MAX_LEVEL = 3.0


@dataclass(frozen=True)
class DofLimits:
    """A DOF's limits computed from the design, at neutral.

    Attributes
    ----------
    dof : str
        The DOF.
    excursion_min, excursion_max : float
        Stroke-limited excursion (``twin workspace``) [m or rad].
    velocity, acceleration : float
        The DOF's speed [m/s or rad/s] and acceleration at which the fastest leg reaches its
        velocity and acceleration limit at neutral (``leg limit / max_j |J_jk|``).
    velocity_range, acceleration_range : tuple of float
        The same limits' least and largest value over the DOF's excursion (the Jacobian
        changes with the pose; the other DOFs at neutral).

    """

    dof: str
    excursion_min: float
    excursion_max: float
    velocity: float
    acceleration: float
    velocity_range: tuple[float, float] = (np.nan, np.nan)
    acceleration_range: tuple[float, float] = (np.nan, np.nan)

    def to_dict(self) -> dict[str, float | str]:
        """JSON-ready."""
        return {"dof": self.dof, "excursion_min": self.excursion_min,
                "excursion_max": self.excursion_max, "velocity": self.velocity,
                "acceleration": self.acceleration, "velocity_range": list(self.velocity_range),
                "acceleration_range": list(self.acceleration_range)}  # fmt: skip


def dof_limits(platform: str, dof: str) -> DofLimits:
    """Return the limits of ``dof`` on ``platform`` computed from its geometry and facts."""
    from twin.platform.facts import load_facts
    from twin.platform.geometry import load_geometry
    from twin.platform.kinematics import jacobian, workspace

    k = _dof(dof)
    geo, facts = load_geometry(platform), load_facts(platform)
    ws = workspace(geo)[dof]
    poses = np.zeros((41, 6))
    poses[:, k] = np.linspace(ws.min, ws.max, 41)
    fastest = np.abs(jacobian(geo, poses)[:, :, k]).max(axis=1)  # along the excursion
    at_neutral = float(np.abs(jacobian(geo, np.zeros(6))[:, k]).max())
    v, a = facts.max_velocity, facts.max_acceleration
    return DofLimits(dof, float(ws.min), float(ws.max), v / at_neutral, a / at_neutral,
                     (float(v / fastest.max()), float(v / fastest.min())),
                     (float(a / fastest.max()), float(a / fastest.min())))  # fmt: skip


def _dof(dof: str) -> int:
    if dof not in DOF_NAMES:
        raise SignalError(f"unknown DOF {dof!r}; expected one of {', '.join(DOF_NAMES)}")
    return dof_index(dof)


@dataclass(frozen=True, eq=False)
class LimitsSignal:
    """One level of the system-limits test: out and back both ways in one DOF.

    Attributes
    ----------
    commands : Trajectory
        Pose-offset commands.
    dof : str
        Driven DOF.
    level : float
        The level (a label: the share of the top move).
    distance_pos, distance_neg : float
        Commanded excursion each way (both > 0) [m or rad].
    vmax, amax, jmax : float
        Profile limits of the moves [per s, s^2, s^3].

    """

    commands: Trajectory
    dof: str
    level: float
    distance_pos: float
    distance_neg: float
    vmax: float
    amax: float
    jmax: float

    def meta(self) -> dict[str, object]:
        """Return the ``signal`` entry of the run's ``meta.json``."""
        return {"kind": "limits", "dof": self.dof, "level": self.level,
                "distance_pos": self.distance_pos, "distance_neg": self.distance_neg,
                "vmax": self.vmax, "amax": self.amax, "jmax": self.jmax}  # fmt: skip


def limits_signal(
    dof: str,
    distance_pos: float,
    distance_neg: float,
    vmax: float,
    amax: float,
    jmax: float,
    level: float = 1.0,
    hold_s: float = HOLD_S,
    rate_hz: float = 100.0,
) -> LimitsSignal:
    """Build one level: rest, 0 -> +d -> 0 -> -d -> 0 by point-to-point moves, rest.

    Raises
    ------
    SignalError
        For an unknown DOF, or a distance, limit or hold that is not a positive finite number.

    """
    k = _dof(dof)
    for value, what in ((distance_pos, "distance +"), (distance_neg, "distance -"),
                        (vmax, "vmax"), (amax, "amax"), (jmax, "jmax")):  # fmt: skip
        number(value, f"limits {what}", lo=0, lo_open=True, hi=1e3, error=SignalError)
    number(hold_s, "limits hold [s]", lo=0, lo_open=True, hi=60, error=SignalError)
    moves = [(d, sign) for d in (distance_pos, distance_neg) for sign in (1.0, -1.0)]
    starts, t = [], REST_S
    profiles = []
    for d, _ in moves:
        p = point_to_point(d, vmax, amax, jmax)
        starts.append(t)
        profiles.append(p)
        t += p.duration + hold_s
    n = round((t + REST_S - hold_s) * rate_hz) + 1
    tt = np.arange(n) / rate_hz
    x = np.zeros(n)
    # out to +d, back to 0, out to -d, back to 0: each move's sign and start position
    for (start, p), (base, sign) in zip(zip(starts, profiles, strict=True),
                                        ((0.0, 1.0), (distance_pos, -1.0), (0.0, -1.0),
                                         (-distance_neg, 1.0)), strict=True):  # fmt: skip
        sel = tt >= start
        x[sel] = base + sign * p.at(tt[sel] - start)[0]
    values = np.zeros((n, 6))
    values[:, k] = x
    return LimitsSignal(Trajectory(rate_hz, values), dof, float(level), float(distance_pos),
                        float(distance_neg), float(vmax), float(amax), float(jmax))  # fmt: skip


@dataclass(frozen=True)
class Reached:
    """Peaks of a motion over a window.

    Attributes
    ----------
    excursion_max, excursion_min : float
        Most positive and most negative pose offset [m or rad].
    velocity, acceleration, jerk : float
        Largest magnitude [per s, s^2, s^3].

    """

    excursion_max: float
    excursion_min: float
    velocity: float
    acceleration: float
    jerk: float

    def to_dict(self) -> dict[str, float]:
        """JSON-ready."""
        return {"excursion_max": self.excursion_max, "excursion_min": self.excursion_min,
                "velocity": self.velocity, "acceleration": self.acceleration,
                "jerk": self.jerk}  # fmt: skip


@dataclass(frozen=True, eq=False)
class LevelResult:
    """What one level commanded, should have reached, reached, and what stopped it.

    Attributes
    ----------
    level : float
        The level (nan for a run without one in its ``meta.json``).
    commanded, expected, reached : Reached
        Peaks of the commands, of the commands through the configuration's filter and delay,
        and of the measured response.
    counts : dict of str to int, or None
        The limiter's samples per kind (:data:`KINDS`); None for a recorded run without them.
    stopped_by : tuple of str
        The limits that stopped the level, the one with the largest shortfall first.
    t, pose, measured_acc : ndarray
        The response over the window (for the plot): time, pose offset and measured
        acceleration of the DOF.
    commanded_pose : ndarray
        The commanded pose offset over the window.
    coupled : dict of str to float, or None
        The largest pose offset in each other DOF over the window (m, rad), when the pose of
        all six was given: beyond one leg's stroke end the others go on, and the platform
        leaves the pure DOF motion.

    """

    level: float
    commanded: Reached
    expected: Reached
    reached: Reached
    counts: dict[str, int] | None
    stopped_by: tuple[str, ...]
    t: FloatArray = field(repr=False)
    pose: FloatArray = field(repr=False)
    measured_acc: FloatArray = field(repr=False)
    commanded_pose: FloatArray = field(repr=False)
    coupled: dict[str, float] | None = None

    def shortfall(self) -> dict[str, float]:
        """Share by which each reached peak falls short of the expected one (0: none)."""
        e, r = self.expected, self.reached
        stroke = max(_short(r.excursion_max, e.excursion_max),
                     _short(-r.excursion_min, -e.excursion_min))  # fmt: skip
        return {"stroke": stroke, "velocity": _short(r.velocity, e.velocity),
                "acceleration": _short(r.acceleration, e.acceleration),
                "force": _short(r.acceleration, e.acceleration)}  # fmt: skip

    def to_dict(self) -> dict[str, object]:
        """JSON-ready."""
        return {"level": None if not np.isfinite(self.level) else self.level,
                "commanded": self.commanded.to_dict(), "expected": self.expected.to_dict(),
                "reached": self.reached.to_dict(), "counts": self.counts,
                "coupled": self.coupled,
                "shortfall": self.shortfall(), "stopped_by": list(self.stopped_by)}  # fmt: skip


def _short(reached: float, expected: float) -> float:
    """Share by which ``reached`` falls short of ``expected`` (>= 0; 0 for a zero expected)."""
    return max(0.0, 1.0 - reached / expected) if expected > 0 else 0.0


@dataclass(frozen=True, eq=False)
class LimitsResult:
    """The system-limits test of one DOF.

    Attributes
    ----------
    dof : str
        Driven DOF.
    levels : tuple of LevelResult
        In the order run.
    computed : DofLimits
        The limits computed from the design.
    source : str
        What was measured.

    """

    dof: str
    levels: tuple[LevelResult, ...]
    computed: DofLimits
    source: str

    def max_reached(self) -> Reached:
        """Return the largest excursion each way, speed, acceleration and jerk of all levels."""
        rs = [lv.reached for lv in self.levels]
        return Reached(max(r.excursion_max for r in rs), min(r.excursion_min for r in rs),
                       max(r.velocity for r in rs), max(r.acceleration for r in rs),
                       max(r.jerk for r in rs))  # fmt: skip

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: every level, the largest reached, the computed limits."""
        return {"test": "system limits", "dof": self.dof,
                "levels": [lv.to_dict() for lv in self.levels],
                "max_reached": self.max_reached().to_dict(),
                "computed": self.computed.to_dict(), "source": self.source}  # fmt: skip

    def format_table(self) -> str:
        """Plain-text summary: per level, commanded / reached and what stopped it."""
        unit = acceleration_unit(self.dof)
        pos = unit.replace("/s^2", "")
        c = self.computed
        lines = [
            f"system limits, {self.dof} ({self.source}); commanded -> reached",
            f"{'level':>6}{'excursion + [' + pos + ']':>22}{'excursion - [' + pos + ']':>22}"
            f"{'speed [' + pos + '/s]':>20}{'accel [' + unit + ']':>22}{'jerk':>9}  stopped by",
        ]
        for lv in self.levels:
            cm, r = lv.commanded, lv.reached
            lines.append(
                f"{lv.level:6.2f}{cm.excursion_max:11.4f}{r.excursion_max:11.4f}"
                f"{cm.excursion_min:11.4f}{r.excursion_min:11.4f}{cm.velocity:10.4f}"
                f"{r.velocity:10.4f}{cm.acceleration:11.3f}{r.acceleration:11.3f}"
                f"{r.jerk:9.1f}  {', '.join(lv.stopped_by) or '-'}"
            )
        m = self.max_reached()
        lines.append(f"largest reached: excursion {m.excursion_min:.4f} .. {m.excursion_max:.4f}, "
                     f"speed {m.velocity:.4f}, acceleration {m.acceleration:.3f}, jerk "
                     f"{m.jerk:.1f}")  # fmt: skip
        lines.append(f"computed (design, at neutral): excursion {c.excursion_min:.4f} .. "
                     f"{c.excursion_max:.4f}, speed {c.velocity:.4f}, acceleration "
                     f"{c.acceleration:.3f}")  # fmt: skip
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """One row per level (:meth:`LevelResult.to_dict`, nested values as ``a.b``)."""
        return frame(lv.to_dict() for lv in self.levels)

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Commanded and reached pose per level, and reached against commanded peaks.

        Parameters
        ----------
        ax : sequence of four Axes, optional
            Where to draw: pose per level, then the three panels of reached against
            commanded peaks; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        fig, axes = subplots(ax, 1, 4, figsize=(13, 3.6))
        ax_p = axes[0]
        for i, lv in enumerate(self.levels):
            ax_p.plot(lv.t - lv.t[0], lv.commanded_pose, ":", color=f"C{i % 10}", lw=0.8)
            ax_p.plot(lv.t - lv.t[0], lv.pose, "-", color=f"C{i % 10}", lw=0.9,
                      label=f"level {lv.level:g}")  # fmt: skip
        for y in (self.computed.excursion_min, self.computed.excursion_max):
            ax_p.axhline(y, color="k", lw=0.7, ls="--")
        ax_p.set_xlabel("time in the level [s]")
        ax_p.set_ylabel(f"{self.dof} (dotted: commanded)")
        ax_p.legend(fontsize=6)
        unit = acceleration_unit(self.dof)
        for ax, name, limit, label in (
            (axes[1], "velocity", self.computed.velocity, f"speed [{unit[:-2]}]"),
            (axes[2], "acceleration", self.computed.acceleration, f"acceleration [{unit}]"),
            (axes[3], "jerk", None, f"jerk [{unit[:-2]}^3]"),
        ):
            x = [getattr(lv.commanded, name) for lv in self.levels]
            y = [getattr(lv.reached, name) for lv in self.levels]
            ax.plot(x, y, "o-", label="reached")
            ax.plot(x, x, "k:", lw=0.8, label="= commanded")
            if limit is not None:
                ax.axhline(limit, color="C3", lw=0.8, ls="--", label="computed limit")
            for xi, yi, lv in zip(x, y, self.levels, strict=True):
                if lv.stopped_by:
                    ax.annotate(lv.stopped_by[0], (xi, yi), fontsize=6)
            ax.set_xlabel(f"commanded {label}")
            ax.set_ylabel(f"reached {label}")
            ax.legend(fontsize=6)
            ax.grid(True, alpha=0.3)
        fig.suptitle(f"system limits, {self.dof}: {self.source}", fontsize=9)
        return finish(fig, path)


def expected_jets(m: Measurement, k: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Commanded pose, speed and acceleration of DOF ``k`` through the filter and the delay."""
    t = m.t
    rows = np.column_stack([m.commands.at(t, d)[:, k] for d in (0, 1, 2)])
    fb = m.config.breaks_hz[k]
    if fb is not None:
        both = Trajectory(1.0 / (t[1] - t[0]), np.tile(rows, (1, 2)), float(t[0]))
        rows = PlatformFilter(float(fb))(both).values[:, :3]
    delay = float(m.config.delays_s[k])
    x, v, a = (np.interp(t - delay, t, rows[:, c], left=rows[0, c]) for c in (0, 1, 2))
    return x, v, a


def _derivative(y: FloatArray, dt: float) -> FloatArray:
    """Savitzky-Golay first derivative over :data:`DIFF_WINDOW_S`.

    Quadratic (the least-squares slope: no overshoot where the motion has a corner, a stroke
    end or a velocity limit, as a cubic's 6 % would be).
    """
    n = max(5, round(DIFF_WINDOW_S / dt) | 1)
    if y.size < n:
        return np.gradient(y, dt)
    return savgol_filter(y, n, 2, deriv=1, delta=dt)


def _smoothed(y: FloatArray, dt: float) -> FloatArray:
    """Savitzky-Golay smoothing over :data:`DIFF_WINDOW_S` (cubic): noise off the peaks."""
    n = max(5, round(DIFF_WINDOW_S / dt) | 1)
    return y if y.size < n else savgol_filter(y, n, 3)


def _peaks(x: FloatArray, v: FloatArray, a: FloatArray, jerk: FloatArray) -> Reached:
    return Reached(float(x.max()), float(x.min()), float(np.abs(v).max()),
                   float(np.abs(a).max()), float(np.abs(jerk).max()))  # fmt: skip


def analyse_limits(
    m: Measurement,
    pose: FloatArray,
    dof: str | None = None,
    counts: dict[str, int] | None = None,
    window: tuple[float, float] | None = None,
    level: float | None = None,
) -> LevelResult:
    """Analyse one level of the system-limits test (or a window of a longer run).

    Parameters
    ----------
    m : Measurement
        Commanded and measured accelerations.
    pose : ndarray, shape (n,) or (n, 6)
        The platform's pose offset on ``m.t`` (the DOF's column, or all six): simulated, or
        from a recorded run's leg lengths (:class:`~twin.agard.positions.PositionRecord`).
    dof : str, optional
        The DOF (default: the run's signal's, or the one the commands move most).
    counts : dict of str to int, optional
        The limiter's samples per kind (:data:`KINDS`) over the window; without them the
        limits are found from the shortfall (:data:`SHORTFALL`).
    window : (float, float), optional
        Time span of the level in the run [s]; default the whole run.
    level : float, optional
        The level's label (default: the run's ``meta.json`` signal's, else nan).

    Raises
    ------
    SignalError
        For a pose of the wrong shape, a window not inside the run, unknown count kinds, or
        commands that do not move the DOF in the window.

    """
    k = driven_dof(m, dof)
    p = np.asarray(pose, dtype=float)
    others = None
    if p.ndim == 2 and p.shape == (m.t.size, 6):
        p, others = p[:, k], p
    if p.shape != m.t.shape or not np.all(np.isfinite(p)):
        raise SignalError(f"the pose must be finite, of shape ({m.t.size},) or ({m.t.size}, 6) "
                          f"on the measurement's times; got {np.shape(pose)}")  # fmt: skip
    if counts is not None:
        unknown = set(counts) - set(KINDS)
        if unknown:
            raise SignalError(f"limit counts are of {', '.join(KINDS)}; got {sorted(unknown)}")
    lo, hi = window_in(window, (float(m.t[0]), float(m.t[-1])), "limits")
    # clear of the post-processing's start and end transients (App. C.2.3's FIR)
    lo, hi = max(lo, float(m.t[0]) + EDGE_S), min(hi, float(m.t[-1]) - EDGE_S)
    sel = (m.t >= lo - 1e-9) & (m.t <= hi + 1e-9)
    if sel.sum() < 10:
        raise SignalError(f"the limits window {lo:g}-{hi:g} s holds fewer than 10 samples")
    t = m.t[sel]
    dt = float(t[1] - t[0])
    cx, cv, ca = (m.commands.at(t, d)[:, k] for d in (0, 1, 2))
    if np.ptp(cx) == 0:
        raise SignalError(f"{m.source}: the {DOF_NAMES[k]} commands do not move between "
                          f"{lo:.2f} and {hi:.2f} s; the limits test needs moves")  # fmt: skip
    ex, ev, ea = (y[sel] for y in expected_jets(m, k))
    commanded = _peaks(cx, cv, ca, np.gradient(ca, dt))
    expected = _peaks(ex, ev, ea, _derivative(ea, dt))
    px, acc = p[sel], _smoothed(m.measured[sel, k], dt)
    reached = _peaks(px, _derivative(px, dt), acc, _derivative(acc, dt))
    if level is None:
        sig = m.meta.get("signal")
        level = float(sig["level"]) if isinstance(sig, dict) and "level" in sig else np.nan
    result = LevelResult(float(level), commanded, expected, reached,
                         None if counts is None else {kd: int(counts.get(kd, 0)) for kd in KINDS},
                         (), t, px, acc, cx)  # fmt: skip
    short = result.shortfall()
    if counts is not None:
        hit = [kd for kd in KINDS if counts.get(kd, 0) > 0]
    else:  # a shortfall names a limit only where the motion comes near it by design
        near = _near_design(expected, dof_limits(m.config.platform, DOF_NAMES[k]))
        hit = [kd for kd, tol in SHORTFALL.items() if short[kd] > tol and near[kd]]
    stopped = tuple(sorted(hit, key=lambda kd: -short[kd]))
    coupled = (
        None
        if others is None
        else {DOF_NAMES[j]: float(np.abs(others[sel, j]).max()) for j in range(6) if j != k}
    )
    return LevelResult(result.level, commanded, expected, reached, result.counts, stopped,
                       t, px, acc, cx, coupled)  # fmt: skip


def _near_design(expected: Reached, design: DofLimits) -> dict[str, bool]:
    """Return, per limit, whether the expected motion reaches :data:`NEAR` of its design value.

    Short of that, a shortfall is the platform's dynamics (a 30 ms acceleration plateau is
    not followed), not a limit.
    """
    lo, hi = design.velocity_range, design.acceleration_range
    v_lim = np.nanmin([design.velocity, lo[0]])
    a_lim = np.nanmin([design.acceleration, hi[0]])
    return {
        "stroke": max(expected.excursion_max / design.excursion_max,
                      expected.excursion_min / design.excursion_min) >= NEAR,
        "velocity": expected.velocity >= NEAR * v_lim,
        "acceleration": expected.acceleration >= NEAR * a_lim,
    }  # fmt: skip


def recorded_counts(rec: RecordedRun) -> dict[str, int] | None:
    """Return the limiter's counts a simulated run wrote to its ``meta.json`` (else None)."""
    lim = rec.meta.get("limits")
    if not isinstance(lim, dict) or not isinstance(lim.get("samples"), dict):
        return None
    return {**{kd: int(lim["samples"].get(kd, 0)) for kd in KINDS[:3]},
            "force": int(lim.get("force_samples", 0))}  # fmt: skip


def run_limits(
    session: Session,
    dof: str,
    levels: Sequence[float] = LEVELS,
    vmax: float | None = None,
    amax: float | None = None,
    jmax: float | None = None,
    size: float | None = None,
) -> LimitsResult:
    """Run the system-limits levels in ``dof`` on a session's bench and analyse them.

    Parameters
    ----------
    session : Session
        Where to run; every level is one run, beyond the platform's limits (limited and
        counted by the actuator limiter, not refused).
    dof : str
        Driven DOF.
    levels : sequence of float
        Each in (0, :data:`MAX_LEVEL`]: the share of the stroke-limited excursion a level's
        moves go to (unless ``size``), and of ``vmax``, ``amax`` and ``jmax``.
    vmax, amax, jmax : float, optional
        Top speed, acceleration and jerk (at level 1); default :data:`OVER` times the DOF's
        computed velocity and acceleration limits, and the top acceleration over
        :data:`JERK_RAMP_S`.
    size : float, optional
        Share of the stroke-limited excursion every level moves to, in (0, MAX_LEVEL]
        (default: the level).

    Raises
    ------
    SignalError
        For an unknown DOF, an empty list of levels or a value out of its range.

    """
    _dof(dof)
    if isinstance(levels, str) or len(levels) == 0:
        raise SignalError(f"give at least one limits level in (0, {MAX_LEVEL:g}]; got {levels!r}")
    lv = [number(x, f"limits level[{i}]", lo=0, lo_open=True, hi=MAX_LEVEL, error=SignalError)
          for i, x in enumerate(levels)]  # fmt: skip
    if size is not None:
        number(size, "limits size", lo=0, lo_open=True, hi=MAX_LEVEL, error=SignalError)
    computed = dof_limits(session.bench.config.platform, dof)
    v = OVER * computed.velocity if vmax is None else vmax
    a = OVER * computed.acceleration if amax is None else amax
    j = a / JERK_RAMP_S if jmax is None else jmax
    for value, what in ((v, "vmax"), (a, "amax"), (j, "jmax")):
        number(value, f"limits {what}", lo=0, lo_open=True, hi=1e3, error=SignalError)
    session.expect(len(lv), f"system limits {dof}")
    out, sources = [], []
    for level in lv:
        share = level if size is None else size
        sig = limits_signal(dof, share * computed.excursion_max, -share * computed.excursion_min,
                            level * v, level * a, level * j, level)  # fmt: skip
        m = session.measure(sig, f"limits-{dof}-{level:g}", check_limits=False)
        sim = session.simulation
        pose = PositionRecord.from_simulation(sim).on(m.t)
        counts = {**sim.limits.samples, "force": sim.limits.force_samples}
        out.append(analyse_limits(m, pose, dof, counts, level=level))
        sources.append(m.source)
    return LimitsResult(dof, tuple(out), computed, joined_sources(sources))
