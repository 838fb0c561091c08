"""The dynamic threshold test (§3.3.4, §4.3.2, Fig 3.8, Fig 4.2).

Square-wave acceleration steps (Fig 3.2b) drive one DOF; the first-order lag with delay of
Eq 3.7, G(s) = e^{-tau_d s} / (tau s + 1), is fitted to the measured acceleration response in
the time domain (least squares over the whole step sequence, the input being the commanded
acceleration). ``t63 = tau_d + tau`` is the time the fitted model takes to reach 63 % of a
step (§3.3.4). The delay can be fixed, as the thesis fixed it to the describing function's
(100 ms in §3.4.4). The configuration's analytic model (Eq 5.11) is put through the same fit
on the same input, so measured and analytic 63 % times compare like for like; the exact
63 % time of the analytic step response from rest is reported too.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy import linalg, signal
from scipy.optimize import brentq, least_squares

from twin.agard.session import Session
from twin.chain.config import MotionSystem
from twin.chain.filter import PlatformFilter
from twin.chain.signals import square_steps
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
#: Least change of the commanded acceleration in one sample, over its range, that makes a step
#: (the §3.3.4 pattern's is a half; a multi-sine's under a tenth at 100 Hz).
MIN_STEP_SHARE = 0.25
#: Longest delay tau_d of the Eq 3.7 fit [s]: the free fit searches [0, 1] s, and a fixed one
#: is allowed as far.
MAX_FIT_DELAY_S = 1.0


def lag_delay_response(t: FloatArray, u: FloatArray, tau: float, delay: float) -> FloatArray:
    """Response of e^{-delay s} / (tau s + 1) to ``u`` (linear between samples), from rest."""
    return np.interp(t - delay, t, lag_response(t, u, max(tau, 1e-6)), left=0.0)


def lag_response(t: FloatArray, u: FloatArray, tau: float) -> FloatArray:
    """Response of 1 / (tau s + 1) to ``u`` (linear between uniform samples ``t``), from rest.

    :func:`scipy.signal.lsim`'s first-order-hold recursion, ``x[i] = x[i-1] Ad + u[i-1] Bd0 +
    u[i] Bd1`` from its own discretisation, run by :func:`scipy.signal.lfilter` instead of a
    Python loop: the same products and sums in the same order (lfilter's transposed direct
    form II adds ``u[i-1] Bd0 - x[i-1] (-Ad)`` first), so the same values (tested), some 50 times
    faster; the threshold fit evaluates it some 100 times a fit.
    """
    if t.size < 2 or not np.allclose(np.diff(t), t[1] - t[0]):
        raise SignalError(f"the lag response needs two or more equally spaced times; got {t.size}"
                          " times" + (" unequally spaced" if t.size >= 2 else ""))  # fmt: skip
    a, b, c, d = signal.tf2ss([1.0], [tau, 1.0])
    dt = t[1] - t[0]
    m = np.vstack([np.hstack([a * dt, b * dt, np.zeros((1, 1))]),
                   np.hstack([np.zeros((1, 2)), np.identity(1)]),
                   np.zeros((1, 3))])  # fmt: skip
    exp_mt = linalg.expm(m.T)
    ad, bd1 = exp_mt[0, 0], exp_mt[2, 0]
    bd0 = exp_mt[1, 0] - bd1
    x = np.zeros(u.size)
    x[1:], _ = signal.lfilter([bd1, bd0], [1.0, -ad], u[1:], zi=u[:1] * bd0)
    # lsim's output, y = x C^T + u D^T, as it computes it
    return np.squeeze(x[:, None] @ c.T) + np.squeeze(u[:, None] @ d.T)


@dataclass(frozen=True)
class LagDelayStepFit:
    """Eq 3.7 fitted to a step response.

    Attributes
    ----------
    delay_s, tau_s : float
        tau_d and tau [s].
    rms_error : float
        RMS residual over the fit span [signal units].

    """

    delay_s: float
    tau_s: float
    rms_error: float

    @property
    def t63_s(self) -> float:
        """Time to 63 % of a step: tau_d + tau [s]."""
        return self.delay_s + self.tau_s


def fit_eq_3_7(
    t: FloatArray, u: FloatArray, y: FloatArray, fixed_delay_s: float | None = None
) -> LagDelayStepFit:
    """Fit Eq 3.7 to the response ``y`` of the input ``u`` (least squares in time).

    Parameters
    ----------
    t, u, y : ndarray, shape (n,)
        Uniform times, commanded and measured acceleration.
    fixed_delay_s : float, optional
        Keep tau_d at this value [s] and fit tau only: in [0, :data:`MAX_FIT_DELAY_S`].

    Raises
    ------
    SignalError
        For a zero input or a fixed delay that is not a number in the range.

    """
    if not np.any(u):
        raise SignalError("the input of the step fit is zero")
    if fixed_delay_s is not None:
        number(fixed_delay_s, "fixed tau_d [s]", lo=0, hi=MAX_FIT_DELAY_S, error=SignalError)

    def residual(x: FloatArray) -> FloatArray:
        delay = fixed_delay_s if fixed_delay_s is not None else x[1]
        return lag_delay_response(t, u, x[0], delay) - y

    best = None
    delays = [0.0] if fixed_delay_s is not None else [0.0, 0.03, 0.1, 0.2]
    for tau0 in (0.02, 0.1, 0.3):
        for d0 in delays:
            x0 = [tau0] if fixed_delay_s is not None else [tau0, d0]
            lo, hi = ([1e-4], [5.0]) if fixed_delay_s is not None else \
                ([1e-4, 0.0], [5.0, MAX_FIT_DELAY_S])  # fmt: skip
            sol = least_squares(residual, x0, bounds=(lo, hi), x_scale=[0.05] * len(x0))
            if best is None or sol.cost < best.cost:
                best = sol
    delay = fixed_delay_s if fixed_delay_s is not None else float(best.x[1])
    rms = float(np.sqrt(2 * best.cost / t.size))
    return LagDelayStepFit(float(delay), float(best.x[0]), rms)


def analytic_t63(config: MotionSystem, dof: str) -> float:
    """Exact 63 % time of the configuration's Eq 5.11 acceleration step response from rest [s]."""
    k = dof_index(dof)
    delay, fb = float(config.delays_s[k]), config.breaks_hz[k]
    if fb is None:
        return delay
    w = 2 * np.pi * fb
    # step response of 1 / (1 + s / w)^2: 1 - (1 + w t) e^{-w t}
    t = brentq(lambda x: 1 - (1 + w * x) * np.exp(-w * x) - (1 - np.exp(-1)), 0, 50 / w)
    return delay + float(t)


