"""Bounds after a rival minimum was ruled out (twin.pilot.selection)."""

import numpy as np
import pytest

from twin.pilot.minima import VUONG_Z, vuong_z
from twin.pilot.selection import selected_sd, selection_limits


def test_the_widened_sd_covers_a_selected_gaussian_estimate_as_promised():
    """Estimates of mu = 0 kept only below -1.05 sd (15 % of them, as the lead-lag pair's from
    five repetitions): two plain sd cover the truth in about 84 %, the selected sd in at least
    the 95.45 % of two sd (Lee et al. 2016), and not by being infinite."""
    rng = np.random.default_rng(5)
    x = rng.standard_normal(40000)
    kept = x[x < -1.05][:2000]
    plain = np.mean(np.abs(kept) <= 2.0)
    sd = np.array([selected_sd(float(e), 1.0, -np.inf, -1.05) for e in kept])
    covered = np.mean(np.abs(kept) <= 2.0 * sd)
    assert 0.80 < plain < 0.88  # the truncated normal's own: (Phi(-1.05) - Phi(-2)) / Phi(-1.05)
    assert covered >= 0.95
    assert np.all(np.isfinite(sd[kept < -1.2])) and np.median(sd) < 5.0


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
