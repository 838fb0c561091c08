"""Chapter 6 replicated over populations (twin.pilot.studies.replication)."""

from __future__ import annotations

import copy
import dataclasses
import json

import numpy as np
import pytest
from planted import planted_rows
from scipy import stats

from twin.cli.main import main
from twin.core.errors import SignalError
from twin.pilot.models.adapt import ADAPTED
from twin.pilot.studies import population, replication
from twin.pilot.studies.population import PopulationResult, anova, compared
from twin.pilot.studies.replication import agreement_probability, replicate, run_populations
from twin.pilot.studies.spread import MOTION_NOISE_SD, VISUAL_DELAY_SD, Spread


@pytest.mark.parametrize(("f", "significant"), [(5.98, True), (15.0, True), (4.67, False),
                                                (0.0, False)])  # fmt: skip
def test_the_agreement_probability_is_that_of_paired_t_tests_on_nine_subjects(f, significant):
    """Independent of the noncentral t: 20,000 simulated nine-subject populations whose
    paired differences have the standardised mean sqrt(F / 9), tested by scipy's one-sample
    t-test; the fraction agreeing with the thesis (p < 0.05 upwards if significant, else
    p >= 0.05) is within 4 binomial sd of the formula. F 5.98 is Table 6.5's target
    crossover, 15.0 Table 6.4's var(u), 4.67 Table 6.4's K_m delay (not significant)."""
    rng = np.random.default_rng(11)
    d = rng.normal(np.sqrt(f / 9), 1.0, (20_000, 9))
    res = stats.ttest_1samp(d, 0.0, axis=1)
    hits = (res.pvalue < 0.05) & (res.statistic > 0) if significant else res.pvalue >= 0.05
    q = agreement_probability(f, significant)
    assert abs(hits.mean() - q) < 4 * np.sqrt(q * (1 - q) / 20_000) + 1e-9


def test_the_agreement_probability_grows_with_the_subjects_and_refuses_bad_input():
    assert agreement_probability(5.98, True, 20) > agreement_probability(5.98, True) > 0.5
    assert agreement_probability(0.0, False, 30) == pytest.approx(0.95)
    for bad in (float("nan"), -1.0, float("inf")):
        with pytest.raises(SignalError, match="F value must be a finite number >= 0"):
            agreement_probability(bad, True)
    with pytest.raises(SignalError, match="at least 2 subjects"):
        agreement_probability(5.0, True, 1)


def test_a_replication_of_planted_populations_flags_only_a_reversed_effect(tmp_path):
    """Eight populations with the filter effects planted at the thesis' own size and direction
    (Tables 6.4-6.7), K_v's reversed: the thesis is a plausible draw (p >= 0.05) for var(u)'s
    and t_lead's filter effects and for every delay and noise effect of the three; for K_v's
    it is not (p < 0.001): the populations' K_v rose. Agreements with the thesis: t_lead's
    (thesis F 60.96) 8 of 8, K_v's none. JSON, table and figure."""
    measures = ("var_u", "k_v", "t_lead")
    results = [PopulationResult(rows, anova(rows, measures), seed)
               for seed in range(8) for rows in [planted_rows(seed)]]  # fmt: skip
    rep = replicate(results)
    k_v = rep.effect("k_v", "filter")
    assert k_v.p_draw < 1e-3 and not k_v.plausible and k_v.agreed == 0
    assert all(d > 0 for d in k_v.d_z)  # reversed: K_v rose
    assert rep.effect("t_lead", "filter").agreed == 8
    for e in rep.effects:
        if e.measure != "k_v" or e.factor != "filter":
            assert e.plausible, (e.measure, e.factor, e.p_draw)
    doc = json.loads(json.dumps(rep.to_dict()))
    d = doc["replication"]["k_v"]["filter"]
    assert d["thesis_F"] == 43.36 and d["thesis_d_z"] == [-np.sqrt(43.36 / 9)]
    assert d["agreed"] == 0 and d["populations"] == 8
    assert d["d_z_5_95"][0] <= d["d_z_median"] <= d["d_z_5_95"][1]
    assert doc["seeds"] == list(range(8)) and doc["implausible"] == ["k_v/filter"]
    table = rep.format_table()
    assert table.splitlines()[2 + measures.index("k_v") * 3].endswith("<- differs")
    assert rep.plot(path=str(tmp_path / "rep.png")) is not None
    assert (tmp_path / "rep.png").stat().st_size > 10_000
    with pytest.raises(SignalError, match="no effect 'k_x' x 'filter'; measures: "):
        rep.effect("k_x", "filter")


