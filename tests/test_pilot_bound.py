"""The Cramer-Rao bound at a given pilot (:func:`twin.pilot.identification.mle.bound_at`)."""

import dataclasses

import numpy as np
import pytest

from twin.chain.config import motion_system
from twin.core.errors import SignalError
from twin.pilot.identification.mle import PARAMETERS, _bounds, bound_at, fit_pitch_pilot
from twin.pilot.models.pitch import PitchPilot, simulate_pitch
from twin.pilot.studies.experiment import pitch_remnant_scale

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
    # why each competes: within chi-square 3.84 of the best, or Vuong's test does not prefer it
    why = out["evidence"]["competing_minima"]
    assert len(why) == len(fit.competing)
    assert all(e["delta_chi2"] < 3.84 or e["vuong_z"] < 1.96 for e in why)
    assert all(e["delta_chi2"] >= 0 for e in why)  # the best is the best


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


def test_an_estimate_on_an_end_of_its_range_is_one_the_data_do_not_move_off():
    """A parameter is on its range's end when it is within 1e-3 of the range from it and moving
    it there costs less than 0.01 in chi-square: t_lag 2e-6 s from zero (the solver creeps
    towards an end where the likelihood is flat), zeta_nm on its lower end 0.02 (not zero) and
    omega_nm on its upper end; k_m 4e-3 from zero is not, where the data pin it there."""
    from twin.pilot.identification.mle import LOWER, UPPER, _on_bound

    x = np.array([1.5, 0.2, 2e-6, 0.275, 4e-3, 0.2, UPPER[6], LOWER[7]])
    sd = np.array([1.0, 1.0, 1.0, 1.0, 1e-4, 1.0, 1.0, 1.0])

    def residual(v):
        return (v - x) / sd  # chi-square zero at x; k_m's moves 1600 onto zero

    assert [PARAMETERS[k] for k in _on_bound(residual, x)] == ["t_lag", "omega_nm", "zeta_nm"]
    assert _on_bound(residual, x + np.where(np.arange(8) == 2, 0.01, 0.0)) == [6, 7]


def test_an_end_competes_where_the_data_hardly_see_a_parameter_and_cannot_rule_the_end_out():
    """Each parameter here is seen alone with the sd given (so that sd is its bound). Checked
    are those whose bound exceeds a third of their distance to the nearer end of their range:
    t_lag 0.04 s with sd 0.05 (moving it onto zero costs 0.64), zeta_nm 0.05 on a range from
    0.02 (costs 0.09), omega_nm 39 on a range to 40 (costs 0.04), t_lead 0.2 with sd 0.1
    (costs 4, more than 3.84: ruled out); not k_v (weak, but on its end already), k_m (its
    sd is a tenth of its distance to zero) nor tau_m (not seen at all: infinite bound)."""
    from twin.pilot.identification.mle import LOWER, _ends_not_ruled_out

    x = np.array([LOWER[0], 0.2, 0.04, 0.275, 0.3, 0.2, 39.0, 0.05])
    sd = np.array([1.0, 0.1, 0.05, 0.01, 0.03, np.inf, 5.0, 0.1])

    def residual(v):
        return np.where(np.isfinite(sd), (v - x) / sd, 0.0)

    ends = _ends_not_ruled_out(residual, x, 0.0, sd, [0])
    assert set(ends) == {"t_lag", "omega_nm", "zeta_nm"}
    for name, end, rise in (("t_lag", 0.0, 0.64), ("omega_nm", 40.0, 0.04),
                            ("zeta_nm", 0.02, 0.09)):  # fmt: skip
        k = PARAMETERS.index(name)
        point, cost = ends[name]
        assert point[k] == end and cost == pytest.approx(rise)
        others = np.delete(np.arange(8), [k, 5])  # the rest stay where the data put them
        assert point[others] == pytest.approx(x[others], abs=1e-6)


