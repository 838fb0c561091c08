"""Time-domain fit of the pitch-task pilot model (Eq 6.5-6.7) to a measured control signal.

The model predicts the control signal from the forcing functions through the whole closed
loop (task, motion system, pilot), as the maximum-likelihood method of the thesis' references
does: fitting u to the measured e and theta instead is biased, because in closed loop they
carry the pilot's own remnant (the motion gain came out 34 % low that way at 15 % remnant).
The prediction is computed over the measurement window in the frequency domain (the window
holds whole periods of the forcing functions, so it is exact); it is deterministic at the
forcing functions' lines only, so the eight parameters minimise the line residuals weighted
by the remnant's variance at each line (from the neighbouring bins): the maximum-likelihood
estimate for a coloured Gaussian remnant. The fit reports the Variance-Accounted-For (Eq 2.25)
and the Cramer-Rao lower bound of each parameter's standard deviation (Eq 2.26: the inverse
Fisher information at the optimum), and names the parameters it cannot pin down. Where the
likelihood has several minima (the lead-lag pair at the thesis' remnant level) the bound is
too narrow; ``intervals=True`` adds each parameter's likelihood-ratio interval from the
profile likelihood (:mod:`twin.pilot.identification.profile`).
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from twin.chain.config import MotionSystem
from twin.core.errors import SignalError
from twin.core.jsonable import plain
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.progress import ProgressFn
from twin.core.results import frame
from twin.pilot.identification.minima import SAME_PREDICTION, competing, distinct, vuong_z, widened
from twin.pilot.identification.profile import inward_point, likelihood_interval, profile_fit
from twin.pilot.identification.profile_wald import profile_wald_sd
from twin.pilot.identification.selection import selected_bounds
from twin.pilot.models.pitch import PitchPilot, aircraft, motion_response

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]
#: p of the fit's chi-square below which the model is said not to describe the data.
MISFIT_P = 1e-3
PARAMETERS = ("k_v", "t_lead", "t_lag", "tau_v", "k_m", "tau_m", "omega_nm", "zeta_nm")
LOWER = np.array([0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 3.0, 0.02])
UPPER = np.array([20.0, 5.0, 5.0, 0.8, 10.0, 0.8, 40.0, 2.0])


def vaf(u: FloatArray, u_hat: FloatArray) -> float:
    """Variance-Accounted-For, Eq 2.25 [%]."""
    return float(100.0 * (1.0 - np.var(u - u_hat) / np.var(u)))


def model_output(
    pilot: PitchPilot,
    ft: FloatArray,
    fd: FloatArray,
    config: MotionSystem,
    rate_hz: float,
    hold: bool = False,
) -> FloatArray:
    """Predicted u over one window from the forcing functions, through the closed loop.

    U = (H_v F_t - (H_v + H_ptheta H_m) H_c F_d) / (1 + (H_v + H_ptheta H_m) H_c), with
    H_v = H_pe e^{-s T_display}, H_m the motion system (Eq 5.11) and H_c = K H_theta,de
    (times a zero-order hold of one sample when ``hold``).
    """
    n = ft.size
    w = 2 * np.pi * np.fft.rfftfreq(n, 1.0 / rate_hz)
    w[0] = 1e-9  # the integrator of H_c: the mean is not predicted
    U = _closed_loop_u(pilot, w, np.fft.rfft(ft), np.fft.rfft(fd), config, hold / rate_hz)
    U[0] = 0.0
    return np.fft.irfft(U, n)


@dataclass(frozen=True)
class PilotFit:
    """Result of the time-domain fit.

    Attributes
    ----------
    pilot : PitchPilot
        Estimated parameters.
    crlb : dict of str to float
        The standard deviation reported for each parameter: its Cramer-Rao bound at the
        estimate where no other minimum competes, else that bound widened so that two of it
        cover each competing minimum's own two bounds
        (:func:`twin.pilot.identification.minima.widened`: the truth may sit in any of them) and
        each point of ``on_range_bound`` and ``range_end`` (a point's parameters on an end of their
        range count as points there), after the widening for the minima the data ruled out
        (:mod:`twin.pilot.identification.selection`; it starts from the bound at the estimate); for
        the lead-lag pair where it counts as identifiable, at least the sd along the likelihood's
        valley (:mod:`twin.pilot.identification.profile_wald`). JSON ``crlb_sd``;
        an unbounded sd (a parameter the data do not see, or one on its range's bound) is
        infinite, null in the JSON.
    vaf_percent : float
        Variance-Accounted-For of u [%].
    residual_sd : float
        Standard deviation of the output error.
    unidentifiable : tuple of str
        Parameters whose bound (``crlb``, so widened by any competing minimum that puts them
        elsewhere) exceeds ``IDENTIFIABLE_REL_SD`` of their value, those on a bound of their
        range (``on_range_bound``), or (with intervals) those whose likelihood-ratio interval
        reaches much farther than two bounds (reported, not hidden).
    intervals : dict of str to (float, float), or None
        Likelihood-ratio interval of each parameter (two standard deviations where the
        likelihood is a parabola; :mod:`twin.pilot.identification.profile`), when asked for: honest
        where the bound is not (the lead-lag pair's several minima). An end at ``UPPER``, or at a
        ``LOWER`` above zero, is open: the data do not bound the parameter there (a lower end
        at zero is the physical limit of a time constant, delay or gain).
    competing : tuple of PitchPilot
        Other minima the data do not tell from the estimate (chi-square within
        ``COMPETING_CHI2``, or not rejected by Vuong's test:
        :mod:`twin.pilot.identification.minima`), best first: from one run at the thesis' remnant
        level, typically the lead-lag pair's other basin (t_lead near 0.5 s, t_lag near 0.9 s).
    crlb_at_estimate : dict of str to float, or None
        The Cramer-Rao bound at the estimate alone (the inverse Fisher information there; with
        parameters on their range's bound, the others' with those held there). JSON
        ``crlb_sd_at_estimate``; non-finite bounds are written as null.
    on_range_bound : dict of str to PitchPilot
        Each parameter whose estimate sits on an end of its range (``LOWER``, ``UPPER``: a lag
        or gain at zero), with the point where its profile into the range has risen by
        ``COMPETING_CHI2`` (the range's other end if it never does). There the curvature
        says nothing of how far into the range the data allow the parameter: a gain pushed
        onto zero is no stationary point, and a lag at zero acts to first order as a delay,
        so the likelihood rises only at second order. The parameter is reported not
        identifiable with an infinite sd, the others' bound is taken with it held on its
        bound, and the profile's point (the others move with it along the valley it opens)
        widens their ``crlb`` as a competing minimum does. JSON ``on_range_bound``.
    range_end : dict of str to PitchPilot
        Each parameter the data hardly see (its bound at the estimate above
        ``IDENTIFIABLE_REL_SD`` of its distance to the nearer end of its range) and cannot tell
        from that end either (the others refitted with it there cost less than
        ``COMPETING_CHI2``), with the fit there: a t_lag of 0.04 s that may as well be none.
        That fit widens the ``crlb`` of all parameters as a competing minimum does, its own to
        at least half its distance to the end (a lag traded for a delay moves tau_v; with a
        lead-only pilot, one run of condition 4, tau_v's reported sd held the truth in 81 % of
        59 fits without this and 100 % with). JSON ``range_end``.
    evidence : dict
        Why each of those competes: ``competing_minima``, a list (in the order of
        ``competing``) of ``{"delta_chi2", "vuong_z"}`` (chi-square above the best, and
        Vuong's statistic for the best against it); ``ruled_out_minima``, the same of the
        minima the data ruled out, which widen the bounds for the selection
        (:mod:`twin.pilot.identification.selection`); ``range_end``, parameter -> the chi-square
        rise with it on its end; ``fit``, the best fit's goodness of fit (:func:`goodness_of_fit`:
        the VAF does not tell a model that does not hold, this does). JSON ``evidence``.

    """

    pilot: PitchPilot
    crlb: dict[str, float]
    vaf_percent: float
    residual_sd: float
    unidentifiable: tuple[str, ...] = ()
    intervals: dict[str, tuple[float, float]] | None = None
    competing: tuple[PitchPilot, ...] = ()
    crlb_at_estimate: dict[str, float] | None = None
    on_range_bound: dict[str, PitchPilot] = dataclasses.field(default_factory=dict)
    range_end: dict[str, PitchPilot] = dataclasses.field(default_factory=dict)
    evidence: dict[str, object] = dataclasses.field(default_factory=dict)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready."""
        p = dataclasses.asdict(self.pilot)
        out: dict[str, object] = {
            "parameters": p,
            "crlb_sd": plain(self.crlb),
            "vaf_percent": self.vaf_percent,
            "residual_sd": self.residual_sd,
            "not_identifiable": list(self.unidentifiable),
            "competing_minima": [dataclasses.asdict(c) for c in self.competing],
            "crlb_sd_at_estimate": plain(self.crlb_at_estimate),
            "on_range_bound": {k: dataclasses.asdict(v) for k, v in self.on_range_bound.items()},
            "range_end": {k: dataclasses.asdict(v) for k, v in self.range_end.items()},
            "evidence": plain(self.evidence),
        }
        if self.intervals is not None:
            out["likelihood_interval_2sd"] = {k: list(v) for k, v in self.intervals.items()}
        return out

    def covers(self, name: str, value: float) -> bool:
        """Whether ``value`` lies within the parameter's interval (2 bounds without one)."""
        est = float(getattr(self.pilot, name))
        if self.intervals is None:
            return abs(value - est) <= 2 * self.crlb[name]
        lo, hi = self.intervals[name]
        return lo <= value <= hi

    def to_frame(self) -> pd.DataFrame:
        """One row per parameter: estimate, reported sd, and whether it is identifiable."""
        est = dataclasses.asdict(self.pilot)
        return frame([{"parameter": k, "estimate": est.get(k), "sd": sd,
                       "sd_at_estimate": (self.crlb_at_estimate or {}).get(k),
                       "identifiable": k not in self.unidentifiable}
                      for k, sd in self.crlb.items()])  # fmt: skip

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Estimated parameters with their reported sd (``crlb``), relative to the estimate.

        Parameters
        ----------
        ax : Axes, optional
            Where to draw: the parameters; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        names = list(self.crlb)
        values = np.array([getattr(self.pilot, n) for n in names], dtype=float)
        rel = np.array([self.crlb[n] for n in names]) / np.where(values == 0, np.nan, abs(values))
        fig, ax = subplots(ax, figsize=(7, 3.5))
        ax.bar(names, rel * 100)
        ax.set_xlabel("parameter (Eq 6.5-6.7)")
        ax.set_ylabel("reported sd / |estimate| [%]")
        ax.set_title(f"pilot-model fit: VAF {self.vaf_percent:.1f} %", fontsize=9)
        ax.tick_params(axis="x", labelsize=8)
        return finish(fig, path)


#: Largest Cramer-Rao sd relative to the estimate for which a parameter counts as identified:
#: beyond it the linearisation the bound rests on fails (the lead-lag pair at the thesis'
#: remnant level: estimates spread 2-3x wider than their bound).
IDENTIFIABLE_REL_SD = 1 / 3
#: Eigenvalues of the Fisher information below this fraction of the largest count as zero: the
#: data do not see those directions (a bound of infinity for the parameters in them).
SINGULAR_REL = 1e-12
#: A parameter whose share of a null vector of the (unit-diagonal) information exceeds this is
#: in the null space: unseen, an infinite bound.
NULL_SHARE = 1e-3
#: The parameters whose bound changes steeply along the likelihood's valley (the lead-lag
#: pair, whose net lead the data pin down: :mod:`twin.pilot.identification.profile_wald`), by index.
VALLEY = (PARAMETERS.index("t_lead"), PARAMETERS.index("t_lag"))
#: Most lines the forcing functions may have (Table 6.2: 10 + 10).
MAX_LINES = 64
#: Fewest neighbouring bins on each side of a line whose power estimates the remnant there,
#: and the band (fraction of the line's frequency) they are taken from when it holds more.
NEIGHBOURS, NEIGHBOURS_REL = 4, 0.1
#: Starting delays (tau_v, tau_m), lead-lag pairs and motion gains of the multi-start search.
START_DELAYS = ((0.30, 0.20), (0.20, 0.15), (0.40, 0.30), (0.25, 0.10))
START_LEADS = (None, (0.1, 0.1), (0.5, 0.5))
START_KM = (None, 0.0)
#: Chi-square margin within which another minimum competes with the best whatever Vuong's
#: test says (the 95 % point of chi-square with one degree of freedom).
COMPETING_CHI2 = 3.84
#: An estimate within this fraction of its range from either end, whose chi-square moved onto
#: that end rises by less than ``ON_BOUND_CHI2``, sits on the bound: where the likelihood is
#: flat to first order there (a lag at zero) the solver creeps towards it and stops short
#: (1e-8 to 1e-6 s of t_lag in the seeded fits).
ON_BOUND_REL, ON_BOUND_CHI2 = 1e-3, 0.01
#: Minima within this chi-square of the best start the profile fits of the intervals.
PROFILE_CHI2 = 10.0
#: Farthest either end of the likelihood-ratio interval may lie from the estimate, relative to
#: two bounds, for the likelihood to count as a parabola and the bound as the parameter's
#: uncertainty. Where the data are informative the interval's width is within about 1.4x of
#: four bounds (median, 50 seeded fits); a side reaching farther means a second minimum or a
#: flat side the bound cannot see. Measured against the reported bound (widened over the
#: competing minima), so a side that only reaches a competing minimum is not flagged again.
QUADRATIC_SIDE_RATIO = 2.0


def _closed_loop_u(
    pilot: PitchPilot, w: FloatArray, Ft, Fd, config: MotionSystem, hold_s: float = 0.0
):
    hv = pilot.h_visual(w)
    hm = pilot.h_ptheta(w) * motion_response(config, w)
    hc = aircraft(w)
    if hold_s:  # zero-order hold of u over hold_s: (1 - e^{-sT}) / (sT)
        s = 1j * w * hold_s
        hc = hc * (1 - np.exp(-s)) / s
    return (hv * Ft - (hv + hm) * hc * Fd) / (1 + (hv + hm) * hc)


def line_data(
    ft: FloatArray, fd: FloatArray, u: FloatArray, rate_hz: float
) -> tuple[FloatArray, NDArray[np.complex128], NDArray[np.complex128], NDArray[np.complex128],
           FloatArray]:  # fmt: skip
    """Spectra at the forcing functions' lines and the variance of u's remnant at each.

    Parameters
    ----------
    ft, fd : ndarray, shape (n,)
        Forcing functions over the window.
    u : ndarray, shape (n,) or (runs, n)
        Control signal of one run or of repetitions of the same condition (averaged, as the
        thesis averages its five repetitions before identification, §2.6 and §6.4).
    rate_hz : float
        Sample rate [Hz].

    Returns
    -------
    w, Ft, Fd, U, variance
        Line frequencies [rad/s], the forcing functions' DFT and the runs' mean DFT of u there,
        and the variance of that mean's remnant at each line. The variance pools every run's
        non-line bins within ``NEIGHBOURS_REL`` of the line (at least ``NEIGHBOURS`` each
        side) and the runs' spread at the line itself; it is scaled by nu / (nu - 2) for its
        nu degrees of freedom, so that its inverse (the weight) is unbiased: with the few bins
        of one run, noisy weights made the fit chase the lines they over-weighted and the
        Cramer-Rao bound computed with them too narrow (omega_nm and t_lead 2x).

    """
    runs_u = np.atleast_2d(u)
    n = runs_u.shape[-1]
    spectra = [np.fft.rfft(x) for x in (ft, fd)]
    su = np.fft.rfft(runs_u, axis=-1)
    power = np.abs(spectra[0]) ** 2 + np.abs(spectra[1]) ** 2
    top = np.sort(power)[::-1][:MAX_LINES]
    if power.sum() <= 0 or top.sum() < (1 - 1e-6) * power.sum():
        raise SignalError(
            f"the forcing functions are not periodic in the window ({n} samples at {rate_hz:g} "
            f"Hz = {n / rate_hz:.3f} s): their power leaks off their lines into every bin. The "
            f"thesis' repeat every 81.92 s: give a window of whole periods at a rate that makes "
            f"it a whole number of samples (e.g. 100 Hz), and check the time column's units "
            f"and rate against the forcing functions'"
        )
    lines = np.flatnonzero(power > 1e-12 * power.max())
    lines = lines[lines > 0]
    if lines.size < 4:
        raise SignalError("the forcing functions excite fewer than 4 lines in the window")
    is_line = np.zeros(power.size, dtype=bool)
    is_line[lines] = True
    runs = runs_u.shape[0]
    mean_u = su[:, lines].mean(axis=0)
    var = np.full(lines.size, np.nan)
    dof = np.zeros(lines.size)
    for i, k in enumerate(lines):
        half = max(NEIGHBOURS, round(NEIGHBOURS_REL * k))
        nb = np.arange(k - half, k + half + 1)
        nb = nb[(nb > 0) & (nb < power.size)]
        nb = nb[~is_line[nb]]
        spread = np.sum(np.abs(su[:, k] - mean_u[i]) ** 2)  # runs - 1 complex dof
        cells = runs * nb.size + runs - 1
        if cells:
            var[i] = (float(np.sum(np.abs(su[:, nb]) ** 2)) + spread) / cells / runs
            dof[i] = 2.0 * cells
    if not np.isfinite(var).any():
        raise SignalError("no bins between the forcing functions' lines to estimate the remnant")
    scale = float(np.mean(np.abs(mean_u) ** 2))
    var = np.where(np.isfinite(var), var, np.nanmedian(var))
    var = var * np.where(dof > 2, dof / np.maximum(dof - 2, 1), 1.0)
    var = np.maximum(var, 1e-12 * scale)  # a noise-free run: equal weights, not infinite ones
    w = 2 * np.pi * lines * rate_hz / n
    return w, spectra[0][lines], spectra[1][lines], mean_u, var


@dataclass(frozen=True, eq=False)
class _LineProblem:
    """The fit's data at the forcing functions' lines and its weighted residual (the MLE's)."""

    ft: FloatArray
    fd: FloatArray
    u: FloatArray  # without its mean, one run or (runs, samples)
    config: MotionSystem
    lines: tuple  # w, Ft, Fd, mean U and the remnant's sd of each part at every line
    hold_s: float
    base: PitchPilot

    @classmethod
    def of(
        cls, ft, fd, u, config: MotionSystem, rate_hz: float, hold: bool, base: PitchPilot
    ) -> _LineProblem:
        """Check a window and take its lines (:func:`line_data`)."""
        ft, fd, u = (np.asarray(a, dtype=float) for a in (ft, fd, u))
        shapes_ok = ft.shape == fd.shape == u.shape[-1:] and ft.ndim == 1 and u.ndim <= 2
        if not shapes_ok or ft.size < 256:
            raise SignalError(
                "f_t and f_d must be 1-D windows (>= 256 samples) and u one window of the same "
                f"length or (runs, samples); got f_t {ft.shape}, f_d {fd.shape}, u {u.shape}"
            )
        if not (np.all(np.isfinite(ft)) and np.all(np.isfinite(fd)) and np.all(np.isfinite(u))):
            raise SignalError("f_t, f_d and u must be finite")
        if not np.ptp(u, axis=-1).all():
            raise SignalError("u is constant in a run: it carries no response to identify")
        u = u - u.mean(axis=-1, keepdims=True)
        w, Ft, Fd, U, var = line_data(ft, fd, u, rate_hz)
        sd = np.sqrt(var / 2)  # real and imaginary parts each carry half the variance
        return cls(ft, fd, u, config, (w, Ft, Fd, U, sd), 1.0 / rate_hz if hold else 0.0, base)

    def make(self, v: FloatArray) -> PitchPilot:
        """Return the pilot with the parameter vector ``v`` (in the order of ``PARAMETERS``)."""
        return dataclasses.replace(self.base, **dict(zip(PARAMETERS, map(float, v), strict=True)))

    def residual(self, v: FloatArray) -> FloatArray:
        """Line residuals in units of the remnant's sd, real parts then imaginary parts."""
        w, Ft, Fd, U, sd = self.lines
        r = (U - _closed_loop_u(self.make(v), w, Ft, Fd, self.config, self.hold_s)) / sd
        return np.concatenate([r.real, r.imag])

    def jacobian(self, v: FloatArray) -> FloatArray:
        """Return the residual's Jacobian at ``v`` by central differences."""
        step = 1e-6 * np.maximum(np.abs(v), 1e-2)
        return np.stack(
            [(self.residual(v + e) - self.residual(v - e)) / (2 * h)
             for h, e in zip(step, np.diag(step), strict=True)], axis=1,
        )  # fmt: skip


def _bounds(jac: FloatArray) -> FloatArray:
    """Cramer-Rao bound of each parameter's sd from the residual's Jacobian (Eq 2.26).

    Where the information is singular (k_m = 0 leaves tau_m unseen; t_lead = t_lag = 0 makes
    the pair's columns proportional; at t_lag = 0 a lag acts as a delay, so t_lag's column and
    tau_v's are equal) the parameters in its null space get an infinite bound
    and the others theirs from the pseudo-inverse, not a bound of zero or all infinite.
    Singular is decided on the information scaled to unit diagonal (so not by the parameters'
    units, nor by whether ``inv`` happens to fail: one BLAS build returned a finite bound of
    5e4 s at t_lag = 0 where another raised), and a parameter is in the null space where its
    share of a null vector exceeds :data:`NULL_SHARE` (the finite differences leave shares of
    1e-6 to 1e-5 on the parameters outside it).
    """
    info = jac.T @ jac
    scale = np.sqrt(np.diag(info))
    scale = np.where(scale > 0, scale, 1.0)  # a column of zeros: its parameter moves nothing
    eig, vec = np.linalg.eigh(info / np.outer(scale, scale))
    null = eig <= max(eig.max(), 0.0) * SINGULAR_REL
    if not null.any():  # well-conditioned: inv() as before, the same bits
        var = np.diag(np.linalg.inv(info))
        if np.all(var > 0) and np.all(np.isfinite(var)):
            return np.sqrt(var)
    unseen = (np.abs(vec[:, null]) > NULL_SHARE).any(axis=1)
    var = (vec[:, ~null] ** 2 / eig[~null]).sum(axis=1) / scale**2
    return np.where(unseen, np.inf, np.sqrt(var))


def bound_at(
    pilot: PitchPilot,
    ft: FloatArray,
    fd: FloatArray,
    u: FloatArray,
    config: MotionSystem,
    rate_hz: float = 100.0,
    hold: bool = True,
) -> dict[str, float]:
    """Return each parameter's Cramer-Rao bound at a given pilot, for the remnant in ``u``.

    The bound proper is the inverse Fisher information at the *true* parameters; a fit can only
    report it at its own estimate (:attr:`PilotFit.crlb_at_estimate`). The two differ where the
    bound depends steeply on the parameters: the lead-lag pair's bounds shrink with t_lag (over
    50 fits of five repetitions at the thesis' remnant level, t_lead's ran from 0.009 s where
    t_lag came out 0.04 s to 0.04 s where it came out 0.17 s), so an estimate whose t_lag came
    out low reports a bound too narrow for the spread it was drawn from. Asked at the truth this
    tells whether the estimator attains the bound (a simulation study's question); asked at a
    hypothesised pilot it tells how precisely a run like ``u`` would pin that pilot down.

    Parameters
    ----------
    pilot : PitchPilot
        Where to evaluate the bound.
    ft, fd : ndarray, shape (n,)
        Target and disturbance over a window of whole periods [rad].
    u : ndarray, shape (n,) or (runs, n)
        Control signal of one run or of repetitions; the remnant's variance at each line is
        taken from it (as :func:`fit_pitch_pilot` does).
    config : MotionSystem
        The motion system in the loop.
    rate_hz : float
        Sample rate [Hz].
    hold : bool
        The loop holds u over each sample (as :func:`fit_pitch_pilot`).

    Returns
    -------
    dict of str to float
        Each parameter's bound (one sd); infinite for a parameter the data do not see there
        (tau_m where k_m = 0; the lead-lag pair where t_lead = t_lag = 0).

    Raises
    ------
    SignalError
        A pilot parameter that is not finite, or a window the fit would refuse (see
        :func:`fit_pitch_pilot`).

    """
    problem = _LineProblem.of(ft, fd, u, config, rate_hz, hold, pilot)
    x = np.array([getattr(pilot, n) for n in PARAMETERS], dtype=float)
    if not np.all(np.isfinite(x)):
        raise SignalError(f"the pilot's parameters must be finite; got {pilot}")
    return dict(zip(PARAMETERS, map(float, _bounds(problem.jacobian(x))), strict=True))


def fit_pitch_pilot(
    ft: FloatArray,
    fd: FloatArray,
    u: FloatArray,
    config: MotionSystem,
    rate_hz: float = 100.0,
    start: PitchPilot | None = None,
    hold: bool = True,
    progress: ProgressFn | None = None,
    intervals: bool = False,
) -> PilotFit:
    """Fit Eq 6.5-6.7 to one measurement window of u (or repetitions of it), given f_t, f_d.

    The closed-loop model's output is deterministic at the forcing functions' lines only; off
    them u is remnant. So the likelihood is that of the line residuals U - U_hat, each with the
    remnant's variance there, estimated from the neighbouring non-line bins (as the FC method
    and AGARD-AR-144 do; :func:`line_data`): a weighted least-squares fit whose inverse Fisher
    information is the Cramer-Rao bound for a coloured remnant (a time-domain fit with one
    white-noise variance for every sample is not). The cost has local minima in the delays and
    the lead-lag pair, so a grid of starts (delays, lead-lag, motion gain on or off) is tried
    and the best kept. Another minimum competes with it when the data do not tell them apart:
    chi-square within ``COMPETING_CHI2`` of the best, or Vuong's test for non-nested models
    does not prefer the best (:mod:`twin.pilot.identification.minima`; the lead-lag pair at the
    thesis' remnant level has a second minimum near t_lead 0.4-0.6 s that one run rarely rules out).
    The truth may sit in any competing minimum, with that minimum's bound as its spread, so
    each parameter's reported bound is widened until two of it cover every competing minimum's
    own two bounds (from one run this lifts omega_nm's coverage from 80 % to over 90 %). A
    parameter is reported not identifiable when that bound exceeds ``IDENTIFIABLE_REL_SD`` of
    its value: one minimum's curvature is then no description of its uncertainty.
    A minimum the data do rule out still tells on the estimate: the data rule it out when
    their noise pulled the estimate away from it, so the estimates that pass are drawn from
    one side. Each parameter's bound is widened to the interval that holds after that
    selection (:mod:`twin.pilot.identification.selection`, Lee et al. 2016): unchanged far from
    where the rival would compete again, wide near it. From five repetitions at the thesis' remnant
    level, where the lead-lag pair's other basin is ruled out in about one fit in eight,
    this takes t_lead's coverage over the fits that counted it identifiable from 82 % (of
    102 of 600) to 96 % (the same fits; 94 % of the 69 still counted) and t_lag off the
    identified parameters in nearly all of them.
    A best minimum with a parameter on an end of its range (t_lag at zero, where a small lag
    acts as a delay) is described by its curvature neither for that parameter nor for those
    that move with it: the parameter is reported on its bound and not identifiable, the
    others' bound is taken with it held there, and the point where its profile into the range
    has risen by ``COMPETING_CHI2`` (the data do not rule it out) widens their bounds as a
    competing minimum does (:attr:`PilotFit.on_range_bound`,
    :func:`twin.pilot.identification.profile.inward_point`; about 0.5 s per such parameter). So does
    the fit with a parameter the data hardly see moved onto the nearer end of its range, where that
    costs less than ``COMPETING_CHI2`` (:attr:`PilotFit.range_end`).
    With ``intervals``, a parameter whose likelihood-ratio interval reaches on either side more
    than ``QUADRATIC_SIDE_RATIO`` times two bounds from the estimate is reported too: the
    profile found what the starts did not, and the interval, not the bound, is its uncertainty.

    Parameters
    ----------
    ft, fd : ndarray, shape (n,)
        Target and disturbance over a window of whole periods [rad].
    u : ndarray, shape (n,) or (runs, n)
        Control signal of one run, or of repetitions of the condition with the same forcing
        functions (averaged at the lines, as the thesis averaged its five repetitions).
    config : MotionSystem
        The motion system the pilot flew with (its Eq 5.11 is part of the loop).
    rate_hz : float
        Sample rate [Hz].
    start : PitchPilot, optional
        Initial guess (added to the grid of starts); the defaults otherwise.
    hold : bool
        The loop holds u over each sample (a digital simulator's zero-order hold, a half-sample
        delay; the twin's pitch task does); False for a continuous loop.
    progress : callable, optional
        Called after each start of the grid and each parameter's interval
        (:mod:`twin.core.progress`).
    intervals : bool
        Also compute each parameter's likelihood-ratio interval from the profile likelihood
        (:attr:`PilotFit.intervals`; typically 5-35 s more).

    """
    p0 = start or PitchPilot()
    problem = _LineProblem.of(ft, fd, u, config, rate_hz, hold, p0)
    residual, make = problem.residual, problem.make
    starts = _starts(p0)
    sols = []
    for x0 in starts:
        sols.append(least_squares(residual, x0, bounds=(LOWER, UPPER),
                                  x_scale=np.maximum(x0, 0.05)))  # fmt: skip
        if progress:
            progress("MLE starts", len(sols), len(starts))
    sols.sort(key=lambda sol: sol.cost)
    best = sols[0]
    minima = distinct([sol.x for sol in sols])
    rivals = competing(residual, minima, COMPETING_CHI2)
    on_bound = _on_bound(residual, best.x)
    crlb = _held_bounds(best.jac, on_bound)
    best_r = residual(best.x)
    # a ruled-out rival refits within the range: its parameters on an end stay there
    ruled = [(residual(x), np.delete(problem.jacobian(x), _on_bound(residual, x), axis=1))
             for x in _ruled_out(residual, best.x, minima, [r.x for r in rivals])]  # fmt: skip
    selected = selected_bounds(best.jac, crlb, best.x, best_r, ruled, COMPETING_CHI2)
    inward = {
        PARAMETERS[k]: inward_point(residual, best.x, k, LOWER, UPPER,
                                    0.01 * (UPPER[k] - LOWER[k]), COMPETING_CHI2)
        for k in on_bound
    }  # fmt: skip
    chi2 = 2.0 * float(best.cost)
    ends = _ends_not_ruled_out(residual, best.x, chi2, crlb, on_bound)
    evidence = {
        "competing_minima": [{"delta_chi2": r.delta_chi2, "vuong_z": r.vuong_z} for r in rivals],
        "ruled_out_minima": [
            {"delta_chi2": float(r @ r - best_r @ best_r), "vuong_z": vuong_z(best_r, r)}
            for r, _ in ruled
        ],
        "range_end": {name: rise for name, (_, rise) in ends.items()},
        "fit": goodness_of_fit(chi2, best_r.size - _free(best.x, on_bound)),
    }
    points = [*(r.x for r in rivals), *inward.values(), *(x for x, _ in ends.values())]
    # a point's own parameters on an end are held there, and spread nothing about it
    spread = [np.where(np.isin(np.arange(x.size), h), 0.0, _held_bounds(problem.jacobian(x), h))
              for x, h in ((x, _on_bound(residual, x)) for x in points)]  # fmt: skip
    reported = widened(best.x, selected, points, spread)
    for k in VALLEY:  # where the pair counts as identifiable, its bound along the valley
        if k not in on_bound and reported[k] < IDENTIFIABLE_REL_SD * abs(best.x[k]):
            sd = profile_wald_sd(residual, lambda v, k=k: _bounds(problem.jacobian(v))[k],
                                 best.x, k, LOWER, UPPER)  # fmt: skip
            reported[k] = max(reported[k], sd)
    fitted = make(best.x)
    mean_u = problem.u if problem.u.ndim == 1 else problem.u.mean(axis=0)
    u_hat = model_output(fitted, problem.ft, problem.fd, config, rate_hz, hold)
    bounds = dict(zip(PARAMETERS, map(float, reported), strict=True))
    at_estimate = dict(zip(PARAMETERS, map(float, crlb), strict=True))
    weak = tuple(
        name for i, name in enumerate(PARAMETERS)
        if i in on_bound
        or not bounds[name] < IDENTIFIABLE_REL_SD * max(abs(float(best.x[i])), 1e-9)
    )  # fmt: skip
    ranges = None
    if intervals:
        near = [x for x in minima if residual(x) @ residual(x) - 2 * best.cost < PROFILE_CHI2]
        ranges = {}
        for k, name in enumerate(PARAMETERS):
            # two bounds, or half the estimate where the bound is no guide (the pair at t_lead
            # = t_lag: the bound is infinite there and the profile still curves)
            scale = max(0.5 * abs(best.x[k]), 0.01 * (UPPER[k] - LOWER[k]))
            step = min(2 * crlb[k], scale) if crlb[k] > 0 else scale
            ranges[name] = likelihood_interval(residual, near, k, LOWER, UPPER, step)
            if progress:
                progress("likelihood intervals", k + 1, len(PARAMETERS))
        reach = QUADRATIC_SIDE_RATIO * 2 * reported
        wide = {name for k, (name, (lo, hi)) in enumerate(ranges.items())
                if not max(hi - best.x[k], best.x[k] - lo) <= reach[k]}  # fmt: skip
        weak = tuple(name for name in PARAMETERS if name in weak or name in wide)
    return PilotFit(fitted, bounds, vaf(mean_u, u_hat), float(np.std(mean_u - u_hat)), weak,
                    ranges, tuple(make(r.x) for r in rivals), at_estimate,
                    {name: make(x) for name, x in inward.items()},
                    {name: make(x) for name, (x, _) in ends.items()}, evidence)  # fmt: skip


def _free(x: FloatArray, on_bound: Sequence[int]) -> int:
    """Return how many parameters moved freely: not on a bound, nor tau_m behind K_m = 0."""
    held = set(on_bound)
    if PARAMETERS.index("k_m") in held and x[PARAMETERS.index("k_m")] == 0:
        held.add(PARAMETERS.index("tau_m"))  # a delay on nothing
    return len(PARAMETERS) - len(held)


def goodness_of_fit(chi2: float, dof: int) -> dict[str, float]:
    """Return the best fit's chi-square against the remnant: ``{"chi2", "dof", "ratio", "p"}``.

    ``ratio`` is chi-square per degree of freedom (line residuals, two per line, less the free
    parameters); ``p`` the chance of one at least this large were the model the pilot and
    the remnant all that is left at the lines (chi-square with ``dof`` degrees of freedom;
    approximate, as the remnant's variance at each line is estimated from its neighbours:
    on the twin's own pilot the ratio's spread matches the chi-square's, see the docs).
    """
    from scipy.stats import chi2 as chi2_dist

    dof = max(int(dof), 1)
    return {"chi2": chi2, "dof": float(dof), "ratio": chi2 / dof,
            "p": float(chi2_dist.sf(chi2, dof))}  # fmt: skip


def fit_text(fit: dict[str, float]) -> str:
    """Return a line saying what :func:`goodness_of_fit`'s ``fit`` means for the estimates."""
    head = (f"goodness of fit: chi-square {fit['chi2']:.1f} for {fit['dof']:.0f} degrees of "
            f"freedom, x{fit['ratio']:.2f} what the remnant leaves at the lines (p ")  # fmt: skip
    p = f"{fit['p']:.2g}" if fit["p"] >= 1e-300 else "< 1e-300"
    if fit["p"] >= MISFIT_P:
        return head + f"{p}): Eq 6.5-6.7 and the remnant account for the data"
    return head + (f"{p}): Eq 6.5-6.7 does not describe these data. The estimates are the "
                   "nearest such pilot's and may be biased; the sds are too narrow, by about "
                   f"x{np.sqrt(fit['ratio']):.1f} (the square root of the ratio) or more. "
                   "Look for what the model leaves out (a target feedforward, a passive "
                   "path from the motion to the stick, a nonlinearity)")  # fmt: skip


def _ruled_out(
    residual: Callable[[FloatArray], FloatArray],
    best: FloatArray,
    minima: list[FloatArray],
    rivals: list[FloatArray],
) -> list[FloatArray]:
    """Return the minima the data ruled out, each once.

    That is every minimum after the best that does not compete and predicts unlike the best,
    the rivals and those already returned (residuals ``SAME_PREDICTION`` apart).
    """
    r0 = residual(best)
    kept = [residual(x) for x in rivals]
    out = []
    for x in minima[1:]:
        r = residual(x)
        near = [q for q in (r0, *kept) if np.linalg.norm(r - q) < SAME_PREDICTION]
        if not near:
            out.append(x)
            kept.append(r)
    return out


def _held_bounds(jac: FloatArray, held: list[int]) -> FloatArray:
    """Return :func:`_bounds` with the parameters ``held`` fixed (theirs infinite)."""
    out = np.full(jac.shape[1], np.inf)
    free = [k for k in range(jac.shape[1]) if k not in held]
    out[free] = _bounds(jac[:, free])
    return out


def _ends_not_ruled_out(
    residual: Callable[[FloatArray], FloatArray],
    x: FloatArray,
    chi2: float,
    bound: FloatArray,
    on_bound: list[int],
) -> dict[str, tuple[FloatArray, float]]:
    """Return the range ends that the parameters the data hardly see cannot be told from.

    A parameter is checked when its bound at the estimate ``x`` (chi-square ``chi2``) exceeds
    ``IDENTIFIABLE_REL_SD`` of its distance to the nearer end of its range (its value, for a
    range from zero), is finite (a parameter the data do not see at all, tau_m with k_m = 0,
    moves nothing) and it is not on an end already. The others are refitted with it on that
    end; where that costs less than ``COMPETING_CHI2`` the fit there competes with the
    estimate (3.84 is conservative here: on a range's end the likelihood-ratio statistic is
    half chi-square(0), half chi-square(1), whose 95 % point is 2.71; Self and Liang 1987).

    Returns
    -------
    dict of str to (ndarray, float)
        Parameter name -> the fit with it on its end, and that fit's chi-square above ``chi2``.

    """
    ends = {}
    for k, name in enumerate(PARAMETERS):
        end = LOWER[k] if x[k] - LOWER[k] <= UPPER[k] - x[k] else UPPER[k]
        seen = np.isfinite(bound[k]) and k not in on_bound
        if not seen or bound[k] < IDENTIFIABLE_REL_SD * abs(float(x[k] - end)):
            continue
        there, point = profile_fit(residual, [x], k, float(end), LOWER, UPPER)
        if there - chi2 < COMPETING_CHI2:
            ends[name] = (point, there - chi2)
    return ends


def _on_bound(residual: Callable[[FloatArray], FloatArray], x: FloatArray) -> list[int]:
    """Return the indices of the parameters of ``x`` that sit on an end of their range.

    A parameter does when it lies within ``ON_BOUND_REL`` of the range from an end and moving
    it onto that end raises the chi-square by less than ``ON_BOUND_CHI2``.
    """
    r = residual(x)
    chi2 = float(r @ r)
    ends = []
    for k in range(x.size):
        for end in (LOWER[k], UPPER[k]):
            if abs(x[k] - end) <= ON_BOUND_REL * (UPPER[k] - LOWER[k]):
                on = x.copy()
                on[k] = end
                r = residual(on)
                if float(r @ r) - chi2 < ON_BOUND_CHI2:
                    ends.append(k)
                    break
    return ends


def _starts(p0: PitchPilot) -> list[FloatArray]:
    """Return the multi-start grid around ``p0``: delays x lead-lag pairs x motion gain on/off."""
    base = np.clip(np.array([getattr(p0, n) for n in PARAMETERS]), LOWER, UPPER)
    starts = [base]
    for (tv, tm), lead, km in itertools.product(START_DELAYS, START_LEADS, START_KM):
        x0 = base.copy()
        x0[3], x0[5] = tv, tm
        if lead is not None:
            x0[1], x0[2] = lead
        if km is not None:
            x0[4] = km
        starts.append(np.clip(x0, LOWER, UPPER))
    return starts
