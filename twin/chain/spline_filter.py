"""Exact response of a continuous linear filter to a trajectory's cubic spline.

A :class:`~twin.trajectory.Trajectory` *is* its not-a-knot cubic spline between samples, so a
continuous filter's output at the sample times can be computed exactly: over each sample
interval the input is a cubic u(tau) = sum_k a_k tau^k, and the state obeys

    x[n+1] = Phi x[n] + sum_k Gamma_k a_k[n],   Phi = e^{A h},
    Gamma_k = int_0^h e^{A (h - tau)} B tau^k dtau.

The recursion runs at the trajectory's own rate (no oversampling, no bilinear warping), in
blocks with the state carried, so memory stays at the size of the input.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy import linalg, signal
from scipy.integrate import quad_vec

from twin.trajectory import SPLINE_BLOCK, Trajectory

FloatArray = NDArray[np.float64]


def _input_matrices(a: FloatArray, b: FloatArray, h: float) -> tuple[FloatArray, FloatArray]:
    """Phi and Gamma (shape (4, nx)) of a SISO system for cubic input over a step h."""
    phi = linalg.expm(a * h)
    gamma = np.array([
        quad_vec(lambda tau, k=k: linalg.expm(a * (h - tau)) @ b[:, 0] * tau**k, 0.0, h,
                 epsabs=0.0, epsrel=1e-13)[0]
        for k in range(4)
    ])  # fmt: skip
    return phi, gamma


def filter_spline(tr: Trajectory, num: FloatArray, den: FloatArray) -> FloatArray:
    """Output of the strictly proper filter ``num(s) / den(s)`` at ``tr``'s sample times.

    Every channel is filtered, starting in steady state at the first sample.

    Parameters
    ----------
    tr : Trajectory
        Input; its cubic spline is the continuous input signal.
    num, den : array_like
        Polynomial coefficients in s, highest power first (``len(num) < len(den)``).

    Returns
    -------
    ndarray, shape (n, k)

    Examples
    --------
    >>> import numpy as np
    >>> tr = Trajectory(100.0, np.outer(np.arange(300.0) * 0.01, np.ones(1)), names=("x",))
    >>> y = filter_spline(tr, [1.0], [0.1, 1.0])  # first-order lag of a ramp lags by 0.1 s
    >>> round(float(tr.values[-1, 0] - y[-1, 0]), 6)
    0.1

    """
    a, b, c, d = signal.tf2ss(num, den)
    if np.any(d != 0):
        raise ValueError("filter_spline needs a strictly proper filter (len(num) < len(den))")
    h = tr.dt
    phi, gamma = _input_matrices(a, b, h)
    nx = a.shape[0]
    # z-domain filters from each state forcing component to the output y[n] = C x[n]
    filters = [signal.ss2tf(phi, np.eye(nx), c, np.zeros((1, nx)), input=i) for i in range(nx)]
    u0 = tr.values[0]
    x0 = -np.linalg.solve(a, b[:, 0])  # steady-state state per unit input
    dc = float(c[0] @ x0)
    out = np.empty_like(tr.values)
    out[0] = dc * u0
    states = [np.zeros((nx, tr.values.shape[1])) for _ in filters]
    for b0 in range(0, tr.n - 1, SPLINE_BLOCK):
        b1 = min(tr.n - 1, b0 + SPLINE_BLOCK)
        spline = tr.block_spline(b0 // SPLINE_BLOCK)
        first = round((spline.x[0] - tr.t0) * tr.rate_hz)
        coef = spline.c[:, b0 - first : b1 - first]  # (4, m, k), highest power first
        coef = coef[::-1].copy()  # a_0 .. a_3
        coef[0] -= u0  # deviation from the initial steady state
        forcing = np.einsum("kx,kmc->xmc", gamma, coef)  # (nx, m, k)
        y = np.zeros(forcing.shape[1:])
        for i, (num_z, den_z) in enumerate(filters):
            # C (zI - Phi)^-1 has a leading zero (one-step delay); dropping it gives
            # y[n+1] = C x[n+1] from the forcing up to interval n
            yi, states[i] = signal.lfilter(num_z[0][1:], den_z, forcing[i], axis=0, zi=states[i])
            y += yi
        out[b0 + 1 : b1 + 1] = dc * u0 + y
    return out
