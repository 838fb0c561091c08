"""Likelihood-ratio intervals of a weighted least-squares fit, from the profile likelihood.

The Cramer-Rao bound is the curvature of the likelihood at its best minimum: honest where the
likelihood is a parabola over the parameters' plausible range. The pitch pilot's is not at
the thesis' remnant level: the lead-lag pair of Eq 6.6 has two or three minima that explain
a run about equally well ((T_L, T_I) near (0.2, 0.1) s, near (0.5, 0.9) s, and T_L = T_I, a
single lead), and omega_nm and tau_m move with the pair, so their bounds are too narrow
(omega_nm: 85 % of 50 seeded estimates within two bounds of the truth).

The profile likelihood follows the valley instead (Venzon & Moolgavkar 1988; Raue et al.
2009): for a value ``theta`` of one parameter the others are fitted again, from each minimum
it is given (the pilot fit gives those within chi-square 10 of the best), and
``chi2(theta)`` is the best of those fits. The interval holds the values whose chi-square
exceeds the best fit's by less than ``rise`` (4: two standard deviations where the
likelihood is a parabola, where the interval equals the estimate plus or minus two
Cramer-Rao bounds); where several minima lie within ``rise`` of the best, the interval is the
hull of their regions (it may then hold values between them that fit worse). An interval
that reaches a bound of the parameter's range without the rise is open on that side: the
data do not bound the parameter there (Raue et al.'s practical non-identifiability).

References: D. J. Venzon and S. H. Moolgavkar, "A method for computing profile-likelihood-
based confidence intervals", Applied Statistics 37 (1988) 87-94. A. Raue et al., "Structural
and practical identifiability analysis of partially observed dynamical models by exploiting
the profile likelihood", Bioinformatics 25 (2009) 1923-1929.

Examples
--------
A straight line: the profile is a parabola and the interval is the estimate plus or minus two
standard errors.

>>> import numpy as np
>>> t = np.linspace(0.0, 1.0, 11)
>>> y = 1.0 + 2.0 * t + np.array([.1, -.1, .05, 0, -.05, .1, -.1, 0, .05, -.05, 0])
>>> residual = lambda v: (v[0] + v[1] * t - y) / 0.1
>>> best = least_squares(residual, [0.0, 0.0]).x
>>> lo, hi = likelihood_interval(residual, [best], 1, [-10, -10], [10, 10], 0.1)
>>> round(hi - lo, 3)   # 4 standard errors of the slope: 4 * 0.1 / sqrt(sum((t - 0.5)^2))
0.381

"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

FloatArray = NDArray[np.float64]
Residual = Callable[[FloatArray], FloatArray]

#: Chi-square rise that bounds the interval: two standard deviations of a parabola.
RISE = 4.0
#: Most refinement steps once the crossing is bracketed, and the bracket width (relative to
#: its distance from the minimum) at which they stop.
MAX_REFINE, REFINE_TOL = 12, 1e-3


def _chi2(residual: Residual, x: FloatArray) -> float:
    r = residual(x)
    return float(r @ r)


def profile_fit(
    residual: Residual,
    minima: Sequence[FloatArray],
    k: int,
    theta: float,
    lower: ArrayLike,
    upper: ArrayLike,
) -> tuple[float, FloatArray]:
    """Best fit with parameter ``k`` held at ``theta``: its chi-square and its parameters.

    Parameters
    ----------
    residual : callable
        Weighted residuals of a parameter vector (chi-square = their sum of squares).
    minima : sequence of ndarray
        Starting points: the other parameters are fitted again from each (with parameter
        ``k`` replaced by ``theta``).
    k : int
        The parameter held.
    theta : float
        Its value.
    lower, upper : array_like
        The parameters' ranges.

    Returns
    -------
    chi2 : float
        The lowest chi-square of those fits (infinite if none converged to a finite one).
    point : ndarray
        Its parameter vector, with ``theta`` at ``k``.

    Raises
    ------
    ValueError
        If ``minima`` is empty.

    """
    if not len(minima):
        raise ValueError("profile_fit needs at least one starting point in minima; got none")
    lo, up = np.delete(np.asarray(lower, float), k), np.delete(np.asarray(upper, float), k)

    def held(v: FloatArray) -> FloatArray:
        return residual(np.insert(v, k, theta))

    best, point = np.inf, np.insert(np.delete(np.asarray(minima[0], float), k), k, theta)
    for x in minima:
        x0 = np.clip(np.delete(np.asarray(x, float), k), lo, up)
        sol = least_squares(held, x0, bounds=(lo, up), x_scale=np.maximum(np.abs(x0), 0.05))
        if 2.0 * float(sol.cost) < best:
            best, point = 2.0 * float(sol.cost), np.insert(sol.x, k, theta)
    return best, point


def inward_point(
    residual: Residual,
    x: FloatArray,
    k: int,
    lower: ArrayLike,
    upper: ArrayLike,
    step: float,
    rise: float,
) -> FloatArray:
    """Where the profile of a parameter on an end of its range has risen by ``rise`` inside it.

    At a minimum with parameter ``k`` on an end of its range the curvature says nothing of how
    far into the range the data allow the parameter: a gain pushed onto zero is no stationary
    point, and a lag at zero acts to first order as a delay, so the chi-square rises only at
    second order. The other parameters move with it along the valley it opens. The profile
    is followed from ``x`` into the range (doubling ``step``, then regula falsi) to the value
    where the chi-square has risen by ``rise``.

    Parameters
    ----------
    residual : callable
        Weighted residuals of a parameter vector.
    x : ndarray
        The minimum. ``x[k]`` is taken to be on the nearer end of its range, and the profile
        is followed towards the other end.
    k : int
        The parameter on its bound.
    lower, upper : array_like
        The parameters' ranges.
    step : float
        First step into the range.
    rise : float
        Chi-square rise at the returned point.

    Returns
    -------
    ndarray
        The profile's fit where the rise is reached, with ``x[k]`` moved there; the fit at
        the range's other end if it never is (the data do not bound the parameter).

    """
    x = np.asarray(x, float)
    lo_k, up_k = float(np.asarray(lower, float)[k]), float(np.asarray(upper, float)[k])
    sign, edge = (1.0, up_k) if x[k] - lo_k <= up_k - x[k] else (-1.0, lo_k)
    chi_min = _chi2(residual, x)

    def rise_at(theta: float) -> float:
        return profile_fit(residual, [x], k, theta, lower, upper)[0] - chi_min

    theta = _crossing(rise_at, float(x[k]), 0.0, sign, edge, step, rise)
    return profile_fit(residual, [x], k, theta, lower, upper)[1]


def likelihood_interval(
    residual: Residual,
    minima: Sequence[FloatArray],
    k: int,
    lower: ArrayLike,
    upper: ArrayLike,
    step: float,
    rise: float = RISE,
) -> tuple[float, float]:
    """Interval of parameter ``k`` where the profile chi-square is below the best + ``rise``.

    Every minimum within ``rise`` of the best is a point of the interval, which is the hull of
    the regions around them (the regions of two separate minima may be apart: the interval
    then holds the values between them too, as an interval must).

    Parameters
    ----------
    residual : callable
        Weighted residuals of a parameter vector (chi-square = their sum of squares).
    minima : sequence of ndarray
        The minima the search found, best first (the profile is fitted from each).
    k : int
        The parameter.
    lower, upper : array_like
        The parameters' ranges.
    step : float
        First step from each minimum on each side (e.g. two Cramer-Rao bounds); doubled until
        the chi-square has risen by ``rise``, then refined by regula falsi on its square root.
    rise : float
        Chi-square rise that bounds the interval.

    Returns
    -------
    (float, float)
        The interval's ends; an end at ``lower[k]`` or ``upper[k]`` is open (not bounded by
        the data within the range).

    """
    chis = [_chi2(residual, np.asarray(x, float)) for x in minima]
    chi_min = min(chis)
    lo_k, up_k = float(np.asarray(lower, float)[k]), float(np.asarray(upper, float)[k])

    def rise_at(theta: float) -> float:
        return profile_fit(residual, minima, k, theta, lower, upper)[0] - chi_min

    ends: list[float] = []
    for x, chi in zip(minima, chis, strict=True):
        if chi - chi_min >= rise:
            continue
        for sign, edge in ((-1.0, lo_k), (1.0, up_k)):
            ends.append(_crossing(rise_at, float(x[k]), chi - chi_min, sign, edge, step, rise))
    return float(min(ends)), float(max(ends))


def _crossing(
    rise_at: Callable[[float], float],
    start: float,
    f_start: float,
    sign: float,
    edge: float,
    step: float,
    rise: float,
) -> float:
    """Where the profile's rise reaches ``rise`` going from ``start`` towards ``edge``."""
    a, fa = start, f_start
    size = max(float(step), 1e-9)
    b = float(np.clip(a + sign * size, min(edge, start), max(edge, start)))
    fb = rise_at(b)
    while fb < rise and b != edge:  # doubling reaches the edge in at most ~log2(range / step)
        a, fa, size = b, fb, 2.0 * size
        b = float(np.clip(a + sign * size, min(edge, start), max(edge, start)))
        fb = rise_at(b)
    if fb < rise:  # open: the data do not bound the parameter on this side
        return b
    # the crossing lies in (a, b]: regula falsi on sqrt(rise) (linear where the likelihood is a
    # parabola), Illinois-modified so that a curved profile still converges from both ends
    target = np.sqrt(rise)
    ga, gb = np.sqrt(max(fa, 0.0)) - target, np.sqrt(fb) - target
    m, side = b, 0
    tol = REFINE_TOL * abs(b - start)
    for _ in range(MAX_REFINE):
        m = b - gb * (b - a) / (gb - ga)
        gm = np.sqrt(max(rise_at(m), 0.0)) - target
        if gm < 0:
            a, ga = m, gm
            if side == -1:
                gb /= 2
            side = -1
        else:
            b, gb = m, gm
            if side == 1:
                ga /= 2
            side = 1
        if abs(b - a) < tol or abs(gm) < 1e-3:
            break
    return float(m)
