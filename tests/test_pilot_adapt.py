"""The adaptive pilot (pilot.models.adapt), the Chapter 6 statistics (pilot.studies.population)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from twin.cli.main import main
from twin.core.errors import SignalError
from twin.pilot.models.adapt import (
    ADAPTED,
    EQUALISATION,
    SPEED_ACCURACY,
    SPEED_ACCURACY_EXPONENT,
    Task,
    adapt,
    predict,
    stable,
    visual_noise_ratio,
)
from twin.pilot.models.pitch import PitchPilot, simulate_pitch
from twin.pilot.studies.population import COMPARED, FACTORS, MEASURES, anova, levels


@pytest.fixture(scope="module")
def srs_and_filter():
    """The default subject adapted to condition 1 (SRS) and condition 5 (1 Hz filter)."""
    return adapt("condition-1"), adapt("condition-5")


def test_behind_the_1_hz_filter_the_pilot_drops_motion_and_lowers_its_crossover(srs_and_filter):
    """§6.4 (Tables 6.4-6.7): with the 1 Hz filter K_m fell to about zero, K_v fell, the
    visual lead rose, both crossovers fell and both phase margins rose, the neuromuscular
    frequency fell; var(e) rose and var(u) fell. The adapted pilot must do each of these by
    itself."""
    srs, filt = srs_and_filter
    assert srs.pilot.k_m > 0.2
    assert filt.pilot.k_m < 0.05 * srs.pilot.k_m
    assert filt.pilot.k_v < srs.pilot.k_v
    assert filt.pilot.t_lead > srs.pilot.t_lead
    assert filt.loops.crossover_d < srs.loops.crossover_d
    assert filt.loops.crossover_t < srs.loops.crossover_t
    assert filt.loops.phase_margin_d > srs.loops.phase_margin_d
    assert filt.loops.phase_margin_t > srs.loops.phase_margin_t
    assert filt.pilot.omega_nm < srs.pilot.omega_nm
    assert filt.performance.var_e > srs.performance.var_e
    assert filt.performance.var_u < srs.performance.var_u


def test_the_neuromuscular_tuning_is_chosen_inside_its_range(srs_and_filter):
    """The remnant a stiff arm passes to the stick bounds omega_nm from above, the phase a
    slow one costs from below: the optimum lies inside the bounds, not on them, in a band
    around the 6-16 rad/s and 0.1-0.5 that pilot models identify."""
    for a in srs_and_filter:
        assert 6.0 < a.pilot.omega_nm < 16.0
        assert 0.1 < a.pilot.zeta_nm < 0.5


def test_a_pilot_with_fixed_limitations_keeps_its_neuromuscular_system():
    """``adapted=EQUALISATION`` is the model before the neuromuscular tuning adapted; unknown
    names are refused."""
    mine = dataclasses.replace(PitchPilot(), omega_nm=9.0, zeta_nm=0.3)
    a = adapt("condition-5", mine, adapted=EQUALISATION)
    assert (a.pilot.omega_nm, a.pilot.zeta_nm) == (9.0, 0.3)
    assert a.to_dict()["adapted"] == list(EQUALISATION)
    with pytest.raises(SignalError, match=r"among k_v, t_lead.*tau_v; got tau_m"):
        adapt("condition-5", adapted=("k_v", "tau_m"))
    with pytest.raises(SignalError, match="got none"):
        adapt("condition-5", adapted=())
    with pytest.raises(SignalError, match=r"visual delay to adapt must be > 0 s"):
        adapt("condition-5", dataclasses.replace(mine, tau_v=0.0), adapted=(*ADAPTED, "tau_v"))
    with pytest.raises(SignalError, match="sequence of names; got the string 'k_v'"):
        adapt("condition-5", adapted="k_v")


def test_a_population_refuses_bad_choices_before_flying():
    """Checked before any subject flies: the run-to-run variation and the adapted names."""
    from twin.pilot.studies.population import run_population

    for sd in (float("nan"), -0.1, 1.5):
        with pytest.raises(SignalError, match=r"log-normal sd in \[0, 1\]"):
            run_population(2, 0, run_to_run_sd=sd)
    with pytest.raises(SignalError, match="got none"):
        run_population(2, 0, adapted=())


def test_the_anova_refuses_a_measure_constant_within_every_subject():
    """A measure that differs between subjects but not between conditions (a neuromuscular
    system that was not adapted) has no within-subject effect to test: refused, not an F."""
    rng = np.random.default_rng(5)
    rows = [{"subject": s, "condition": n, "filter": fb, "delay": dl, "noise": nz,
             **{m: n + s + rng.normal(0, 0.1) for m in COMPARED}, "omega_nm": 10.0 + s}
            for s in (1, 2, 3) for n, (fb, dl, nz) in LEVELS.items()]  # fmt: skip
    assert anova(rows, tuple(m for m in COMPARED if m != "omega_nm"))["k_v"]
    with pytest.raises(SignalError, match="omega_nm does not vary over the conditions"):
        anova(rows)


def test_the_adapted_pilot_beats_its_neighbours(srs_and_filter):
    """Optimality: moving any adapted parameter by 10 % raises the cost (or breaks the loop)."""
    task = Task.pitch("condition-1")
    a = srs_and_filter[0]
    for name in ADAPTED:
        for k in (0.9, 1.1):
            p = dataclasses.replace(a.pilot, **{name: getattr(a.pilot, name) * k})
            assert predict(p, task).cost >= a.performance.cost * (1 - 1e-6) or not stable(p, task)


def test_the_frequency_domain_prediction_matches_a_flown_run():
    """predict()'s var(e) and var(u) without remnant equal those of the pitch task flown in the
    time domain through the whole chain (condition 1, no noise) within 5 %."""
    pilot = PitchPilot()
    perf = predict(pilot, Task.pitch("condition-1"), noise_ratio=1e-12)
    run = simulate_pitch(pilot, "condition-1", 1, 0, 0.0)
    assert float(np.var(run.e)) == pytest.approx(perf.var_e, rel=0.05)
    assert float(np.var(run.u)) == pytest.approx(perf.var_u, rel=0.05)


def test_stability_is_nyquists():
    task = Task.pitch("condition-1")
    assert stable(PitchPilot(), task)
    assert not stable(dataclasses.replace(PitchPilot(), k_v=40.0), task)


def test_bad_weights_are_refused():
    with pytest.raises(SignalError, match="weight"):
        adapt("srs", weight=-1.0)
    with pytest.raises(SignalError, match="noise ratio"):
        adapt("srs", noise_ratio=float("nan"))


#: Table 6.3 by hand: condition -> (1 Hz filter, 35 ms delay, noise on).
LEVELS = {1: (0, 0, 0), 2: (0, 0, 1), 3: (0, 1, 0), 4: (0, 1, 1),
          5: (1, 0, 0), 6: (1, 0, 1), 7: (1, 1, 0), 8: (1, 1, 1)}  # fmt: skip


def test_the_anova_finds_planted_effects_and_keeps_the_json_contract():
    """Rows with planted effects (filter +1, delay -1, noise none; subject offsets, noise sd
    0.2) on every measure: filter F large, '+', delay F large, '-', p < 0.01 for both; the
    contract's keys and types. Levels from a hand-written Table 6.3."""
    rng = np.random.default_rng(3)
    rows = []
    for s in range(1, 7):
        offset = rng.normal(0, 1)
        for n, (fb, dl, nz) in LEVELS.items():
            assert levels(n) == {"filter": fb, "delay": dl, "noise": nz}
            values = {m: offset + fb - dl + rng.normal(0, 0.2) for m in COMPARED}
            rows.append({"subject": s, "condition": n, "filter": fb, "delay": dl, "noise": nz,
                         **values})  # fmt: skip
    result = anova(rows)
    doc = json.loads(json.dumps({"anova": result}))
    assert set(MEASURES) <= set(doc["anova"])
    for m in MEASURES:
        assert set(doc["anova"][m]) == set(FACTORS)
        f, d = doc["anova"][m]["filter"], doc["anova"][m]["delay"]
        assert f["F"] > 50 and f["p"] < 0.01 and f["direction"] == "+"
        assert d["F"] > 50 and d["p"] < 0.01 and d["direction"] == "-"
        for factor in FACTORS:
            assert isinstance(doc["anova"][m][factor]["F"], float)
            assert doc["anova"][m][factor]["direction"] in "+-"


