"""Time-domain fit of the pitch-task pilot model (Eq 6.5-6.7) to a measured control signal.

The model predicts the control signal from the forcing functions through the whole closed
loop (task, motion system, pilot), as the maximum-likelihood method of the thesis' references
does: fitting u to the measured e and theta instead is biased, because in closed loop they
carry the pilot's own remnant (the motion gain came out 34 % low that way at 15 % remnant).
The prediction is computed over the measurement window in the frequency domain (the window
holds whole periods of the forcing functions, so it is exact), and the eight parameters
minimise the sum of squared output errors: the maximum-likelihood estimate for a white
Gaussian output error. The fit reports the Variance-Accounted-For (Eq 2.25) and the
Cramer-Rao lower bound of each parameter's standard deviation (Eq 2.26: the inverse Fisher
information, sigma^2 (J^T J)^-1 at the optimum).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from twin.chain.config import MotionSystem
from twin.errors import SignalError
from twin.pilot.pitch import DISPLAY_DELAY_S, PitchPilot, aircraft, motion_response
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
    hv = pilot.h_pe(w) * np.exp(-1j * w * DISPLAY_DELAY_S)
    hm = pilot.h_ptheta(w) * motion_response(config, w)
    hc = aircraft(w)
    U = (hv * np.fft.rfft(ft) - (hv + hm) * hc * np.fft.rfft(fd)) / (1 + (hv + hm) * hc)
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

    """

    pilot: PitchPilot
    crlb: dict[str, float]
    vaf_percent: float
    residual_sd: float

    def to_dict(self) -> dict[str, object]:
        """JSON-ready."""
        p = dataclasses.asdict(self.pilot)
        return {"parameters": p, "crlb_sd": self.crlb, "vaf_percent": self.vaf_percent,
                "residual_sd": self.residual_sd}  # fmt: skip

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


def fit_pitch_pilot(
    ft: FloatArray,
    fd: FloatArray,
    u: FloatArray,
    config: MotionSystem,
    rate_hz: float = 100.0,
    start: PitchPilot | None = None,
) -> PilotFit:
    """Fit Eq 6.5-6.7 to one measurement window of u, given the forcing functions.

    Several starting delays are tried (the cost has local minima in the delays) and the best
    fit is kept.

    Parameters
    ----------
    ft, fd, u : ndarray, shape (n,)
        Target, disturbance and control signal over a window of whole periods [rad].
    config : MotionSystem
        The motion system the pilot flew with (its Eq 5.11 is part of the loop).
    rate_hz : float
        Sample rate [Hz].
    start : PitchPilot, optional
        Initial guess; the defaults otherwise.

    """
    ft, fd, u = (np.asarray(a, dtype=float) for a in (ft, fd, u))
    if not (ft.shape == fd.shape == u.shape) or u.ndim != 1 or u.size < 256:
        raise SignalError("f_t, f_d and u must be 1-D windows of equal length (>= 256 samples)")
    if not (np.all(np.isfinite(ft)) and np.all(np.isfinite(fd)) and np.all(np.isfinite(u))):
        raise SignalError("f_t, f_d and u must be finite")
    p0 = start or PitchPilot()
    u = u - u.mean()

    def make(v: FloatArray) -> PitchPilot:
        return dataclasses.replace(p0, **dict(zip(PARAMETERS, map(float, v), strict=True)))

    def residual(v: FloatArray) -> FloatArray:
        return model_output(make(v), ft, fd, config, rate_hz) - u

    base = np.clip(np.array([getattr(p0, n) for n in PARAMETERS]), LOWER, UPPER)
    best = None
    for tv, tm in ((0.30, 0.20), (0.20, 0.15), (0.40, 0.30)):
        x0 = base.copy()
        x0[3], x0[5] = tv, tm
        sol = least_squares(residual, x0, bounds=(LOWER, UPPER), x_scale=np.maximum(x0, 0.05))
        if best is None or sol.cost < best.cost:
            best = sol
    r = best.fun
    dof = max(1, r.size - best.x.size)
    sigma2 = float(r @ r / dof)
    try:
        cov = sigma2 * np.linalg.inv(best.jac.T @ best.jac)
        sd = np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:
        sd = np.full(best.x.size, np.inf)
    fitted = make(best.x)
    u_hat = model_output(fitted, ft, fd, config, rate_hz)
    return PilotFit(fitted, dict(zip(PARAMETERS, map(float, sd), strict=True)), vaf(u, u_hat),
                    float(np.sqrt(sigma2)))  # fmt: skip
