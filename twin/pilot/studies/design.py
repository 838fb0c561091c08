"""How many subjects an experiment needs to find each effect, designed on the twin's subjects.

The replication (:mod:`twin.pilot.studies.replication`) asks whether the thesis' nine participants
are a plausible draw of the twin's populations. The engineer planning the next experiment asks the
converse: if the twin is right, how many participants will show each effect (p < 0.05 in the
thesis' direction), and will the effects the thesis did not find stay out? And one population of
nine that misses an effect, or the thesis' experiment itself, is it a surprise?

Each main effect of the 2 x 2 x 2 within-subject design (Table 6.3) is a paired comparison:
its repeated-measures F(1, n - 1) is t^2 of the subjects' differences between the factor's two
levels, each level the mean of the subject's four cells at it (tested against statsmodels'
``AnovaRM``). So the subjects of every flown population are one pool of such differences, a
sample of the twin's subjects, and an experiment with N subjects is N of them drawn at random
(a bootstrap over subjects, which keeps the correlations between a subject's measures),
tested as the ANOVA tests them. An effect is *found* when p < 0.05, and *agrees* with the
thesis when found in its direction where it found the effect, and not found where it found
none (:meth:`twin.pilot.studies.population.PopulationResult.agreement`; tested draw by draw against
it). Beside the twin: the same for a world in which the thesis' conclusions are the truth -
the effects it found at its estimates (noncentral t,
:func:`twin.pilot.studies.replication.agreement_probability`), those it did not find absent.

The pool's size limits what it can tell. A bootstrap takes the pool for the population, so
its d_z for the truth: experiments go up to half the pool (at most :data:`MAX_SUBJECTS`), and
an effect within two standard errors of zero in the pool may be none at all - for it, the size
from which large experiments would find it is the pool's sampling, not a prediction (marked in
the table). And the pool's tails are few subjects: where the differences are skewed (a few
subjects whose target crossover rose behind the filter), which of them the pool holds moves
the prediction. So the pool itself is resampled (:data:`RESAMPLES`) and each prediction comes
with its 5-95 % over the resamples. The default pool, 20 populations of nine, is 180
subjects. The predicted agreement at the flown populations' size is printed beside their own
count; the pool holds those very populations, so this is a check of the approach in-sample
(``bench/pilot_adaptive.py --design-only`` flies fresh ones: 20 populations of 18 agreed with
the design within its interval and theirs on every effect, docs).

Examples
--------
>>> subjects_for([0.5, 0.8, 0.79, 0.81, 0.9], 0.8, first=2)   # stays at 0.8 from 5 on
5
>>> window([0.5, 0.85, 0.9, 0.7], 0.8, first=2)   # rises, then falls
(3, 4)

"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from twin.core.errors import SignalError
from twin.core.results import frame
from twin.core.thesis import TABLES_6_4_TO_6_7
from twin.pilot.studies.population import FACTORS, MEASURES, PopulationResult
from twin.pilot.studies.replication import ALPHA, THESIS_SUBJECTS, agreement_probability, alike

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from twin.core.plotting import AxesArg

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Largest experiment designed (subjects; and at most half the pool).
MAX_SUBJECTS = 60
#: Power an experiment is designed for (the usual 80 %).
POWER = 0.8
#: Simulated experiments per size.
DRAWS = 4000
#: Resamples of the pool, for the design's own uncertainty (its pool is finite), and the
#: simulated experiments per size in each.
RESAMPLES, RESAMPLE_DRAWS = 50, 400
#: The issue's acceptance: every filter effect of the JSON contract found in the thesis'
#: direction, and delay and noise not found on either crossover (Table 6.5).
ACCEPTANCE = (
    *((m, "filter") for m in MEASURES),
    *((m, f) for f in ("delay", "noise")
      for m in ("crossover_disturbance_rad_s", "crossover_target_rad_s")),
)  # fmt: skip
#: Fewest subjects pooled for a design (experiments then go up to 20 subjects).
MIN_POOL = 40
#: One row per subject and cell: every combination of the factors' levels.
CELLS = frozenset((a, b, c) for a in (0, 1) for b in (0, 1) for c in (0, 1))


def subject_differences(rows: Sequence[dict[str, float]], measure: str, factor: str) -> FloatArray:
    """Each subject's mean at the factor's second level minus its mean at the first.

    Parameters
    ----------
    rows : sequence of dict
        One population's rows (:attr:`PopulationResult.rows`): ``subject``, the factors' levels
        (0, 1) and the measures, one row per subject and cell of the 2 x 2 x 2 design.
    measure, factor : str
        The measure and the factor (:data:`twin.pilot.studies.population.FACTORS`).

    Returns
    -------
    ndarray, shape (subjects,)
        In subject order. Their t statistic squared is the ANOVA's F for the main effect.

    Raises
    ------
    SignalError
        An unknown factor, a subject without exactly one row per cell, or a measure that is
        not a finite number.

    """
    if factor not in FACTORS:
        raise SignalError(f"unknown factor {factor!r}; factors: {', '.join(FACTORS)}")
    cells: dict[int, dict[tuple[int, ...], float]] = {}
    for r in rows:
        value = float(r[measure])
        if not np.isfinite(value):
            raise SignalError(f"subject {r['subject']}, condition {r.get('condition')}: "
                              f"{measure} is {value}; a design needs finite measures")  # fmt: skip
        cell = tuple(int(r[f]) for f in FACTORS)
        own = cells.setdefault(int(r["subject"]), {})
        if cell in own:
            raise SignalError(f"subject {r['subject']} has two rows for the cell "
                              f"{dict(zip(FACTORS, cell, strict=True))}")  # fmt: skip
        own[cell] = value
    k = list(FACTORS).index(factor)
    out = []
    for subject, own in sorted(cells.items()):
        if set(own) != CELLS:
            raise SignalError(f"subject {subject} has cells {sorted(own)}; a design needs one "
                              f"row per cell of the 2 x 2 x 2 design, levels 0 and 1")  # fmt: skip
        second = [v for c, v in own.items() if c[k] == 1]
        first = [v for c, v in own.items() if c[k] == 0]
        out.append(np.mean(second) - np.mean(first))
    return np.asarray(out, dtype=float)


def subjects_for(agreement: Sequence[float], power: float = POWER, first: int = 2) -> int | None:
    """Return the fewest subjects from which the agreement stays at ``power`` or above.

    For a curve that rises with the subjects (an effect to be found).

    Parameters
    ----------
    agreement : sequence of float
        Probability of agreement for ``first``, ``first + 1``, ... subjects.
    power : float
        The target.
    first : int
        Subjects of the first entry.

    Returns
    -------
    int or None
        None if the last entry is below ``power`` (more subjects than were tried).

    """
    a = np.asarray(agreement, dtype=float)
    below = np.flatnonzero(a < power)
    if below.size == 0:
        return first
    if below[-1] == a.size - 1:
        return None
    return first + int(below[-1]) + 1


def window(
    agreement: Sequence[float], power: float = POWER, first: int = 2
) -> tuple[int, int] | None:
    """Return the fewest and the most subjects at which the agreement reaches ``power``.

    For a curve that may rise and then fall (effects to be found and others to stay out).

    Returns
    -------
    (int, int) or None
        None if it never does.

    """
    at = np.flatnonzero(np.asarray(agreement, dtype=float) >= power)
    return None if at.size == 0 else (first + int(at[0]), first + int(at[-1]))


@dataclass(frozen=True)
class Design:
    """The twin's subjects pooled: per main effect, agreement with the thesis by subjects.

    Attributes
    ----------
    effects : tuple of (str, str)
        (measure, factor) per column of ``differences``.
    differences : ndarray, shape (pool, effects)
        Every pooled subject's difference between the factor's levels, per effect.
    agreement : ndarray, shape (sizes, effects)
        Probability that an experiment with 2, 3, ... subjects (up to half the pool, at most
        :data:`MAX_SUBJECTS`) of the twin's agrees with the thesis on each effect (bootstrap,
        ``draws`` per size).
    acceptance : ndarray, shape (sizes,)
        Probability that it agrees on every effect of :data:`ACCEPTANCE` at once.
    flown : dict
        (measure, factor) -> populations that agreed, of those flown (their size: ``subjects``).
    flown_acceptance : int
        Populations that agreed on every effect of :data:`ACCEPTANCE` at once.
    populations, subjects : int
        Populations pooled and their subjects each.
    spread : ndarray, shape (2, sizes, effects)
        5 % and 95 % of ``agreement`` over resamples of the pool.
    acceptance_spread : ndarray, shape (2, sizes)
        The same for ``acceptance``.
    draws : int
        Simulated experiments per size.

    """

    effects: tuple[tuple[str, str], ...]
    differences: FloatArray
    agreement: FloatArray
    acceptance: FloatArray
    flown: dict[tuple[str, str], int]
    flown_acceptance: int
    populations: int
    subjects: int
    spread: FloatArray
    acceptance_spread: FloatArray
    draws: int = DRAWS

    @property
    def sizes(self) -> range:
        """The numbers of subjects designed for."""
        return range(2, 2 + self.agreement.shape[0])

    def d_z(self, k: int) -> float:
        """Effect ``k``'s standardised size over the pool: mean difference over its sd."""
        x = self.differences[:, k]
        sd = float(np.std(x, ddof=1))
        return float(np.mean(x)) / sd if sd > 0 else 0.0

    def d_z_se(self, k: int) -> float:
        """Return the standard error of :meth:`d_z`: sqrt((1 + d_z^2 / 2) / pool)."""
        return float(np.sqrt((1 + self.d_z(k) ** 2 / 2) / self.differences.shape[0]))

    def near_zero(self, k: int) -> bool:
        """Whether effect ``k`` is within two standard errors of none in the pool."""
        return abs(self.d_z(k)) < 2 * self.d_z_se(k)

    def at(self, n: int) -> FloatArray:
        """Agreement per effect for ``n`` subjects."""
        if n not in self.sizes:
            raise SignalError(f"designed for {self.sizes[0]} to {self.sizes[-1]} subjects (at "
                              f"most half the pool of {self.differences.shape[0]}); got "
                              f"{n}")  # fmt: skip
        return self.agreement[n - self.sizes[0]]

    def acceptance_at(self, n: int) -> float:
        """Probability that ``n`` subjects agree on every effect of :data:`ACCEPTANCE`."""
        self.at(n)  # checks n
        return float(self.acceptance[n - self.sizes[0]])

    def found(self, k: int) -> bool:
        """Whether the thesis found effect ``k`` (p < 0.05, Tables 6.4-6.7)."""
        measure, factor = self.effects[k]
        return TABLES_6_4_TO_6_7[measure][factor][1] is not None

    def thesis_agreement(self, k: int, n: int) -> float:
        """Agreement for ``n`` subjects if the thesis' conclusions were the truth.

        An effect it found at its estimate; one it did not find absent (F = 0).
        """
        measure, factor = self.effects[k]
        f = TABLES_6_4_TO_6_7[measure][factor][0] if self.found(k) else 0.0
        return agreement_probability(f, self.found(k), n)

    def needed(self, k: int, power: float = POWER) -> int | None:
        """Subjects from which the twin's effect ``k`` agrees with the thesis at ``power``.

        None where the thesis found no effect (:meth:`lost_from`), or where more subjects
        than designed are needed.
        """
        if not self.found(k):
            return None
        return subjects_for(self.agreement[:, k], power, self.sizes[0])

    def needed_spread(self, k: int, power: float = POWER) -> tuple[int | None, int | None]:
        """:meth:`needed` from the 5 % and the 95 % curves of the pool's resamples.

        The fewer subjects from the optimistic curve, the more from the pessimistic one (None:
        more than designed). (None, None) where the thesis found no effect.
        """
        if not self.found(k):
            return None, None
        fewest, most = (subjects_for(self.spread[i, :, k], power, self.sizes[0]) for i in (1, 0))
        return fewest, most

    def lost_from(self, k: int, power: float = POWER) -> int | None:
        """Subjects from which an effect the thesis did not find no longer agrees at ``power``.

        The twin's effect is then found (p < 0.05) in more than ``1 - power`` of experiments
        that size. None if it agrees at ``power`` up to the largest size designed, or where
        the thesis found the effect.
        """
        if self.found(k):
            return None
        below = np.flatnonzero(self.agreement[:, k] < power)
        return None if below.size == 0 else self.sizes[0] + int(below[0])

    def thesis_needed(self, k: int, power: float = POWER) -> int | None:
        """Return :meth:`needed` for the thesis' estimate as the true effect (found ones only)."""
        if not self.found(k):
            return None
        return subjects_for([self.thesis_agreement(k, n) for n in self.sizes], power,
                            self.sizes[0])  # fmt: skip

    def thesis_acceptance(self, n: int) -> float:
        """Return the acceptance's probability for ``n`` subjects if the thesis were the truth.

        The product of its effects' :meth:`thesis_agreement`: the thesis gives no
        correlations between its effects, so they are taken as independent (the twin's are
        not: its subjects carry their measures together).
        """
        keys = [self.effects.index(e) for e in ACCEPTANCE]
        return float(np.prod([self.thesis_agreement(k, n) for k in keys]))

    def acceptance_window(self, power: float = POWER) -> tuple[int, int] | None:
        """Fewest and most subjects at which the twin meets the acceptance at ``power``.

        The acceptance asks for effects to be found (likelier with more subjects) and others
        to stay out (less likely, where the twin has them at all), so it may rise and fall.
        """
        return window(self.acceptance, power, self.sizes[0])

    def _flown_size(self) -> int | None:
        """Return the flown populations' size, if designed for (else None)."""
        return self.subjects if self.subjects in self.sizes else None

    def spread_at(self, n: int) -> FloatArray:
        """5 % and 95 % of the agreement per effect for ``n`` subjects, shape (2, effects)."""
        self.at(n)  # checks n
        return self.spread[:, n - self.sizes[0]]

    def acceptance_spread_at(self, n: int) -> FloatArray:
        """5 % and 95 % of the acceptance's probability for ``n`` subjects, shape (2,)."""
        self.at(n)  # checks n
        return self.acceptance_spread[:, n - self.sizes[0]]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``{"design": {MEASURE: {FACTOR: {...}}}, "acceptance": {...}, ...}``.

        Per effect: ``d_z`` and ``d_z_se`` (pooled), ``near_zero``,
        ``agreement_at_flown_size`` (predicted for the flown populations' size; null if it is
        beyond the sizes designed) with its ``_5_95`` over the pool's resamples and the
        thesis', ``flown_agreed`` (of ``populations``), ``subjects_for_80`` (null: not found by
        the thesis, or more than designed) with its ``_5_95`` and the thesis',
        ``below_80_from`` (effects the thesis did not find), ``agreement_by_subjects`` (from 2
        on).
        """
        n = self._flown_size()
        out: dict[str, dict[str, Any]] = {}
        for k, (m, f) in enumerate(self.effects):
            out.setdefault(m, {})[f] = {
                "d_z": self.d_z(k), "d_z_se": self.d_z_se(k), "near_zero": self.near_zero(k),
                "thesis_direction": TABLES_6_4_TO_6_7[m][f][1],
                "agreement_at_flown_size": None if n is None else float(self.at(n)[k]),
                "agreement_at_flown_size_5_95":
                    None if n is None else self.spread_at(n)[:, k].tolist(),
                "thesis_agreement_at_flown_size": self.thesis_agreement(k, self.subjects),
                "flown_agreed": self.flown[m, f], "subjects_for_80": self.needed(k),
                "subjects_for_80_5_95": list(self.needed_spread(k)),
                "thesis_subjects_for_80": self.thesis_needed(k),
                "below_80_from": self.lost_from(k),
                "agreement_by_subjects": self.agreement[:, k].tolist(),
            }  # fmt: skip
        win = self.acceptance_window()
        nine = self.acceptance_at(THESIS_SUBJECTS) if THESIS_SUBJECTS in self.sizes else None
        flown = None if n is None else self.acceptance_spread_at(n).tolist()
        return {"design": out, "pool": self.differences.shape[0],
                "populations": self.populations, "subjects_per_population": self.subjects,
                "draws": self.draws, "sizes": [self.sizes[0], self.sizes[-1]],
                "acceptance": {"effects": [f"{m}/{f}" for m, f in ACCEPTANCE],
                               "at_thesis_size": nine,
                               "at_flown_size": None if n is None else self.acceptance_at(n),
                               "at_flown_size_5_95": flown,
                               "flown_agreed": self.flown_acceptance,
                               "thesis_at_thesis_size": self.thesis_acceptance(THESIS_SUBJECTS),
                               "window_80": None if win is None else list(win),
                               "by_subjects": self.acceptance.tolist()}}  # fmt: skip

    def format_table(self) -> str:
        """Plain-text table: per effect, agreement at the flown size and subjects for 80 %."""
        n, last = self._flown_size(), self.sizes[-1]
        lines = [
            f"Designing the experiment on the twin's subjects ({self.differences.shape[0]} "
            f"pooled from {self.populations} populations of {self.subjects}; {self.draws} "
            f"simulated experiments per size, 2 to {last} subjects; 5-95 % over "
            f"{RESAMPLES} resamples of the pool)",
            f"{'measure':30s} {'factor':6s} {'d_z +- 2 se':>13s} | "
            f"{f'agree with {self.subjects}: twin (5-95 %)':>30s} {'flown':>6s} {'thesis':>6s} "
            f"| {'80 % with: twin (5-95 %)':>26s} {'thesis':>6s}",
        ]
        for k, (m, f) in enumerate(self.effects):
            if self.found(k):
                lo, hi = (_count(x, last) for x in self.needed_spread(k))
                twin = _count(self.needed(k), last) + (f" ({lo} to {hi})" if lo != hi else "")
                th = _count(self.thesis_needed(k), last)
            else:  # the thesis found no effect: up to how many subjects the twin's stays out
                lost = self.lost_from(k)
                twin, th = (f"<{lost}" if lost else f"<={last}"), f"<={last}"
            mark = "*" if self.near_zero(k) and not self.found(k) else " "
            if n is None:
                pred = "-"
            else:
                lo_a, hi_a = self.spread_at(n)[:, k]
                pred = f"{self.at(n)[k]:.2f} ({lo_a:.2f}-{hi_a:.2f})"
            lines.append(
                f"{m:30s} {f:6s} {self.d_z(k):+6.2f} {2 * self.d_z_se(k):5.2f}{mark} | "
                f"{pred:>30s} {self.flown[m, f] / self.populations:6.2f} "
                f"{self.thesis_agreement(k, self.subjects):6.2f} | {twin:>26s} {th:>6s}"
            )
        win = self.acceptance_window()
        if n is None:
            flown = "-"
        else:
            lo_a, hi_a = self.acceptance_spread_at(n)
            flown = f"{self.acceptance_at(n):.0%}, {lo_a:.0%}-{hi_a:.0%}"
        nine = self.acceptance_at(THESIS_SUBJECTS) if THESIS_SUBJECTS in self.sizes else None
        lines += [
            "d_z: the pooled subjects' standardised effect (mean difference over its sd) and "
            "two standard errors; *: an effect the thesis did not find that is within them of "
            "zero in the pool: its '<N' is the pool's sampling, not a prediction",
            "agree: p < 0.05 in the thesis' direction where it found the effect, p >= 0.05 "
            "where not; twin: predicted from the pool; flown: the populations' own share (in "
            "the pool: a check in-sample); thesis: its found effects at its estimates, the "
            "others absent",
            f"80 % with: where the thesis found the effect, the fewest subjects from which it "
            f"is found in 80 % of experiments ('>{last}': more than designed); where it found "
            f"none, up to how many it stays out in 80 % ('<N': the twin's effect is found in "
            f"over 20 % of experiments of N subjects)",
            "the acceptance (every filter effect of the contract found, delay and noise not "
            "found on either crossover) holds at once in "
            + ("-" if nine is None else f"{nine:.0%}")
            + f" of the twin's experiments with {THESIS_SUBJECTS} subjects (the thesis' size; "
            f"if its conclusions were the truth, its effects taken as independent: "
            f"{self.thesis_acceptance(THESIS_SUBJECTS):.0%}); in 80 % "
            + ("with no size designed" if win is None else f"from {win[0]} to {win[1]} subjects")
            + f" (best {self.acceptance.max():.0%}, with "
            f"{self.sizes[int(np.argmax(self.acceptance))]}); the flown populations: "
            f"{self.flown_acceptance} of {self.populations} (predicted {flown})",
        ]
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """One row per main effect (measure and factor): the ``design`` of :meth:`to_dict`."""
        design = self.to_dict()["design"]
        return frame(
            {"measure": m, "factor": f, **v} for m, by in design.items() for f, v in by.items()
        )

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Agreement against subjects per filter effect, the twin's beside the thesis'.

        One panel per filter effect and one for the acceptance: the twin's curve with its
        5-95 % band, the thesis' conclusions as the truth (dashed) and the flown share (dot),
        saved to ``path`` if given; returns the matplotlib figure.

        Parameters
        ----------
        ax : sequence of Axes, optional
            Where to draw: one per filter effect and one for the acceptance, four per
            row, in row order (the count :attr:`panels` gives); a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        from twin.core.plotting import finish, subplots

        panels = [k for k, (_, f) in enumerate(self.effects) if f == "filter"]
        cols = 4
        rows = -(-(len(panels) + 1) // cols)
        fig, axes = subplots(ax, rows, cols, figsize=(13, 2.4 * rows + 0.6), sharex=True,
                             sharey=True, squeeze=False)  # fmt: skip
        n = np.asarray(self.sizes)
        flat = axes.ravel()
        shown = self._flown_size() is not None
        for ax, k in zip(flat, panels, strict=False):
            ax.fill_between(n, *self.spread[:, :, k], color="C0", alpha=0.2, lw=0)
            ax.plot(n, self.agreement[:, k], "C0", label="twin (pooled subjects; 5-95 %)")
            ax.plot(n, [self.thesis_agreement(k, int(x)) for x in n], "k--",
                    label="the thesis' conclusions as the truth")  # fmt: skip
            if shown:
                ax.plot(self.subjects, self.flown[self.effects[k]] / self.populations, "C3o",
                        label=f"flown: {self.populations} populations")  # fmt: skip
            ax.set_title(f"filter: {self.effects[k][0]}", fontsize=8)
        ax = flat[len(panels)]
        ax.fill_between(n, *self.acceptance_spread, color="C0", alpha=0.2, lw=0)
        ax.plot(n, self.acceptance, "C0")
        ax.plot(n, [self.thesis_acceptance(int(x)) for x in n], "k--")
        if shown:
            ax.plot(self.subjects, self.flown_acceptance / self.populations, "C3o")
        ax.set_title("the acceptance, all at once (thesis: independent)", fontsize=8)
        for ax in flat[len(panels) + 1 :]:
            ax.set_visible(False)
        for ax in flat[: len(panels) + 1]:
            ax.axhline(POWER, color="0.6", ls=":", lw=1)
            ax.axvline(THESIS_SUBJECTS, color="0.6", ls=":", lw=1)
            ax.set_ylim(0, 1.02)
            ax.grid(alpha=0.3)
        for ax in axes[-1]:
            ax.set_xlabel("subjects", fontsize=8)
        flat[0].legend(fontsize=7)
        fig.suptitle("Probability that an experiment finds each of Chapter 6's filter effects "
                     "(p < 0.05, the thesis' direction); dotted: 80 % and the thesis' nine",
                     fontsize=9)  # fmt: skip
        return finish(fig, path, dpi=110)


def _count(n: int | None, last: int) -> str:
    """Format a subject count: ``>last`` when more than designed."""
    return f">{last}" if n is None else str(n)


def agreements(
    differences: FloatArray,
    directions: Sequence[str | None],
    n: int,
    rng: np.random.Generator,
    draws: int = DRAWS,
) -> BoolArray:
    """Simulate experiments of ``n`` subjects drawn from the pool; agreement per draw, effect.

    Parameters
    ----------
    differences : ndarray, shape (pool, effects)
        The pooled subjects' differences.
    directions : sequence of str or None
        Per effect, the thesis' direction (``"+"``/``"-"``), or None where it found none.
    n : int
        Subjects per experiment (at least 2).
    rng : numpy.random.Generator
        Draws the subjects: ``rng.integers(pool, size=(draws, n))``, first.
    draws : int
        Experiments.

    Returns
    -------
    ndarray of bool, shape (draws, effects)

    """
    idx = rng.integers(differences.shape[0], size=(draws, n))
    x = differences[idx]
    mean = x.mean(axis=1)
    x -= mean[:, None, :]
    sd = np.sqrt(np.einsum("dne,dne->de", x, x) / (n - 1))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = mean / (sd / np.sqrt(n))
    t = np.where(sd > 0, t, 0.0)  # every draw the same subject: no test
    found = np.abs(t) > stats.t.ppf(1 - ALPHA / 2, n - 1)  # p < ALPHA, two-sided
    sign = np.array([0.0 if d is None else (1.0 if d == "+" else -1.0) for d in directions])
    return np.where(sign == 0, ~found, found & (np.sign(t) == sign))


def design(
    results: Sequence[PopulationResult],
    seed: int | None = None,
    draws: int = DRAWS,
    resamples: int = RESAMPLES,
    resample_draws: int = RESAMPLE_DRAWS,
) -> Design:
    """Pool the subjects of flown populations; design experiments of 2 to 60 subjects.

    (Up to half the pool, where that is fewer.)

    Parameters
    ----------
    results : sequence of PopulationResult
        Populations flown alike (distinct seeds, the same subjects, settings and measures,
        :func:`twin.pilot.studies.replication.alike`), with every effect of :data:`ACCEPTANCE`
        measured; at least :data:`MIN_POOL` subjects in all.
    seed : int, optional
        Seed of the simulated experiments (default: the first population's).
    draws : int
        Simulated experiments per size.
    resamples, resample_draws : int
        Resamples of the pool (at least 2), and simulated experiments per size in each: the
        design's own uncertainty.

    Returns
    -------
    Design

    Raises
    ------
    SignalError
        Populations not alike, an effect of the acceptance not measured, too few subjects
        pooled, or rows that are unbalanced or not finite.

    """
    if resamples < 2:
        raise SignalError(f"the design's spread needs at least 2 resamples; got {resamples}")
    subjects = alike(results)
    effects = tuple((m, f) for m in results[0].anova for f in FACTORS)
    missing = [f"{m}/{f}" for m, f in ACCEPTANCE if (m, f) not in effects]
    if missing:
        raise SignalError(f"a design needs every effect of the acceptance measured; missing: "
                          f"{', '.join(missing)}")  # fmt: skip
    diffs = np.vstack([
        np.column_stack([subject_differences(r.rows, m, f) for m, f in effects])
        for r in results
    ])  # fmt: skip
    if diffs.shape[0] < MIN_POOL:
        raise SignalError(f"a design pools at least {MIN_POOL} subjects (experiments go up to "
                          f"half the pool); got {diffs.shape[0]}")  # fmt: skip
    directions = [TABLES_6_4_TO_6_7[m][f][1] for m, f in effects]
    accept = [effects.index(e) for e in ACCEPTANCE]
    rng = np.random.default_rng(np.random.SeedSequence([results[0].seed if seed is None
                                                         else seed, 17]))  # fmt: skip
    sizes = range(2, min(MAX_SUBJECTS, diffs.shape[0] // 2) + 1)

    def curves(pool: FloatArray, k: int) -> tuple[FloatArray, FloatArray]:
        agree, joint = [], []
        for n in sizes:
            a = agreements(pool, directions, n, rng, k)
            agree.append(a.mean(axis=0))
            joint.append(a[:, accept].all(axis=1).mean())
        return np.asarray(agree), np.asarray(joint)

    agree, joint = curves(diffs, draws)
    resampled = [curves(diffs[rng.integers(len(diffs), size=len(diffs))], resample_draws)
                 for _ in range(resamples)]  # fmt: skip
    spread = np.percentile([a for a, _ in resampled], [5, 95], axis=0)
    joint_spread = np.percentile([j for _, j in resampled], [5, 95], axis=0)
    agreed = [r.agreement() for r in results]
    flown = {(m, f): sum(bool(a[m][f]) for a in agreed) for m, f in effects}
    both = sum(all(a[m][f] for m, f in ACCEPTANCE) for a in agreed)
    return Design(effects, diffs, agree, joint, flown, both, len(results), subjects, spread,
                  joint_spread, draws)  # fmt: skip
