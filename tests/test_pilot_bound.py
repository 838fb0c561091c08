"""The Cramer-Rao bound at a given pilot (:func:`twin.pilot.mle.bound_at`)."""

import dataclasses

import numpy as np
import pytest

from twin.chain.config import motion_system
from twin.errors import SignalError
from twin.pilot.experiment import pitch_remnant_scale
from twin.pilot.mle import PARAMETERS, bound_at, fit_pitch_pilot
from twin.pilot.pitch import PitchPilot, simulate_pitch

TRUTH = PitchPilot(tau_v=0.275)  # visual + display delay on the 10 ms simulation grid
CFG = motion_system("condition-8")


@pytest.fixture(scope="module")
def runs():
    """Five repetitions of condition 8 at the thesis' remnant level (15 %)."""
    return simulate_pitch(TRUTH, CFG, 5, seed=3, remnant_scale=pitch_remnant_scale(TRUTH, 0.15))


def test_the_fits_bound_covers_every_minimum_it_cannot_rule_out(runs):
    """At its estimate the fit's bound is :func:`bound_at`'s (the same Fisher information;
    they differ only in their finite differences); the bound it reports is widened until two
    of it cover each competing minimum's own two bounds: the largest of bound + half the
    distance from the estimate over the estimate and the competing minima."""
    fit = fit_pitch_pilot(runs.ft, runs.fd, runs.u, CFG)
    assert fit.competing  # five repetitions at this remnant level still leave the pair's two
    minima = (fit.pilot, *fit.competing)
    at = [bound_at(p, runs.ft, runs.fd, runs.u, CFG) for p in minima]
    for name in PARAMETERS:
        assert at[0][name] == pytest.approx(fit.crlb_at_estimate[name], rel=0.02), name
        est = getattr(fit.pilot, name)
        cover = max(b[name] + abs(getattr(p, name) - est) / 2
                    for p, b in zip(minima, at, strict=True))  # fmt: skip
        assert cover == pytest.approx(fit.crlb[name], rel=0.02), name
        assert fit.crlb[name] >= fit.crlb_at_estimate[name]
    out = fit.to_dict()
    assert len(out["competing_minima"]) == len(fit.competing)


def test_the_lead_lag_bounds_scale_with_the_lag(runs):
    """Why the reported bound of t_lead and t_lag is too narrow when t_lag comes out low: with
    the net lead t_lead - t_lag held (the data pin it down) and the other parameters at the
    truth, halving t_lag (0.1 to 0.05 s) narrows t_lead's bound by more than a quarter and
    t_lag's by more than a tenth, while k_v's changes by less than a fifth."""
    low = dataclasses.replace(TRUTH, t_lead=TRUTH.t_lead - 0.05, t_lag=TRUTH.t_lag - 0.05)
    at_truth = bound_at(TRUTH, runs.ft, runs.fd, runs.u, CFG)
    at_low = bound_at(low, runs.ft, runs.fd, runs.u, CFG)
    assert at_low["t_lead"] < 0.75 * at_truth["t_lead"]
    assert at_low["t_lag"] < 0.9 * at_truth["t_lag"]
    assert at_truth["k_v"] / at_low["k_v"] == pytest.approx(1.0, abs=0.2)


def test_a_parameter_the_data_do_not_see_gets_an_infinite_bound_and_only_it(runs):
    """k_m = 0 leaves tau_m unseen; at t_lag = 0 a first-order lag acts as a delay, so t_lag
    and tau_v cannot be told apart. Those get an infinite bound, the others a finite one near
    their bound with the parameter seen (not zero, not all infinite)."""
    at = bound_at(TRUTH, runs.ft, runs.fd, runs.u, CFG)
    no_motion = bound_at(dataclasses.replace(TRUTH, k_m=0.0), runs.ft, runs.fd, runs.u, CFG)
    assert no_motion["tau_m"] == np.inf
    for name in set(PARAMETERS) - {"tau_m"}:
        assert 0.5 < no_motion[name] / at[name] < 2.0, name
    no_lag = bound_at(dataclasses.replace(TRUTH, t_lag=0.0), runs.ft, runs.fd, runs.u, CFG)
    assert {n for n, b in no_lag.items() if not np.isfinite(b)} == {"t_lag", "tau_v"}
    assert all(b > 0 for b in no_lag.values())


def test_bound_at_refuses_what_it_cannot_use(runs):
    with pytest.raises(SignalError, match="pilot's parameters must be finite"):
        bound_at(dataclasses.replace(TRUTH, k_v=np.nan), runs.ft, runs.fd, runs.u, CFG)
    with pytest.raises(SignalError, match="constant"):
        bound_at(TRUTH, runs.ft, runs.fd, np.zeros_like(runs.u), CFG)
    with pytest.raises(SignalError, match="1-D windows"):
        bound_at(TRUTH, runs.ft[:100], runs.fd, runs.u, CFG)


@pytest.mark.slow
def test_a_lag_on_its_bound_is_not_identifiable_and_widens_what_moves_with_it():
    """A pilot with a lead and no lag (t_lag = 0), one run of condition 8 at the thesis'
    remnant level (seed 3, run 0): the fit puts t_lag on the bound of its range, where the
    likelihood is not stationary and its curvature says nothing of how far into the range the
    data allow the lag. t_lag is reported on its bound and not identifiable, and every other
    parameter's reported sd covers the point of t_lag's profile into the range where the
    chi-square has risen by 3.84, so the truth stays within two of them."""
    from twin.pilot.mle import COMPETING_CHI2, LOWER, UPPER, _LineProblem
    from twin.pilot.profile import inward_point

    truth = dataclasses.replace(TRUTH, t_lead=0.15, t_lag=0.0)
    r = simulate_pitch(truth, CFG, 1, seed=3, remnant_scale=pitch_remnant_scale(truth, 0.15))
    fit = fit_pitch_pilot(r.ft, r.fd, r.u[0], CFG)
    assert fit.on_range_bound == ("t_lag",)
    assert "t_lag" in fit.unidentifiable
    assert fit.to_dict()["on_range_bound"] == ["t_lag"]
    problem = _LineProblem.of(r.ft, r.fd, r.u[0], CFG, 100.0, True, truth)
    x = np.array([getattr(fit.pilot, n) for n in PARAMETERS])
    k = PARAMETERS.index("t_lag")
    p = inward_point(problem.residual, x, k, LOWER, UPPER, 0.05, COMPETING_CHI2)
    assert p[k] > 0.02  # the profile leaves the bound before the chi-square rises by 3.84
    for j, name in enumerate(PARAMETERS):
        assert fit.crlb[name] >= fit.crlb_at_estimate[name], name
        assert abs(p[j] - x[j]) <= 2 * fit.crlb[name] * (1 + 1e-6), name
        if name not in fit.unidentifiable:
            assert abs(x[j] - getattr(truth, name)) <= 2 * fit.crlb[name], name
    # omega_nm moves with the lag: its bound at the estimate alone would be far too narrow
    assert fit.crlb["omega_nm"] > 2 * fit.crlb_at_estimate["omega_nm"]