def test_the_visual_remnant_carries_the_cost_of_speed():
    """The speed-accuracy trade-off: processing in half the pilot's own visual delay
    multiplies the visual observation noise by 2^k; not adapted, the visual ratio is the
    common one, and a visual ratio equal to it predicts what the common one does."""
    own = PitchPilot()
    fast = dataclasses.replace(own, tau_v=own.tau_v / 2)
    assert visual_noise_ratio(fast, own, 0.01, ADAPTED) is None
    assert visual_noise_ratio(fast, own, 0.01, (*ADAPTED, *SPEED_ACCURACY)) == pytest.approx(
        0.01 * 2**SPEED_ACCURACY_EXPONENT)  # fmt: skip
    task = Task.pitch("condition-1")
    same, plain = predict(own, task, 0.03, 0.01, 0.01), predict(own, task, 0.03, 0.01)
    assert (same.var_e, same.var_u) == pytest.approx((plain.var_e, plain.var_u), rel=1e-12)
    noisier = predict(own, task, 0.03, 0.01, 0.04)
    assert noisier.var_e > plain.var_e and noisier.var_u > plain.var_u


def test_a_pilot_who_perceives_motion_less_well_uses_it_less():
    """The motion channel's own observation noise: a felt-rate ratio equal to the common one
    predicts what the common one does; more noise on the felt rate (none on the display)
    raises var(e), and the pilot adapted to it uses motion less (lower K_m) and makes up
    with visual lead, monotonically over a factor of 4 each way."""
    own, task = PitchPilot(), Task.pitch("condition-1")
    same, plain = predict(own, task, 0.03, 0.01, None, 0.01), predict(own, task, 0.03, 0.01)
    assert (same.var_e, same.var_u) == pytest.approx((plain.var_e, plain.var_u), rel=1e-12)
    assert predict(own, task, 0.03, 0.01, None, 0.04).var_e > plain.var_e
    pilots = [adapt("condition-1", motion_noise=m).pilot for m in (0.25, 1.0, 4.0)]
    assert pilots[0].k_m > pilots[1].k_m > pilots[2].k_m > 0
    assert pilots[0].t_lead < pilots[1].t_lead < pilots[2].t_lead
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(SignalError, match="motion channel"):
            adapt("condition-1", motion_noise=bad)


