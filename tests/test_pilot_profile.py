"""Likelihood-ratio intervals from the profile likelihood (pilot.identification.profile), and the
pilot fit's intervals where its Cramer-Rao bounds are too narrow."""

import numpy as np
import pytest
from scipy.optimize import least_squares

from twin.pilot.identification.profile import inward_point, likelihood_interval, profile_fit

T = np.linspace(0.0, 2.0, 21)
RNG = np.random.default_rng(5)
Y = 0.5 - 1.5 * T + 0.2 * RNG.standard_normal(T.size)


def _line(v):
    return (v[0] + v[1] * T - Y) / 0.2


def test_a_linear_fit_gives_the_estimate_plus_minus_two_standard_errors():
    """Where the likelihood is a parabola the interval is exactly the Wald interval."""
    best = least_squares(_line, [0.0, 0.0]).x
    jac = np.column_stack([np.ones_like(T), T]) / 0.2
    se = np.sqrt(np.diag(np.linalg.inv(jac.T @ jac)))
    for k in range(2):
        lo, hi = likelihood_interval(_line, [best], k, [-50, -50], [50, 50], se[k] / 3)
        assert lo == pytest.approx(best[k] - 2 * se[k], rel=1e-5)
        assert hi == pytest.approx(best[k] + 2 * se[k], rel=1e-5)


def _two_minima(v):
    """x0 is known only through x0^2 (two equally good minima, +-1); x1 is a plain mean."""
    return np.array([(v[0] ** 2 - 1.0) / 0.05, (v[1] - 3.0) / 0.1, v[0] * 0 + 0.0])


def test_an_interval_spans_every_equally_good_minimum_it_is_given():
    minima = [np.array([1.0, 3.0]), np.array([-1.0, 3.0])]
    # chi2 rises by 4 where x0^2 = 1 +- 2 * 0.05: |x0| = sqrt(0.9) and sqrt(1.1)
    lo, hi = likelihood_interval(_two_minima, minima, 0, [-5, -5], [5, 5], 0.05)
    assert lo == pytest.approx(-np.sqrt(1.1), abs=1e-4) and hi == pytest.approx(
        np.sqrt(1.1), abs=1e-4
    )
    # from the best minimum alone the interval is its own region only
    lo0, hi0 = likelihood_interval(_two_minima, minima[:1], 0, [-5, -5], [5, 5], 0.05)
    assert lo0 == pytest.approx(np.sqrt(0.9), abs=1e-4) and hi0 == pytest.approx(
        np.sqrt(1.1), abs=1e-4
    )
    chi2, point = profile_fit(_two_minima, minima, 0, -1.0, [-5, -5], [5, 5])
    assert chi2 == pytest.approx(0.0) and point == pytest.approx([-1.0, 3.0], abs=1e-4)
    # from one minimum only, the profile of x1 still finds its own interval (x0 refitted)
    lo1, hi1 = likelihood_interval(_two_minima, minima[:1], 1, [-5, -5], [5, 5], 0.1)
    assert lo1 == pytest.approx(2.8, abs=1e-3) and hi1 == pytest.approx(3.2, abs=1e-3)


def test_a_side_the_data_do_not_bound_is_open_at_the_range():
    """A parameter seen only through a saturation: above 1 any value fits as well."""

    def saturated(v):
        return np.array([(min(v[0], 1.0) - 1.0) / 0.1, (v[1] - 2.0) / 0.1])

    for step in (0.2, 0.01):  # however small the first step, the open side reaches the end
        lo, hi = likelihood_interval(saturated, [np.array([1.5, 2.0])], 0, [0, 0], [10, 10], step)
        assert hi == 10.0  # open above: the range's end
        assert lo == pytest.approx(0.8, abs=1e-3)  # 2 sd below the saturation


