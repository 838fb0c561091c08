"""Monte-Carlo simulations of Chapter 2 (§2.5): FC versus ARX identification.

N closed-loop runs of the roll task with the Table 2.1 pilot and fresh remnant (10 % of the
power of u by default) are identified with both methods; the sample standard deviation and bias
of the estimates at the 24 input frequencies are compared, and the ARX model's analytic
standard deviation (Eq 2.16-2.17, and the same parameter covariance propagated through the exact
H(theta) by sampling) is averaged over the runs for comparison with the sample one (Fig 2.9).
Runs are simulated in batches, vectorised; each batch is a task (:mod:`twin.core.tasks`), so a
study runs on one process or a Dask cluster with the same result.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from twin.core.errors import SignalError
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.progress import ProgressFn
from twin.core.results import frame
from twin.core.tasks.engine import Engine, using
from twin.pilot.identification.arx import ARX_RATE_HZ, ArxOrders, decimate, fit_arx, select_orders
from twin.pilot.identification.fc import fc_estimate
from twin.pilot.identification.fit import fit_pilot, parameter_errors
from twin.pilot.models.forcing import roll_task
from twin.pilot.models.loop import remnant_scale_for, simulate_loop
from twin.pilot.models.model import RollPilot

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: Parameter draws per run for the sampled standard deviation (averaged over many runs, so
#: fewer than a single-run estimate needs).
SAMPLED_DRAWS = 100
#: Most runs one study may have (1e8 runs: about 200 h on one core; split bigger studies).
MAX_RUNS = 100_000_000


@dataclass(frozen=True, eq=False)
class MonteCarloResult:
    """Estimates of all runs at the input frequencies.

    Attributes
    ----------
    omega_rad_s : ndarray, shape (m,)
        Input frequencies.
    fc, arx : dict of str to ndarray of complex, shape (runs, m)
        ``pe`` and ``px`` estimates of each method.
    arx_std_mag, arx_std_phase : dict of str to ndarray, shape (m,)
        The ARX model's analytic standard deviations (Eq 2.16, 2.17), averaged over the runs.
    arx_sampled_std_mag, arx_sampled_std_phase : dict of str to ndarray, shape (m,)
        The same parameter covariance propagated through the exact H(theta) by sampling
        (:meth:`~twin.pilot.identification.arx.ArxModel.sampled_std`), averaged over the runs.
    truth : dict of str to ndarray of complex
        The pilot model's true responses.
    orders : ArxOrders
        ARX structure (chosen by FPE on the first run).
    pilots : dict of str to list of RollPilot
        Fitted pilot models (first ``fit_runs`` runs) per method.

    """

    omega_rad_s: FloatArray
    fc: dict[str, ComplexArray]
    arx: dict[str, ComplexArray]
    arx_std_mag: dict[str, FloatArray]
    arx_std_phase: dict[str, FloatArray]
    arx_sampled_std_mag: dict[str, FloatArray]
    arx_sampled_std_phase: dict[str, FloatArray]
    truth: dict[str, ComplexArray]
    orders: ArxOrders
    pilots: dict[str, list[RollPilot]]

    @property
    def runs(self) -> int:
        """Number of runs."""
        return self.fc["pe"].shape[0]

    def sample_std_mag(self, method: str, response: str) -> FloatArray:
        """Sample standard deviation of ``|H|`` over the runs."""
        return np.abs(getattr(self, method)[response]).std(axis=0, ddof=1)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready result: standard deviations of ``|H|`` per method at the input frequencies.

        ``parameter_errors`` (mean absolute error per parameter, Table 2.3) is included when
        pilot models were fitted.
        """
        out: dict[str, object] = {
            "runs": self.runs,
            "omega_rad_s": self.omega_rad_s.tolist(),
            "arx_orders": self.orders.__dict__,
        }
        for resp in ("pe", "px"):
            out[resp] = {
                "fc_std_gain": self.sample_std_mag("fc", resp).tolist(),
                "arx_std_gain": self.sample_std_mag("arx", resp).tolist(),
                "arx_analytic_std_gain": self.arx_std_mag[resp].tolist(),
                "arx_sampled_std_gain": self.arx_sampled_std_mag[resp].tolist(),
            }
        if any(self.pilots.values()):
            out["parameter_errors"] = {
                m: parameter_errors(self.pilots[m], RollPilot()) for m in ("fc", "arx")
            }
        return out

    def to_frame(self) -> pd.DataFrame:
        """One row per input frequency: the standard deviations of ``|H|`` per method."""
        d = self.to_dict()
        cols: dict[str, object] = {"omega_rad_s": self.omega_rad_s}
        for resp in ("pe", "px"):
            cols |= {f"{resp}_{k}": v for k, v in d[resp].items()}  # type: ignore[union-attr]
        return frame(cols)

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Plot the standard deviation of ``|H|`` over the runs: FC against ARX (§2.5).

        Parameters
        ----------
        ax : sequence of two Axes, optional
            Where to draw: ``pe`` and ``px``; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        fig, axes = subplots(ax, 1, 2, figsize=(9, 4), sharey=True)
        w = self.omega_rad_s
        for ax, resp in zip(axes, ("pe", "px"), strict=True):
            ax.loglog(w, self.sample_std_mag("fc", resp), "o", label="FC (Monte-Carlo)")
            ax.loglog(w, self.sample_std_mag("arx", resp), "s", label="ARX (Monte-Carlo)")
            ax.loglog(w, self.arx_std_mag[resp], "k-", lw=0.8, label="ARX analytic (Eq 2.16)")
            ax.set_title(f"H_{resp}: {self.runs} runs")
            ax.set_xlabel("frequency [rad/s]")
        axes[0].set_ylabel("standard deviation of |H| [-]")
        axes[0].legend(fontsize=8)
        return finish(fig, path)

    def sample_std_phase(self, method: str, response: str) -> FloatArray:
        """Sample standard deviation of the phase [deg] over the runs."""
        h = getattr(self, method)[response]
        return np.degrees(np.angle(h / self.truth[response])).std(axis=0, ddof=1)


