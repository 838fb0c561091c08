"""Chapter 6 measured as the thesis did: the pilot model identified from simulated runs."""

import json

import numpy as np
import pytest

from twin.cli.main import main
from twin.core.errors import SignalError
from twin.pilot.studies.identified import IDENTIFIED, identified_population, identified_subject
from twin.pilot.studies.population import fly_subject, subjects


@pytest.fixture(scope="module")
def subject_rows():
    """One subject of population 0: its pilots' own measures and the identified ones."""
    s = subjects(2, 0)[0]
    return fly_subject(s, 0), identified_subject(s, 0)


@pytest.mark.slow  # the subject's identification takes 40-50 s
def test_the_identified_measures_are_those_of_the_pilots_flown(subject_rows):
    """Same subject, same pilots: where the pilot uses what it is fitted for, the MLE finds
    its parameters (K_v, omega_nm within 15 %, K_m within 25 % where it is used), the model
    fits as the remnant allows (chi-square per degree of freedom 0.3-3), and every measure
    the thesis compared is there, tau_m among them."""
    own, identified = subject_rows
    for a, b in zip(own, identified, strict=True):
        assert a["condition"] == b["condition"] and set(IDENTIFIED) <= set(b)
        assert b["k_v"] == pytest.approx(a["k_v"], rel=0.15)
        assert b["omega_nm"] == pytest.approx(a["omega_nm"], rel=0.15)
        if a["k_m"] > 0:
            assert b["k_m"] == pytest.approx(a["k_m"], rel=0.25)
        assert 0.3 < b["chi2_per_dof"] < 3.0
        assert np.isfinite(b["tau_m"])


@pytest.mark.slow  # the subject's identification takes 40-50 s
def test_tau_m_is_identified_where_motion_is_used_and_not_behind_the_filter(subject_rows):
    """Behind the 1 Hz filter the adapted subject does not use motion (K_m = 0), so the fit
    cannot see tau_m: flagged, not hidden (Table 6.7's tau_m is an estimate of nothing there)."""
    own, identified = subject_rows
    for a, b in zip(own, identified, strict=True):
        assert b["tau_m_identifiable"] == float(a["k_m"] > 0)


def test_identify_is_refused_where_it_means_nothing(capsys):
    for argv, needs in ((["subjects", "--feedthrough", "0.5"], "--identify"),
                        (["fixed", "--identify"], "unrecognized arguments: --identify"),
                        (["subjects", "--identify", "--populations", "3",
                          "--feedthrough", "1.5"], "--feedthrough: must be a")):  # fmt: skip
        assert main(["pilot", "experiment", *argv]) == 2
        assert needs in capsys.readouterr().err
    with pytest.raises(SignalError, match=r"feedthrough must be .* \[0, 1\]; got nan"):
        identified_population(2, 0, feedthrough=float("nan"))


@pytest.mark.slow
def test_nine_subjects_identified_find_the_large_filter_effects(capsys):
    """A population of nine measured as the thesis did (the CLI's JSON): the filter's effects
    the thesis found with F above 40 (Tables 6.4-6.7: disturbance crossover 159.68, its phase
    margin 68.95, var(e) 357.79, K_v 43.36, K_m 66.20, t_lead 60.96, t_lag 132.26, omega_nm
    53.11) come out in their direction with p < 0.05."""
    assert main(["pilot", "experiment", "subjects", "--identify", "--json",
                 "--quiet"]) == 0  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    assert out["identified"] == 0.0 and "tau_m" in out["anova"]
    for m in ("crossover_disturbance_rad_s", "phase_margin_disturbance_deg", "var_e", "k_v",
              "k_m", "t_lead", "t_lag", "omega_nm"):  # fmt: skip
        assert out["agreement"][m]["filter"], (m, out["anova"][m]["filter"])


def test_populations_measured_differently_are_not_pooled():
    """A population whose pilot model was identified (with or without a feedthrough) is not
    comparable with one whose measures are the pilots' own (replication.alike)."""
    from planted import planted_rows

    from twin.pilot.studies.population import PopulationResult, anova
    from twin.pilot.studies.replication import alike

    def population(seed, identified):
        rows = planted_rows(seed)
        return PopulationResult(rows, anova(rows, ("k_v",)), seed, identified=identified)

    assert alike([population(0, None), population(1, None)]) == 9
    for identified in (0.0, 0.5):
        with pytest.raises(SignalError, match="identification"):
            alike([population(0, None), population(1, identified)])


@pytest.mark.slow
def test_identified_populations_replicate_as_one_flown_alone(capsys):
    """Populations measured as the thesis did, flown together for a replication (the CLI's
    JSON), are each the population flown alone (same ANOVA), tau_m is among the replicated
    effects, and each population carries its fits' chi-square per dof."""
    assert main(["pilot", "experiment", "subjects", "--identify", "--populations",
                 "2", "--subjects", "2", "--seed", "5", "--json", "--quiet"]) == 0  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    alone = identified_population(2, 6)
    assert out["per_population"][1]["anova"] == json.loads(json.dumps(alone.anova))
    assert "filter" in out["replication"]["tau_m"]
    for entry in out["per_population"]:
        lo, mid, hi = entry["chi2_per_dof_5_50_95"]
        assert 0.2 < lo <= mid <= hi < 5.0


@pytest.mark.slow  # the subject's identification takes 40-50 s
def test_the_condition_figure_of_an_identified_population_shows_the_fits(subject_rows, tmp_path):
    """Fig 6.5-6.9 of identified measures: tau_v, tau_m and each fit's chi-square per dof too."""
    from twin.pilot.studies.population import PopulationResult

    _, identified = subject_rows
    fig = PopulationResult(identified, {}, 0, identified=0.0).plot_conditions(tmp_path / "c.png")
    titles = [ax.get_title() for ax in fig.axes]
    assert {"tau_v (Fig 6.9a)", "tau_m (Fig 6.9b)", "fit chi-square per dof"} <= set(titles)
    assert (tmp_path / "c.png").stat().st_size > 0