def test_a_minimum_on_a_bound_is_followed_into_the_range_to_the_chi_square_rise():
    """A line whose intercept must be >= 0.8 while the data want 0.5: the fit sits on the
    bound, and along the profile into the range the slope moves with the intercept. The point
    returned is where the chi-square has risen by 3.84, with the slope refitted there (for a
    line, chi2(a) = chi2_free + (a - a_free)^2 / se_a^2, and the slope the one that minimises
    the residual given a)."""
    lower, upper = [0.8, -50.0], [50.0, 50.0]
    at = least_squares(_line, [1.0, 0.0], bounds=(lower, upper)).x
    assert at[0] == pytest.approx(0.8)
    free = least_squares(_line, [0.0, 0.0]).x
    jac = np.column_stack([np.ones_like(T), T]) / 0.2
    se = np.sqrt(np.diag(np.linalg.inv(jac.T @ jac)))

    def chi2(v):
        return float(_line(v) @ _line(v))

    for step in (0.01, 1.0):  # a first step short of the rise, and one beyond it
        p = inward_point(_line, at, 0, lower, upper, step, 3.84)
        assert chi2(p) - chi2(at) == pytest.approx(3.84, abs=1e-2)
        a = free[0] + se[0] * np.sqrt(3.84 + chi2(at) - chi2(free))
        assert p[0] == pytest.approx(a, rel=1e-3)
        slope = np.sum((Y - a) * T) / np.sum(T * T)  # least squares of y - a on t
        assert p[1] == pytest.approx(slope, rel=1e-3)
    # the same line pinned from above (intercept <= 0.2): the point lies below the bound
    top = least_squares(_line, [0.0, -2.0], bounds=([-50, -50], [0.2, 50])).x
    q = inward_point(_line, top, 0, [-50, -50], [0.2, 50], 0.05, 3.84)
    assert chi2(q) - chi2(top) == pytest.approx(3.84, abs=1e-2)
    assert q[0] == pytest.approx(free[0] - se[0] * np.sqrt(3.84 + chi2(top) - chi2(free)), rel=1e-3)


def test_a_profile_that_never_rises_ends_at_the_far_end_of_the_range():
    """x0 is seen only through a saturation at 1 (on its lower end, 1, the fit is as good as
    anywhere above): the data do not bound it, so the point is the range's other end."""

    def saturated(v):
        return np.array([(min(v[0], 1.0) - 1.0) / 0.1, (v[1] - 2.0) / 0.1])

    p = inward_point(saturated, np.array([1.0, 2.0]), 0, [1, 0], [5, 10], 0.1, 3.84)
    assert p == pytest.approx([5.0, 2.0])


def test_a_profile_needs_a_start():
    with pytest.raises(ValueError, match="at least one starting point"):
        profile_fit(_line, [], 0, 1.0, [-5, -5], [5, 5])


@pytest.mark.slow
def test_the_pilot_fit_interval_covers_omega_nm_where_the_bound_misses():
    """Seeded run 4 of the coverage bench (condition 8, 15 % remnant): the fit lands on the
    single-lead minimum (t_lead = t_lag) with omega_nm 2.9 bounds above the truth; the
    likelihood-ratio interval, fitted from every minimum, holds the truth; it reaches more than
    twice two bounds below the estimate, so omega_nm is reported not identifiable by its
    bound (QUADRATIC_SIDE_RATIO)."""
    from twin.chain.config import motion_system
    from twin.pilot.identification.mle import QUADRATIC_SIDE_RATIO, fit_pitch_pilot
    from twin.pilot.models.pitch import PitchPilot, simulate_pitch
    from twin.pilot.studies.experiment import pitch_remnant_scale

    truth = PitchPilot(tau_v=0.275)
    cfg = motion_system("condition-8")
    r = simulate_pitch(truth, cfg, 50, seed=1, remnant_scale=pitch_remnant_scale(truth, 0.15))
    fit = fit_pitch_pilot(r.ft, r.fd, r.u[4], cfg, intervals=True)
    z = (fit.pilot.omega_nm - truth.omega_nm) / fit.crlb["omega_nm"]
    assert z > 2.0  # the bound misses here ...
    assert fit.covers("omega_nm", truth.omega_nm)  # ... the interval does not
    lo, _ = fit.intervals["omega_nm"]
    assert fit.pilot.omega_nm - lo > QUADRATIC_SIDE_RATIO * 2 * fit.crlb["omega_nm"]
    assert "omega_nm" in fit.unidentifiable  # reported: the bound is not its uncertainty
    assert {"t_lead", "t_lag"} <= set(fit.unidentifiable)  # bound infinite at t_lead = t_lag
    assert fit.covers("t_lead", truth.t_lead)  # the profile still bounds it
    for name, (lo, hi) in fit.intervals.items():
        assert lo <= getattr(fit.pilot, name) <= hi, name
    assert set(fit.to_dict()["likelihood_interval_2sd"]) == set(fit.crlb)