@pytest.mark.parametrize("scale", [1.0, 1.5])
def test_the_predictive_p_is_uniform_when_the_new_draw_comes_from_the_same_distribution(scale):
    """4000 sets of 20 normal draws and one more (sd ``scale`` times theirs): the fraction
    with p < 0.05 is 0.05 and with p < 0.5 is 0.5, within 4 binomial sd."""
    from twin.pilot.studies.replication import predictive_p

    rng = np.random.default_rng(5)
    p = np.array([predictive_p(rng.normal(3, 1, 20), rng.normal(3, scale), scale)
                  for _ in range(4000)])  # fmt: skip
    for level in (0.05, 0.5):
        assert abs(np.mean(p < level) - level) < 4 * np.sqrt(level * (1 - level) / 4000)
    with pytest.raises(SignalError, match="at least 2 finite draws"):
        predictive_p([1.0, float("nan")], 0.0)
    with pytest.raises(SignalError, match="the new draw must be finite"):
        predictive_p([1.0, 2.0], float("nan"))
    with pytest.raises(SignalError, match="no spread to predict a draw from"):
        predictive_p([1.0, 1.0, 1.0], 1.0)


def test_the_predictive_log_density_is_a_density_peaked_at_the_draws_mean():
    """It integrates to 1 over the new draw (whatever the scale), is highest at the draws'
    mean and falls as p falls; summed over a replication's effects it is the replication's
    score, and the thesis' sign counts where it gave one (the likelier sign where not)."""
    from twin.pilot.studies.replication import (
        EffectReplication,
        Replication,
        predictive_log_density,
        predictive_p,
    )

    draws = np.random.default_rng(6).normal(2.0, 0.5, 10)
    grid = np.linspace(-30, 34, 6401)
    for scale in (0.5, 1.0, 2.0):
        density = np.exp([predictive_log_density(draws, v, scale) for v in grid])
        assert np.trapezoid(density, grid) == pytest.approx(1.0, abs=2e-3)
        assert grid[np.argmax(density)] == pytest.approx(draws.mean(), abs=1e-2)
    near, far = draws.mean() + 0.3, draws.mean() + 1.5
    assert predictive_log_density(draws, near) > predictive_log_density(draws, far)
    assert predictive_p(draws, near) > predictive_p(draws, far)
    with pytest.raises(SignalError, match="no spread"):
        predictive_log_density([1.0, 1.0], 1.0)

    def effect(direction):
        return EffectReplication("m", "filter", 9.0, direction, (-9.0, -16.0), 9, 0, 0.5)

    assert effect("-").log_density > effect("+").log_density
    assert effect(None).log_density == effect("-").log_density
    both = Replication((effect("-"), effect("+")), (0, 1), 9, ADAPTED, 0.1)
    assert both.log_density == pytest.approx(effect("-").log_density + effect("+").log_density)
    assert "log predictive density" in both.format_table()


def test_the_thesis_standardised_effect_has_its_direction_or_both_signs():
    from twin.pilot.studies.replication import EffectReplication

    def effect(f, direction):
        return EffectReplication("m", "filter", f, direction, (-9.0, -16.0), 9, 0, 0.5)

    assert effect(9.0, "-").thesis_d_z == (-1.0,)
    assert effect(9.0, "+").thesis_d_z == (1.0,)
    assert effect(9.0, None).thesis_d_z == (-1.0, 1.0)
    assert effect(9.0, "-").d_z.tolist() == [-1.0, -4 / 3]
    # +1 is far from the draws at -1 and -1.33; -1 is among them, so "either sign" is plausible
    assert effect(9.0, "+").p_draw < effect(9.0, None).p_draw == effect(9.0, "-").p_draw


