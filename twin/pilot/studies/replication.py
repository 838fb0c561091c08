"""Chapter 6 replicated: whether the thesis' result is a plausible draw of the twin's.

An ANOVA over nine subjects is a draw, the thesis' too. Even the thesis' own participants,
flown again, would not give p < 0.05 every time for an effect whose F was 5.98 (the 1 Hz
filter on the target crossover, Table 6.5): F = 5.32 is p = 0.05 at df (1, 8). So one
simulated population that misses such an effect says little, and one that matches it says as
little. This module flies several seeded populations (:mod:`twin.pilot.studies.population`) and
compares, per measure and main effect, the twin's populations with the thesis' one:

- **effect size**: a factor of two levels within subjects has F(1, n - 1) = t^2, with t the
  paired t statistic of the subjects' differences between its levels (their marginal means).
  d_z = t / sqrt(n), signed by the effect's direction, is the standardised effect (Cohen's
  d_z), comparable across numbers of subjects; the thesis' is sqrt(F / 9) with its direction
  (nine participants, §6.3.4; where it found no effect it gave no direction, so both signs);
- **is the thesis a plausible draw of the twin?** If the twin were the thesis' population,
  the thesis' d_z would be one more draw from the distribution of the twin's d_z over
  populations. The predictive test (a Student-t prediction interval from the populations'
  mean and sd, the thesis' draw scaled by its own sample size) gives the probability of a
  draw at least as far out; below 0.05 the twin differs from the thesis by more than the two
  samplings explain, in either direction (an effect too weak, or too strong and uniform: the
  twin's subjects may differ from each other less than people do). Each effect is tested on
  its own: of 36, about two fall below 0.05 by chance even if the twin were the thesis (fewer:
  the undirected effects, tried at both signs, are conservative; effects of the same
  populations are correlated). Calibration (Monte Carlo of noncentral t, nine subjects, 20
  populations): 5-6 % false alarms in all for true d_z from 0 to 6, but d_z's skew splits
  them unevenly for large effects: about 5 % with the thesis' d_z *above* the twin's and
  0.2-0.8 % below. So a twin effect flagged as larger than the thesis' is conservative, one
  flagged as smaller less so than its p. Calibrated for populations of nine; with other
  sizes the two d_z carry different small-sample bias;
- **agreements**, descriptive: how many populations agree with the thesis
  (:meth:`PopulationResult.agreement`: p < 0.05 in its direction where it found the effect,
  p >= 0.05 where not), beside how many would if the true effect were exactly the thesis'
  estimate (:func:`agreement_probability`, the power of the paired t-test at the thesis' F).
  Not a test: the thesis' F is itself a draw (its 95 % interval for var(u)'s F 15.0 allows
  agreement probabilities from 0.17 to 1).

The converse, how many subjects an experiment needs to find each effect if the twin is
right, pools the populations' subjects: :mod:`twin.pilot.studies.design`.

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
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import stats

from twin.core.errors import SignalError
from twin.core.progress import ProgressFn
from twin.core.results import frame
from twin.core.tasks.engine import Engine, using
from twin.core.thesis import TABLES_6_4_TO_6_7
from twin.pilot.models.adapt import ADAPTED
from twin.pilot.studies.identified import (
    check_feedthrough,
    identified_result,
    identified_subject,
    identified_tasks,
)
from twin.pilot.studies.population import (
    ADAPTATION_SD,
    FACTORS,
    PopulationResult,
    checked_settings,
    effect_axes,
    fly_subject,
    population_result,
    population_tasks,
    signed_f,
)
from twin.pilot.studies.spread import DEFAULT_SPREAD, Spread

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from twin.core.plotting import AxesArg

FloatArray = NDArray[np.float64]

#: Participants of the thesis' experiment (§6.3.4; the ANOVA's df (1, 8)).
THESIS_SUBJECTS = 9
#: Significance level of Tables 6.4-6.7.
ALPHA = 0.05
#: Below this probability of a draw as far out, the thesis is not a plausible draw of the twin.
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


def predictive_p(draws: ArrayLike, value: float, scale: float = 1.0) -> float:
    """Two-sided probability that one more draw lies at least as far from the draws' mean.

    Student-t prediction interval: with the draws' mean m, sd s and number N, the new draw
    ``value`` (whose spread is ``scale`` times the draws') gives
    t = (value - m) / (s sqrt(1 / N + scale^2)) on N - 1 degrees of freedom. Exact for normal
    draws; with N = 2 it has one degree of freedom and can flag almost nothing.

    Parameters
    ----------
    draws : array_like
        At least 2 draws.
    value : float
        The new draw.
    scale : float
        Its sd relative to the draws' sd.

    Returns
    -------
    float

    Examples
    --------
    >>> round(predictive_p([-1.0, 0.0, 1.0], 0.0), 2)
    1.0

    """
    t, _, df = _predictive_t(_one_row(draws), value, scale)
    return float(2 * stats.t.sf(abs(t[0]), df))


def predictive_log_density(draws: ArrayLike, value: float, scale: float = 1.0) -> float:
    """Log density of one more draw at ``value``: the Student-t of :func:`predictive_p`.

    Summed over effects, it scores how well the draws predict the values (higher is better),
    which a p value does not: it rewards a prediction that is both near and sharp.

    Parameters
    ----------
    draws, value, scale
        As :func:`predictive_p`.

    Returns
    -------
    float
        The log of the predictive density at ``value`` (per unit of the draws).

    """
    return float(predictive_log_densities(_one_row(draws), value, scale)[0])


def predictive_log_densities(draws: ArrayLike, value: float, scale: float = 1.0) -> FloatArray:
    """:func:`predictive_log_density` for each row of ``draws`` (shape (rows, N)).

    Raises
    ------
    SignalError
        Rows of fewer than 2 draws, a draw that is not finite, or a row without spread.

    """
    t, spread, df = _predictive_t(np.asarray(draws, dtype=float), value, scale)
    return stats.t.logpdf(t, df) - np.log(spread)


def _one_row(draws: ArrayLike) -> FloatArray:
    """One set of draws as a single row (a 1-D sequence)."""
    x = np.asarray(draws, dtype=float)
    if x.ndim != 1:
        raise SignalError(f"draws must be one sequence; got shape {x.shape}")
    return x[None, :]


def _predictive_t(x: FloatArray, value: float, scale: float) -> tuple[FloatArray, FloatArray, int]:
    """(t, the prediction's spread, degrees of freedom) of :func:`predictive_p`, per row."""
    if x.ndim != 2 or x.shape[1] < 2 or not np.all(np.isfinite(x)):
        raise SignalError(f"a predictive test needs rows of at least 2 finite draws; got "
                          f"{x.tolist() if x.size <= 40 else f'shape {x.shape}'}")  # fmt: skip
    if not (np.isfinite(value) and np.isfinite(scale) and scale > 0):
        raise SignalError(f"the new draw must be finite and its scale > 0; got {value}, {scale}")
    sd = np.std(x, axis=1, ddof=1)
    if np.any(sd == 0):
        raise SignalError(f"the draws are all {x[np.argmin(sd), 0]}: no spread to predict a "
                          "draw from")  # fmt: skip
    spread = sd * np.sqrt(1.0 / x.shape[1] + scale**2)
    return (value - x.mean(axis=1)) / spread, spread, x.shape[1] - 1


@dataclass(frozen=True)
class EffectReplication:
    """One main effect over several populations, beside the thesis.

    Attributes
    ----------
    measure, factor : str
        The measure (:data:`twin.pilot.studies.population.COMPARED`) and the factor.
    thesis_f : float
        The thesis' F (Tables 6.4-6.7, nine subjects).
    thesis_direction : str or None
        ``"+"``/``"-"`` where the thesis found the effect, None where it found none.
    signed_f : tuple of float
        The twin's F per population, negative where its direction is ``"-"``.
    subjects : int
        Subjects per population.
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
    subjects: int
    agreed: int
    probability: float

    @property
    def populations(self) -> int:
        """Number of populations."""
        return len(self.signed_f)

    @property
    def expected(self) -> float:
        """Agreements expected if the true effect were exactly the thesis' estimate."""
        return self.probability * self.populations

    @property
    def d_z(self) -> FloatArray:
        """The twin's standardised effect per population: sign(effect) sqrt(F / n)."""
        f = np.asarray(self.signed_f, dtype=float)
        return np.sign(f) * np.sqrt(np.abs(f) / self.subjects)

    @property
    def thesis_d_z(self) -> tuple[float, ...]:
        """The thesis' standardised effect: one value with its direction, or both signs."""
        d = float(np.sqrt(self.thesis_f / THESIS_SUBJECTS))
        if self.thesis_direction is None:
            return (-d, d)
        return (signed_f(d, self.thesis_direction),)

    @property
    def p_draw(self) -> float:
        """Probability of a draw of the twin at least as far out as the thesis'.

        :func:`predictive_p` of the thesis' d_z (either sign where the thesis gave none),
        whose sampling spread is sqrt(n / 9) times a population's of n subjects.
        """
        return max(predictive_p(self.d_z, d, self._thesis_scale) for d in self.thesis_d_z)

    @property
    def log_density(self) -> float:
        """Log predictive density of the thesis' d_z (:func:`predictive_log_density`).

        Where the thesis gave no direction, the likelier sign's (a score: over both signs it
        is not a normalised density).
        """
        return float(self.log_densities(np.arange(self.populations)[None, :])[0])

    def log_densities(self, picks: ArrayLike) -> FloatArray:
        """:attr:`log_density` over the populations of each row of indices ``picks``.

        Parameters
        ----------
        picks : array_like of int, shape (rows, N)
            Population indices, N >= 2 per row.

        Returns
        -------
        ndarray, shape (rows,)

        """
        draws = self.d_z[np.asarray(picks, dtype=int)]
        return np.max([predictive_log_densities(draws, d, self._thesis_scale)
                       for d in self.thesis_d_z], axis=0)  # fmt: skip

    @property
    def _thesis_scale(self) -> float:
        """The thesis' sampling spread of d_z relative to a population's: sqrt(n / 9)."""
        return float(np.sqrt(self.subjects / THESIS_SUBJECTS))

    @property
    def plausible(self) -> bool:
        """Whether the thesis' result is a plausible draw of the twin (:data:`PLAUSIBLE`)."""
        return self.p_draw >= PLAUSIBLE

    def quantiles(self) -> tuple[float, float, float]:
        """5 %, median and 95 % of the twin's d_z over populations."""
        q = np.percentile(self.d_z, [5, 50, 95])
        return float(q[0]), float(q[1]), float(q[2])

    def to_dict(self) -> dict[str, object]:
        """JSON-ready."""
        lo, med, hi = self.quantiles()
        return {"thesis_F": self.thesis_f, "thesis_direction": self.thesis_direction,
                "thesis_d_z": list(self.thesis_d_z), "signed_F": list(self.signed_f),
                "d_z_median": med, "d_z_5_95": [lo, hi], "p_draw": self.p_draw,
                "plausible": self.plausible, "log_density": self.log_density,
                "agreed": self.agreed,
                "populations": self.populations, "agreement_probability": self.probability,
                "expected_agreements": self.expected}  # fmt: skip


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
    spread : Spread
        How they differ in motion perception and visual delay.

    """

    effects: tuple[EffectReplication, ...]
    seeds: tuple[int, ...]
    subjects: int
    adapted: tuple[str, ...]
    run_to_run_sd: float
    spread: Spread = DEFAULT_SPREAD

    def effect(self, measure: str, factor: str) -> EffectReplication:
        """Return one effect by name."""
        for e in self.effects:
            if (e.measure, e.factor) == (measure, factor):
                return e
        names = sorted({e.measure for e in self.effects})
        raise SignalError(f"no effect {measure!r} x {factor!r}; measures: {', '.join(names)}; "
                          f"factors: {', '.join(FACTORS)}")  # fmt: skip

    @property
    def log_density(self) -> float:
        """Sum of the effects' log predictive densities of the thesis' results.

        A score of the twin's settings against the thesis (higher: the thesis' main effects
        are likelier draws of the twin); compare settings on the same seeds and measures.
        """
        return float(sum(e.log_density for e in self.effects))

    def implausible(self) -> list[EffectReplication]:
        """Return the effects where the thesis is not a plausible draw of the twin."""
        return [e for e in self.effects if not e.plausible]

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: ``{"replication": {MEASURE: {FACTOR: {...}}}, "seeds", ...}``."""
        rep: dict[str, dict[str, object]] = {}
        for e in self.effects:
            rep.setdefault(e.measure, {})[e.factor] = e.to_dict()
        return {"replication": rep, "seeds": list(self.seeds), "subjects": self.subjects,
                "adapted": list(self.adapted), "run_to_run_sd": self.run_to_run_sd,
                **self.spread.to_dict(),
                "implausible": [f"{e.measure}/{e.factor}" for e in self.implausible()],
                "log_density": self.log_density}  # fmt: skip

    def format_table(self) -> str:
        """Plain-text table: the twin's standardised effects over populations beside the thesis'."""
        n = len(self.seeds)
        lines = [
            f"Chapter 6 replicated by {n} populations of {self.subjects} adaptive subjects "
            f"(seeds {_seed_list(self.seeds)}; run-to-run variation {self.run_to_run_sd:.0%}; "
            f"{self.spread.describe()})",
            f"{'measure':30s} {'factor':6s} {'twin d_z: median':>16s} {'5-95 %':>13s} | "
            f"{'thesis d_z':>10s} {'p draw':>7s} | agree expected",
        ]
        for e in self.effects:
            lo, med, hi = e.quantiles()
            d = e.thesis_d_z[-1]
            thesis = f"{d:+.2f}" if e.thesis_direction else f"+-{d:.2f}"
            lines.append(
                f"{e.measure:30s} {e.factor:6s} {med:+16.2f} {lo:+6.2f} {hi:+6.2f} | "
                f"{thesis:>10s} {e.p_draw:7.3f} | {e.agreed:2d}/{n:<2d} {e.expected:8.1f}"
                + ("" if e.plausible else "  <- differs")
            )
        bad = self.implausible()
        lines += [
            "d_z: standardised effect, sign(effect) sqrt(F / subjects) (the thesis' F(1, 8) "
            "with its direction; +- where it found none)",
            f"p draw: probability that a draw of the twin lies as far from its mean as the "
            f"thesis' (predictive t); below {PLAUSIBLE}: '<- differs' (of 36, about two by chance)",
            "agree: populations with p < 0.05 in the thesis' direction where it found the effect, "
            "p >= 0.05 where not; expected: if the true effect were exactly the thesis' estimate",
            f"the thesis is a plausible draw of the twin for {len(self.effects) - len(bad)} of "
            f"{len(self.effects)} main effects; log predictive density of the thesis' effects "
            f"{self.log_density:.1f} (higher: likelier)",
        ]
        if self.subjects != THESIS_SUBJECTS:
            lines.append(f"(the test is calibrated for populations of {THESIS_SUBJECTS}, the "
                         f"thesis' size; with {self.subjects} it is approximate)")  # fmt: skip
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """One row per main effect (:meth:`EffectReplication.to_dict`)."""
        return frame(e.to_dict() for e in self.effects)

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Standardised effects over populations (5-95 % and median) beside the thesis'.

        Parameters
        ----------
        ax : sequence of three Axes, optional
            Where to draw: one per factor; a new figure by default.
        path : str, optional
            A PNG (or any matplotlib format) to write the figure to.

        Returns
        -------
        matplotlib.figure.Figure

        """
        from twin.core.plotting import finish

        measures = list(dict.fromkeys(e.measure for e in self.effects))
        label = "standardised effect d_z = sign sqrt(F / subjects)"
        fig, axes = effect_axes(measures, 0.35 * len(measures) + 2, label, ax)
        crit = float(stats.t.ppf(1 - ALPHA / 2, self.subjects - 1) / np.sqrt(self.subjects))
        for ax, factor in zip(axes, FACTORS, strict=True):
            for i, m in enumerate(measures):
                e = self.effect(m, factor)
                lo, med, hi = e.quantiles()
                colour = "C0" if e.plausible else "C3"
                ax.plot([lo, hi], [i, i], color=colour, lw=3, alpha=0.5)
                ax.plot(med, i, "o", color=colour, ms=5)
                marker = "k|" if e.thesis_direction else "kx"
                ax.plot(e.thesis_d_z, [i] * len(e.thesis_d_z), marker, ms=9, mew=2)
            for sign in (-1, 1):
                ax.axvline(sign * crit, color="0.6", ls=":", lw=1)
        axes[0].invert_yaxis()
        fig.suptitle(
            f"{len(self.seeds)} populations of {self.subjects} adaptive subjects: twin's d_z, "
            "5-95 % (bar) and median (dot); thesis' (| found; x not found, either sign); "
            f"dotted: p = 0.05 for {self.subjects} subjects;\nred: the thesis is not a "
            f"plausible draw of the twin (predictive p < {PLAUSIBLE})",
            fontsize=9,
        )
        return finish(fig, path, dpi=110)


def _seed_list(seeds: Sequence[int]) -> str:
    """``0-19`` for consecutive seeds, else the list."""
    s = list(seeds)
    if s == list(range(s[0], s[0] + len(s))):
        return f"{s[0]}-{s[-1]}"
    return ", ".join(map(str, s))


def alike(results: Sequence[PopulationResult]) -> int:
    """Check that populations are distinct draws flown alike; return their subjects each.

    Raises
    ------
    SignalError
        No populations, repeated seeds, or populations that differ in subjects, adapted
        parameters, run-to-run variation, measures, how they were measured or the subjects'
        spreads (:class:`~twin.pilot.studies.spread.Spread`).

    """
    if not results:
        raise SignalError("no populations given: fly some first")
    seeds = [r.seed for r in results]
    if len(set(seeds)) != len(seeds):
        raise SignalError(
            f"a replication or design needs distinct populations; seeds {seeds} repeat"
        )
    first = results[0]
    subjects = len({r["subject"] for r in first.rows})
    want = (subjects, first.adapted, first.run_to_run_sd, tuple(first.anova), first.identified,
            first.spread)  # fmt: skip
    for r in results[1:]:
        got = (len({row["subject"] for row in r.rows}), r.adapted, r.run_to_run_sd,
               tuple(r.anova), r.identified, r.spread)  # fmt: skip
        if got != want:
            raise SignalError(f"populations differ in subjects, adapted parameters, run-to-run "
                              f"variation, measures, identification or the subjects' "
                              f"spreads: {got} vs {want}")  # fmt: skip
    return subjects


def replicate(results: Sequence[PopulationResult]) -> Replication:
    """Summarise populations flown with the same settings (:func:`run_populations`).

    Parameters
    ----------
    results : sequence of PopulationResult
        At least two populations with distinct seeds, the same number of subjects, adapted
        parameters, run-to-run variation and measures.

    Returns
    -------
    Replication

    Raises
    ------
    SignalError
        Fewer than two populations, repeated seeds, populations that differ, or an F that is
        not finite.

    """
    if len(results) < 2:
        raise SignalError(f"a replication needs at least 2 populations; got {len(results)}")
    subjects = alike(results)
    first = results[0]
    seeds = [r.seed for r in results]
    agreements = [r.agreement() for r in results]
    effects = []
    for measure in first.anova:
        for factor in FACTORS:
            bad = [r.seed for r in results if not np.isfinite(r.anova[measure][factor]["F"])]
            if bad:
                raise SignalError(f"{measure} x {factor}: F is not finite in population(s) "
                                  f"{bad} (no spread between subjects' differences)")  # fmt: skip
            thesis_f, direction = TABLES_6_4_TO_6_7[measure][factor]
            cells = [r.anova[measure][factor] for r in results]
            signed = tuple(signed_f(c["F"], c["direction"]) for c in cells)
            agreed = sum(bool(a[measure][factor]) for a in agreements)
            prob = agreement_probability(thesis_f, direction is not None, subjects)
            effects.append(EffectReplication(measure, factor, thesis_f, direction, signed,
                                             subjects, agreed, prob))  # fmt: skip
    return Replication(tuple(effects), tuple(seeds), subjects, first.adapted,
                       first.run_to_run_sd, first.spread)  # fmt: skip


def run_populations(
    n_populations: int = 20,
    n_subjects: int = THESIS_SUBJECTS,
    seed: int = 0,
    progress: ProgressFn | None = None,
    scheduler: Engine | str | None = None,
    adapted: tuple[str, ...] = ADAPTED,
    run_to_run_sd: float = ADAPTATION_SD,
    identified: float | None = None,
    spread: Spread = DEFAULT_SPREAD,
) -> tuple[Replication, list[PopulationResult]]:
    """Fly ``n_populations`` populations (seeds ``seed``, ``seed + 1``, ...) and replicate.

    Every subject of every population is one task, so the workers stay busy across
    populations; each population equals :func:`~twin.pilot.studies.population.run_population` with
    its seed.

    Parameters
    ----------
    n_populations : int
        Populations (at least 2; 20 for a distribution).
    n_subjects : int
        Subjects per population (the thesis' nine by default).
    seed : int
        The first population's seed.
    progress : callable, optional
        Called as subjects finish (:mod:`twin.core.progress`).
    scheduler : Engine or str, optional
        Where the subjects fly (:mod:`twin.core.tasks.engine`; default this process).
    adapted : tuple of str
        What the subjects adapt (:data:`twin.pilot.models.adapt.ADAPTED`).
    run_to_run_sd : float
        Their run-to-run variation (log-normal sd, 0 to 1).
    identified : float, optional
        Measure the pilot model as the thesis did, identified from the runs, with a passive
        feedthrough of this relative size (0: none; :mod:`twin.pilot.studies.identified`); None (the
        default): the pilots' own measures.
    spread : Spread
        How the subjects differ in motion perception and visual delay
        (:class:`twin.pilot.studies.spread.Spread`).

    Returns
    -------
    (Replication, list of PopulationResult)
        The summary and the populations.

    Raises
    ------
    SignalError
        Fewer than two populations or subjects, or a bad setting.
    TypeError
        A ``spread`` that is not a :class:`~twin.pilot.studies.spread.Spread`.
    TaskError
        When a subject failed (named with its number and seed).

    """
    if n_populations < 2:
        raise SignalError(f"a replication needs at least 2 populations; got {n_populations}")
    adapted = checked_settings(adapted, run_to_run_sd, spread)
    seeds = list(range(seed, seed + n_populations))
    if identified is None:
        fly, tasks_of, result_of, extra = fly_subject, population_tasks, population_result, ()
    else:
        check_feedthrough(identified)
        fly, tasks_of, result_of = identified_subject, identified_tasks, identified_result
        extra = (identified,)
    tasks = [tasks_of(n_subjects, s, adapted, run_to_run_sd, *extra, spread) for s in seeds]
    args = [a for t in tasks for a in t[0]]
    inputs = [i for t in tasks for i in t[1]]
    with using(scheduler) as engine:
        flown = engine.map(fly, args, inputs, "subjects", progress).values()
    results = [result_of(flown[k * n_subjects : (k + 1) * n_subjects], s, adapted,
                         run_to_run_sd, *extra, spread)
               for k, s in enumerate(seeds)]  # fmt: skip
    return replicate(results), results
