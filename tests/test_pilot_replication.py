"""Chapter 6 replicated over populations (twin.pilot.replication)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import stats

from twin.cli.main import main
from twin.errors import SignalError
from twin.pilot import population, replication
from twin.pilot.population import COMPARED, PopulationResult, anova, levels
from twin.pilot.replication import agreement_probability, replicate, run_populations
from twin.thesis import TABLE_6_3, TABLES_6_4_TO_6_7


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


def planted_rows(seed: int, subjects: int = 9, reversed_measure: str = "k_v") -> list[dict]:
    """Rows with the thesis' filter directions planted (effect 1, noise sd 0.3, subject
    offsets sd 1), no delay or noise effect, and ``reversed_measure``'s filter effect reversed."""
    rng = np.random.default_rng(seed)
    rows = []
    for s in range(1, subjects + 1):
        offset = rng.normal(0, 1)
        for n in TABLE_6_3:
            lv = levels(n)
            values = {}
            for m in COMPARED:
                sign = -1.0 if TABLES_6_4_TO_6_7[m]["filter"][1] == "-" else 1.0
                sign *= -1.0 if m == reversed_measure else 1.0
                values[m] = offset + sign * lv["filter"] + rng.normal(0, 0.3)
            rows.append({"subject": s, "condition": n, **lv, **values})
    return rows


def test_a_replication_summarises_planted_populations_and_flags_a_reversed_effect(tmp_path):
    """Five populations with the filter effects planted in the thesis' direction except
    K_v's (reversed): var(u)'s and t_lead's agree in 5 of 5 and are plausible; K_v's agrees in
    none, and with the thesis' F 43.36 (almost certain to agree) that is flagged as the
    twin's; the signed F carry the planted directions; JSON, table and figure."""
    measures = ("var_u", "k_v", "t_lead")
    results = [PopulationResult(rows, anova(rows, measures), seed)
               for seed in range(5) for rows in [planted_rows(seed)]]  # fmt: skip
    rep = replicate(results)
    for m in measures:
        e = rep.effect(m, "filter")
        planted = TABLES_6_4_TO_6_7[m]["filter"][1]
        if m == "k_v":
            assert e.agreed == 0 and not e.plausible and e.p_so_few < 1e-6
            assert all(f > 0 for f in e.signed_f)  # reversed: K_v rose
        else:
            assert e.agreed == 5 and e.plausible, m
            assert all((f < 0) == (planted == "-") for f in e.signed_f), m
    flagged = [f"{e.measure}/{e.factor}" for e in rep.implausible()]
    assert [f for f in flagged if f.endswith("/filter")] == ["k_v/filter"]
    doc = json.loads(json.dumps(rep.to_dict()))
    k_v = doc["replication"]["k_v"]["filter"]
    assert k_v["thesis_F"] == 43.36 and k_v["agreed"] == 0 and k_v["populations"] == 5
    assert k_v["signed_F_5_95"][0] <= k_v["signed_F_median"] <= k_v["signed_F_5_95"][1]
    assert doc["seeds"] == list(range(5)) and doc["implausible"] == flagged
    table = rep.format_table()
    assert "<- the twin's" in table.splitlines()[2 + measures.index("k_v") * 3]
    assert rep.plot(str(tmp_path / "rep.png")) is not None
    assert (tmp_path / "rep.png").stat().st_size > 10_000
    with pytest.raises(SignalError, match="no effect 'k_x' x 'filter'; measures: "):
        rep.effect("k_x", "filter")


def test_a_replication_refuses_one_population_and_mixed_settings():
    rows = planted_rows(0, subjects=4)
    one = PopulationResult(rows, anova(rows), 0)
    with pytest.raises(SignalError, match="at least 2 populations; got 1"):
        replicate([one])
    other = PopulationResult(rows, anova(rows), 1, run_to_run_sd=0.05)
    with pytest.raises(SignalError, match="populations differ"):
        replicate([one, other])
    with pytest.raises(SignalError, match="at least 2 populations"):
        run_populations(1)
    with pytest.raises(SignalError, match="run-to-run variation must be"):
        run_populations(2, run_to_run_sd=float("nan"))


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
    assert main(["pilot", "experiment", "--populations", "3"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--populations counts populations of adaptive subjects" in err and "\n" not in err
    assert main(["pilot", "experiment", "--pilot", "adaptive", "--populations", "0"]) == 2
    assert "--populations: must be an integer in [1, 1,000]" in capsys.readouterr().err


def test_the_thesis_f_within_the_twins_spread_is_signed_only_where_the_thesis_gave_a_sign():
    from twin.pilot.replication import EffectReplication

    def effect(f, direction, signed):
        return EffectReplication("m", "filter", f, direction, signed, 0, 0.5)

    spread = (-10.0, -8.0, -6.0, -4.0, -2.0)
    assert effect(5.98, "-", spread).thesis_within  # -5.98 within [-9.6, -2.4]
    assert not effect(5.98, "+", spread).thesis_within  # +5.98 is not
    assert not effect(43.36, "-", spread).thesis_within
    assert effect(5.0, None, spread).thesis_within  # no sign: against |F| in [2.4, 9.6]
    assert not effect(0.5, None, spread).thesis_within


def test_cli_populations_json_and_figure(monkeypatch, tmp_path, capsys):
    """``--populations 2 --json --plot``: the summary, each population's ANOVA, the figure
    (a subject's rows stand in for flying it)."""
    monkeypatch.setattr(replication, "fly_subject", fake_fly)
    png = tmp_path / "rep.png"
    code = main(["pilot", "experiment", "--pilot", "adaptive", "--populations", "2",
                 "--subjects", "3", "--seed", "4", "--scheduler", "inline", "--json",
                 "--plot", str(png)])  # fmt: skip
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["seeds"] == [4, 5] and doc["subjects"] == 3
    assert [p["seed"] for p in doc["populations"]] == [4, 5]
    assert set(doc["populations"][0]["anova"]) == set(doc["replication"]) == set(COMPARED)
    assert doc["replication"]["k_v"]["filter"]["populations"] == 2
    assert png.stat().st_size > 10_000