@pytest.mark.slow
def test_a_lag_on_its_bound_is_not_identifiable_and_widens_what_moves_with_it():
    """A pilot with a lead and no lag (t_lag = 0), one run of condition 8 at the thesis'
    remnant level (seed 0, no competing minimum): the fit puts t_lag on the end of its range,
    where a small lag acts as a delay and the curvature says nothing of how far into the range
    the data allow it. t_lag is reported there with no sd; the others' bound is taken with it
    held there (tau_v stays identifiable: with t_lag free its column equals tau_v's) and
    widened to cover the profile's point where the chi-square has risen by 3.84: the larger
    of that bound and the bound at the point plus half the distance to it."""
    truth = dataclasses.replace(TRUTH, t_lead=0.15, t_lag=0.0)
    r = simulate_pitch(truth, CFG, 1, seed=0, remnant_scale=pitch_remnant_scale(truth, 0.15))
    fit = fit_pitch_pilot(r.ft, r.fd, r.u[0], CFG)
    assert fit.competing == ()  # the widening below is the profile point's alone
    assert list(fit.on_range_bound) == ["t_lag"]
    # t_lead's sd is also taken along the likelihood's valley
    # (twin.pilot.identification.profile_wald), with t_lag free to leave zero there: wider here,
    # enough to flag it from this one run
    assert set(fit.unidentifiable) - {"t_lead"} == {"t_lag"}
    assert fit.crlb["t_lag"] == np.inf
    out = fit.to_dict()
    assert out["crlb_sd"]["t_lag"] is None and set(out["on_range_bound"]) == {"t_lag"}
    point = fit.on_range_bound["t_lag"]
    assert point.t_lag > 0.02  # the profile leaves the bound before the chi-square rises 3.84
    at_point = bound_at(point, r.ft, r.fd, r.u[0], CFG)
    for name in set(PARAMETERS) - {"t_lag"}:
        est = getattr(fit.pilot, name)
        half = abs(getattr(point, name) - est) / 2
        cover = max(fit.crlb_at_estimate[name], at_point[name] + half)
        if name == "t_lead":  # the valley can only widen it
            assert fit.crlb[name] >= cover * (1 - 0.02), name
        else:
            assert fit.crlb[name] == pytest.approx(cover, rel=0.02), name
        assert abs(est - getattr(truth, name)) <= 2 * fit.crlb[name], name
    # the widening is not cosmetic: tau_v moves with the lag along the valley
    assert fit.crlb["tau_v"] > 2 * fit.crlb_at_estimate["tau_v"]


@pytest.mark.slow
def test_the_seeded_fit_that_missed_on_the_lags_bound_now_covers_the_truth():
    """Run 160 of the coverage bench (condition 8, 15 % remnant, 200 one-run estimates, seed
    1): the fit lands with t_lag on zero, and with the bound at the estimate alone t_lead, k_m
    and omega_nm all missed the truth by more than two bounds. Widened over t_lag's profile
    into its range, every parameter reported identifiable holds it."""
    r = simulate_pitch(TRUTH, CFG, 200, seed=1, remnant_scale=pitch_remnant_scale(TRUTH, 0.15))
    fit = fit_pitch_pilot(r.ft, r.fd, r.u[160], CFG)
    assert list(fit.on_range_bound) == ["t_lag"]
    for name in ("t_lead", "k_m", "omega_nm"):
        error = abs(getattr(fit.pilot, name) - getattr(TRUTH, name))
        assert error > 2 * fit.crlb_at_estimate[name], name
    for name in set(PARAMETERS) - set(fit.unidentifiable):
        assert abs(getattr(fit.pilot, name) - getattr(TRUTH, name)) <= 2 * fit.crlb[name], name


@pytest.mark.slow
def test_a_lag_the_data_cannot_tell_from_none_widens_the_delay_it_trades_with():
    """A lead-only pilot (t_lag = 0), twelve runs of condition 8 at the thesis' remnant level
    (seed 0). In runs 6 and 10 t_lag comes out inside its range (0.046 and 0.013 s), flagged,
    and the run cannot tell it from no lag: the fit with t_lag = 0 and the others refitted is
    within chi-square 3.84 (`range_end`). That fit widens the others as a competing minimum
    does, with t_lag held on zero there (where its column equals tau_v's), and t_lag's own sd
    to at least half its distance to zero. In run 6 tau_v's estimate has traded delay for the
    lag: its bound at the estimate and the competing minimum's widening both miss the truth,
    and the end's widening holds it."""
    truth = dataclasses.replace(TRUTH, t_lead=0.15, t_lag=0.0)
    r = simulate_pitch(truth, CFG, 12, seed=0, remnant_scale=pitch_remnant_scale(truth, 0.15))
    for run in (6, 10):
        u = r.u[run]
        fit = fit_pitch_pilot(r.ft, r.fd, u, CFG)
        assert list(fit.range_end) == ["t_lag"] and not fit.on_range_bound, run
        end = fit.range_end["t_lag"]
        assert end.t_lag == 0.0
        assert 0.0 <= fit.evidence["range_end"]["t_lag"] < 3.84
        assert fit.crlb["t_lag"] >= fit.pilot.t_lag / 2
        # tau_v moves with the lag onto zero, and its sd covers the move
        assert fit.crlb["tau_v"] >= abs(end.tau_v - fit.pilot.tau_v) / 2 > 0.005
        others = (*fit.competing, end)
        spread = [bound_at(p, r.ft, r.fd, u, CFG) for p in fit.competing]
        held = bound_at(dataclasses.replace(end, t_lag=1e-9), r.ft, r.fd, u, CFG)
        for name in set(PARAMETERS) - {"t_lag", "tau_v"}:  # (tau_v's is singular at t_lag 0)
            est = getattr(fit.pilot, name)
            cover = max(fit.crlb_at_estimate[name], *(
                b[name] + abs(getattr(p, name) - est) / 2
                for p, b in zip(others, [*spread, held], strict=True)))  # fmt: skip
            if fit.evidence["ruled_out_minima"]:  # widened for the selection too (run 10)
                assert fit.crlb[name] >= cover * (1 - 0.05), (run, name)
            else:
                assert fit.crlb[name] == pytest.approx(cover, rel=0.05), (run, name)
        error = abs(fit.pilot.tau_v - truth.tau_v)
        assert error <= 2 * fit.crlb["tau_v"], run
        if run == 6:
            assert fit.competing
            assert error > 2 * fit.crlb_at_estimate["tau_v"]
            rival = max(b["tau_v"] + abs(p.tau_v - fit.pilot.tau_v) / 2
                        for p, b in zip(fit.competing, spread, strict=True))  # fmt: skip
            assert error > 2 * rival


