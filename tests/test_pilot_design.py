"""Experiments designed on the twin's subjects (twin.pilot.studies.design)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from planted import planted_rows
from scipy import stats

from twin.core.errors import SignalError
from twin.core.thesis import TABLES_6_4_TO_6_7
from twin.pilot.studies.design import (
    ACCEPTANCE,
    Design,
    agreements,
    design,
    subject_differences,
    subjects_for,
    window,
)
from twin.pilot.studies.population import FACTORS, MEASURES, PopulationResult, anova

#: The contract's measures (every effect of the acceptance) and one more.
MEASURED = (*MEASURES, "t_lead")
#: Simulated experiments per size in these tests (the default's quarter: faster, coarser).
DRAWS = 1000


def population(seed: int, subjects: int = 9) -> PopulationResult:
    """A population of planted subjects (:func:`planted.planted_rows`) and its ANOVA."""
    rows = planted_rows(seed, subjects)
    return PopulationResult(rows, anova(rows, MEASURED), seed)


@pytest.fixture(scope="module")
def planted() -> tuple[list[PopulationResult], Design]:
    """Six populations of nine planted subjects and their design."""
    results = [population(seed) for seed in range(6)]
    return results, design(results, draws=DRAWS, resamples=8, resample_draws=200)


def test_a_main_effects_f_is_the_squared_t_of_the_subjects_differences():
    """The design's premise: in the 2 x 2 x 2 within-subject ANOVA (statsmodels AnovaRM, as
    the populations' Tables 6.4-6.7) each main effect's F is t^2 of the paired t-test on the
    subjects' differences between the factor's marginal means, and its direction their sign."""
    rows = planted_rows(3, subjects=7)
    table = anova(rows, MEASURED)
    for m in MEASURED:
        for f in FACTORS:
            d = subject_differences(rows, m, f)
            t = stats.ttest_1samp(d, 0.0).statistic
            assert d.shape == (7,)
            assert t**2 == pytest.approx(table[m][f]["F"], rel=1e-9)
            assert ("+" if d.mean() > 0 else "-") == table[m][f]["direction"]


def test_a_simulated_experiment_agrees_as_the_populations_anova_does(planted):
    """Each simulated experiment is tested as a flown population is: the first 8 draws of
    nine subjects, rebuilt as populations from the pooled subjects' rows and put through
    AnovaRM and PopulationResult.agreement, agree with the thesis exactly where the
    vectorised test says they do, effect by effect."""
    results, d = planted
    rows = [[r for r in p.rows if r["subject"] == s] for p in results for s in range(1, 10)]
    directions = [TABLES_6_4_TO_6_7[m][f][1] for m, f in d.effects]
    fast = agreements(d.differences, directions, 9, np.random.default_rng(4), draws=8)
    idx = np.random.default_rng(4).integers(len(rows), size=(8, 9))
    for draw, chosen in enumerate(idx):
        flown = [{**r, "subject": j + 1} for j, i in enumerate(chosen) for r in rows[i]]
        agree = PopulationResult(flown, anova(flown, MEASURED), 0).agreement()
        assert [agree[m][f] for m, f in d.effects] == fast[draw].tolist(), draw


def test_the_simulated_experiments_have_the_power_of_a_paired_t_test():
    """A pool of 50,000 subjects whose differences have d_z = 0.5: the share of simulated
    experiments that find the effect upwards at p < 0.05 is the paired t-test's power (G*Power
    4, 'means: difference from constant', d_z 0.5, two tails: 34 subjects for 80 %, power
    0.808) within 4 binomial sd and 0.01 for the pool's own d_z, 5 to 34 subjects; an effect
    that is not there (d_z 0, no direction) stays out in 95 %; found the wrong way it never
    agrees."""
    rng = np.random.default_rng(2)
    pool = np.column_stack([rng.normal(0.5, 1.0, 50_000), rng.normal(0.0, 1.0, 50_000)])
    for n, power in ((5, None), (20, None), (34, 0.808)):
        a = agreements(pool, ["+", None], n, np.random.default_rng(n)).mean(axis=0)
        want = power or float(stats.nct.sf(stats.t.ppf(0.975, n - 1), n - 1, 0.5 * np.sqrt(n)))
        assert abs(a[0] - want) < 4 * np.sqrt(want * (1 - want) / 4000) + 0.01
        assert abs(a[1] - 0.95) < 4 * np.sqrt(0.95 * 0.05 / 4000) + 0.01
    down = agreements(pool, ["-", None], 34, np.random.default_rng(1)).mean(axis=0)
    assert down[0] < 0.001


def test_subjects_for_and_the_window_of_a_curve():
    assert subjects_for([0.9, 0.95], first=5) == 5
    assert subjects_for([0.5, 0.9, 0.7, 0.85, 0.99], first=2) == 5
    assert subjects_for([0.5, 0.9, 0.79]) is None
    assert window([0.5, 0.81, 0.9, 0.85, 0.6], first=3) == (4, 6)
    assert window([0.5, 0.7]) is None


def test_a_design_on_planted_subjects_recovers_their_effects(planted, tmp_path):
    """54 subjects (six populations of nine) with the filter effects planted at the thesis'
    own standardised size and direction (Tables 6.4-6.7), K_v's reversed, no delay or noise
    effect: the pooled d_z is the planted one within 4 standard errors; nine subjects agree
    with the thesis as often as its estimate predicts (within 0.15: the pool's d_z is itself
    an estimate) and K_v's reversed effect never, so neither does the acceptance; the
    experiments go up to half the pool; table, JSON and figure."""
    d = planted[1]
    assert d.differences.shape == (54, len(MEASURED) * 3) and d.sizes == range(2, 28)
    se = np.sqrt(1 / 54)
    for k, (m, f) in enumerate(d.effects):
        size, direction = TABLES_6_4_TO_6_7[m][f]
        planted = 0.0 if f != "filter" else np.sqrt(size / 9) * (-1 if direction == "-" else 1)
        planted *= -1 if m == "k_v" and f == "filter" else 1
        assert abs(d.d_z(k) - planted) < 4 * se * np.sqrt(1 + planted**2 / 2), (m, f)
        if f == "filter" and m != "k_v":  # planted at the thesis' F (delay, noise: at 0)
            assert abs(d.at(9)[k] - d.thesis_agreement(k, 9)) < 0.15, (m, f)
        if f != "filter":  # absent: within two standard errors of zero, mostly
            assert d.lost_from(k) is None or d.near_zero(k), (m, f)
    kv = d.effects.index(("k_v", "filter"))
    assert d.at(9)[kv] < 0.01 and d.needed(kv) is None and d.flown["k_v", "filter"] == 0
    assert d.flown_acceptance == 0 and d.acceptance.max() < 0.01 and d.acceptance_window() is None
    assert np.all(d.spread[0] <= d.spread[1]) and d.spread.shape == (2, 26, len(d.effects))
    for k, (m, f) in enumerate(d.effects):  # the pool's own uncertainty brackets its estimate
        lo, hi = d.spread_at(9)[:, k]
        assert lo - 0.1 <= d.at(9)[k] <= hi + 0.1, (m, f)
    target = d.effects.index(("crossover_target_rad_s", "filter"))
    assert np.array_equal(d.acceptance_spread_at(9), d.acceptance_spread[:, 7])
    lo, hi = d.spread_at(9)[:, target]
    assert hi - lo > 0.05  # F 5.98 at nine: which subjects the pool holds matters
    assert d.needed(target) is not None and d.needed(target) > 9  # F 5.98: 57 % at nine
    # G*Power 3.1, d_z sqrt(5.98 / 9) = 0.815, two tails: 80 % from 14 subjects (0.805)
    assert d.thesis_needed(target) == 14
    delay = d.effects.index(("var_u", "delay"))  # the thesis found none
    assert d.thesis_needed(delay) is None and d.needed(delay) is None
    assert d.thesis_agreement(delay, 30) == pytest.approx(0.95)  # absent, as concluded
    # the thesis' conclusions as the truth at nine: target crossover 0.57, var(u) 0.92, the
    # other six filter effects over 0.99 (F 27 and more), four absent effects 0.95 each
    assert d.thesis_acceptance(9) == pytest.approx(0.575 * 0.922 * 0.95**4, abs=0.01)
    doc = json.loads(json.dumps(d.to_dict()))
    assert doc["pool"] == 54 and doc["sizes"] == [2, 27]
    assert doc["design"]["k_v"]["filter"]["flown_agreed"] == 0
    assert doc["acceptance"]["window_80"] is None and doc["acceptance"]["flown_agreed"] == 0
    assert len(doc["acceptance"]["by_subjects"]) == 26
    table = d.format_table()
    assert "54 pooled from 6 populations of 9" in table and "in 80 % with no size" in table
    assert d.plot(path=str(tmp_path / "design.png")) is not None
    assert (tmp_path / "design.png").stat().st_size > 10_000


def test_an_effect_the_twin_has_and_the_thesis_did_not_find_is_lost_with_many_subjects():
    """A hand-made design: an effect to be found that rises with the subjects and one the
    thesis did not find whose agreement falls: the acceptance holds between the two."""
    found = np.linspace(0.3, 1.0, 29)
    lost = np.linspace(0.95, 0.5, 29)
    curves = np.column_stack([found, lost])
    d = Design((("k_v", "filter"), ("k_v", "delay")), np.zeros((60, 2)), curves, found * lost,
               {}, 0, 6, 10, np.stack([curves - 0.1, curves + 0.1]),
               np.stack([found * lost - 0.1, found * lost + 0.1]))  # fmt: skip
    assert d.needed(0) == 2 + int(np.flatnonzero(found >= 0.8)[0])
    assert d.lost_from(1) == 2 + int(np.flatnonzero(lost < 0.8)[0])
    assert d.needed(1) is None and d.lost_from(0) is None
    # the pool's resamples: the optimistic curve reaches 80 % sooner, the pessimistic later
    assert d.needed_spread(0) == (subjects_for(found + 0.1), subjects_for(found - 0.1))
    assert d.needed_spread(0)[0] < d.needed(0) < d.needed_spread(0)[1]
    assert d.needed_spread(1) == (None, None)
    assert d.acceptance_window() == window(found * lost)


def test_a_design_is_seeded_and_refuses_bad_populations(planted):
    results = planted[0]
    again = design(results, draws=200, resamples=2)
    same = design(results, draws=200, resamples=2)
    assert np.array_equal(same.agreement, again.agreement)
    assert np.array_equal(same.spread, again.spread)
    assert not np.array_equal(design(results, seed=99, draws=200, resamples=2).agreement,
                              again.agreement)  # fmt: skip
    with pytest.raises(SignalError, match="at least 2 resamples; got 1"):
        design(results, resamples=1)
    with pytest.raises(SignalError, match=r"at least 40 subjects .* got 27"):
        design(results[:3])
    with pytest.raises(SignalError, match="no populations given"):
        design([])
    with pytest.raises(SignalError, match="populations differ in subjects"):
        design([*results[:5], population(7, subjects=4)])
    few = [PopulationResult(r.rows, {"k_v": r.anova["k_v"]}, r.seed) for r in results]
    with pytest.raises(SignalError, match="missing: crossover_disturbance_rad_s/filter"):
        design(few)
    # one population of 44 (its ANOVA borrowed: only its size matters here)
    wide = design([PopulationResult(planted_rows(10, 44), results[0].anova, 10)], draws=100,
                  resamples=2, resample_draws=50)  # fmt: skip
    assert wide.sizes[-1] == 22 and wide.to_dict()["design"]["k_v"]["filter"][
        "agreement_at_flown_size"] is None  # fmt: skip
    with pytest.raises(SignalError, match=r"designed for 2 to 22 subjects \(at most half the "):
        wide.at(44)


def test_subject_differences_refuse_unbalanced_or_broken_rows():
    rows = planted_rows(0, subjects=2)
    with pytest.raises(SignalError, match=r"subject 1 has cells \[.*\]; a design needs one row"):
        subject_differences(rows[1:], "k_v", "filter")
    with pytest.raises(SignalError, match="subject 1 has two rows for the cell"):
        subject_differences([*rows, rows[0]], "k_v", "filter")
    with pytest.raises(SignalError, match="unknown factor 'flter'"):
        subject_differences(rows, "k_v", "flter")
    bad = [{**r, "k_v": float("nan")} if i == 3 else r for i, r in enumerate(rows)]
    with pytest.raises(SignalError, match="subject 1, condition 4: k_v is nan; a design needs"):
        subject_differences(bad, "k_v", "delay")


def test_cli_populations_design_the_next_experiment(monkeypatch, tmp_path, capsys):
    """``--populations 5`` of nine (45 subjects pooled): ``--json`` carries the design under
    ``design``; ``--plot`` adds ``-subjects.png`` (a subject's planted rows stand in for flying
    it; the text table is :meth:`Design.format_table`'s, tested above)."""
    from test_pilot_replication import fake_fly

    from twin.cli.main import main
    from twin.pilot.studies import replication

    monkeypatch.setattr(replication, "fly_subject", fake_fly)
    png = str(tmp_path / "rep.png")
    assert main(["pilot", "experiment", "subjects", "--populations", "5",
                 "--scheduler", "inline", "--json", "--plot", png]) == 0  # fmt: skip
    doc = json.loads(capsys.readouterr().out)
    kv = doc["design"]["design"]["k_v"]["filter"]
    assert doc["design"]["pool"] == 45 and kv["flown_agreed"] == 0  # planted reversed
    assert kv["agreement_at_flown_size"] < 0.01 and kv["subjects_for_80"] is None
    assert doc["design"]["acceptance"]["effects"] == [f"{m}/{f}" for m, f in ACCEPTANCE]
    assert (tmp_path / "rep-subjects.png").stat().st_size > 10_000