def test_subjects_differ_in_how_well_they_perceive_motion():
    """Each subject's motion noise (relative to its visual) is log-normal with the stated
    spread, drawn from its own stream: the other draws are those of a population drawn
    without it (its delays, neuromuscular system and priorities from the first stream)."""
    from twin.pilot.studies.population import SUBJECT_SPREAD, subjects
    from twin.pilot.studies.spread import MOTION_NOISE_SD, Spread

    many = subjects(400, seed=3)
    logs = np.log([s.motion_noise for s in many])
    assert abs(np.mean(logs)) < 3 * MOTION_NOISE_SD / np.sqrt(400)
    assert np.std(logs, ddof=1) == pytest.approx(MOTION_NOISE_SD, rel=0.15)
    rng = np.random.default_rng(np.random.SeedSequence([3, 14]))
    first = rng.normal(*SUBJECT_SPREAD["tau_v"])
    assert many[0].limitations.tau_v == max(first, 0.3 * SUBJECT_SPREAD["tau_v"][0])
    assert [s.motion_noise for s in subjects(5, seed=3)] == [s.motion_noise for s in many[:5]]
    # every subject's other draws are the same whatever the spread; at 0 (or -0) all are 1
    flat, wide = subjects(9, 3, Spread(motion=0.0)), subjects(9, 3, Spread(motion=2.0))
    zero = subjects(9, 3, Spread(-0.0))
    assert [s.motion_noise for s in flat] == [1.0] * 9 == [s.motion_noise for s in zero]
    for a, b, c in zip(flat, wide, many[:9], strict=True):
        assert (a.limitations, a.weight, a.noise_ratio) == (b.limitations, b.weight,
                                                            b.noise_ratio)  # fmt: skip
        assert (a.limitations, a.weight, a.noise_ratio) == (c.limitations, c.weight,
                                                            c.noise_ratio)  # fmt: skip


