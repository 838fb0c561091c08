"""Bounds that hold after a rival minimum was ruled out: inference after selection.

When the data rule out another minimum (:func:`twin.pilot.identification.minima.competing`), the fit
reports the best minimum's own Cramer-Rao bound, and a parameter whose bound is then small counts as
identifiable. But ruling the rival out selects the data: it happens when the noise pulled
the estimate away from the rival. The lead-lag pair of the pitch pilot, fitted to five
repetitions at the thesis' remnant level (condition 8, 600 seeded fits), shows it: over all
515 fits whose best minimum was the truth-like one, t_lead's bound held the truth in 95 % (the
estimates unbiased, 0.199 s for 0.2); in the 75 where the other basin (t_lead near 0.5 s) was
ruled out, and the pair so counted as identifiable, it held in 76 %, the estimates 0.182 s
on average. A Gaussian estimate kept only on the side of a threshold 1.05 sd below the truth
(those 15 %) is 1.6 sd low on average and within two sd of the truth in 84 % (the bound at
the estimate, which shrinks with t_lag, adds to the misses).

Given the selection, the estimate is a truncated Gaussian: the polyhedral lemma of Lee et
al. (2016) gives the interval that holds after it. Moving the data along the direction that
moves one parameter's estimate alone (the best fit's residual does not change; the rival's
changes by the part of that direction its own Jacobian cannot absorb), the estimate can go
from its value up to a limit where the rival would compete again (chi-square within the
margin, or Vuong's test no longer preferring the best). With ``a, b`` those limits on either
side, the truth ``mu`` lies in the interval whose ends make the truncated normal's CDF at the
estimate 1 - alpha/2 and alpha/2. Far from a limit that is the estimate plus or minus two
bounds; near one it reaches well past the estimate on that side (and is open, an infinite
sd, where no truth within 50 bounds puts the estimate so near the limit). The reported sd is
widened to half the interval's longer side. As in the lemma, the rest of the data (the part
that does not move this estimate) is held as observed. The linearisation in the data is that
of the bound itself (the rival refits to first order, by its own Jacobian); the limits are
found on the rival's residual so changed, with Vuong's statistic as the fit uses it.
Approximations, stated: the lemma is applied to that linearised selection; where the rival
is ruled out on several stretches of the line, the one holding the estimate is used (a finer
conditioning, still valid); the limits are searched to ``REACH`` bounds on a grid of
``REACH / GRID`` (a quarter bound), so a stretch where the rival competes that is shorter
than that can be stepped over, and then bisected.

Reference: J. D. Lee, D. L. Sun, Y. Sun and J. E. Taylor, "Exact post-selection inference,
with application to the lasso", The Annals of Statistics 44 (2016) 907-927.

Examples
--------
An estimate far below the limit keeps its bound; one just below it gets an interval that
reaches far up:

>>> round(selected_sd(0.0, 1.0, -np.inf, 10.0), 3)
1.0
>>> round(selected_sd(0.0, 1.0, -np.inf, 1.0), 1)
2.0

"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq
from scipy.special import log_ndtr, ndtr
from scipy.stats import norm

from twin.pilot.identification.minima import VUONG_Z, vuong_z

FloatArray = NDArray[np.float64]

#: Two-sided level of the reported interval, the estimate plus or minus two sd (95.45 %).
ALPHA = 2 * float(norm.sf(2.0))
#: Farthest a limit is looked for, in bounds of the parameter from the estimate: beyond it the
#: selection is too far in the tail to change the interval (at 8 bounds, by under 1e-6).
REACH = 8.0
#: Steps of the search for a limit (a grid of ``REACH`` / ``GRID`` bounds, then bisection).
GRID, BISECT = 32, 20


def selected_sd(estimate: float, sd: float, lower: float, upper: float) -> float:
    """Return the sd whose two cover the post-selection interval of a truncated Gaussian.

    Parameters
    ----------
    estimate : float
        The estimate, drawn from N(mu, sd^2) and kept only within (``lower``, ``upper``).
    sd : float
        Its standard deviation (the Cramer-Rao bound), positive and finite.
    lower, upper : float
        The selection's limits (``-inf`` / ``inf`` where it has none on that side).

    Returns
    -------
    float
        Half the longer side of the interval of the truths ``mu`` not rejected at ``ALPHA``
        (so that the estimate plus or minus two of it holds that interval: a superset where
        the interval is lopsided), and never below ``sd``; ``inf`` where the interval is open
        (no truth within 50 sd puts the estimate so near the limit, or it is on the limit).
        ``sd`` itself without limits.

    """
    if not (np.isfinite(lower) or np.isfinite(upper)):
        return sd

    def cdf_gap(mu: float, target: float) -> float:
        # the truncated CDF at the estimate, which falls as the truth mu rises, minus target
        a, z, b = (lower - mu) / sd, (estimate - mu) / sd, (upper - mu) / sd
        return float(np.exp(_log_mass(a, z) - _log_mass(a, b))) - target

    span = (estimate - 50.0 * sd, estimate + 50.0 * sd)
    ends = []
    for target in (1 - ALPHA / 2, ALPHA / 2):
        if not cdf_gap(span[0], target) >= 0 >= cdf_gap(span[1], target):
            return np.inf
        ends.append(brentq(cdf_gap, *span, args=(target,)))
    return max(abs(ends[0] - estimate) / 2.0, abs(ends[1] - estimate) / 2.0, sd)


def _log_mass(a: float, b: float) -> float:
    """Return log P(a < Z < b) for a standard normal Z, accurate far into either tail."""
    if not b > a:
        return -np.inf
    if a >= 0.0:  # both in the upper tail: the mirror image, by the lower tail's log CDF
        a, b = -b, -a
    if b <= 0.0:
        return float(log_ndtr(b) + np.log1p(-np.exp(log_ndtr(a) - log_ndtr(b))))
    return float(np.log(ndtr(b) - ndtr(a)))


def selection_limits(
    best: FloatArray,
    rival: FloatArray,
    rival_jac: FloatArray,
    direction: FloatArray,
    sd: float,
    chi2: float,
) -> tuple[float, float]:
    """How far one parameter's estimate may move before a ruled-out rival would compete.

    Parameters
    ----------
    best, rival : ndarray, shape (n,)
        Weighted residuals (data minus model) at the best minimum and at the rival.
    rival_jac : ndarray, shape (n, p)
        The residual's Jacobian at the rival.
    direction : ndarray, shape (n,)
        ``J C e_k / C_kk``, with ``J`` the Jacobian of the best's residual (data minus model)
        and ``C = (J^T J)^-1``: the data changed by ``-s`` times it move the parameter's
        estimate by ``s`` and leave the best fit's residual as it is.
    sd : float
        The parameter's bound at the best minimum.
    chi2 : float
        The margin within which a rival competes whatever Vuong's test says.

    Returns
    -------
    (float, float)
        The limits below and above the estimate, relative to it (``-inf`` / ``inf`` where the
        rival stays ruled out within ``REACH`` bounds).

    """
    q, *_ = np.linalg.lstsq(rival_jac, direction, rcond=None)
    unabsorbed = direction - rival_jac @ q
    base = float(best @ best)

    def ruled_out(s: float) -> bool:
        r = rival - s * unabsorbed
        return float(r @ r) - base >= chi2 and vuong_z(best, r) >= VUONG_Z

    limits = []
    for sign in (-1.0, 1.0):
        steps = sign * sd * REACH * np.arange(1, GRID + 1) / GRID
        out = next((s for s in steps if not ruled_out(s)), None)
        if out is None:
            limits.append(sign * np.inf)
            continue
        inside = out - sign * sd * REACH / GRID
        for _ in range(BISECT):
            mid = 0.5 * (inside + out)
            inside, out = (mid, out) if ruled_out(mid) else (inside, mid)
        limits.append(0.5 * (inside + out))
    return limits[0], limits[1]


def selected_bounds(
    jac: FloatArray,
    bound: FloatArray,
    x: FloatArray,
    best: FloatArray,
    rivals: list[tuple[FloatArray, FloatArray]],
    chi2: float,
) -> FloatArray:
    """Return each parameter's bound widened for the rivals the data ruled out.

    Parameters
    ----------
    jac : ndarray, shape (n, p)
        The residual's Jacobian at the best minimum.
    bound : ndarray, shape (p,)
        The best minimum's bounds (infinite where the data do not see a parameter; those,
        and parameters held on an end of their range, are returned as they are).
    x : ndarray, shape (p,)
        The best minimum.
    best : ndarray, shape (n,)
        Its weighted residual.
    rivals : list of (ndarray, ndarray)
        Each ruled-out rival's residual and Jacobian (the columns of its parameters on an end
        of their range left out: its refit cannot move them out of the range).
    chi2 : float
        The margin within which a rival competes whatever Vuong's test says.

    Returns
    -------
    ndarray, shape (p,)
        :func:`selected_sd` of each parameter, with the limits of all rivals (the nearest on
        each side).

    """
    out = np.asarray(bound, float).copy()
    if not rivals:
        return out
    seen = np.flatnonzero(np.isfinite(out) & (out > 0))
    cov = np.linalg.pinv(jac[:, seen].T @ jac[:, seen])
    for i, k in enumerate(seen):
        # the sd of this direction (equal to ``bound`` unless the information is singular,
        # where ``bound`` takes the unseen parameters' part too and may be wider: kept then)
        sd = float(np.sqrt(cov[i, i]))
        direction = jac[:, seen] @ cov[:, i] / cov[i, i]
        lower, upper = -np.inf, np.inf
        for rival, rival_jac in rivals:
            lo, hi = selection_limits(best, rival, rival_jac, direction, sd, chi2)
            lower, upper = max(lower, lo), min(upper, hi)
        out[k] = max(out[k], selected_sd(float(x[k]), sd, x[k] + lower, x[k] + upper))
    return out
