"""How sure a choice between two settings of the simulated subjects is: halves of populations.

Settings that the thesis does not give (the subjects' spreads, :mod:`twin.pilot.studies.spread`) are
chosen by the log predictive density of the thesis' main effects under the twin's populations
(:attr:`twin.pilot.studies.replication.Replication.log_density`). Flown on the same seeds, two
settings draw the same people, so their difference is much surer than either score; but the
populations are still few (10-20), and one or two outlying populations can decide a sum over 36
effects. :func:`log_density_difference` scores both settings again on halves of the populations (the
same half for both; every half where there are at most :data:`ALL_HALVES`, else random ones)
and reports the difference's 5-95 % over halves and how often the first setting scores higher:
would a profile of half as many populations have made the same choice? The halves' scores are
of half-size profiles (fewer degrees of freedom), so their 5-95 % is not an interval for the
full difference; and where the better setting was picked on these same populations, its share
is biased in its favour. (Halves, not a bootstrap: resampling with replacement repeats
populations, which shrinks their spread and sharpens every prediction, so the bootstrap's
scores are biased and its interval can miss the full sample's difference.)
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from twin.core.errors import SignalError
from twin.pilot.studies.replication import Replication

#: Halves enumerated up to this many (20 populations: 184,756); beyond, ``resamples`` random.
ALL_HALVES = 200_000
#: Random halves drawn by default where there are more than :data:`ALL_HALVES`.
RESAMPLES = 2000


@dataclass(frozen=True)
class ScoreDifference:
    """The log-density difference of two settings over the same populations.

    Attributes
    ----------
    difference : float
        ``a.log_density - b.log_density`` (positive: the thesis is likelier under ``a``).
    low, high : float
        5 % and 95 % of the difference over halves of the populations (half-size profiles:
        not an interval for ``difference``).
    share : float
        Fraction of halves in which ``a`` scores higher.
    resamples : int
        Halves scored.
    exact : bool
        Whether every half was scored (else random halves).

    """

    difference: float
    low: float
    high: float
    share: float
    resamples: int
    exact: bool = False

    def format(self) -> str:
        """One line: the difference, its 5-95 % over halves, and how often the first wins."""
        which = "all" if self.exact else "random"
        return (f"{self.difference:+.1f}; on half the populations {self.low:+.1f} to "
                f"{self.high:+.1f}, higher in {self.share:.1%} of {self.resamples} "
                f"({which}) halves")  # fmt: skip


def log_density_difference(
    a: Replication, b: Replication, resamples: int = RESAMPLES, seed: int = 0
) -> ScoreDifference:
    """Compare two settings flown on the same seeds, on all populations and on halves.

    Parameters
    ----------
    a, b : Replication
        The two settings' replications (:func:`twin.pilot.studies.replication.run_populations`),
        with the same seeds (at least 4 populations), subjects and effects.
    resamples : int
        Random halves drawn (at least 100) where there are more than :data:`ALL_HALVES`
        halves; else every half is scored.
    seed : int
        Seed of the random halves.

    Returns
    -------
    ScoreDifference

    Raises
    ------
    SignalError
        Replications over other seeds, subjects or effects, fewer than 4 populations, too
        few halves, or an effect that is not finite or the same in every population.

    """
    if a.seeds != b.seeds or a.subjects != b.subjects:
        raise SignalError(f"a paired comparison needs the same populations; seeds "
                          f"{list(a.seeds)} and {list(b.seeds)}, subjects {a.subjects} and "
                          f"{b.subjects}")  # fmt: skip
    names = [(e.measure, e.factor) for e in a.effects]
    if names != [(e.measure, e.factor) for e in b.effects]:
        raise SignalError("the two replications compare different effects with the thesis")
    if resamples < 100:
        raise SignalError(f"a comparison needs at least 100 random halves; got {resamples}")
    n = len(a.seeds)
    if n < 4:
        raise SignalError(f"a comparison on halves needs at least 4 populations; got {n}")
    for e in (*a.effects, *b.effects):
        if not np.all(np.isfinite(e.d_z)):
            raise SignalError(f"{e.measure} x {e.factor}: an effect is not finite in "
                              f"{list(e.d_z)}")  # fmt: skip
    exact = math.comb(n, n // 2) <= ALL_HALVES
    if exact:
        halves = np.array(list(itertools.combinations(range(n), n // 2)))
    else:
        rng = np.random.default_rng(np.random.SeedSequence([seed, 17]))
        halves = np.argsort(rng.random((resamples, n)), axis=1)[:, : n // 2]
    full = np.arange(n)[None, :]
    diff = [sum(ea.log_densities(picks) - eb.log_densities(picks)
                for ea, eb in zip(a.effects, b.effects, strict=True))
            for picks in (full, halves)]  # fmt: skip
    lo, hi = np.percentile(diff[1], [5, 95])
    return ScoreDifference(float(diff[0][0]), float(lo), float(hi), float(np.mean(diff[1] > 0)),
                           len(halves), exact)  # fmt: skip