@dataclass(frozen=True, eq=False)
class ThresholdResult:
    """The dynamic threshold test of one DOF.

    Attributes
    ----------
    dof : str
        Driven DOF.
    amplitude, step_s : float
        Step amplitude [m/s^2 or rad/s^2] and length [s].
    fit : LagDelayStepFit
        Eq 3.7 fitted to the measured response.
    analytic_fit : LagDelayStepFit
        The same fit to the configuration's analytic response (Eq 5.11) to the same input.
    analytic_t63_s : float
        Exact 63 % time of the analytic step response from rest [s].
    t, commanded, measured : ndarray
        The fit span: time, commanded and measured acceleration (baseline removed).
    source : str
        What was measured.

    """

    dof: str
    amplitude: float
    step_s: float
    fit: LagDelayStepFit
    analytic_fit: LagDelayStepFit
    analytic_t63_s: float
    t: FloatArray
    commanded: FloatArray
    measured: FloatArray
    source: str

    def to_dict(self) -> dict[str, object]:
        """JSON-ready (``delay_ms``, ``tau_ms``, ``t63_ms`` and the analytic values)."""
        return {
            "test": "dynamic threshold",
            "dof": self.dof,
            "amplitude": self.amplitude,
            "step_s": self.step_s,
            "delay_ms": self.fit.delay_s * 1e3,
            "tau_ms": self.fit.tau_s * 1e3,
            "t63_ms": self.fit.t63_s * 1e3,
            "rms_error": self.fit.rms_error,
            "analytic_fit": {
                "delay_ms": self.analytic_fit.delay_s * 1e3,
                "tau_ms": self.analytic_fit.tau_s * 1e3,
                "t63_ms": self.analytic_fit.t63_s * 1e3,
            },
            "analytic_step_t63_ms": self.analytic_t63_s * 1e3,
            "source": self.source,
        }

    def format_table(self) -> str:
        """Plain-text summary."""
        a, f = self.analytic_fit, self.fit
        unit = acceleration_unit(self.dof)
        return "\n".join(
            [
                f"dynamic threshold, {self.dof}: steps of {self.amplitude:g} {unit} lasting "
                f"{self.step_s:g} s ({self.source})",
                f"{'':22}{'tau_d [ms]':>11}{'tau [ms]':>10}{'t63 [ms]':>10}",
                f"{'measured, Eq 3.7 fit':22}{f.delay_s * 1e3:11.1f}{f.tau_s * 1e3:10.1f}"
                f"{f.t63_s * 1e3:10.1f}",
                f"{'Eq 5.11, same fit':22}{a.delay_s * 1e3:11.1f}{a.tau_s * 1e3:10.1f}"
                f"{a.t63_s * 1e3:10.1f}",
                f"Eq 5.11 step from rest reaches 63 % after {self.analytic_t63_s * 1e3:.1f} ms",
            ]
        )

    def to_frame(self) -> pd.DataFrame:
        """One row per sample: time, commanded and measured response (the plotted traces)."""
        return frame({"t_s": self.t, "commanded": self.commanded, "measured": self.measured})

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Commanded, measured and fitted responses (as Fig 3.8 / Fig 4.2).

        Parameters
        ----------
        ax : Axes, optional
            Where to draw: the responses; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        fig, ax = subplots(ax, figsize=(7, 3.5))
        ax.plot(self.t, self.commanded, "k-", lw=0.8, label="commanded")
        ax.plot(self.t, self.measured, lw=0.7, alpha=0.8, label="measured")
        f = self.fit
        ax.plot(
            self.t,
            lag_delay_response(self.t, self.commanded, f.tau_s, f.delay_s),
            "C3--",
            label=f"Eq 3.7: tau_d {f.delay_s * 1e3:.0f} ms, tau {f.tau_s * 1e3:.0f} ms",
        )
        unit = acceleration_unit(self.dof)
        ax.set_xlabel("time [s]")
        ax.set_ylabel(f"{self.dof} acceleration [{unit}]")
        ax.set_title(f"dynamic threshold: {self.source}", fontsize=9)
        ax.legend(fontsize=7)
        return finish(fig, path)


