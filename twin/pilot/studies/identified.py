"""Chapter 6's experiment measured as the thesis did: the pilot model identified from the runs.

:func:`twin.pilot.studies.population.fly_subject` takes a subject's pilot-model measures from the
pilots it flew (the repetitions' geometric mean: what a perfect identification of their
average would give) and var(e), var(u) from the frequency domain. The thesis measured them
(§6.3.5-6.3.6): the runs recorded, and Eq 6.5-6.7 fitted by maximum likelihood to the five
repetitions' average. Here each repetition's pilot (the same adaptation and run-to-run
variation, :func:`twin.pilot.studies.population.flown_conditions`: the same subjects and pilots as
:func:`~twin.pilot.studies.population.fly_subject`'s) flies the pitch task in the time domain on the
reduced platform (:func:`twin.pilot.models.pitch.simulate_pitch`, its remnant at
``REMNANT_RATIO`` of the subject's condition-1 control power, the thesis' level), the MLE
(:func:`twin.pilot.identification.mle.fit_pitch_pilot`) is fitted to their average, and:

* var(e) and var(u) are the runs' own (time domain, averaged);
* K_v ... zeta_nm, tau_v and tau_m are the fit's, with all its identification error, and
  the crossovers and phase margins those of the identified pilot
  (:func:`twin.pilot.models.pitch.open_loops`);
* ``chi2_per_dof`` is the fit's goodness of fit (about 1 where Eq 6.5-6.7 holds) and
  ``tau_m_identifiable`` 1 where the fit did not flag tau_m.

So tau_m, which a subject who does not use the motion behind the filter does not have, gets a
value as it did in the thesis, and Table 6.7's tau_m row can be compared. With a
``feedthrough`` each subject also has a passive path from the motion to the stick, that share
of its condition-1 motion response at 3 rad/s (:class:`twin.pilot.models.pitch.Feedthrough`; an
assumption), which Eq 6.5-6.7 does not hold. About 12 s a subject on two cores (110 s for
nine), about 5x that with a feedthrough, whose loop is stepped a sample at a time.
"""

from __future__ import annotations

import numpy as np

from twin.core.errors import SignalError
from twin.core.progress import ProgressFn
from twin.core.tasks.engine import Engine, using
from twin.pilot.identification.mle import PARAMETERS, fit_pitch_pilot
from twin.pilot.models.adapt import ADAPTED
from twin.pilot.models.pitch import Feedthrough, simulate_pitch
from twin.pilot.studies.experiment import pitch_remnant_scale
from twin.pilot.studies.population import (
    ADAPTATION_SD,
    COMPARED,
    PopulationResult,
    Subject,
    anova,
    checked_settings,
    condition_row,
    flown_conditions,
    population_tasks,
)
from twin.pilot.studies.spread import DEFAULT_SPREAD, Spread, checked

#: Remnant power relative to u's on the SRS baseline (the thesis' level, §6.3.4).
REMNANT_RATIO = 0.15
#: A run whose var(e) exceeds this many times the adapted pilot's has lost control for good.
DIVERGED = 100.0
#: Measures compared with the thesis when the model is identified: the contract's, the
#: lead-lag pair, the neuromuscular tuning and both delays (Tables 6.4-6.7).
IDENTIFIED = (*COMPARED, "tau_m")
#: Largest feedthrough (share of the motion response at 3 rad/s) flown: the passive path is
#: positive feedback, and at 2 the default subject's loop diverges behind the filter.
MAX_FEEDTHROUGH = 1.0