def test_subjects_differ_in_visual_delay_by_the_spread_set():
    """The visual delay's sd is a setting: its draws are the same standard deviates scaled,
    so one seed's subjects are the same people more or less alike in visual delay, and all
    their other draws are unchanged."""
    from twin.pilot.studies.population import subjects
    from twin.pilot.studies.spread import Spread

    many = subjects(400, seed=5, spread=Spread(visual_delay=0.02))
    tau_v = np.array([s.limitations.tau_v for s in many])
    assert abs(tau_v.mean() - 0.30) < 3 * 0.02 / np.sqrt(400)
    assert np.std(tau_v, ddof=1) == pytest.approx(0.02, rel=0.15)
    reference = subjects(9, 5, Spread(visual_delay=0.03))
    for spread in (Spread(visual_delay=0.0), Spread(visual_delay=0.01), Spread(1.0, 0.03)):
        other = subjects(9, 5, spread)
        for a, b in zip(reference, other, strict=True):
            assert dataclasses.replace(a.limitations, tau_v=0.3) == dataclasses.replace(
                b.limitations, tau_v=0.3)  # fmt: skip
            assert (a.weight, a.noise_ratio) == (b.weight, b.noise_ratio)
            want = 0.30 + spread.visual_delay * (a.limitations.tau_v - 0.30) / 0.03
            assert b.limitations.tau_v == pytest.approx(want, abs=1e-15)
    assert {s.limitations.tau_v for s in subjects(9, 5, Spread(visual_delay=0.0))} == {0.30}


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (
            {"motion": float("nan")},
            r"motion perception's spread must be a log-normal sd in \[0, 3\]",
        ),
        ({"motion": 3.5}, r"motion perception's spread .* got 3.5"),
        ({"visual_delay": -0.01}, r"visual delay's spread must be an sd in s in \[0, 0.1\]"),
        ({"visual_delay": float("inf")}, r"visual delay's spread .* got inf"),
        ({"visual_delay": "fast"}, r"visual delay's spread .* got 'fast'"),
        ({"visual_delay": "0.01"}, r"visual delay's spread .* got '0.01'"),
        ({"motion": True}, r"motion perception's spread .* got True"),
    ],
)
def test_a_spread_out_of_range_is_refused_naming_it(kwargs, message):
    from twin.pilot.studies.population import subjects
    from twin.pilot.studies.spread import Spread

    with pytest.raises(SignalError, match=message):
        Spread(**kwargs)
    assert Spread(-0.0, -0.0).to_dict() == {"motion_spread": 0.0, "visual_delay_sd": 0.0}
    assert str(Spread(-0.0, -0.0).motion) == "0.0"
    with pytest.raises(TypeError, match=r"spread must be a twin\.pilot\.studies\.spread\.Spread"):
        subjects(3, 0, 0.5)


def test_a_repetition_flies_with_the_subjects_motion_perception():
    """Without run-to-run variation a repetition is the adapted pilot, and its predicted
    performance is the adaptation's: the subject's motion noise is carried into both (a
    repetition predicted without it would differ)."""
    from twin.pilot.studies.population import Subject, _repetition

    subject = Subject(1, PitchPilot(), 0.03, 0.01, motion_noise=2.4)
    task = Task.pitch("condition-1")
    a = adapt(task, subject.limitations, subject.weight, subject.noise_ratio,
              motion_noise=subject.motion_noise)  # fmt: skip
    pilot, perf = _repetition(a, subject, task, np.random.default_rng(0), 0.0)
    assert pilot == a.pilot
    assert (perf.var_e, perf.var_u, perf.cost) == pytest.approx(
        (a.performance.var_e, a.performance.var_u, a.performance.cost), rel=1e-12)  # fmt: skip
    alike = predict(a.pilot, task, 0.03, 0.01)
    assert abs(alike.cost / perf.cost - 1) > 1e-3


def test_population_measures_follow_what_was_adapted():
    """tau_v is among the ANOVA's measures (beside Table 6.7's F 35.8) only where the subjects
    adapt it; a subject's rows carry it either way."""
    from twin.pilot.studies.population import population_result
    from twin.pilot.studies.spread import Spread

    rng = np.random.default_rng(4)
    flown = [[{"subject": s, "condition": n, "filter": fb, "delay": dl, "noise": nz,
               **{m: s + fb + rng.normal(0, 0.1) for m in COMPARED}}
              for n, (fb, dl, nz) in LEVELS.items()] for s in (1, 2, 3)]  # fmt: skip
    assert "tau_v" not in population_result(flown, 0, ADAPTED, 0.1, Spread()).anova
    with_delay = population_result(flown, 0, (*ADAPTED, *SPEED_ACCURACY), 0.1, Spread())
    assert with_delay.anova["tau_v"]["filter"]["direction"] == "+"
    assert "tau_v" in with_delay.format_table()


def test_an_adapted_pilot_without_motion_flies_as_predicted(srs_and_filter):
    """Behind the 1 Hz filter the adapted K_m is 0: the pilot flies (time domain, the whole
    chain) and its var(e), var(u) without remnant match the frequency-domain prediction
    within 5 %."""
    pilot = srs_and_filter[1].pilot
    assert pilot.k_m == 0.0
    perf = predict(pilot, Task.pitch("condition-5"), noise_ratio=1e-12)
    run = simulate_pitch(pilot, "condition-5", 1, 0, 0.0)
    assert float(np.var(run.e)) == pytest.approx(perf.var_e, rel=0.05)
    assert float(np.var(run.u)) == pytest.approx(perf.var_u, rel=0.05)