def _batch(pilot, fd, ft, runs, seed, scale, orders, fit_runs):
    d = simulate_loop(pilot, fd, ft, runs, seed, scale)
    fc = fc_estimate(d.e, d.u, d.x, fd, ft, d.fd[0], d.ft[0])
    w = fc.omega_rad_s
    u, e, x = (decimate(s, d.rate_hz) for s in (d.u, d.e, d.x))
    pe, px = np.empty((runs, w.size), complex), np.empty((runs, w.size), complex)
    # sums of the analytic standard deviations: (linear, sampled) x (mag, phase) x response
    sums = np.zeros((2, 2, 2, w.size))
    pilots = {"fc": [], "arx": []}
    for i in range(runs):
        m = fit_arx(u[i], e[i], x[i], orders, ARX_RATE_HZ)
        pe[i], px[i] = m.responses(w)
        for j, std in enumerate((m.std(w), m.sampled_std(w, SAMPLED_DRAWS, (seed, i)))):
            sums[j] += [[std["pe"][0], std["px"][0]], [std["pe"][1], std["px"][1]]]
        if i < fit_runs:
            pilots["fc"].append(fit_pilot(w, fc.h_pe[i], fc.h_px[i], pilot))
            pilots["arx"].append(fit_pilot(w, pe[i], px[i], pilot))
    return w, fc.h_pe, fc.h_px, pe, px, sums, pilots