def identified_subject(
    subject: Subject,
    seed: int = 0,
    adapted: tuple[str, ...] = ADAPTED,
    run_to_run_sd: float = ADAPTATION_SD,
    feedthrough: float = 0.0,
) -> list[dict[str, float]]:
    """Fly ``subject``'s repetitions of every condition and identify its pilot model.

    The arguments are :func:`twin.pilot.studies.population.fly_subject`'s, and ``feedthrough`` the
    relative size of a passive path (0: none). Returns one row per condition, as
    ``fly_subject``'s, the measures identified (see the module's docstring).
    """
    rows: list[dict[str, float]] = []
    scale, path = 0.0, None
    for n, task, a, flown in flown_conditions(subject, seed, adapted, run_to_run_sd):
        if not rows:  # condition 1 (the SRS baseline) comes first
            scale = pitch_remnant_scale(a.pilot, REMNANT_RATIO)
            path = Feedthrough.relative(feedthrough, a.pilot) if feedthrough else None
        runs = [simulate_pitch(pilot, task.config, 1, run_seed(seed, subject, n, k), scale,
                               feedthrough=path)
                for k, (pilot, _) in enumerate(flown)]  # fmt: skip
        var_e = [float(np.var(r.e[0])) for r in runs]
        lost = [k for k, v in enumerate(var_e) if not v < DIVERGED * a.performance.var_e]
        if lost:
            raise SignalError(
                f"subject {subject.number}, condition {n}: repetition {lost[0] + 1}'s loop "
                f"diverged (var(e) above {DIVERGED:g} times the adapted pilot's)"
                + (f"; the feedthrough {feedthrough:g} destabilises it: give a smaller one"
                   if feedthrough else "")
            )  # fmt: skip
        u = np.vstack([r.u[0] for r in runs])
        fit = fit_pitch_pilot(runs[0].ft, runs[0].fd, u, task.config)
        row = condition_row(subject, n, fit.pilot, task, float(np.mean(var_e)),
                            float(np.mean([np.var(r.u[0]) for r in runs])), PARAMETERS)  # fmt: skip
        rows.append({**row, "chi2_per_dof": fit.evidence["fit"]["ratio"],
                     "tau_m_identifiable": float("tau_m" not in fit.unidentifiable)})  # fmt: skip
    return rows


def run_seed(seed: int, subject: Subject, condition: int, repetition: int) -> int:
    """Seed of one repetition's remnant (and motion noise) in population ``seed``."""
    key = [seed, 16, subject.number, condition, repetition]
    return int(np.random.SeedSequence(key).generate_state(1)[0])


def identified_population(
    n_subjects: int = 9,
    seed: int = 0,
    progress: ProgressFn | None = None,
    scheduler: Engine | str | None = None,
    adapted: tuple[str, ...] = ADAPTED,
    run_to_run_sd: float = ADAPTATION_SD,
    feedthrough: float = 0.0,
    spread: Spread = DEFAULT_SPREAD,
) -> PopulationResult:
    """Fly the eight conditions with ``n_subjects`` subjects, identify, and run the ANOVA.

    The subjects and their pilots are :func:`twin.pilot.studies.population.run_population`'s with
    the same arguments; the measures are identified from their runs
    (:func:`identified_subject`), and the ANOVA covers :data:`IDENTIFIED`: tau_v too, whether
    or not the subjects adapt it (its estimate varies, as the thesis' did).

    Raises
    ------
    SignalError
        A run-to-run variation out of range, a feedthrough outside [0,
        ``MAX_FEEDTHROUGH``], or a loop that diverged.
    TypeError
        A ``spread`` that is not a :class:`~twin.pilot.studies.spread.Spread`.

    """
    adapted = checked_settings(adapted, run_to_run_sd, spread)
    check_feedthrough(feedthrough)
    args, names = identified_tasks(n_subjects, seed, adapted, run_to_run_sd, feedthrough, spread)
    with using(scheduler) as engine:
        flown = engine.map(identified_subject, args, names, "subjects", progress).values()
    return identified_result(flown, seed, adapted, run_to_run_sd, feedthrough, spread)


def check_feedthrough(feedthrough: float) -> None:
    """Refuse a feedthrough outside [0, ``MAX_FEEDTHROUGH``] (or NaN)."""
    if not 0 <= feedthrough <= MAX_FEEDTHROUGH:
        raise SignalError(f"feedthrough must be a share of the motion response in "
                          f"[0, {MAX_FEEDTHROUGH:g}]; got {feedthrough}")  # fmt: skip


def identified_tasks(
    n_subjects: int,
    seed: int,
    adapted: tuple[str, ...],
    run_to_run_sd: float,
    feedthrough: float,
    spread: Spread,
) -> tuple[list[tuple], list[dict[str, int]]]:
    """Arguments of :func:`identified_subject` per subject of population ``seed``, and names.

    :func:`twin.pilot.studies.population.population_tasks`'s, each with the feedthrough.
    """
    args, names = population_tasks(n_subjects, seed, adapted, run_to_run_sd, spread)
    return [(*a, feedthrough) for a in args], names


def identified_result(
    flown: list[list[dict[str, float]]],
    seed: int,
    adapted: tuple[str, ...],
    run_to_run_sd: float,
    feedthrough: float,
    spread: Spread,
) -> PopulationResult:
    """Assemble the subjects' identified rows (in subject order) and their ANOVA."""
    rows = [row for r in flown for row in r]
    return PopulationResult(rows, anova(rows, IDENTIFIED), seed, adapted, run_to_run_sd,
                            feedthrough, checked(spread))  # fmt: skip
