"""The Fourier-coefficient method (§2.3, Eq 2.1-2.3) for two pilot responses at once.

At the disturbance frequencies the Fourier coefficients U_1, E_1, X_1 are measured; the
coefficients at the target frequencies are linearly interpolated to them (U~_2, E~_2, X~_2),
and the two equations U = E H_pe - X H_px are solved (Eq 2.3). The interpolated coefficients
are those divided by the target's own (the closed-loop responses to the target, which vary
smoothly with frequency; the second equation is homogeneous, so the scaling is free):
interpolating the raw coefficients, whose phase turns quickly between the lines, costs 60 %
error on noise-free data. The same is done at the target
frequencies with the roles swapped, giving estimates at all 24 input frequencies.
Everything is vectorised over runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from twin.pilot.models.forcing import MEASUREMENT_S, ForcingFunction

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


def _interpolation(k_from: NDArray, k_to: NDArray) -> FloatArray:
    """Matrix W so that values at bins ``k_to`` ~ W @ values at bins ``k_from`` (linear)."""
    eye = np.eye(k_from.size)
    return np.stack([np.interp(k_to, k_from, eye[i]) for i in range(k_from.size)], axis=1)


@dataclass(frozen=True, eq=False)
class FcEstimate:
    """Pilot responses estimated by the FC method.

    Attributes
    ----------
    omega_rad_s : ndarray, shape (m,)
        The input frequencies, ascending.
    h_pe, h_px : ndarray of complex, shape (runs, m)
        Estimates per run.

    """

    omega_rad_s: FloatArray
    h_pe: ComplexArray
    h_px: ComplexArray


def _solve(ua, ea, xa, ub, eb, xb):
    """Solve [ua; ub] = [[ea, -xa]; [eb, -xb]] [h_pe; h_px] (Eq 2.3)."""
    det = eb * xa - ea * xb
    return (ub * xa - ua * xb) / det, (ea * ub - eb * ua) / det


def fc_estimate(
    e: FloatArray,
    u: FloatArray,
    x: FloatArray,
    fd: ForcingFunction,
    ft: ForcingFunction,
    fd_window: FloatArray,
    ft_window: FloatArray,
) -> FcEstimate:
    """Estimate H_pe and H_px from windows of whole periods.

    Parameters
    ----------
    e, u, x : ndarray, shape (runs, samples)
        Error, control and state over the measurement window.
    fd, ft : ForcingFunction
        The forcing functions (for their lines).
    fd_window, ft_window : ndarray, shape (samples,)
        The forcing functions over the same window.

    """
    n = e.shape[-1]
    E, U, X = (np.fft.rfft(np.atleast_2d(s), axis=-1) * (2 / n) for s in (e, u, x))
    k1, k2 = fd.bins(), ft.bins()
    to1, to2 = _interpolation(k2, k1), _interpolation(k1, k2)
    F1 = (np.fft.rfft(fd_window) * (2 / n))[k1]  # the forcing functions' own coefficients
    F2 = (np.fft.rfft(ft_window) * (2 / n))[k2]
    at1 = [c[:, k1] / F1 for c in (U, E, X)]
    at2 = [c[:, k2] / F2 for c in (U, E, X)]
    pe1, px1 = _solve(*at1, *(c @ to1.T for c in at2))
    pe2, px2 = _solve(*at2, *(c @ to2.T for c in at1))
    w = np.concatenate([fd.omega_rad_s, ft.omega_rad_s])
    order = np.argsort(w)
    return FcEstimate(w[order], np.hstack([pe1, pe2])[:, order], np.hstack([px1, px2])[:, order])


def _expectations(r1: FloatArray, epsilon: float = 0.01) -> tuple[FloatArray, FloatArray]:
    """E1 and E2 of Eq 2.8-2.9 for signal-to-noise ratios ``r1`` (van Lunteren, 1979).

    delta follows from epsilon = 2 e^{-r1} sinh(delta), the probability of underestimating the
    variance (1 %, Mulder 1999).
    """
    from scipy import special

    r = np.asarray(r1, dtype=float)
    delta = np.arcsinh(0.5 * epsilon * np.exp(np.minimum(r, 700.0)))
    e1 = np.exp(-r)
    # r1 * integral_delta^r1 e^{p - r1} / p dp = r1 e^{-r1} (Ei(r1) - Ei(delta))
    big = r > 50.0
    ei_term = np.where(
        big,
        (1 + 1 / r + 2 / r**2 + 6 / r**3),  # r e^{-r} Ei(r) for large r (asymptotic)
        r * np.exp(-np.minimum(r, 50.0)) * special.expi(np.minimum(r, 50.0)),
    )
    ei_term = ei_term - r * np.exp(-r) * special.expi(delta)
    e2 = np.exp(delta - r) + np.exp(-delta - r) - 1 + ei_term + r * np.exp(-r) * special.exp1(delta)
    return e1, e2


def _neighbour_power(
    C: ComplexArray, lines: NDArray, excited: NDArray, bins: int = 2
) -> FloatArray:
    """Mean ``|C|^2`` over the non-excited bins next to each line (noise power per bin)."""
    taken = set(int(k) for k in excited)
    out = np.empty((C.shape[0], lines.size))
    for i, k in enumerate(lines):
        ks = [k + j for j in range(-bins, bins + 1) if j and k + j > 0 and k + j not in taken]
        out[:, i] = np.mean(np.abs(C[:, ks]) ** 2, axis=1)
    return out


def fc_variance(
    e: FloatArray,
    u: FloatArray,
    x: FloatArray,
    fd: ForcingFunction,
    ft: ForcingFunction,
    fd_window: FloatArray,
    ft_window: FloatArray,
    h_c: ComplexArray,
) -> dict[str, FloatArray]:
    """Analytic bias and standard deviation of the FC estimates (Eq 2.4-2.11).

    At the disturbance lines, as the thesis gives them: the remnant power in u is taken from
    the neighbouring non-excited bins, referred to the disturbance input by Eq 2.10 to give the
    signal-to-noise ratio r_1 of f_d; the target's r_2 (its remnant referred to the target
    input, ``|1 + H_c (H_pe + H_px)|^2 / |H_pe|^2``) is interpolated to these lines (r~_2). E1
    and E2 follow from Eq 2.8-2.9 with a 1 % probability of underestimating the variance.

    Parameters
    ----------
    e, u, x, fd, ft, fd_window, ft_window
        As :func:`fc_estimate`.
    h_c : ndarray of complex, shape (m1,)
        The controlled dynamics at the disturbance lines (Eq 2.6 needs 1 / H_c).

    Returns
    -------
    dict
        ``omega_rad_s`` (disturbance lines) and, per run, ``bias_pe``, ``bias_px`` (complex),
        ``std_mag_pe``, ``std_mag_px``, ``std_phase_pe``, ``std_phase_px`` [deg].

    """
    n = e.shape[-1]
    est = fc_estimate(e, u, x, fd, ft, fd_window, ft_window)
    k1, k2 = fd.bins(), ft.bins()
    at1 = np.isin(np.round(est.omega_rad_s * MEASUREMENT_S / (2 * np.pi)).astype(int), k1)
    pe1, px1 = est.h_pe[:, at1], est.h_px[:, at1]
    at2 = ~at1
    pe2, px2 = est.h_pe[:, at2], est.h_px[:, at2]
    U = np.fft.rfft(np.atleast_2d(u), axis=-1) * (2 / n)
    excited = np.concatenate([k1, k2])
    s_u1 = _neighbour_power(U, k1, excited)
    s_u2 = _neighbour_power(U, k2, excited)
    w2 = ft.omega_rad_s
    F1 = np.abs((np.fft.rfft(fd_window) * (2 / n))[k1]) ** 2
    F2 = np.abs((np.fft.rfft(ft_window) * (2 / n))[k2]) ** 2
    loop1 = np.abs(1 + h_c * (pe1 + px1)) ** 2
    r1 = F1 / (s_u1 * loop1)
    hc_t = _hc_at(h_c, fd.omega_rad_s, w2)
    loop2 = np.abs(1 + hc_t * (pe2 + px2)) ** 2 / np.abs(pe2) ** 2
    r2 = F2 / (s_u2 * loop2)
    r2_tilde = r2 @ _interpolation(k2, k1).T
    E1, E2 = _expectations(r1)
    var_pe = np.abs(pe1) ** 2 * (E2 - E1**2) + (1 - 2 * E1 + E2) / r2_tilde
    px_ref = px1 + 1 / h_c
    var_px = np.abs(px_ref) ** 2 * (E2 - E1**2) + (1 - 2 * E1 + E2) / r2_tilde
    deg = 180 / np.pi
    return {
        "omega_rad_s": fd.omega_rad_s,
        "bias_pe": -pe1 * E1,
        "bias_px": -px_ref * E1,
        "std_mag_pe": np.sqrt(np.clip(var_pe, 0, None)),
        "std_mag_px": np.sqrt(np.clip(var_px, 0, None)),
        "std_phase_pe": deg * np.sqrt(np.clip(var_pe, 0, None)) / np.abs(pe1),
        "std_phase_px": deg * np.sqrt(np.clip(var_px, 0, None)) / np.abs(px1),
    }


def _hc_at(h_c: ComplexArray, w_from: FloatArray, w_to: FloatArray) -> ComplexArray:
    """H_c at other frequencies, for a double integrator k / s^2 known at ``w_from``."""
    k = np.real(h_c * (1j * w_from) ** 2)
    return np.mean(k) / (1j * w_to) ** 2
