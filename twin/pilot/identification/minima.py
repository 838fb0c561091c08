"""Minima of a weighted least-squares fit that the data cannot tell apart (Vuong's test).

The pitch pilot's likelihood has several minima at the thesis' remnant level: the lead-lag
pair of Eq 6.6 near (T_L, T_I) = (0.2, 0.1) s and near (0.5, 0.9) s explain one run about
equally well (over 200 seeded one-run fits of condition 8, the truth-like minimum's
chi-square minus the other's had a median of -0.1 and a 5-95 % range of -5.1 to +2.0). The
chi-square difference between two minima of one likelihood is not a likelihood-ratio
statistic of nested hypotheses: the minima are two non-nested models (each the model
restricted to its basin), and the difference's spread grows with how differently they
predict each observation, not with a count of parameters. Vuong's (1989) test calibrates it
by that spread: with ``d_i`` the difference of the squared weighted residuals of observation
``i`` (the log-likelihood ratio of one observation, times two),

    z = sum(d_i) / (sqrt(n) * sd(d_i))

is asymptotically standard normal when the two minima are equally close to the truth; the
data prefer the better minimum only when ``z`` exceeds the two-sided 5 % point (1.96). Over
the 200 one-run fits above the test preferred one basin in one run (the truth-like one); a
fixed chi-square margin of 3.84 preferred one in 28, the wrong one in 6. Vuong's theorem
assumes independent, identically distributed observations and models fitted separately;
here the observations are some 40 line residuals of unequal information and the two models
are basins of one likelihood, so 1.96 is a calibration that the seeded fits above bear out,
not an exact 5 % level.

Reference: Q. H. Vuong, "Likelihood ratio tests for model selection and non-nested
hypotheses", Econometrica 57 (1989) 307-333.

Examples
--------
Two minima that predict every observation alike cannot be told apart; one that misses a
tenth of the observations by three standard deviations can:

>>> import numpy as np
>>> noise = np.random.default_rng(0).standard_normal(400)
>>> vuong_z(noise, noise) == 0.0
True
>>> miss = noise + np.where(np.arange(400) % 10 == 0, 3.0, 0.0)
>>> bool(vuong_z(noise, miss) > VUONG_Z)
True

"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: Vuong's statistic beyond which the data prefer the better of two minima (the two-sided 5 %
#: point of the standard normal, as Vuong's directional test uses).
VUONG_Z = 1.96
#: Distance between two minima's residual vectors (noise sd, over all observations) within
#: which they count as one prediction.
SAME_PREDICTION = 0.1


def vuong_z(best: FloatArray, rival: FloatArray) -> float:
    """Vuong's statistic of the better minimum against a rival, from their weighted residuals.

    Parameters
    ----------
    best, rival : ndarray, shape (n,)
        Residuals in units of each observation's noise sd (chi-square = sum of squares) at the
        best minimum and at the rival.

    Returns
    -------
    float
        ``sum(d) / (sqrt(n) sd(d))`` with ``d = rival**2 - best**2``: positive where the best
        fits better; 0 where the two predict every observation alike.

    """
    d = np.asarray(rival, float) ** 2 - np.asarray(best, float) ** 2
    sd = float(np.std(d))
    return 0.0 if sd == 0.0 else float(np.sum(d) / (np.sqrt(d.size) * sd))


class Rival(NamedTuple):
    """A minimum that competes with the best, and why.

    ``delta_chi2`` is its chi-square above the best's, ``vuong_z`` Vuong's statistic of the
    best against it.
    """

    x: FloatArray
    delta_chi2: float
    vuong_z: float


def distinct(points: Sequence[FloatArray]) -> list[FloatArray]:
    """Return ``points`` (best first) with each minimum once (equal within 0.1 % or 1e-4)."""
    kept: list[FloatArray] = []
    for x in points:
        if not any(np.allclose(x, m, rtol=1e-3, atol=1e-4) for m in kept):
            kept.append(np.asarray(x, float))
    return kept


def competing(
    residual: Callable[[FloatArray], FloatArray], minima: Sequence[FloatArray], chi2: float
) -> list[Rival]:
    """Return the minima after the first (the best) that the data do not tell from it.

    A rival competes when its chi-square exceeds the best's by less than ``chi2`` or when
    Vuong's test does not prefer the best (:func:`vuong_z` below ``VUONG_Z``). A rival that
    predicts like one already kept (residuals within ``SAME_PREDICTION`` noise sd in all) is
    that rival again and is not repeated; one that predicts like the best but elsewhere is
    kept (the data do not see the difference).

    Parameters
    ----------
    residual : callable
        Weighted residuals of a parameter vector.
    minima : sequence of ndarray
        Distinct minima, best first.
    chi2 : float
        Chi-square margin within which a rival competes whatever Vuong's test says.

    Returns
    -------
    list of Rival
        The competing minima, best first, each with its chi-square above the best and
        Vuong's statistic.

    Raises
    ------
    ValueError
        No minima.

    """
    if not minima:
        raise ValueError("competing() needs at least one minimum (the best, first)")
    best = residual(minima[0])
    rivals: list[Rival] = []
    seen: list[FloatArray] = []
    for x in minima[1:]:
        r = residual(x)
        # a search stopped at another point of a rival's flat valley is that rival again
        if any(np.linalg.norm(r - q) < SAME_PREDICTION for q in seen):
            continue
        delta, z = float(r @ r - best @ best), vuong_z(best, r)
        if delta < chi2 or z < VUONG_Z:
            rivals.append(Rival(x, delta, z))
            seen.append(r)
    return rivals


def widened(
    best: FloatArray, bound: FloatArray, rivals: Sequence[FloatArray], bounds: Sequence[FloatArray]
) -> FloatArray:
    """Return each parameter's sd widened so that two of it cover every competing minimum.

    Where the data do not tell several minima apart, the truth may sit in any of them, and
    its spread about its own minimum is that minimum's bound. The widened sd is the smallest
    for which ``best +- 2 sd`` holds every minimum's own ``x +- 2 bound``: the largest of
    ``bound_j + |x_j - best| / 2`` over the best and the rivals (equal to ``bound`` without
    rivals).

    Parameters
    ----------
    best, bound : ndarray, shape (p,)
        The best minimum and its bound.
    rivals, bounds : sequence of ndarray, shape (p,)
        The competing minima and their bounds.

    Examples
    --------
    >>> widened(np.array([0.2]), np.array([0.02]), [np.array([0.5])], [np.array([0.1])])
    array([0.25])

    """
    hull = [np.asarray(b, float) + np.abs(np.asarray(x, float) - best) / 2
            for x, b in zip(rivals, bounds, strict=True)]  # fmt: skip
    return np.max([np.asarray(bound, float), *hull], axis=0)