@pytest.mark.slow
def test_a_minimum_the_data_rule_out_widens_the_bound_for_the_selection():
    """Five repetitions of condition 8 at the thesis' remnant level, seed 23: the lead-lag
    pair's other basin is ruled out (chi-square 15 above the best, Vuong's test prefers the
    best), nothing competes, and the estimate came out low, as those that pass do: t_lead
    0.173 s with a bound of 0.013 s at the estimate, which misses the truth (0.2) by more than
    two. Widened for the selection (:mod:`twin.pilot.identification.selection`) it holds the truth;
    t_lag, whose estimate lies near the limit where the other basin would compete again, is no
    longer counted as identified."""
    r = simulate_pitch(TRUTH, CFG, 5, seed=23, remnant_scale=pitch_remnant_scale(TRUTH, 0.15))
    fit = fit_pitch_pilot(r.ft, r.fd, r.u, CFG)
    assert not fit.competing and not fit.range_end and not fit.on_range_bound
    ruled = fit.evidence["ruled_out_minima"]
    assert ruled and all(e["delta_chi2"] >= 3.84 and e["vuong_z"] >= 1.96 for e in ruled)
    error = abs(fit.pilot.t_lead - TRUTH.t_lead)
    assert error > 2 * fit.crlb_at_estimate["t_lead"]
    assert "t_lead" not in fit.unidentifiable and error <= 2 * fit.crlb["t_lead"]
    assert "t_lag" in fit.unidentifiable
    assert fit.crlb_at_estimate["t_lag"] < fit.pilot.t_lag / 3  # it was, by its own bound
    assert all(fit.crlb[n] >= fit.crlb_at_estimate[n] for n in PARAMETERS)


def test_a_nearly_singular_information_is_singular_whatever_inv_returns():
    """Two columns equal to 1e-7 (the information's condition about 1e15): ``inv`` returns a
    finite, positive variance for both there (on some BLAS builds, at t_lag = 0, 5e4 s), but
    the data do not tell them apart, so both get an infinite bound and the others their own."""
    rng = np.random.default_rng(0)
    jac = rng.normal(size=(200, 4))
    jac[:, 3] = jac[:, 2] + 1e-7 * rng.normal(size=200)
    assert np.all(np.isfinite(np.diag(np.linalg.inv(jac.T @ jac))))  # inv alone does not see it
    sd = _bounds(jac)
    assert np.isinf(sd[2:]).all()
    free = np.sqrt(np.diag(np.linalg.inv(jac[:, :2].T @ jac[:, :2])))
    assert np.all(np.isfinite(sd[:2])) and np.all(sd[:2] >= free * (1 - 1e-9))


def test_a_null_vector_blurred_by_finite_differences_leaves_the_others_seen():
    """The null direction of two equal columns picks up shares of 1e-5 on the others (as the
    finite differences leave them): only the pair is unseen, the others keep about the bound
    they have with the pair's sum fitted in its place."""
    rng = np.random.default_rng(1)
    jac = rng.normal(size=(200, 4))
    jac[:, 3] = jac[:, 2] + 1e-5 * jac[:, 0] + 1e-9 * rng.normal(size=200)
    sd = _bounds(jac)
    assert np.isinf(sd[2:]).all()
    merged = np.column_stack([jac[:, 0], jac[:, 1], jac[:, 2] + jac[:, 3]])
    own = np.sqrt(np.diag(np.linalg.inv(merged.T @ merged)))[:2]
    assert sd[:2] == pytest.approx(own, rel=1e-3)