def test_a_replication_refuses_one_population_and_mixed_settings():
    rows = planted_rows(0, subjects=4)
    one = PopulationResult(rows, anova(rows), 0)
    with pytest.raises(SignalError, match="at least 2 populations; got 1"):
        replicate([one])
    other = PopulationResult(rows, anova(rows), 1, run_to_run_sd=0.05)
    with pytest.raises(SignalError, match="populations differ"):
        replicate([one, other])
    with pytest.raises(SignalError, match=r"distinct populations; seeds \[0, 0\] repeat"):
        replicate([one, one])
    fewer = PopulationResult(rows, anova(rows, ("k_v",)), 1)
    with pytest.raises(SignalError, match="measures, identification or the subjects' spreads"):
        replicate([one, fewer])
    flat = copy.deepcopy(one.anova)
    flat["k_v"]["delay"]["F"] = float("inf")
    with pytest.raises(SignalError, match=r"k_v x delay: F is not finite in population\(s\) \[1\]"):
        replicate([one, PopulationResult(rows, flat, 1)])
    with pytest.raises(SignalError, match="at least 2 populations"):
        run_populations(1)
    with pytest.raises(SignalError, match="run-to-run variation must be"):
        run_populations(2, run_to_run_sd=float("nan"))
    for other in (Spread(motion=0.0), Spread(visual_delay=VISUAL_DELAY_SD + 0.01)):
        with pytest.raises(SignalError, match="the subjects' spreads"):
            replicate([one, PopulationResult(rows, anova(rows), 1, spread=other)])
    with pytest.raises(
        TypeError, match=r"spread must be a twin.pilot.studies.spread.Spread .* float"
    ):
        run_populations(2, spread=0.5)


def fake_fly(subject, seed, adapted, sd):
    """Planted rows for one subject, seeded by population and subject, in place of flying."""
    rows = planted_rows(1000 * seed + subject.number, subjects=1)
    return [{**r, "subject": subject.number} for r in rows]


def test_run_populations_flies_each_population_as_run_population_does(monkeypatch):
    """All subjects of all populations are one map: each population must still be the one
    ``run_population`` gives for its seed (a subject's rows stand in for flying it)."""
    monkeypatch.setattr(population, "fly_subject", fake_fly)
    monkeypatch.setattr(replication, "fly_subject", fake_fly)
    rep, results = run_populations(2, 3, seed=5)
    assert rep.seeds == (5, 6) and rep.subjects == 3
    for r in results:
        alone = population.run_population(3, r.seed)
        assert json.dumps(alone.to_dict()) == json.dumps(r.to_dict())


def test_cli_populations_only_with_adaptive_subjects(capsys):
    assert main(["pilot", "experiment", "fixed", "--populations", "3"]) == 2
    err = capsys.readouterr().err.strip()
    assert "unrecognized arguments: --populations 3" in err and "\n" not in err
    assert "twin pilot experiment fixed --help" in err
    assert main(["pilot", "experiment", "subjects", "--populations", "0"]) == 2
    assert "--populations: must be an integer in [1, 1,000]" in capsys.readouterr().err
    assert main(["pilot", "experiment", "subjects", "--runs", "3"]) == 2
    assert "unrecognized arguments: --runs 3" in capsys.readouterr().err
    assert main(["pilot", "experiment", "fixed", "--motion-spread", "1"]) == 2
    assert "unrecognized arguments: --motion-spread 1" in capsys.readouterr().err
    assert main(["pilot", "experiment", "subjects", "--motion-spread", "nan"]) == 2
    err = capsys.readouterr().err.strip()
    assert (
        err.startswith("twin: error: argument --motion-spread:")
        and "[0, 3]" in err
        and "\n" not in err
    )
    assert main(["pilot", "experiment", "fixed", "--visual-delay-spread", "0.01"]) == 2
    assert "unrecognized arguments: --visual-delay-spread" in capsys.readouterr().err
    for bad in ("nan", "-0.01", "0.2"):
        assert main(["pilot", "experiment", "subjects",
                     "--visual-delay-spread", bad]) == 2  # fmt: skip
        err = capsys.readouterr().err.strip()
        assert err.startswith("twin: error: argument --visual-delay-spread:") and "[0, 0.1]" in err
        assert "\n" not in err


