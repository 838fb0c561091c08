"""Pilot-model parameters from identified frequency responses (§2.5.2.4, Table 2.3).

The seven parameters of :data:`twin.pilot.models.model.ESTIMATED` are fitted to estimates of H_pe
and H_px (the canal dynamics are kept at their Table 2.1 values, as in the thesis) by least squares
on the complex relative error, ``|H_model / H_estimate - 1|``, of both responses together.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from twin.pilot.models.model import ESTIMATED, RollPilot

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: Bounds of the estimated parameters (same order as ESTIMATED).
LOWER = np.array([0.01, 0.0, 0.0, 0.0, 0.0, 0.01, 2.0])
UPPER = np.array([5.0, 20.0, 1.0, 20.0, 1.0, 2.0, 50.0])


def fit_pilot(
    w: FloatArray, h_pe: ComplexArray, h_px: ComplexArray, start: RollPilot | None = None
) -> RollPilot:
    """Fit the pilot model to H_pe and H_px estimated at ``w`` [rad/s].

    Parameters
    ----------
    w : ndarray, shape (m,)
        Frequencies [rad/s].
    h_pe, h_px : ndarray of complex, shape (m,)
        Estimates.
    start : RollPilot, optional
        Initial guess (and the fixed canal constants); Table 2.1 by default.

    """
    p0 = start or RollPilot()

    def residual(v: FloatArray) -> FloatArray:
        p = p0.with_vector(v)
        r = np.concatenate([p.h_pe(w) / h_pe - 1, p.h_px(w) / h_px - 1])
        return np.concatenate([r.real, r.imag])

    x0 = np.clip(p0.vector(), LOWER, UPPER)
    sol = least_squares(residual, x0, bounds=(LOWER, UPPER), x_scale=np.maximum(x0, 0.05))
    return p0.with_vector(sol.x)


def parameter_errors(estimates: list[RollPilot], truth: RollPilot) -> dict[str, float]:
    """Mean absolute error of each estimated parameter over many runs (Table 2.3)."""
    true = truth.vector()
    err = np.abs(np.array([e.vector() for e in estimates]) - true)
    return {name: float(v) for name, v in zip(ESTIMATED, err.mean(axis=0), strict=True)}