def analyse_threshold(
    m: Measurement, dof: str | None = None, fixed_delay_s: float | None = None
) -> ThresholdResult:
    """Fit Eq 3.7 to a step-signal measurement (and the analytic model to the same input).

    Raises
    ------
    SignalError
        For a run whose ``meta.json`` says it was driven by another signal than steps (a
        multi-sine), or whose commanded acceleration holds no steps: its largest change from
        one sample to the next is under :data:`MIN_STEP_SHARE` of its range (a multi-sine's
        is under a tenth; the §3.3.4 pattern's is a half).

    """
    sig = m.meta.get("signal")
    sig = sig if isinstance(sig, dict) else {}
    kind = sig.get("kind")
    if kind is not None and kind != "steps":
        raise SignalError(f"{m.source}: a {kind} signal (meta.json signal.kind); the dynamic "
                          "threshold needs acceleration steps (run twin agard threshold on a "
                          "configuration to record them)")  # fmt: skip
    k = driven_dof(m, dof)
    u = m.commanded[:, k]
    du = np.abs(np.diff(u))
    if du.max() <= MIN_STEP_SHARE * np.ptp(u):
        raise SignalError(f"{m.source}: the {DOF_NAMES[k]} commands hold no acceleration steps "
                          f"(their acceleration changes by at most {du.max():.3g} a sample over "
                          f"a range of {np.ptp(u):.3g}); the dynamic threshold needs steps (run "
                          "twin agard threshold on a configuration to record them)")  # fmt: skip
    steps = np.flatnonzero(du > 0.3 * du.max())
    first, last = m.t[steps[0]], m.t[steps[-1]]
    span = (m.t >= first - 0.5) & (m.t <= min(last + 1.5, m.t[-1]))
    before = m.t < first - 0.1
    baseline = float(m.measured[before, k].mean()) if before.sum() > 10 else 0.0
    t, uu = m.t[span], u[span]
    y = m.measured[span, k] - baseline
    fit = fit_eq_3_7(t, uu, y, fixed_delay_s)
    # the analytic model's response to the same commanded acceleration
    acc = Trajectory(1.0 / (t[1] - t[0]), np.repeat(uu[:, None], 6, axis=1), float(t[0]))
    model = m.config
    y_a = acc.values[:, k]
    if model.breaks_hz[k] is not None:
        y_a = PlatformFilter(model.breaks_hz)(acc).values[:, k]
    y_a = np.interp(t - model.delay_s, t, y_a, left=0.0)
    analytic = fit_eq_3_7(t, uu, y_a, fixed_delay_s)
    amplitude = float(sig.get("amplitude", np.abs(u).max()))
    step_s = float(sig.get("step_s", np.median(np.diff(m.t[steps]))))
    return ThresholdResult(
        DOF_NAMES[k],
        amplitude,
        step_s,
        fit,
        analytic,
        analytic_t63(model, DOF_NAMES[k]),
        t,
        uu,
        y,
        m.source,
    )


def run_threshold(
    session: Session,
    dof: str,
    amplitude: float = 0.1,
    step_s: float = 1.0,
    fixed_delay_s: float | None = None,
    repeats: int = 1,
) -> ThresholdResult:
    """Run the square-wave steps in ``dof`` and fit Eq 3.7 (defaults: §3.3.4, 0.1 for 1 s)."""
    sig = square_steps(dof, amplitude, step_s, repeats=repeats)
    m = session.measure(sig, f"steps-{dof}-{amplitude:g}-{step_s:g}s")
    return analyse_threshold(m, dof, fixed_delay_s)