def test_cli_populations_json_and_figure(monkeypatch, tmp_path, capsys):
    """``--populations 2 --json --plot``: the summary, each population's ANOVA, the figure
    (a subject's rows stand in for flying it)."""
    monkeypatch.setattr(replication, "fly_subject", fake_fly)
    png = tmp_path / "rep.png"
    code = main(["pilot", "experiment", "subjects", "--populations", "2",
                 "--subjects", "3", "--seed", "4", "--scheduler", "inline", "--json",
                 "--plot", str(png)])  # fmt: skip
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["seeds"] == [4, 5] and doc["subjects"] == 3
    assert doc["motion_spread"] == MOTION_NOISE_SD and doc["visual_delay_sd"] == VISUAL_DELAY_SD
    assert [p["seed"] for p in doc["per_population"]] == [4, 5]
    default = set(compared(ADAPTED))  # tau_v only where the subjects adapt it
    assert set(doc["per_population"][0]["anova"]) == set(doc["replication"]) == default
    assert doc["replication"]["k_v"]["filter"]["populations"] == 2
    assert doc["design"] is None  # six subjects pooled: too few to design on
    assert png.stat().st_size > 10_000 and not (tmp_path / "rep-subjects.png").exists()
    assert main(["pilot", "experiment", "subjects", "--populations", "2",
                 "--subjects", "3", "--scheduler", "inline",
                 "--motion-spread", "1.5", "--visual-delay-spread", "0.01"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "motion perception spread 1.5, visual delay sd 10 ms)" in out
    assert "calibrated for populations of 9, the thesis' size; with 3" in out
    assert (
        "(no design of experiments: it pools at least 40 subjects; these populations have 6)" in out
    )


def test_halves_say_how_sure_a_choice_of_settings_is(monkeypatch):
    """The difference of two settings' log densities is the replications' own; halves of the
    populations (every one of the 924 of twelve, or random ones) give its spread; a setting
    whose effects sit nearer the thesis wins in nearly every half, one barely different does
    not win in every half."""
    from twin.pilot.studies import compare_settings
    from twin.pilot.studies.compare_settings import log_density_difference

    results = [PopulationResult(planted_rows(s, subjects=9), {}, s) for s in range(12)]
    results = [PopulationResult(r.rows, anova(r.rows), r.seed) for r in results]
    near = replicate(results)

    def weaker(rep, by):  # every effect's F scaled down: d_z further from the thesis'
        effects = tuple(dataclasses.replace(e, signed_f=tuple(by * f for f in e.signed_f))
                        for e in rep.effects)  # fmt: skip
        return dataclasses.replace(rep, effects=effects)

    d = log_density_difference(near, near)
    assert d.difference == 0.0 and d.low == d.high == 0.0 and d.share == 0.0
    other = weaker(near, 0.25)
    d = log_density_difference(near, other)
    assert d.difference == pytest.approx(near.log_density - other.log_density, rel=1e-9)
    assert 0 < d.low < d.high and d.share > 0.95 and d.exact and d.resamples == 924
    close = log_density_difference(near, weaker(near, 0.97))
    assert abs(close.difference) < 0.1 * d.difference and close.share < 0.95, close
    assert d.format().endswith("higher in 100.0% of 924 (all) halves")
    monkeypatch.setattr(compare_settings, "ALL_HALVES", 100)  # too many: random halves
    r = log_density_difference(near, other, resamples=500, seed=3)
    assert not r.exact and r.resamples == 500 and r.difference == d.difference
    assert r.share > 0.95 and abs(r.low - d.low) < 0.2 * (d.high - d.low)
    assert r == log_density_difference(near, other, resamples=500, seed=3)  # seeded
    with pytest.raises(SignalError, match="same populations"):
        log_density_difference(near, replicate(results[:6]))
    with pytest.raises(SignalError, match="at least 100 random halves"):
        log_density_difference(near, near, resamples=10)
    with pytest.raises(SignalError, match="at least 4 populations"):
        log_density_difference(*[replicate(results[:3])] * 2)
    broken = dataclasses.replace(near, effects=(dataclasses.replace(
        near.effects[0], signed_f=(float("nan"),) * 12), *near.effects[1:]))  # fmt: skip
    with pytest.raises(SignalError, match="not finite"):
        log_density_difference(near, broken)