def monte_carlo(
    runs: int = 1000,
    seed: int = 0,
    remnant_ratio: float = 0.1,
    pilot: RollPilot | None = None,
    batch: int = 500,
    fit_runs: int = 0,
    progress: ProgressFn | None = None,
    scheduler: Engine | str | None = None,
) -> MonteCarloResult:
    """Run the Chapter 2 Monte-Carlo study.

    Each batch of runs is one task (:mod:`twin.core.tasks`), a pure function of the pilot, the
    remnant scale, the ARX orders and its seed: the result is bit-identical whatever runs the
    batches (this process, a local cluster, a remote one).

    Parameters
    ----------
    runs : int
        Number of closed-loop runs (10,000 in the thesis).
    seed : int
        Seed; batch ``b`` uses ``seed + b`` (same seed and batch size, same bits).
    remnant_ratio : float
        Remnant power over control-signal power (0.1 in §2.5.1).
    pilot : RollPilot, optional
        The simulated pilot; Table 2.1 by default.
    batch : int
        Runs simulated together, vectorised, in one task (memory: about 0.26 MB per run).
    fit_runs : int
        Fit the pilot model to the first this many runs of each batch (slow: ~0.1 s a run).
    progress : callable, optional
        Called with the runs done as batches finish.
    scheduler : Engine or str, optional
        Where the batches run (:func:`twin.core.tasks.engine.using`; default this process).

    Raises
    ------
    SignalError
        For fewer than 2 or more than :data:`MAX_RUNS` runs, a batch size below 1, or
        ``fit_runs`` outside [0, batch].
    TaskError
        When a batch failed (named with its seed).

    """
    if not 2 <= runs <= MAX_RUNS:
        raise SignalError(f"a Monte-Carlo study needs 2 to {MAX_RUNS:,} runs; got {runs}")
    if batch < 1:
        raise SignalError(f"a Monte-Carlo batch needs at least 1 run; got {batch}")
    if not 0 <= fit_runs <= batch:
        raise SignalError(f"fit_runs (fits per batch) must be in [0, {batch}]; got {fit_runs}")
    p = pilot or RollPilot()
    fd, ft = roll_task()
    with using(scheduler) as engine:  # a remote scheduler is reached (or refused) first
        scale = remnant_scale_for(p, fd, ft, remnant_ratio)
        first = simulate_loop(p, fd, ft, 1, seed + 10_000, scale)
        orders = select_orders(
            *(decimate(s[0], first.rate_hz) for s in (first.u, first.e, first.x))
        ).orders
        sizes = [min(batch, runs - b0) for b0 in range(0, runs, batch)]
        args = [(p, fd, ft, n, seed + b, scale, orders, fit_runs) for b, n in enumerate(sizes)]
        inputs = [{"batch": b, "runs": n, "seed": seed + b} for b, n in enumerate(sizes)]
        counted = _RunCounter(progress, sizes) if progress else None
        parts = engine.map(_batch, args, inputs, "Monte-Carlo batches", counted).values()
    w = parts[0][0]
    fc = {"pe": np.vstack([q[1] for q in parts]), "px": np.vstack([q[2] for q in parts])}
    arx = {"pe": np.vstack([q[3] for q in parts]), "px": np.vstack([q[4] for q in parts])}
    mean = sum(q[5] for q in parts) / runs
    std = [[dict(zip(("pe", "px"), mean[j, k], strict=True)) for k in (0, 1)] for j in (0, 1)]
    pilots = {m: [pp for q in parts for pp in q[6][m]] for m in ("fc", "arx")}
    truth = {"pe": p.h_pe(w), "px": p.h_px(w)}
    return MonteCarloResult(w, fc, arx, *std[0], *std[1], truth, orders, pilots)


class _RunCounter:
    """Progress in runs, not batches: finished batches are counted as their runs."""

    def __init__(self, progress: ProgressFn, sizes: list[int]) -> None:
        self.progress, self.sizes, self.total = progress, sizes, sum(sizes)

    def __call__(self, message: str, done: float | None = None, total: float | None = None):
        if done is None:
            self.progress(message)
            return
        # batches finish in any order; all but the last are full, so done batches ~ runs
        runs = min(int(done) * self.sizes[0], self.total)
        self.progress("Monte-Carlo runs", runs, self.total)
