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

from twin.pilot.forcing import ForcingFunction

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
