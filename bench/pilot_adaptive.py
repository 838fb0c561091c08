"""Chapter 6 with adaptive subjects and the MLE's honesty, measured in one run.

1. ``twin pilot experiment subjects --subjects 6`` wall time on both cores (goal
   <= 60 s on this 2-core machine); over 20 seeded populations of nine subjects (the
   thesis' participants), how often each main effect of Tables 6.4-6.7 agrees with the thesis
   (direction and p < 0.05 where it found an effect, p >= 0.05 where not), beside how often
   it would if the true effect were the thesis' own F, the twin's standardised effects over
   populations (median, 5-95 %) and whether the thesis is a plausible draw of them
   (:mod:`twin.pilot.studies.replication`; figure ``out/bench-chapter6-replication.png``);
   once with the default run-to-run variation of the adapted parameters (10 %), once (10
   populations) with half of it, as the variation is an assumption and the ANOVA's power
   depends on it.
2. The 1 Hz filter's effect on each of the first five populations' 45 subjects adapted
   without run-to-run variation (condition 5 against condition 1), for the pilot who adapts
   its equalisation and neuromuscular tuning and for one whose neuromuscular system is fixed
   (the model before): how many subjects go the thesis' way per measure.
3. Closed-loop MLE coverage: 200 seeded runs (``--coverage-runs``; 200 per seed, seeds 1, 2,
   ...: ``--coverage-runs 1200 --coverage-only --no-intervals`` gives the README's 1200
   five-repetition estimates of seeds 1-6, about 30 min on an idle machine, and with
   ``--coverage-seed 11`` the fresh ones of seeds 11-16) of a known pilot
   (condition 8, 15 % remnant, the thesis' level) fitted one by one (two workers); per
   parameter, among the estimates where it counted as identifiable, the fraction within 2
   Cramer-Rao sd of the truth, with the bound at the truth (the bound proper: does the
   estimator attain it?) and with the bound the fit reports (widened to cover the minima the
   data do not rule out, :mod:`twin.pilot.identification.minima`, over the profile of a parameter on
   an end of its range and over the fit with a weak parameter on the end it cannot be told from,
   and for the selection where the data rule a minimum out,
   :mod:`twin.pilot.identification.selection`; printed with how often, and by how much, it is wider
   than the bound at the estimate); and the fraction of all estimates whose likelihood-ratio
   interval (:mod:`twin.pilot.identification.profile`) holds the truth (goal >= 90 %). Each with its
   95 % Wilson interval: 50 estimates pin a coverage down to about +-8 %, 200 to about +-4 %. Once
   with one run per estimate, once with five repetitions averaged (the thesis' five per condition,
   §6.3.4). With ``--no-intervals`` the fits skip the intervals and the rule that flags by them.
4. The same coverage (480 estimates, no intervals) on data whose nuisance the twin's remnant
   model did not shape: condition 4 with half the remnant and a white stick-sensor noise of
   half u's sd added (five repetitions averaged), and a pilot the defaults are not (a lead
   with no lag, t_lag on the end of its range) on the same nuisance, one run each.
5. Subjects who also adapt their visual delay (``--visual-delay-only``, about 25 min): the
   speed-accuracy trade-off of :func:`twin.pilot.models.adapt.visual_noise_ratio` (an assumption):
   section 2's per-subject count and a replication over 10 populations, tau_v among the
   measures (Table 6.7: F 35.8, lower behind the filter). And Table 6.7's tau_m (F 140.1,
   "close to zero" behind the filter): the adapted pilot of conditions 1 and 5 flown 20 times
   each (15 % remnant) and fitted: is tau_m identifiable, and where do its estimates land?
   And measured as the thesis did (``--motion-delay-only``, about 70 s): 18 subjects adapted
   to conditions 1 and 5, five repetitions each, the MLE on their average; tau_m, K_m,
   t_lead, K_v and tau_v per condition and the d_z of their differences beside the thesis'.
6. Designing the next experiment on the twin's subjects (``--design-only``; about 40 min
   with ``--design-subjects 18``):
   section 1's 20 populations pooled (180 subjects, :mod:`twin.pilot.studies.design`) tell how often
   an experiment of N subjects agrees with the thesis on each effect, and from how many
   subjects it agrees on all of the acceptance's at once (every filter effect of the JSON
   contract found, delay and noise not found on either crossover) in 80 %; then
   ``DESIGN_CHECK_POPULATIONS`` fresh populations (seeds from 100) of ``--design-subjects``
   subjects (default: the fewest with which it does, or nine) are flown, and their
   agreements counted beside the prediction: is the design right about experiments it did
   not pool?
7. The subjects' unknown spreads against the thesis (``--spread-profile``, about 7 min a
   cell): ``SPREAD_POPULATIONS`` populations of nine (``--profile-populations``, from
   ``--profile-seed``) for each motion perception spread, visual-delay sd and run-to-run
   variation of ``SPREAD_GRID`` (``--profile-motion``, ``--profile-visual-delay``,
   ``--profile-run-to-run``; :mod:`twin.pilot.studies.spread`'s defaults are chosen here); per cell
   the log predictive density of the thesis' 36 effects
   (:attr:`twin.pilot.studies.replication.Replication.log_density`: higher, the thesis' results are
   likelier draws of the twin), how many are plausible draws, the filter effects' d_z beside
   the thesis', and how often nine subjects meet the acceptance at once (the design's); then
   every cell against the best on the same populations and on halves of them
   (:mod:`twin.pilot.studies.compare_settings`).

``--motion-spread SD`` and ``--visual-delay-spread S`` set the subjects' spreads for every
section but 7 (``--motion-spread 0 --visual-delay-spread 0.03``: the subjects before either,
with which the README's older Chapter 6 figures were measured).
"""

