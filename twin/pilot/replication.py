"""Chapter 6 replicated: how often a population should agree with the thesis, and how often it does.

An ANOVA over nine subjects is a draw. Even the thesis' own participants, flown again, would
not give p < 0.05 every time for an effect whose F was 5.98 (the 1 Hz filter on the target
crossover, Table 6.5): F = 5.32 is p = 0.05 at df (1, 8). So one simulated population that
misses such an effect says little, and one that matches it says as little. This module
flies several seeded populations (:mod:`twin.pilot.population`) and compares, per measure
and main effect:

- the distribution of the twin's F over populations (median and 5-95 %, signed by the
  effect's direction) with the thesis' F;
- how many populations agree with the thesis (:meth:`PopulationResult.agreement`) with how
  many would if the true effect were the thesis' own estimate: the *replication
  probability* :func:`agreement_probability`;
- whether so few agreements are plausible: the binomial probability of at most that many
  (below 0.05: the twin is farther from the thesis than the thesis' own sampling explains).
  Each effect is tested on its own: of 36 effects, about two are marked by chance even if
  the twin were the thesis' subjects.

The replication probability (an "observed power", Cohen 1988; stated as an assumption): a
factor of two levels within subjects has F(1, n - 1) = t^2, with t the paired t statistic of
the subjects' differences between the levels. Its noncentrality for n subjects is estimated
from the thesis' F as delta = sqrt(F n / 9) (nine participants, §6.3.4). Where the thesis
found an effect, agreement is t beyond the two-sided 5 % point in the thesis' direction;
where it found none, |t| within it. The estimate takes the thesis' F at face value; F is
biased upward as an estimate of delta^2 (E[F] is about 1 + delta^2), so these probabilities
favour the thesis' effects being found.

Examples
--------
>>> round(agreement_probability(5.98, significant=True), 2)   # Table 6.5, target crossover
0.57
>>> round(agreement_probability(0.0, significant=False), 2)   # no effect at all
0.95

"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

from twin.errors import SignalError
from twin.pilot.adapt import ADAPTED
from twin.pilot.population import (
    ADAPTATION_SD,
    FACTORS,
    PopulationResult,
    checked_settings,
    effect_axes,
    fly_subject,
    population_result,
    population_tasks,
    signed_log,
)
from twin.progress import ProgressFn
from twin.tasks.engine import Engine, using
from twin.thesis import TABLES_6_4_TO_6_7

#: Participants of the thesis' experiment (§6.3.4; the ANOVA's df (1, 8)).
THESIS_SUBJECTS = 9
#: Significance level of Tables 6.4-6.7.
ALPHA = 0.05
#: Below this binomial probability of so few agreements, the difference is the twin's.
PLAUSIBLE = 0.05


def agreement_probability(
    f_thesis: float, significant: bool, subjects: int = THESIS_SUBJECTS, alpha: float = ALPHA
) -> float:
    """Probability that one population agrees with the thesis on a main effect.

    Parameters
    ----------
    f_thesis : float
        The thesis' F(1, 8) for the effect (Tables 6.4-6.7), taken as the true effect size.
    significant : bool
        Whether the thesis found the effect (then agreement is p < ``alpha`` in its
        direction; otherwise p >= ``alpha``).
    subjects : int
        Subjects of the population (at least 2).
    alpha : float
        Significance level.

    Returns
    -------
    float

    """
    if not (np.isfinite(f_thesis) and f_thesis >= 0):
        raise SignalError(f"an F value must be a finite number >= 0; got {f_thesis}")
    if subjects < 2:
        raise SignalError(f"a within-subject effect needs at least 2 subjects; got {subjects}")
    df = subjects - 1
    delta = float(np.sqrt(f_thesis * subjects / THESIS_SUBJECTS))
    t_crit = float(stats.t.ppf(1 - alpha / 2, df))
    if significant:
        return float(stats.nct.sf(t_crit, df, delta))
    return float(stats.nct.cdf(t_crit, df, delta) - stats.nct.cdf(-t_crit, df, delta))


@dataclass(frozen=True)
class EffectReplication:
    """One main effect over several populations, beside the thesis.

    Attributes
    ----------
    measure, factor : str
        The measure (:data:`twin.pilot.population.COMPARED`) and the factor.
    thesis_f : float
        The thesis' F (Tables 6.4-6.7).
    thesis_direction : str or None
        ``"+"``/``"-"`` where the thesis found the effect, None where it found none.
    signed_f : tuple of float
        The twin's F per population, negative where its direction is ``"-"``.
    agreed : int
        Populations that agree with the thesis.
    probability : float
        :func:`agreement_probability` for the populations' size.

    """

    measure: str
    factor: str
    thesis_f: float
    thesis_direction: str | None
    signed_f: tuple[float, ...]
    agreed: int
    probability: float

    @property
    def populations(self) -> int:
        """Number of populations."""
        return len(self.signed_f)

    @property
    def expected(self) -> float:
        """Agreements expected if the true effect were the thesis' estimate."""
        return self.probability * self.populations

    @property
    def p_so_few(self) -> float:
        """Binomial probability of at most :attr:`agreed` agreements at :attr:`probability`."""
        return float(stats.binom.cdf(self.agreed, self.populations, self.probability))

    @property
    def plausible(self) -> bool:
        """Whether the agreements are within the thesis' own sampling (:data:`PLAUSIBLE`)."""
        return self.p_so_few >= PLAUSIBLE

    def quantiles(self) -> tuple[float, float, float]:
        """5 %, median and 95 % of the signed F over populations."""
        q = np.percentile(self.signed_f, [5, 50, 95])
        return float(q[0]), float(q[1]), float(q[2])

    @property
    def thesis_within(self) -> bool:
        """Whether the thesis' F lies within the twin's 5-95 % over populations.

        Signed where the thesis found the effect; where it found none (it gives no direction)
        its F against the 5-95 % of the twin's unsigned F.
        """
        if self.thesis_direction is None:
            lo, hi = np.percentile(np.abs(self.signed_f), [5, 95])
            return bool(lo <= self.thesis_f <= hi)
        lo, _, hi = self.quantiles()
        signed = -self.thesis_f if self.thesis_direction == "-" else self.thesis_f
        return bool(lo <= signed <= hi)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready."""
        lo, med, hi = self.quantiles()
        return {"thesis_F": self.thesis_f, "thesis_direction": self.thesis_direction,
                "signed_F": list(self.signed_f), "signed_F_median": med,
                "signed_F_5_95": [lo, hi], "thesis_within_5_95": self.thesis_within,
                "agreed": self.agreed,
                "populations": self.populations, "agreement_probability": self.probability,
                "expected_agreements": self.expected, "p_so_few": self.p_so_few,
                "plausible": self.plausible}  # fmt: skip


@dataclass(frozen=True)
class Replication:
    """Several seeded populations' ANOVAs summarised per main effect.

    Attributes
    ----------
    effects : tuple of EffectReplication
        One per measure and factor, in the populations' ANOVA order.
    seeds : tuple of int
        The populations' seeds.
    subjects : int
        Subjects per population.
    adapted : tuple of str
        What the subjects adapted.
    run_to_run_sd : float
        Their run-to-run variation.

    """

    effects: tuple[EffectReplication, ...]
    seeds: tuple[int, ...]
    subjects: int
    adapted: tuple[str, ...]
    run_to_run_sd: float

    def effect(self, measure: str, factor: str) -> EffectReplication:
        """Return one effect by name."""
        for e in self.effects:
            if (e.measure, e.factor) == (measure, factor):
                return e
        names = sorted({e.measure for e in self.effects})
        raise SignalError(f"no effect {measure!r} x {factor!r}; measures: {', '.join(names)}; "
                          f"factors: {', '.join(FACTORS)}")  # fmt: skip

    def implausible(self) -> list[EffectReplication]:
        """Return the effects with fewer agreements than the thesis' own sampling explains."""
        return [e for e in self.effects if not e.plausible]

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: ``{"replication": {MEASURE: {FACTOR: {...}}}, "seeds", ...}``."""
        rep: dict[str, dict[str, object]] = {}
        for e in self.effects:
            rep.setdefault(e.measure, {})[e.factor] = e.to_dict()
        return {"replication": rep, "seeds": list(self.seeds), "subjects": self.subjects,
                "adapted": list(self.adapted), "run_to_run_sd": self.run_to_run_sd,
                "implausible": [f"{e.measure}/{e.factor}" for e in self.implausible()]}  # fmt: skip

    def format_table(self) -> str:
        """Plain-text table: the twin's F over populations beside the thesis'."""
        n = len(self.seeds)
        lines = [
            f"Chapter 6 replicated by {n} populations of {self.subjects} adaptive subjects "
            f"(seeds {self.seeds[0]}-{self.seeds[-1]}; run-to-run variation "
            f"{self.run_to_run_sd:.0%}): signed F (median, 5-95 %) beside the thesis'; "
            "agreements beside those expected if the thesis' F were the true effect",
            f"{'measure':30s} {'factor':6s} {'median F':>9s} {'5-95 % F':>17s} | "
            f"{'thesis F':>9s} within | agree expected  P(so few)",
        ]
        for e in self.effects:
            lo, med, hi = e.quantiles()
            thesis = (("-" if e.thesis_direction == "-" else "+") + f"{e.thesis_f:.2f}"
                      if e.thesis_direction else f"{e.thesis_f:.2f} ns")  # fmt: skip
            lines.append(
                f"{e.measure:30s} {e.factor:6s} {med:+9.2f} {lo:+8.1f} {hi:+8.1f} | "
                f"{thesis:>9s} {'yes' if e.thesis_within else 'no':>6s} | "
                f"{e.agreed:2d}/{n:<2d} {e.expected:8.1f}  {e.p_so_few:9.3f}"
                + ("" if e.plausible else "  <- the twin's")
            )
        bad = self.implausible()
        lines.append(f"{len(self.effects) - len(bad)} of {len(self.effects)} main effects "
                     f"agree as often as the thesis' own F predicts (P(so few) >= "
                     f"{PLAUSIBLE}); the thesis' F is within the twin's 5-95 % for "
                     f"{sum(e.thesis_within for e in self.effects)} (signed where it found "
                     "the effect, unsigned where not)")  # fmt: skip
        return "\n".join(lines)

    def plot(self, path: str | None = None):
        """Signed F per effect over populations (5-95 % and median) beside the thesis' F.

        Parameters
        ----------
        path : str, optional
            A PNG (or any matplotlib format) to write the figure to.

        Returns
        -------
        matplotlib.figure.Figure

        """
        from twin.plotting import finish

        measures = list(dict.fromkeys(e.measure for e in self.effects))
        fig, axes = effect_axes(measures, 0.35 * len(measures) + 2)
        crit = float(stats.f.ppf(1 - ALPHA, 1, self.subjects - 1))
        for ax, factor in zip(axes, FACTORS, strict=True):
            for i, m in enumerate(measures):
                e = self.effect(m, factor)
                lo, med, hi = signed_log(e.quantiles())
                colour = "C0" if e.plausible else "C3"
                ax.plot([lo, hi], [i, i], color=colour, lw=3, alpha=0.5)
                ax.plot(med, i, "o", color=colour, ms=5)
                if e.thesis_direction:
                    t = e.thesis_f * (-1 if e.thesis_direction == "-" else 1)
                    ax.plot(signed_log(t), i, "k|", ms=10, mew=2)
                else:  # no direction given: either side
                    ax.plot(signed_log([-e.thesis_f, e.thesis_f]), [i, i], "kx", ms=7, mew=1.5)
            for s in (-1, 1):
                ax.axvline(signed_log(s * crit), color="0.6", ls=":", lw=1)
        axes[0].invert_yaxis()
        fig.suptitle(
            f"{len(self.seeds)} populations of {self.subjects} adaptive subjects: twin's F, "
            "5-95 % (bar) and median (dot); thesis' F (| significant; x not, either sign); "
            "dotted: p = 0.05;\nred: fewer agreements than the thesis' own F predicts",
            fontsize=9,
        )
        return finish(fig, path, dpi=110)


def replicate(results: Sequence[PopulationResult]) -> Replication:
    """Summarise populations flown with the same settings (:func:`run_populations`)."""
    if len(results) < 2:
        raise SignalError(f"a replication needs at least 2 populations; got {len(results)}")
    first = results[0]
    subjects = len({r["subject"] for r in first.rows})
    for r in results[1:]:
        got = (len({row["subject"] for row in r.rows}), r.adapted, r.run_to_run_sd)
        want = (subjects, first.adapted, first.run_to_run_sd)
        if got != want:
            raise SignalError(f"populations differ in subjects, adapted parameters or run-to-run "
                              f"variation: {got} vs {want}")  # fmt: skip
    effects = []
    for measure in first.anova:
        for factor in FACTORS:
            thesis_f, direction = TABLES_6_4_TO_6_7[measure][factor]
            signed = tuple(float(r.anova[measure][factor]["F"])
                           * (-1.0 if r.anova[measure][factor]["direction"] == "-" else 1.0)
                           for r in results)  # fmt: skip
            agreed = sum(bool(r.agreement()[measure][factor]) for r in results)
            prob = agreement_probability(thesis_f, direction is not None, subjects)
            effects.append(EffectReplication(measure, factor, thesis_f, direction, signed,
                                             agreed, prob))  # fmt: skip
    return Replication(tuple(effects), tuple(r.seed for r in results), subjects,
                       first.adapted, first.run_to_run_sd)  # fmt: skip


def run_populations(
    n_populations: int = 20,
    n_subjects: int = THESIS_SUBJECTS,
    seed: int = 0,
    progress: ProgressFn | None = None,
    scheduler: Engine | str | None = None,
    adapted: tuple[str, ...] = ADAPTED,
    run_to_run_sd: float = ADAPTATION_SD,
) -> tuple[Replication, list[PopulationResult]]:
    """Fly ``n_populations`` populations (seeds ``seed``, ``seed + 1``, ...) and replicate.

    Every subject of every population is one task, so the workers stay busy across
    populations; each population equals :func:`~twin.pilot.population.run_population` with
    its seed. Returns the summary and the populations.
    """
    if n_populations < 2:
        raise SignalError(f"a replication needs at least 2 populations; got {n_populations}")
    adapted = checked_settings(adapted, run_to_run_sd)
    seeds = list(range(seed, seed + n_populations))
    tasks = [population_tasks(n_subjects, s, adapted, run_to_run_sd) for s in seeds]
    args = [a for t in tasks for a in t[0]]
    inputs = [i for t in tasks for i in t[1]]
    with using(scheduler) as engine:
        flown = engine.map(fly_subject, args, inputs, "subjects", progress).values()
    results = [population_result(flown[k * n_subjects:(k + 1) * n_subjects], s, adapted,
                                 run_to_run_sd) for k, s in enumerate(seeds)]  # fmt: skip
    return replicate(results), results
