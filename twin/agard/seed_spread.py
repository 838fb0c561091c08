"""Reproductions that depend on the noise's seed, as distributions over seeds.

A figure that depends on the seed is a distribution; one seed matching the thesis is not a
reproduction. These functions repeat a reproduction over seeds and summarise it as the median
and the 5-95 % range:

* :func:`table_5_6_delays`: the delay fitted with equal weights (the thesis' fit) and with
  signal-to-noise weights behind the 1 Hz filter (SRS + MPI filter, 25 ms), heave and pitch
  (Table 5.6: 12.0 and 14.2 ms);
* :func:`threshold_taus`: the dynamic threshold's tau (§3.4.4: 1 Hz filter, 100 ms fixed,
  0.1 m/s^2 steps of 1 s in surge; thesis about 300 ms).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from twin.agard.df import sweep
from twin.agard.session import Session
from twin.agard.threshold import run_threshold
from twin.core.errors import UsageError
from twin.core.progress import ProgressFn
from twin.core.thesis import CHAPTER_3_4, TABLE_5_6_MPI_IMU
from twin.measurement.measure import Bench, configure

#: Seed of repetition ``i`` (far apart, so neighbouring repetitions share no stream).
SEED_STRIDE = 1000


@dataclass(frozen=True)
class Spread:
    """One quantity over seeds.

    Attributes
    ----------
    name : str
        What it is, with its unit.
    values : tuple of float
        One value per seed, in seed order.
    thesis : float or None
        The thesis' value, where it gives one.

    """

    name: str
    values: tuple[float, ...]
    thesis: float | None = None

    @property
    def median(self) -> float:
        """Median over seeds."""
        return float(np.median(self.values))

    @property
    def range_5_95(self) -> tuple[float, float]:
        """5th and 95th percentiles over seeds."""
        lo, hi = np.percentile(self.values, [5, 95])
        return float(lo), float(hi)

    def contains_thesis(self) -> bool | None:
        """Whether the thesis' value lies in the 5-95 % range (None: no thesis value)."""
        if self.thesis is None:
            return None
        lo, hi = self.range_5_95
        return lo <= self.thesis <= hi

    def format(self) -> str:
        """One line: median, 5-95 %, the thesis' value."""
        lo, hi = self.range_5_95
        ref = f"  (thesis {self.thesis:g})" if self.thesis is not None else ""
        return (f"{self.name:34s} median {self.median:6.1f}  5-95 % [{lo:6.1f}, {hi:6.1f}]  "
                f"over {len(self.values)} seeds{ref}")  # fmt: skip


def _seeds(seeds: int) -> range:
    if seeds < 2:
        raise UsageError(f"a distribution needs at least 2 seeds; got {seeds}")
    return range(seeds)


def table_5_6_delays(
    seeds: int = 20, model: str = "reduced", progress: ProgressFn | None = None
) -> list[Spread]:
    """Table 5.6's fitted delays behind the 1 Hz filter (SRS, 25 ms) over ``seeds`` seeds [ms].

    Returns
    -------
    list of Spread
        Heave and pitch, equal weights (with the thesis' value) and SNR-weighted.

    """
    cfg = configure("srs", break_hz=1.0, delay_ms=25.0)
    rows: dict[tuple[str, str], list[float]] = {}
    for i in _seeds(seeds):
        r = sweep(Bench(cfg, model, seed=SEED_STRIDE * i), ("heave", "pitch"))
        for dof in ("heave", "pitch"):
            rows.setdefault((dof, "equal weights"), []).append(r[dof].delay_equal_weights_s * 1e3)
            rows.setdefault((dof, "SNR-weighted"), []).append(r[dof].delay_s * 1e3)
        if progress:
            progress("seeds", i + 1, seeds)
    return [
        Spread(f"{dof} delay, {kind} [ms]", tuple(v),
               TABLE_5_6_MPI_IMU[dof][1.0][0] if kind == "equal weights" else None)
        for (dof, kind), v in rows.items()
    ]  # fmt: skip


def threshold_taus(
    seeds: int = 20, model: str = "reduced", progress: ProgressFn | None = None
) -> Spread:
    """§3.4.4's dynamic threshold tau over ``seeds`` seeds [ms] (MPI 2008, surge)."""
    taus = []
    for i in _seeds(seeds):
        with Session(Bench(configure("mpi-2008"), model, seed=SEED_STRIDE * i)) as s:
            taus.append(run_threshold(s, "surge", 0.1, 1.0, fixed_delay_s=0.1).fit.tau_s * 1e3)
        if progress:
            progress("seeds", i + 1, seeds)
    return Spread("threshold tau, 1 Hz filter [ms]", tuple(taus), CHAPTER_3_4["threshold_tau_ms"])


def plot_spreads(spreads: Iterable[Spread], path: str | None = None, unit: str = "ms"):
    """Each quantity's values over seeds as points, median and 5-95 % as a bar, thesis as a star.

    Parameters
    ----------
    spreads : iterable of Spread
        The quantities (one row each).
    path : str, optional
        Save the figure here.
    unit : str
        The quantities' common unit (the x axis).

    Returns
    -------
    matplotlib.figure.Figure

    """
    from twin.core.plotting import finish, subplots

    spreads = list(spreads)
    fig, ax = subplots(None, figsize=(7, 0.6 + 0.55 * len(spreads)))
    for row, s in enumerate(spreads):
        jitter = np.linspace(-0.15, 0.15, len(s.values))
        ax.plot(s.values, row + jitter, ".", color="0.6", ms=4)
        lo, hi = s.range_5_95
        ax.plot([lo, hi], [row, row], color="C0", lw=3, label="5-95 %" if row == 0 else None)
        ax.plot(s.median, row, "|", color="C0", ms=14, mew=2, label="median" if row == 0 else None)
        if s.thesis is not None:
            ax.plot(s.thesis, row, "*", color="C3", ms=11,
                    label="thesis" if not any(x.thesis is not None for x in spreads[:row])
                    else None)  # fmt: skip
    ax.set_yticks(range(len(spreads)), [s.name for s in spreads], fontsize=8)
    ax.set_xlabel(f"value over seeds [{unit}]")
    ax.grid(True, axis="x", alpha=0.4)
    ax.legend(fontsize=8, loc="best")
    return finish(fig, path)