import argparse
import time
from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from statsmodels.stats.proportion import proportion_confint

from twin.chain.config import motion_system
from twin.core.errors import SignalError
from twin.core.tasks.engine import Engine
from twin.core.thesis import TABLES_6_4_TO_6_7
from twin.pilot.identification.mle import PARAMETERS, bound_at, fit_pitch_pilot
from twin.pilot.models.adapt import ADAPTED, EQUALISATION, SPEED_ACCURACY, adapt
from twin.pilot.models.pitch import Feedthrough, PitchPilot, simulate_pitch
from twin.pilot.studies.compare_settings import log_density_difference
from twin.pilot.studies.design import ACCEPTANCE, MAX_SUBJECTS, Design, design
from twin.pilot.studies.experiment import pitch_remnant_scale
from twin.pilot.studies.identified import MAX_FEEDTHROUGH
from twin.pilot.studies.population import (
    ADAPTATION_SD,
    PopulationResult,
    Subject,
    checked_settings,
    filter_effect,
    run_population,
    subjects,
)
from twin.pilot.studies.replication import run_populations
from twin.pilot.studies.spread import DEFAULT_SPREAD, MOTION_NOISE_SD, VISUAL_DELAY_SD, Spread

REPETITIONS, POPULATIONS, SUBJECTS = 5, 20, 9
#: Where section 1 draws the replication (``out/`` is not tracked).
FIGURE = "out/bench-chapter6-replication.png"
#: Populations whose subjects are adapted without run-to-run variation (section 2).
EFFECT_POPULATIONS = 5
#: The pilot of section 3: visual + display delay on the 10 ms simulation grid.
TRUTH = PitchPilot(tau_v=0.275)


#: Section 2's models: the pilot who adapts its equalisation and neuromuscular tuning, and
#: the one whose neuromuscular system is fixed (the model before).
MODELS = (("equalisation and neuromuscular tuning", ADAPTED),
          ("equalisation only (neuromuscular system fixed)", EQUALISATION))  # fmt: skip
#: Section 5's model: the visual delay adapted too.
VISUAL_DELAY = (
    ("equalisation, neuromuscular tuning and visual delay", (*ADAPTED, *SPEED_ACCURACY)),
)
#: Populations of section 5.
VISUAL_DELAY_POPULATIONS = 10
#: The subjects' spreads for every section but 7 (``--motion-spread``,
#: ``--visual-delay-spread``).
SETTINGS = {"spread": DEFAULT_SPREAD}
#: Section 7's grid by default (``--profile-motion``, ``--profile-visual-delay``,
#: ``--profile-run-to-run``): motion perception spreads, visual-delay sds (s) and run-to-run
#: variations; and populations per cell (``--profile-populations``).
SPREAD_GRID = {"motion": (0.5, 1.0), "visual_delay": (0.0, 0.01, 0.015, 0.02, 0.03),
               "run_to_run": (ADAPTATION_SD,)}  # fmt: skip
SPREAD_POPULATIONS = 10
#: Fresh populations flown to check section 6's design, and their first seed.
DESIGN_CHECK_POPULATIONS, DESIGN_CHECK_SEED = 20, 100


