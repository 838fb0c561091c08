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
Fisher information at the optimum), and names the parameters it cannot pin down.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from twin.chain.config import MotionSystem
from twin.errors import SignalError
from twin.pilot.pitch import PitchPilot, aircraft, motion_response
from twin.plotting import finish, pyplot

FloatArray = NDArray[np.float64]
PARAMETERS = ("k_v", "t_lead", "t_lag", "tau_v", "k_m", "tau_m", "omega_nm", "zeta_nm")
LOWER = np.array([0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 3.0, 0.02])
UPPER = np.array([20.0, 5.0, 5.0, 0.8, 10.0, 0.8, 40.0, 2.0])


def vaf(u: FloatArray, u_hat: FloatArray) -> float:
    """Variance-Accounted-For, Eq 2.25 [%]."""
    return float(100.0 * (1.0 - np.var(u - u_hat) / np.var(u)))


def model_output(
    pilot: PitchPilot, ft: FloatArray, fd: FloatArray, config: MotionSystem, rate_hz: float
) -> FloatArray:
    """Predicted u over one window from the forcing functions, through the closed loop.

    U = (H_v F_t - (H_v + H_ptheta H_m) H_c F_d) / (1 + (H_v + H_ptheta H_m) H_c), with
    H_v = H_pe e^{-s T_display}, H_m the motion system (Eq 5.11) and H_c = K H_theta,de.
    """
    n = ft.size
    w = 2 * np.pi * np.fft.rfftfreq(n, 1.0 / rate_hz)
    w[0] = 1e-9  # the integrator of H_c: the mean is not predicted
    U = _closed_loop_u(pilot, w, np.fft.rfft(ft), np.fft.rfft(fd), config)
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
        Cramer-Rao lower bound of each parameter's standard deviation.
    vaf_percent : float
        Variance-Accounted-For of u [%].
    residual_sd : float
        Standard deviation of the output error.
    unidentifiable : tuple of str
        Parameters whose Cramer-Rao bound exceeds their value (reported, not hidden).

    """

    pilot: PitchPilot
    crlb: dict[str, float]
    vaf_percent: float
    residual_sd: float
    unidentifiable: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, object]:
        """JSON-ready."""
        p = dataclasses.asdict(self.pilot)
        return {"parameters": p, "crlb_sd": self.crlb, "vaf_percent": self.vaf_percent,
                "residual_sd": self.residual_sd,
                "not_identifiable": list(self.unidentifiable)}  # fmt: skip

    def plot(self, path: str | None = None):
        """Estimated parameters with their Cramer-Rao bounds (1 sd), relative to the estimate.

        Parameters
        ----------
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        plt = pyplot()
        names = list(self.crlb)
        values = np.array([getattr(self.pilot, n) for n in names], dtype=float)
        rel = np.array([self.crlb[n] for n in names]) / np.where(values == 0, np.nan, abs(values))
        fig, ax = plt.subplots(figsize=(7, 3.5))
        ax.bar(names, rel * 100)
        ax.set_xlabel("parameter (Eq 6.5-6.7)")
        ax.set_ylabel("CRLB sd / |estimate| [%]")
        ax.set_title(f"pilot-model fit: VAF {self.vaf_percent:.1f} %", fontsize=9)
        ax.tick_params(axis="x", labelsize=8)
        return finish(fig, path)


#: Largest Cramer-Rao sd relative to the estimate for which a parameter counts as identified:
#: beyond it the linearisation the bound rests on fails (the lead-lag pair at the thesis'
#: remnant level: estimates spread 2-3x wider than their bound).
IDENTIFIABLE_REL_SD = 1 / 3
#: Most lines the forcing functions may have (Table 6.2: 10 + 10).
MAX_LINES = 64
#: Neighbouring bins on each side of a line whose power estimates the remnant there.
NEIGHBOURS = 4
#: Starting delays (tau_v, tau_m), lead-lag pairs and motion gains of the multi-start search.
START_DELAYS = ((0.30, 0.20), (0.20, 0.15), (0.40, 0.30), (0.25, 0.10))
START_LEADS = (None, (0.1, 0.1), (0.5, 0.5))
START_KM = (None, 0.0)


def _closed_loop_u(pilot: PitchPilot, w: FloatArray, Ft, Fd, config: MotionSystem):
    hv = pilot.h_visual(w)
    hm = pilot.h_ptheta(w) * motion_response(config, w)
    hc = aircraft(w)
    return (hv * Ft - (hv + hm) * hc * Fd) / (1 + (hv + hm) * hc)


