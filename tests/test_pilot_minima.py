"""Minima the data cannot tell apart: Vuong's test (:mod:`twin.pilot.identification.minima`)."""

import numpy as np
import pytest

from twin.pilot.identification.minima import VUONG_Z, competing, distinct, vuong_z, widened

LINES = 40  # real and imaginary parts at Table 6.2's 20 lines


def test_vuong_z_is_standard_normal_when_two_minima_are_equally_close():
    """Vuong (1989), Theorem 5.1: for two models equally close to the truth the statistic is
    asymptotically N(0, 1). Two predictions offset either side of the truth by the same
    amounts, 4000 noise draws of 40 observations: it exceeds 1.96 in size in 5 % of draws
    (3.5-6.5 %: 4000 draws pin 5 % to +-0.7 %, the rest is the 40 observations' distance
    from the asymptote), and its mean and sd are those of N(0, 1) within 0.05 and 0.1."""
    rng = np.random.default_rng(11)
    offset = rng.uniform(0.2, 1.5, LINES)
    z = np.array([vuong_z(e - offset, e + offset) for e in rng.standard_normal((4000, LINES))])
    assert 0.035 < np.mean(np.abs(z) > VUONG_Z) < 0.065
    assert abs(z.mean()) < 0.05 and abs(z.std() - 1.0) < 0.1


def test_vuong_z_prefers_a_minimum_that_fits_clearly_better():
    """A rival that misses by 1.5 noise sd at every observation is rejected in nearly every
    draw; one that misses by a tenth of that is rejected about as rarely as chance allows."""
    rng = np.random.default_rng(12)
    noise = rng.standard_normal((500, LINES))
    far = np.mean([vuong_z(e, e + 1.5) > VUONG_Z for e in noise])
    near = np.mean([vuong_z(e, e + 0.15) > VUONG_Z for e in noise])
    assert far > 0.99
    assert near < 0.2


def test_competing_keeps_the_minima_the_data_do_not_rule_out():
    """y = a^2 t has minima at +-a that predict alike (z = 0: they compete whatever the
    chi-square margin); a third point that fits far worse does not compete."""
    t = np.linspace(0.0, 1.0, 50)
    y = 4.0 * t + np.random.default_rng(13).normal(0.0, 0.1, t.size)

    def residual(v):
        return (v[0] ** 2 * t - y) / 0.1

    minima = distinct([np.array([2.0]), np.array([2.0 + 1e-6]), np.array([-2.0]), np.array([1.0])])
    assert len(minima) == 3  # the two equal points are one minimum
    rivals = competing(residual, minima, chi2=0.0)
    assert [float(r.x[0]) for r in rivals] == [-2.0]
    best = residual(minima[0])
    assert rivals[0].delta_chi2 == pytest.approx(0.0, abs=1e-9)  # +-2 predict alike
    assert rivals[0].vuong_z == vuong_z(best, residual(rivals[0].x))
    # within the chi-square margin a rival competes whatever Vuong's test says
    worse = residual(np.array([1.0]))
    assert vuong_z(residual(minima[0]), worse) > VUONG_Z
    margin = float(worse @ worse - residual(minima[0]) @ residual(minima[0])) + 1.0
    wide = competing(residual, minima, chi2=margin)
    assert [float(r.x[0]) for r in wide] == [-2.0, 1.0]
    assert wide[1].delta_chi2 == pytest.approx(margin - 1.0) and wide[1].vuong_z > VUONG_Z

    # a point of a rival's flat valley that predicts like it (within 0.1 noise sd) is that
    # rival again, not a second one
    def valley(v):
        return (v[0] ** 2 * t + 1e-4 * v[1] - y) / 0.1

    points = [np.array([2.0, 0.0]), np.array([-2.0, 0.0]), np.array([-2.0, 5.0])]
    assert len(distinct(points)) == 3
    assert [list(r.x) for r in competing(valley, points, chi2=0.0)] == [[-2.0, 0.0]]
    assert len(competing(valley, [points[0], points[2]], chi2=0.0)) == 1
    with pytest.raises(ValueError, match="at least one minimum"):
        competing(residual, [], chi2=3.84)


def test_widened_covers_each_minimums_own_two_bounds():
    """Two widened sd about the best hold every competing minimum's x +- 2 bound; without
    rivals, and where a rival's interval already lies inside, the bound is unchanged."""
    best, bound = np.array([0.2, 11.0]), np.array([0.02, 0.1])
    assert np.array_equal(widened(best, bound, [], []), bound)
    rival, rb = np.array([0.5, 11.05]), np.array([0.1, 0.01])
    sd = widened(best, bound, [rival], [rb])
    assert np.all(best - 2 * sd <= rival - 2 * rb) and np.all(rival + 2 * rb <= best + 2 * sd)
    assert sd[1] == bound[1]  # 11.05 +- 0.02 lies inside 11.0 +- 0.2
    assert sd[0] == pytest.approx(0.1 + 0.3 / 2)
    # a rival where the data do not see a parameter (k_m = 0 leaves tau_m unseen) makes that
    # parameter's sd infinite, and only that one
    sd = widened(best, bound, [rival], [np.array([0.1, np.inf])])
    assert sd[1] == np.inf and np.isfinite(sd[0])