def main(
    runs: int = 200,
    coverage_only: bool = False,
    intervals: bool = True,
    nuisance_only: bool = False,
    visual_delay_only: bool = False,
    coverage_seed: int = 1,
) -> None:
    if nuisance_only:
        nuisance()
        return
    if visual_delay_only:
        visual_delay()
        return
    if coverage_only:
        coverage(runs, intervals, coverage_seed)
        return
    t0 = time.perf_counter()
    run_population(6, 0, scheduler="local:2", spread=SETTINGS["spread"])
    wall = time.perf_counter() - t0
    print(f"adaptive experiment, 6 subjects, 2 workers: {wall:.1f} s (goal <= 60 s)")
    design_check(populations(ADAPTATION_SD, POPULATIONS))
    populations(ADAPTATION_SD / 2, POPULATIONS // 2)
    subject_effects()
    coverage(runs, intervals, coverage_seed)
    nuisance()
    visual_delay()


def populations(sd: float, n: int, adapted: tuple[str, ...] = ADAPTED) -> list[PopulationResult]:
    """Section 1: agreement with Tables 6.4-6.7 over seeded populations, beside the agreement
    the thesis' own F predicts (:mod:`twin.pilot.studies.replication`); returns the populations."""
    rep, results = run_populations(n, SUBJECTS, 0, scheduler="local:2", run_to_run_sd=sd,
                                   spread=SETTINGS["spread"],
                                   adapted=adapted)  # fmt: skip
    full = sum(e.agreed == e.populations for e in rep.effects)
    print(f"{n} populations of {SUBJECTS} subjects (the thesis' nine), run-to-run variation "
          f"{sd:.0%}: {full} of {len(rep.effects)} main effects agree with Tables 6.4-6.7 in "
          "every population")  # fmt: skip
    print(rep.format_table())
    if sd == ADAPTATION_SD and adapted == ADAPTED:
        Path("out").mkdir(exist_ok=True)
        rep.plot(path=FIGURE)
        print(f"figure: {FIGURE}")
    return results


def spread_profile(grid: dict[str, tuple[float, ...]], n: int, seed: int = 0) -> None:
    """Section 7: the subjects' spreads and run-to-run variation profiled against Tables
    6.4-6.7, ``n`` populations of nine a cell from ``seed``; then each cell against the best
    on halves of the populations (:mod:`twin.pilot.studies.compare_settings`; from 4
    populations)."""
    filters = [(m, "filter") for m in TABLES_6_4_TO_6_7 if m not in ("tau_v", "tau_m")]
    head = " ".join(f"{m[:9]:>9s}" for m, _ in filters)
    print(f"\n{n} populations of {SUBJECTS} a cell, seeds {seed}-{seed + n - 1}")
    print(f"{'motion':>6s} {'tau_v sd':>8s} {'rr':>5s} {'log dens':>8s} {'plaus':>5s} "
          f"{'accept9':>7s} | {head}")  # fmt: skip
    cells = [(sd, Spread(m, v)) for sd in grid["run_to_run"] for m in grid["motion"]
             for v in grid["visual_delay"]]  # fmt: skip
    reps = []
    for k, (sd, spread) in enumerate(cells):
        rep, results = run_populations(n, SUBJECTS, seed, scheduler="local:2",
                                       run_to_run_sd=sd, spread=spread)  # fmt: skip
        reps.append(rep)
        plausible = len(rep.effects) - len(rep.implausible())
        accept = design(results, resamples=2).acceptance_at(SUBJECTS)
        if k == 0:
            thesis = " ".join(f"{rep.effect(m, f).thesis_d_z[0]:+9.2f}" for m, f in filters)
            print(f"{'thesis':>6s} {'':8s} {'':5s} {'':8s} {'':5s} {'':7s} | {thesis}")
        d = " ".join(f"{rep.effect(m, f).quantiles()[1]:+9.2f}" for m, f in filters)
        print(f"{spread.motion:6.2f} {spread.visual_delay:8.3f} {sd:5.2f} {rep.log_density:8.1f} "
              f"{plausible:3d}/{len(rep.effects)} {accept:7.2f} | {d}", flush=True)  # fmt: skip
    if len(cells) > 1 and n < 4:
        print("(no comparison on halves: it needs at least 4 populations a cell)")
    if len(cells) > 1 and n >= 4:
        best = max(range(len(cells)), key=lambda k: reps[k].log_density)
        sd, spread = cells[best]
        print(f"against the best ({spread.describe()}, run-to-run {sd:.0%}), on the same "
              "populations and on halves of them:")  # fmt: skip
        for (sd, spread), rep in zip(cells, reps, strict=True):
            if rep is not reps[best]:
                diff = log_density_difference(rep, reps[best]).format()
                print(f"  {spread.motion:4.2f} {spread.visual_delay:6.3f} {sd:4.2f}: {diff}")


def design_check(pool: list[PopulationResult], subjects_n: int | None = None) -> None:
    """Section 6: the design from the pooled populations, checked on fresh populations."""
    plan = design(pool)
    print(plan.format_table())
    Path("out").mkdir(exist_ok=True)
    plan.plot(path="out/bench-chapter6-subjects.png")
    win = plan.acceptance_window()
    n = subjects_n or (win[0] if win else SUBJECTS)
    plan.at(n)  # refuses a size beyond the design before anything flies
    t0 = time.perf_counter()
    _, fresh = run_populations(DESIGN_CHECK_POPULATIONS, n, DESIGN_CHECK_SEED,
                               spread=SETTINGS["spread"],
                               scheduler="local:2")  # fmt: skip
    print(f"\n{DESIGN_CHECK_POPULATIONS} fresh populations of {n} subjects (seeds "
          f"{DESIGN_CHECK_SEED}-{DESIGN_CHECK_SEED + DESIGN_CHECK_POPULATIONS - 1}, "
          f"{time.perf_counter() - t0:.0f} s)")  # fmt: skip
    compare_design(plan, fresh)


def compare_design(plan: Design, fresh: list[PopulationResult]) -> None:
    """Print the agreements of ``fresh`` populations beside ``plan``'s prediction for them.

    The prediction with its 5-95 % over the pool's resamples, the flown share with its 95 %
    Wilson interval; ``<- apart`` where the two intervals do not meet.
    """
    n = len({r["subject"] for r in fresh[0].rows})
    agree = [r.agreement() for r in fresh]

    def line(name: str, predicted: float, spread: np.ndarray, hits: int) -> str:
        lo, hi = proportion_confint(hits, len(fresh), method="wilson")
        apart = spread[0] > hi + 1e-9 or spread[1] < lo - 1e-9
        return (f"  {name:37s} predicted {predicted:4.2f} ({spread[0]:.2f}-{spread[1]:.2f})  "
                f"flown {hits:2d}/{len(fresh)} ({lo:.2f}-{hi:.2f})"
                + ("  <- apart" if apart else ""))  # fmt: skip

    print(f"agreements of {len(fresh)} populations of {n} beside the design's prediction "
          "(5-95 % over the pool's resamples; flown: 95 % Wilson interval)")  # fmt: skip
    spread = plan.spread_at(n)
    for k, (m, f) in enumerate(plan.effects):
        print(line(f"{m} {f}", plan.at(n)[k], spread[:, k], sum(a[m][f] for a in agree)))
    both = sum(all(a[m][f] for m, f in ACCEPTANCE) for a in agree)
    print(line("acceptance, all at once", plan.acceptance_at(n),
               plan.acceptance_spread_at(n), both))  # fmt: skip


def visual_delay() -> None:
    """Section 5: subjects who also trade their visual delay against the visual remnant, and
    the motion delay of a pilot who no longer uses motion."""
    subject_effects(VISUAL_DELAY)
    populations(ADAPTATION_SD, VISUAL_DELAY_POPULATIONS, VISUAL_DELAY[0][1])
    motion_delay()
    motion_delay_measured()


def motion_delay(runs: int = 20) -> None:
    """Section 5: tau_m fitted where the adapted pilot uses motion (condition 1) and where it
    does not (condition 5, K_m = 0)."""
    print(f"tau_m of the adapted default pilot, fitted to {runs} seeded runs each (15 % "
          "remnant): estimates median (5-95 %)")  # fmt: skip
    for n in (1, 5):
        config = f"condition-{n}"
        truth = adapt(config).pilot
        r = simulate_pitch(truth, config, runs, seed=11, remnant_scale=pitch_remnant_scale(truth))
        args = [(r.ft, r.fd, r.u[i], truth, config, False) for i in range(runs)]
        with Engine("local:2") as engine:
            done = engine.map(_fit, args, [{"run": i} for i in range(runs)], "fits").values()
        tau_m = np.array([f.pilot.tau_m for f, _ in done])
        k_m = np.array([f.pilot.k_m for f, _ in done])
        seen = sum("tau_m" not in f.unidentifiable for f, _ in done)
        print(f"  {config}: true K_m {truth.k_m:.3f}, tau_m {truth.tau_m:.3f} s; tau_m "
              f"identifiable in {seen} of {runs}; tau_m {_spread(tau_m)} s, below 0.05 s in "
              f"{np.sum(tau_m < 0.05)}; K_m {_spread(k_m)}")  # fmt: skip


def measured_as_the_thesis(subject: Subject, feedthrough: float = 0.0) -> dict[str, dict]:
    """One subject adapted to conditions 1 and 5, flown five repetitions each (15 % remnant
    of its condition-1 control power) and identified as the thesis did: the MLE on the
    averaged repetitions. With ``feedthrough`` > 0 the subject also has a passive path from
    the felt motion to the stick, that share of its condition-1 motion response at 3 rad/s
    (:class:`twin.pilot.models.pitch.Feedthrough`, the same in both conditions; not adapted to).
    Returns per condition the estimates, what was unidentifiable and chi-square per degree
    of freedom."""
    effect = filter_effect(subject)
    pilots = [replace(subject.limitations, **{k: effect[k][i] for k in ADAPTED}) for i in (0, 1)]
    scale = pitch_remnant_scale(pilots[0])
    path = Feedthrough.relative(feedthrough, pilots[0]) if feedthrough else None
    out = {}
    for pilot, n in zip(pilots, (1, 5), strict=True):
        config = motion_system(f"condition-{n}")
        runs = simulate_pitch(pilot, config, REPETITIONS, 1000 * subject.number + n, scale,
                              feedthrough=path)  # fmt: skip
        fit = fit_pitch_pilot(runs.ft, runs.fd, runs.u, config)
        out[n] = {**{k: getattr(fit.pilot, k) for k in PARAMETERS},
                  "unidentifiable": list(fit.unidentifiable),
                  "chi2_per_dof": fit.evidence["fit"]["ratio"]}  # fmt: skip
    return out


def motion_delay_measured(n_subjects: int = 18, feedthrough: float = 0.0) -> None:
    """Section 5: Table 6.7's tau_m as the thesis measured it - the twin's subjects' runs
    identified by the MLE - beside the thesis' F (140.1, lower behind the filter); with
    ``feedthrough``, subjects who also have a passive path of that relative size."""
    subs = subjects(n_subjects, 0, SETTINGS["spread"])
    with Engine("local:2") as engine:
        done = engine.map(measured_as_the_thesis, [(s, feedthrough) for s in subs],
                          [{"subject": s.number} for s in subs], "subjects").values()  # fmt: skip
    extra = (f", each with a passive feedthrough {feedthrough:g} of its condition-1 motion "
             "response at 3 rad/s (an assumption)") if feedthrough else ""  # fmt: skip
    print(f"\nTable 6.7 measured as the thesis did: {n_subjects} subjects adapted to conditions "
          f"1 and 5{extra}, five repetitions each (15 % remnant), the MLE on their average; "
          "median (5-95 %) per condition and d_z of the paired differences "
          "(condition 5 - 1)")  # fmt: skip
    for k in PARAMETERS:
        a = np.array([[d[1][k], d[5][k]] for d in done])
        diff = a[:, 1] - a[:, 0]
        thesis = TABLES_6_4_TO_6_7.get(k, {}).get("filter")
        th = "" if thesis is None else (f"; thesis d_z {'-' if thesis[1] == '-' else '+'}"
                                        f"{np.sqrt(thesis[0] / 9):.2f}")  # fmt: skip
        print(f"  {k:7s} condition 1 {_spread(a[:, 0])}, condition 5 {_spread(a[:, 1])}; d_z "
              f"{diff.mean() / diff.std(ddof=1):+.2f}{th}")  # fmt: skip
    print("  goodness of fit, chi-square per degree of freedom (about 1 where the model holds): "
          + "; ".join(f"condition {n} {_spread(np.array([d[n]['chi2_per_dof'] for d in done]))}"
                      for n in (1, 5)))  # fmt: skip
    flagged = sum("tau_m" in d[5]["unidentifiable"] for d in done)
    print(f"  tau_m not identifiable behind the filter in {flagged} of {n_subjects} subjects "
          f"(condition 1: {sum('tau_m' in d[1]['unidentifiable'] for d in done)})")  # fmt: skip


def _spread(x: np.ndarray) -> str:
    """Median (5-95 %) of ``x``."""
    lo, mid, hi = np.percentile(x, [5, 50, 95])
    return f"{mid:.3f} ({lo:.3f}-{hi:.3f})"


def subject_effects(models: tuple[tuple[str, tuple[str, ...]], ...] = MODELS) -> None:
    """Section 2: the filter's effect per adapted subject, for each of ``models``."""
    spread = SETTINGS["spread"]
    subs = [s for seed in range(EFFECT_POPULATIONS) for s in subjects(SUBJECTS, seed, spread)]
    for name, adapted in models:
        with Engine("local:2") as engine:
            effects = list(engine.map(filter_effect, [(s, adapted) for s in subs],
                                      [{"subject": i} for i in range(len(subs))],
                                      "subjects").values())  # fmt: skip
        print(
            f"the 1 Hz filter's effect on {len(subs)} subjects adapting {name}, without "
            "run-to-run variation: subjects going the thesis' way (median ratio filter / SRS)"
        )
        for m, by in TABLES_6_4_TO_6_7.items():
            if m not in effects[0]:
                continue
            # a measure at zero in both conditions (K_m off in both) has no direction
            both = np.array([e[m] for e in effects])
            ratio = np.divide(both[:, 1], both[:, 0], out=np.ones(len(both)), where=both[:, 0] != 0)
            ratio[(both[:, 0] == 0) & (both[:, 1] > 0)] = np.inf
            way = np.sum(ratio < 1) if by["filter"][1] == "-" else np.sum(ratio > 1)
            print(
                f"  {m:30s} thesis {by['filter'][1]}: {way:2d} of {len(subs)} "
                f"(x{np.median(ratio):.2f})"
            )


def coverage(runs: int, intervals: bool = True, seed: int = 1) -> None:
    """Section 3: the closed-loop MLE's coverage, from seeds ``seed``, ``seed + 1``, ..."""
    for reps in (1, REPETITIONS):
        what = "one run" if reps == 1 else f"{reps} repetitions averaged (as the thesis)"
        case = Case(f"each from {what}", TRUTH, "condition-8", seed, reps, batch=200)
        _coverage(case, runs, intervals)


@dataclass(frozen=True)
class Case:
    """Seeded data for a coverage figure: whose, flown where, and what was added."""

    label: str
    truth: PitchPilot
    config: str
    seed: int
    repetitions: int
    remnant: float = 1.0  # times the thesis' level (15 % of the control power)
    white: float = 0.0  # white stick-sensor noise added to u, times u's sd
    batch: int = 0  # estimates simulated per seed (case.seed, case.seed + 1, ...); 0: all


#: Section 4: data whose nuisance the twin's remnant model did not shape.
NUISANCE = (
    Case("condition 4, half the remnant + white stick noise of half u's sd, five repetitions",
         TRUTH, "condition-4", 7, REPETITIONS, 0.5, 0.5, batch=120),
    Case("a lead-only pilot (t_lead 0.15 s, t_lag 0), the same nuisance, one run",
         PitchPilot(tau_v=0.275, t_lead=0.15, t_lag=0.0), "condition-4", 7, 1, 0.5, 0.5,
         batch=120),
)  # fmt: skip


#: Estimates of each section-4 figure: 60 had left the lead-lag pair's coverage open (t_lag
#: 83 % of 12 identifiable, Wilson 55-95 %); 480 pin it to about +-4 %.
NUISANCE_RUNS = 480


def nuisance(runs: int = NUISANCE_RUNS) -> None:
    """Section 4: the MLE's coverage on data the twin's remnant model did not shape."""
    for case in NUISANCE:
        _coverage(case, runs, intervals=False)


def _draws(case: Case, runs: int):
    """Yield the seeded data of ``runs`` estimates of ``case``: (f_t, f_d, u of each estimate),
    simulated in batches of ``case.batch`` estimates, batch ``b`` with seed ``case.seed + b``."""
    cfg = motion_system(case.config)
    scale = pitch_remnant_scale(case.truth, 0.15) * case.remnant
    reps = case.repetitions
    batch = case.batch or runs
    for b, first in enumerate(range(0, runs, batch)):
        n, seed = min(batch, runs - first), case.seed + b
        r = simulate_pitch(case.truth, cfg, n * reps, seed=seed, remnant_scale=scale)
        u = r.u
        if case.white:
            u = u + np.random.default_rng(seed).normal(0.0, case.white * u.std(), u.shape)
        yield r.ft, r.fd, [u[i * reps] if reps == 1 else u[i * reps : (i + 1) * reps]
                           for i in range(n)]  # fmt: skip


def _coverage(case: Case, runs: int, intervals: bool) -> None:
    """Fit ``runs`` seeded estimates of ``case`` and print each parameter's coverage."""
    args = [(ft, fd, u, case.truth, case.config, intervals)
            for ft, fd, us in _draws(case, runs) for u in us]  # fmt: skip
    t0 = time.perf_counter()
    with Engine("local:2") as engine:
        done = engine.map(_fit, args, [{"run": i} for i in range(runs)], "fits").values()
    print(f"MLE coverage over {runs} estimates, {case.label} (fits "
          f"{'with' if intervals else 'without'} intervals, {time.perf_counter() - t0:.0f} s "
          "on two workers; goal >= 90 %, 95 % Wilson interval in brackets):")  # fmt: skip
    rival = sum(bool(f.competing) for f, _ in done)
    print(f"  {rival} of {runs} fits had another minimum the data do not rule out")
    for what, key in (
        ("on an end of its range", "on_range_bound"),
        ("the data cannot tell from an end of its range", "range_end"),
    ):
        some = [f for f, _ in done if getattr(f, key)]
        count = Counter(name for f in some for name in getattr(f, key))
        print(f"  {len(some)} of {runs} fits had a parameter {what} "
              f"({', '.join(f'{k} {v}' for k, v in count.items()) or '-'})")  # fmt: skip
    for n in PARAMETERS:
        ok = [(f, at) for f, at in done if n not in f.unidentifiable]
        truth = getattr(case.truth, n)
        proper = [abs(getattr(f.pilot, n) - truth) <= 2 * at[n] for f, at in ok]
        plug_in = [abs(getattr(f.pilot, n) - truth) <= 2 * f.crlb[n] for f, _ in ok]
        line = (f"  {n:9s} of {len(ok):3d} identifiable, within 2 bounds at the truth "
                f"{_share(proper)}, reported {_share(plug_in)}")  # fmt: skip
        if intervals:
            inside = [f.covers(n, truth) for f, _ in done]
            line += f"; likelihood-ratio interval {_share(inside)} of {runs}"
        print(line + _widening(n, [f for f, _ in ok]))


def _widening(name: str, fits: list) -> str:
    """What the honesty costs in precision: how often, and by how much, the reported sd of
    ``name`` is wider than the Cramer-Rao bound at the estimate (over ``fits``)."""
    ratio = np.array([f.crlb[name] / f.crlb_at_estimate[name] for f in fits
                      if f.crlb_at_estimate and np.isfinite(f.crlb_at_estimate[name])
                      and f.crlb_at_estimate[name] > 0])  # fmt: skip
    if not ratio.size:
        return ""
    wide = ratio[ratio > 1 + 1e-9]
    if not wide.size:
        return "; never widened"
    return (
        f"; widened in {wide.size}, by x{np.median(wide):.2f} (median; 95th percentile "
        f"x{np.percentile(wide, 95):.2f})"
    )


def _share(hits: list[bool]) -> str:
    """Return a coverage with its 95 % Wilson interval, e.g. '92% (81%-97%)'."""
    if not hits:
        return "  -"
    lo, hi = proportion_confint(sum(hits), len(hits), method="wilson")
    return f"{np.mean(hits):4.0%} ({lo:.0%}-{hi:.0%})"


def _fit(ft, fd, u, truth: PitchPilot, config: str, intervals: bool):
    """One MLE fit (with likelihood-ratio intervals if asked), and the bound at the truth (a
    task of the engine)."""
    cfg = motion_system(config)
    fit = fit_pitch_pilot(ft, fd, u, cfg, intervals=intervals)
    return fit, bound_at(truth, ft, fd, u, cfg)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--coverage-runs", type=int, default=200, metavar="N",
                        help="estimates per coverage figure (default 200: +-4 %% at 90 %%; "
                             "about 30 min each on two cores with the intervals)")  # fmt: skip
    parser.add_argument("--coverage-only", action="store_true", help="section 3 only")
    parser.add_argument("--coverage-seed", type=int, default=1, metavar="S",
                        help="section 3's first seed (default 1; 200 estimates per seed; "
                             "seeds 7-10 are section 4's)")  # fmt: skip
    parser.add_argument("--nuisance-only", action="store_true",
                        help="section 4 only (about 7 min)")  # fmt: skip
    parser.add_argument("--visual-delay-only", action="store_true",
                        help="section 5 only (about 25 min)")  # fmt: skip
    parser.add_argument("--motion-delay-only", action="store_true",
                        help="section 5's tau_m fits only, and 18 subjects measured as the "
                             "thesis did (about 70 s)")  # fmt: skip
    parser.add_argument("--feedthrough", type=float, nargs="+", default=[0.0], metavar="R",
                        help="with --motion-delay-only: measure the subjects once per R, each "
                             "with a passive pitch-to-stick path R of its motion response at 3 "
                             "rad/s (default 0: none; about 2 min more each)")  # fmt: skip
    parser.add_argument("--design-only", action="store_true",
                        help="section 1's populations and section 6's design and its check "
                             "(about 40 min with --design-subjects 18)")  # fmt: skip
    parser.add_argument("--design-subjects", type=int, default=None,
                        help="subjects per population of section 6's check (default: from "
                             "how many the design says the acceptance holds in 80 %%, or "
                             "9)")  # fmt: skip
    parser.add_argument("--spread-profile", action="store_true",
                        help="section 7 only: the subjects' spreads and run-to-run variation "
                             "profiled against Tables 6.4-6.7 (about 7 min a cell of 10 "
                             "populations)")  # fmt: skip
    for name, what in (("motion", "motion perception spreads"),
                       ("visual-delay", "visual-delay sds in s"),
                       ("run-to-run", "run-to-run variations")):  # fmt: skip
        key = name.replace("-", "_")
        parser.add_argument(
            f"--profile-{name}",
            type=float,
            nargs="+",
            metavar="X",
            default=list(SPREAD_GRID[key]),
            help=f"section 7's {what} (default: {SPREAD_GRID[key]})",
        )
    parser.add_argument("--profile-populations", type=int, default=SPREAD_POPULATIONS,
                        metavar="N", help="section 7's populations a cell (default: "
                        f"{SPREAD_POPULATIONS})")  # fmt: skip
    parser.add_argument(
        "--profile-seed",
        type=int,
        default=0,
        metavar="S",
        help="section 7's first seed (default 0)",
    )
    parser.add_argument("--motion-spread", type=float, default=MOTION_NOISE_SD, metavar="SD",
                        help="the subjects' spread in motion perception for every section but "
                             "7 (default: twin.pilot.studies.spread.MOTION_NOISE_SD; 0 with "
                             "--visual-delay-spread 0.03: the subjects before either)")  # fmt: skip
    parser.add_argument("--visual-delay-spread", type=float, default=VISUAL_DELAY_SD,
                        metavar="S", help="the subjects' visual-delay sd in s for every section "
                        "but 7 (default: twin.pilot.studies.spread.VISUAL_DELAY_SD)")  # fmt: skip
    parser.add_argument("--no-intervals", action="store_true",
                        help="fit without the likelihood-ratio intervals (and their rule): "
                             "about 6x faster")  # fmt: skip
    args = parser.parse_args()
    if args.coverage_runs < 1:
        parser.error(f"--coverage-runs must be at least 1; got {args.coverage_runs}")
    if args.design_subjects is not None and not 2 <= args.design_subjects <= MAX_SUBJECTS:
        parser.error(f"--design-subjects must be 2 to {MAX_SUBJECTS}; got {args.design_subjects}")
    if not all(0 <= r <= MAX_FEEDTHROUGH for r in args.feedthrough):  # also refuses NaN
        parser.error(f"--feedthrough ratios must be 0 to {MAX_FEEDTHROUGH:g}; "
                     f"got {args.feedthrough}")  # fmt: skip
    grid = {"motion": args.profile_motion, "visual_delay": args.profile_visual_delay,
            "run_to_run": args.profile_run_to_run}  # fmt: skip
    checks = [("--motion-spread", lambda x: Spread(motion=x), [args.motion_spread]),
              ("--visual-delay-spread", lambda x: Spread(visual_delay=x),
               [args.visual_delay_spread]),
              ("--profile-motion", lambda x: Spread(motion=x), grid["motion"]),
              ("--profile-visual-delay", lambda x: Spread(visual_delay=x),
               grid["visual_delay"]),
              ("--profile-run-to-run", lambda x: checked_settings(ADAPTED, x),
               grid["run_to_run"])]  # fmt: skip
    for flag, check, values in checks:
        for x in values:
            try:
                check(x)
            except SignalError as e:
                parser.error(f"{flag}: {e}")
    SETTINGS["spread"] = Spread(args.motion_spread, args.visual_delay_spread)
    grid = {k: tuple(dict.fromkeys(v)) for k, v in grid.items()}  # each value once
    if args.profile_populations < 2 or args.profile_seed < 0:
        parser.error(f"--profile-populations must be >= 2 and --profile-seed >= 0; got "
                     f"{args.profile_populations} and {args.profile_seed}")  # fmt: skip
    if args.coverage_seed < 0:
        parser.error(f"--coverage-seed must be a seed >= 0; got {args.coverage_seed}")
    if args.motion_delay_only:
        motion_delay()
        for ratio in args.feedthrough:
            motion_delay_measured(feedthrough=ratio)
        raise SystemExit(0)
    if args.spread_profile:
        spread_profile(grid, args.profile_populations, args.profile_seed)
        raise SystemExit(0)
    if args.design_only:
        design_check(populations(ADAPTATION_SD, POPULATIONS), args.design_subjects)
        raise SystemExit(0)
    main(
        args.coverage_runs,
        args.coverage_only,
        not args.no_intervals,
        args.nuisance_only,
        args.visual_delay_only,
        args.coverage_seed,
    )