def test_cli_adapt_prints_parameters_and_margins(capsys):
    assert main(["pilot", "adapt", "condition-5", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["pilot"]["k_m"] < 0.05
    assert doc["crossover_disturbance_rad_s"] > 0
    assert main(["pilot", "experiment", "subjects", "--subjects", "1"]) == 2
    assert "--subjects: must be an integer in [2, 1,000]" in capsys.readouterr().err
    assert main(["pilot", "adapt", "srs", "--weight", "0"]) == 2
    assert "--weight: must be a number in (0, 1000]; got 0" in capsys.readouterr().err
    assert main(["pilot", "experiment", "fixed", "--fixed-neuromuscular"]) == 2
    assert "unrecognized arguments: --fixed-neuromuscular" in capsys.readouterr().err
    assert main(["pilot", "adapt", "condition-5", "--fixed-neuromuscular", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["adapted"] == list(EQUALISATION)
    assert doc["pilot"]["omega_nm"] == PitchPilot().omega_nm
    assert main(["pilot", "experiment", "fixed", "--adapt-visual-delay"]) == 2
    assert "unrecognized arguments: --adapt-visual-delay" in capsys.readouterr().err
    # the fixed pilot has no subjects: refused, not silently ignored
    assert main(["pilot", "experiment", "fixed", "--subjects", "3"]) == 2
    assert "unrecognized arguments: --subjects 3" in capsys.readouterr().err


@pytest.mark.slow
def test_a_pilot_who_trades_speed_for_remnant_processes_faster_behind_the_filter(capsys):
    """Table 6.7 (tau_v, F 35.80, lower with the 1 Hz filter; the thesis: "the visual cues
    were processed faster" where they had to give the lead, §6.4.2.2). Without any assumed
    cost of speed: at a fixed visual delay, the adapted cost rises faster with tau_v behind the
    filter (1.6e-4 against 1.2e-4 per s at 0.25-0.35 s), so any cost of speed that is convex in
    tau_v puts the optimum lower there. With the trade-off of visual_noise_ratio: on the SRS
    baseline the pilot keeps its own delay within 5 % (how k was chosen), behind the filter
    it processes faster, and the other filter effects of the first test still hold."""
    slopes = []
    for n in (1, 5):
        cost = [adapt(f"condition-{n}", dataclasses.replace(PitchPilot(), tau_v=t)).performance.cost
                for t in (0.25, 0.35)]  # fmt: skip
        slopes.append((cost[1] - cost[0]) / 0.1)
    assert slopes[1] > 1.15 * slopes[0] > 0, slopes
    assert main(["pilot", "adapt", "condition-1", "--adapt-visual-delay", "--json"]) == 0
    srs = json.loads(capsys.readouterr().out)
    assert main(["pilot", "adapt", "condition-5", "--adapt-visual-delay", "--json"]) == 0
    filt = json.loads(capsys.readouterr().out)
    assert srs["adapted"][-1] == "tau_v"
    own = PitchPilot().tau_v
    assert srs["pilot"]["tau_v"] == pytest.approx(own, rel=0.05)
    assert filt["pilot"]["tau_v"] < srs["pilot"]["tau_v"]
    assert filt["pilot"]["k_m"] < 0.05 * srs["pilot"]["k_m"]
    assert filt["crossover_target_rad_s"] < srs["crossover_target_rad_s"]
    assert filt["var_u_deg2"] < srs["var_u_deg2"]


@pytest.mark.slow
def test_nine_adaptive_subjects_predict_the_filter_effects_of_chapter_6():
    """Tables 6.4-6.7 with the thesis' nine participants (§6.3.4), five repetitions each, over
    five seeded populations (an ANOVA on simulated subjects is a draw, so its agreement is
    counted over draws): in at least 4 of 5 the 1 Hz filter's effects on var(e), the
    disturbance crossover, both phase margins, K_v, K_m, t_lead, t_lag and omega_nm (Table 6.7)
    have the thesis' direction with p < 0.05, and delay and noise have no significant effect
    on the disturbance crossover; on the target crossover they have none in at least 3 of 5.

    And as a replication (twin.pilot.studies.replication): the median effect over the populations
    has the thesis' direction for every filter effect of Tables 6.4-6.7, including the three that
    single populations miss most (var(u), the target crossover, zeta_nm); the thesis' target
    crossover effect is a plausible draw of the twin's populations (predictive p >= 0.05;
    over 20 populations p = 0.33, docs). And the default population (seed 0) meets the
    issue's acceptance at once."""
    from twin.pilot.studies.design import ACCEPTANCE
    from twin.pilot.studies.replication import run_populations

    rep, results = run_populations(5, 9, 0, scheduler="local:2")
    checked = {(m, "filter") for m in ("var_e", "crossover_disturbance_rad_s", "k_v", "k_m",
                                       "phase_margin_disturbance_deg", "phase_margin_target_deg",
                                       "t_lead", "t_lag", "omega_nm")}  # fmt: skip
    checked |= {("crossover_disturbance_rad_s", f) for f in ("delay", "noise")}
    target = {("crossover_target_rad_s", f) for f in ("delay", "noise")}
    hits = dict.fromkeys(checked | target, 0)
    for result in results:
        agree = result.agreement()
        for measure, factor in hits:
            hits[measure, factor] += agree[measure][factor]
    missed = {k: v for k, v in hits.items() if v < (4 if k in checked else 3)}
    assert not missed, missed
    # the acceptance at once, on what `twin pilot experiment subjects` flies by
    # default (seed 0): one draw; over 20 populations it holds in 39 % (28-50 %) of
    # nine-subject experiments, 43 % were the thesis' conclusions the truth (docs)
    agree = results[0].agreement()
    assert results[0].seed == 0 and all(agree[m][f] for m, f in ACCEPTANCE), agree
    for e in rep.effects:
        if e.factor == "filter":
            assert np.sign(e.quantiles()[1]) == (-1 if e.thesis_direction == "-" else 1), e
    assert rep.effect("crossover_target_rad_s", "filter").plausible, rep.format_table()


@pytest.mark.slow
def test_nearly_every_adapted_subject_flies_with_less_control_activity_behind_the_filter():
    """Table 6.4 (var(u), F 15.00, lower with the 1 Hz filter, "mainly caused by a higher
    fraction of the remnant variance", §6.4.1) and Table 6.5 (target crossover, F 5.98, lower):
    the nine subjects of a population, each adapted to conditions 1 and 5 without run-to-run
    variation, fly with less control activity behind the filter - at least 8 of 9 - and a
    lower target crossover - at least 7 of 9; their neuromuscular frequency falls (Table 6.7,
    F 53.11) in all nine."""
    from twin.core.tasks.engine import Engine
    from twin.pilot.studies.population import filter_effect, subjects

    subs = subjects(9, 0)
    with Engine("local:2") as engine:
        inputs = [{"subject": s.number} for s in subs]
        effects = engine.map(filter_effect, [(s,) for s in subs], inputs, "subjects").values()
    lower = {m: sum(e[m][1] < e[m][0] for e in effects)
             for m in ("var_u", "crossover_target_rad_s", "omega_nm")}  # fmt: skip
    assert lower["var_u"] >= 8, lower
    assert lower["crossover_target_rad_s"] >= 7, lower
    assert lower["omega_nm"] == 9, lower


@pytest.mark.slow
def test_behind_the_filter_the_motion_delay_is_not_identifiable():
    """Table 6.7 (tau_m, F 140.10: behind the 1 Hz filter "significantly reduced and attained
    values close to zero", with K_m). The adapted pilot does not use motion there (K_m = 0),
    so tau_m acts on nothing: fitted to its runs (15 % remnant) the MLE reports K_m near zero
    (as the thesis' did) and tau_m not identifiable, whatever value the fit lands on; where
    the pilot uses motion (condition 1) tau_m is identified within two bounds of its own."""
    from twin.chain.config import motion_system
    from twin.pilot.identification.mle import fit_pitch_pilot
    from twin.pilot.studies.experiment import pitch_remnant_scale

    for n in (1, 5):
        truth = adapt(f"condition-{n}").pilot
        runs = simulate_pitch(truth, f"condition-{n}", 3, 11, pitch_remnant_scale(truth))
        for u in runs.u:
            fit = fit_pitch_pilot(runs.ft, runs.fd, u, motion_system(f"condition-{n}"))
            if n == 1:
                assert "tau_m" not in fit.unidentifiable
                assert abs(fit.pilot.tau_m - truth.tau_m) <= 2 * fit.crlb["tau_m"]
            else:
                assert truth.k_m == 0.0 and fit.pilot.k_m < 0.15
                assert "tau_m" in fit.unidentifiable