def line_data(
    ft: FloatArray, fd: FloatArray, u: FloatArray, rate_hz: float
) -> tuple[FloatArray, NDArray[np.complex128], NDArray[np.complex128], NDArray[np.complex128],
           FloatArray]:  # fmt: skip
    """Spectra at the forcing functions' lines and the remnant's variance at each.

    Returns
    -------
    w, Ft, Fd, U, variance
        Line frequencies [rad/s], the forcing functions' and u's DFT there, and E|U_remnant|^2
        at each line from the mean power of the ``NEIGHBOURS`` non-line bins on each side.

    """
    n = u.size
    spectra = [np.fft.rfft(x) for x in (ft, fd, u)]
    power = np.abs(spectra[0]) ** 2 + np.abs(spectra[1]) ** 2
    top = np.sort(power)[::-1][:MAX_LINES]
    if power.sum() <= 0 or top.sum() < (1 - 1e-6) * power.sum():
        raise SignalError(
            f"the window ({n} samples at {rate_hz:g} Hz = {n / rate_hz:.3f} s) does not hold "
            f"whole periods of the forcing functions (their lines leak into every bin); give "
            f"81.92 s at a rate that makes it a whole number of samples (e.g. 100 Hz)"
        )
    lines = np.flatnonzero(power > 1e-12 * power.max())
    lines = lines[lines > 0]
    if lines.size < 4:
        raise SignalError("the forcing functions excite fewer than 4 lines in the window")
    is_line = np.zeros(power.size, dtype=bool)
    is_line[lines] = True
    var = np.empty(lines.size)
    for i, k in enumerate(lines):
        nb = np.arange(k - NEIGHBOURS, k + NEIGHBOURS + 1)
        nb = nb[(nb > 0) & (nb < power.size)]
        nb = nb[~is_line[nb]]
        var[i] = float(np.mean(np.abs(spectra[2][nb]) ** 2)) if nb.size else np.nan
    scale = float(np.mean(np.abs(spectra[2][lines]) ** 2))
    if not np.isfinite(var).any():
        raise SignalError("no bins between the forcing functions' lines to estimate the remnant")
    var = np.where(np.isfinite(var), var, np.nanmedian(var))
    var = np.maximum(var, 1e-12 * scale)  # a noise-free run: equal weights, not infinite ones
    w = 2 * np.pi * lines * rate_hz / n
    return w, spectra[0][lines], spectra[1][lines], spectra[2][lines], var


def fit_pitch_pilot(
    ft: FloatArray,
    fd: FloatArray,
    u: FloatArray,
    config: MotionSystem,
    rate_hz: float = 100.0,
    start: PitchPilot | None = None,
) -> PilotFit:
    """Fit Eq 6.5-6.7 to one measurement window of u, given the forcing functions.

    The closed-loop model's output is deterministic at the forcing functions' lines only; off
    them u is remnant. So the likelihood is that of the line residuals U - U_hat, each with the
    remnant's variance there, estimated from the neighbouring non-line bins (as the FC method
    and AGARD-AR-144 do): a weighted least-squares fit whose inverse Fisher information is an
    honest Cramer-Rao bound for a coloured remnant (a time-domain fit with one white-noise
    variance for every sample is not). The cost has local minima in the delays and the
    lead-lag pair, so a grid of starts (delays, lead-lag, motion gain on or off) is tried and
    the best kept. Parameters whose bound exceeds ``IDENTIFIABLE_REL_SD`` of their value are
    listed as not identifiable (often t_lead and t_lag, which trade off with K_v).

    Parameters
    ----------
    ft, fd, u : ndarray, shape (n,)
        Target, disturbance and control signal over a window of whole periods [rad].
    config : MotionSystem
        The motion system the pilot flew with (its Eq 5.11 is part of the loop).
    rate_hz : float
        Sample rate [Hz].
    start : PitchPilot, optional
        Initial guess (added to the grid of starts); the defaults otherwise.

    """
    ft, fd, u = (np.asarray(a, dtype=float) for a in (ft, fd, u))
    if not (ft.shape == fd.shape == u.shape) or u.ndim != 1 or u.size < 256:
        raise SignalError("f_t, f_d and u must be 1-D windows of equal length (>= 256 samples)")
    if not (np.all(np.isfinite(ft)) and np.all(np.isfinite(fd)) and np.all(np.isfinite(u))):
        raise SignalError("f_t, f_d and u must be finite")
    p0 = start or PitchPilot()
    u = u - u.mean()
    w, Ft, Fd, U, var = line_data(ft, fd, u, rate_hz)
    sd = np.sqrt(var / 2)  # real and imaginary parts each carry half the variance

    def make(v: FloatArray) -> PitchPilot:
        return dataclasses.replace(p0, **dict(zip(PARAMETERS, map(float, v), strict=True)))

    def residual(v: FloatArray) -> FloatArray:
        r = (U - _closed_loop_u(make(v), w, Ft, Fd, config)) / sd
        return np.concatenate([r.real, r.imag])

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
    best = None
    for x0 in starts:
        sol = least_squares(residual, x0, bounds=(LOWER, UPPER), x_scale=np.maximum(x0, 0.05))
        if best is None or sol.cost < best.cost:
            best = sol
    try:
        crlb = np.sqrt(np.clip(np.diag(np.linalg.inv(best.jac.T @ best.jac)), 0, None))
    except np.linalg.LinAlgError:
        crlb = np.full(best.x.size, np.inf)
    fitted = make(best.x)
    u_hat = model_output(fitted, ft, fd, config, rate_hz)
    bounds = dict(zip(PARAMETERS, map(float, crlb), strict=True))
    weak = tuple(n for n, v in zip(PARAMETERS, best.x, strict=True)
                 if not bounds[n] < IDENTIFIABLE_REL_SD * max(abs(float(v)), 1e-9))  # fmt: skip
    return PilotFit(fitted, bounds, vaf(u, u_hat), float(np.std(u - u_hat)), weak)
