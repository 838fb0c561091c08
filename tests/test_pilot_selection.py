"""Bounds after a rival minimum was ruled out (twin.pilot.identification.selection)."""

import numpy as np
import pytest

from twin.pilot.identification.minima import VUONG_Z, vuong_z
from twin.pilot.identification.selection import selected_sd, selection_limits


@pytest.mark.parametrize("lower, upper", [(-np.inf, -1.05), (0.8, np.inf), (-2.5, -0.5)])
def test_the_widened_sd_covers_a_selected_gaussian_estimate_as_promised(lower, upper):
    """Estimates of mu = 0 kept only within a selection (the first: below -1.05 sd, 15 % of
    them, as the lead-lag pair's from five repetitions). Two plain sd cover the truth in the
    truncated normal's own share; the selected sd in at least the 95.45 % of two sd (Lee et
    al. 2016), and not by being infinite."""
    from scipy.stats import norm

    rng = np.random.default_rng(5)
    x = rng.standard_normal(60000)
    kept = x[(x > lower) & (x < upper)][:1500]
    plain = np.mean(np.abs(kept) <= 2.0)
    inside = norm.cdf(min(upper, 2.0)) - norm.cdf(max(lower, -2.0))
    share = inside / (norm.cdf(upper) - norm.cdf(lower))
    assert plain == pytest.approx(share, abs=0.03)
    sd = np.array([selected_sd(float(e), 1.0, lower, upper) for e in kept])
    assert np.mean(np.abs(kept) <= 2.0 * sd) >= 0.95
    inner = (kept > lower + 0.2) & (kept < upper - 0.2)  # away from the limits: finite
    assert np.all(np.isfinite(sd[inner])) and np.median(sd) < 5.0


def test_far_from_any_limit_the_sd_is_the_bound():
    assert selected_sd(0.3, 0.1, -np.inf, np.inf) == 0.1
    assert selected_sd(0.3, 0.1, 0.3 - 1.0, 0.3 + 1.0) == pytest.approx(0.1, rel=1e-6)
    assert selected_sd(0.0, 1.0, -np.inf, 0.01) == np.inf  # on the limit: no truth rejected


def _rival(sd, n=60, seed=3):
    """A best fit's residual and the data change that moves an estimate of bound ``sd`` by one
    unit (its norm is 1 / sd: J C e_k / C_kk, C = (J^T J)^-1, C_kk = sd^2)."""
    rng = np.random.default_rng(seed)
    best = rng.standard_normal(n)
    direction = rng.standard_normal(n)
    return best, direction / np.linalg.norm(direction) / sd


def test_a_rival_that_absorbs_the_change_stays_ruled_out():
    best, direction = _rival(0.1)
    rival = best + 0.8 * np.sign(best)  # worse everywhere: ruled out
    jac = direction[:, None]  # its Jacobian absorbs the data change entirely
    assert selection_limits(best, rival, jac, direction, 0.1, 3.84) == (-np.inf, np.inf)


def test_the_limit_is_where_the_rival_would_compete_again():
    """A rival 6 noise sd away along the direction the estimate moves in (its own Jacobian
    cannot follow): moving the estimate towards it by a few bounds revives it, away never."""
    sd = 0.05
    best, direction = _rival(sd)
    e = direction / np.linalg.norm(direction)
    best = best - (best @ e) * e
    rival = best + 6.0 * e
    assert float(rival @ rival - best @ best) > 3.84 and vuong_z(best, rival) > VUONG_Z
    jac = np.random.default_rng(4).standard_normal((best.size, 2))
    jac -= np.outer(e, e @ jac)
    lo, hi = selection_limits(best, rival, jac, direction, sd, 3.84)
    assert lo == -np.inf
    # chi-square (6 - s / sd)^2 falls to 3.84 at s = 4.04 sd, unless Vuong's test gives first
    assert sd < hi <= (6.0 - np.sqrt(3.84)) * sd * 1.001
    for s, ruled_out in ((0.999 * hi, True), (1.001 * hi, False)):
        r = rival - s * direction
        assert (float(r @ r - best @ best) >= 3.84 and vuong_z(best, r) >= VUONG_Z) == ruled_out


def test_the_limit_matches_refitting_both_minima_to_changed_data():
    """A linear model of the data (the best) and the same model with parameter 0 held 5 sd
    above the truth (a rival, like the lead-lag pair's other basin), each refitted exactly by
    least squares. Change the data so that the best's estimate of parameter 0 moves by s,
    refit both, and find by brute force where the rival would compete again: the limit
    :func:`selection_limits` finds from the residuals and Jacobians at the observed data
    alone is that one, on the side towards the rival, with none on the other."""
    rng = np.random.default_rng(11)
    n = 80
    a = rng.standard_normal((n, 3))  # the best model: m = A theta
    cov = np.linalg.inv(a.T @ a)
    sd = float(np.sqrt(cov[0, 0]))
    held = (0.2 + 5 * sd) * a[:, 0]  # the rival: parameter 0 held there, the others free
    y = a @ np.array([0.2, 1.0, -0.5]) + rng.standard_normal(n)

    def refit(data):
        theta = np.linalg.lstsq(a, data, rcond=None)[0]
        phi = np.linalg.lstsq(a[:, 1:], data - held, rcond=None)[0]
        return theta, data - a @ theta, data - held - a[:, 1:] @ phi  # data minus model

    theta, best, rival = refit(y)
    direction = -a @ cov[:, 0] / cov[0, 0]  # J C e_k / C_kk with J = -A, the residual's
    assert float(rival @ rival - best @ best) >= 3.84 and vuong_z(best, rival) >= 1.96

    def competes(s):
        moved, r_best, r_rival = refit(y - s * direction)
        assert moved[0] - theta[0] == pytest.approx(s, abs=1e-9)  # moves parameter 0 by s
        assert np.allclose(r_best, best)  # and leaves the best's residual as it was
        return float(r_rival @ r_rival - r_best @ r_best) < 3.84 or vuong_z(r_best, r_rival) < 1.96

    lo, hi = selection_limits(best, rival, -a[:, 1:], direction, sd, 3.84)
    assert lo == -np.inf and 0 < hi < 5 * sd
    assert not competes(0.99 * hi) and competes(1.01 * hi)
    assert not any(competes(-s) for s in sd * np.linspace(0.1, 8.0, 80))
