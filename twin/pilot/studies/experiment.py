"""Chapter 6's experiment in simulation: the eight motion conditions of Table 6.3.

The same pilot (fixed: the model does not adapt, so every difference is the motion's) flies the
pitch task through each condition; the variances of e, u and theta are split into target,
disturbance and remnant parts (§6.4.1), the disturbance and target open loops give crossover
frequencies and phase margins (§6.4.2.1), and each factor's effect (platform filter, delay,
noise) is the mean over the four conditions with it minus the mean over the four without, as in
a 2x2x2 factorial design.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from twin.chain.config import MotionSystem, motion_system
from twin.core.errors import SignalError
from twin.core.progress import ProgressFn
from twin.core.results import frame
from twin.core.tasks.engine import Engine, using
from twin.core.thesis import TABLE_6_3
from twin.pilot.identification.mle import fit_pitch_pilot
from twin.pilot.models.forcing import pitch_task
from twin.pilot.models.pitch import PitchPilot, open_loops, simulate_pitch, variance_decomposition
from twin.pilot.studies.condition_figure import Panel, plot_conditions

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from twin.core.plotting import AxesArg

FACTORS = ("filter", "delay", "noise")
MEASURES = ("var_e", "var_u", "var_theta", "crossover_d", "phase_margin_d", "crossover_t",
            "phase_margin_t", "motion_lead_phase_deg")  # fmt: skip


def pitch_remnant_scale(pilot: PitchPilot, ratio: float = 0.15, seed: int = 0) -> float:
    """Gain on the unit remnant making its power ``ratio`` times that of u (SRS baseline)."""
    if not 0 < ratio < 1:
        raise SignalError(f"remnant power ratio must be between 0 and 1; got {ratio}")
    base = simulate_pitch(pilot, "condition-1", 16, seed, 0.0)
    unit = simulate_pitch(pilot, "condition-1", 16, seed, 1.0)
    un = unit.u - base.u
    p_uf, p_n, p_un = np.mean(base.u**2), np.mean(unit.n**2), np.mean(un**2)
    cross = 2 * np.mean(base.u * un)
    # ratio (p_uf + g cross + g^2 p_un) = g^2 p_n
    a, b, c = p_n - ratio * p_un, -ratio * cross, -ratio * p_uf
    return float((-b + np.sqrt(b * b - 4 * a * c)) / (2 * a))


@dataclass(frozen=True)
class ExperimentResult:
    """Measures per condition and the factor effects.

    Attributes
    ----------
    conditions : dict of int to dict of str to float
        Condition number -> measure -> value (variances in deg^2, crossovers in rad/s, phase
        margins and the motion-lead phase in deg), plus the variance parts.
    effects : dict of str to dict of str to float
        Factor -> measure -> effect (with minus without).

    """

    conditions: dict[int, dict[str, object]]
    effects: dict[str, dict[str, float]]

    def to_dict(self) -> dict[str, object]:
        """JSON-ready result: ``conditions`` and ``effects``."""
        return {"conditions": self.conditions, "effects": self.effects}

    def to_frame(self) -> pd.DataFrame:
        """One row per condition: its measures (nested values as ``a.b``)."""
        return frame({"condition": n, **v} for n, v in self.conditions.items())

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Measures per condition as Fig 6.5-6.9: variances, open loops, estimated parameters.

        Parameters
        ----------
        ax : sequence of 16 Axes, optional
            Where to draw: the panels of the measures, four per row, in row order; a new
            figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        c = self.conditions
        panels = []
        for i, x in enumerate(("e", "u", "theta")):
            runs = {n: c[n].get("runs_deg2", {}).get(x, [c[n].get(f"var_{x}", np.nan)])
                    for n in c}  # fmt: skip
            parts = {n: c[n]["parts_deg2"][x] for n in c if "parts_deg2" in c[n]}
            panels.append(Panel(f"var({x}) (Fig 6.5{'abc'[i]})", f"var({x}) [deg^2]", runs,
                                parts or None))  # fmt: skip
        one = (("vaf_percent", "pilot model VAF, run 1 (Fig 6.6)", "VAF [%]"),
               ("crossover_d", "disturbance crossover (Fig 6.7)", "[rad/s]"),
               ("phase_margin_d", "disturbance phase margin (Fig 6.7)", "[deg]"),
               ("crossover_t", "target crossover (Fig 6.7)", "[rad/s]"),
               ("phase_margin_t", "target phase margin (Fig 6.7)", "[deg]"))  # fmt: skip
        for key, title, unit in one:
            label = unit if key == "vaf_percent" else f"{title.split(' (')[0]} {unit}"
            panels.append(Panel(title, label, {n: [c[n].get(key, np.nan)] for n in c}))
        for name, unit in (("k_v", "-"), ("k_m", "-"), ("t_lead", "s"), ("t_lag", "s"),
                           ("tau_v", "s"), ("tau_m", "s"), ("omega_nm", "rad/s"),
                           ("zeta_nm", "-")):  # fmt: skip
            est = {n: [c[n].get("estimated", {}).get(name, np.nan)] for n in c}
            panels.append(Panel(f"estimated {name}, run 1 (Fig 6.8-6.9)", f"{name} [{unit}]",
                                est))  # fmt: skip
        runs_n = max((len(v) for v in panels[0].samples.values()), default=0)
        over = f"mean and 95 % CI over {runs_n} runs" if runs_n > 1 else "one run"
        return plot_conditions(
            panels,
            f"Table 6.3 conditions, one fixed pilot: variances, {over} "
            "(bars: target / disturbance / remnant parts);\nopen loops of the pilot model; "
            "parameters estimated from each condition's first run",
            path,
            ax=ax,
        )

    def format_table(self) -> str:
        """Plain-text table of the conditions and the effects."""
        head = (f"{'cond':>4} {'filter':>6} {'delay':>6} {'noise':>5} {'var e':>7} {'var u':>7} "
                f"{'wc,d':>5} {'pm,d':>5} {'wc,t':>5} {'pm,t':>5} {'lead':>6}")  # fmt: skip
        lines = ["pitch task through the Table 6.3 conditions (pilot fixed; deg^2, rad/s, deg)",
                 head]  # fmt: skip
        for n, c in self.conditions.items():
            fb, delay, noise = TABLE_6_3[n]
            filt, nz = ("1 Hz" if fb else "-"), ("+" if noise else "-")
            lines.append(
                f"{n:4d} {filt:>6} {delay * 1e3:4.0f}ms {nz:>5} "
                f"{c['var_e']:7.3f} {c['var_u']:7.3f} {c['crossover_d']:5.2f} "
                f"{c['phase_margin_d']:5.1f} {c['crossover_t']:5.2f} {c['phase_margin_t']:5.1f} "
                f"{c['motion_lead_phase_deg']:6.1f}"
            )
        lines.append("effects (with minus without):")
        for f, eff in self.effects.items():
            lines.append(f"  {f:6s} " + "  ".join(f"{m} {v:+.3g}" for m, v in eff.items()))
        return "\n".join(lines)


def run_experiment(
    pilot: PitchPilot | None = None,
    runs: int = 5,
    seed: int = 0,
    remnant_ratio: float = 0.15,
    conditions: Sequence[int] = tuple(TABLE_6_3),
    progress: ProgressFn | None = None,
    fit: bool = False,
    scheduler: Engine | str | None = None,
) -> ExperimentResult:
    """Fly every condition ``runs`` times and compute the measures and factor effects.

    With ``fit``, the pilot model is also estimated (closed-loop MLE,
    :mod:`twin.pilot.identification.mle`) from each condition's first run, as the thesis did per
    condition (Fig 6.6, 6.8, 6.9). Each condition is a task (:mod:`twin.core.tasks`; condition ``n``
    uses seed ``seed + n``), so the result is the same whatever runs them (``scheduler``; default
    this process).
    """
    p = pilot or PitchPilot()
    with using(scheduler) as engine:  # a remote scheduler is reached (or refused) first
        scale = pitch_remnant_scale(p, remnant_ratio, seed)
        flown = engine.map(
            fly_condition,
            [(p, n, runs, seed + n, scale, fit) for n in conditions],
            [{"condition": n, "runs": runs, "seed": seed + n} for n in conditions],
            "conditions",
            progress,
        ).values()
    out = dict(zip(conditions, flown, strict=True))
    effects = {}
    for i, f in enumerate(FACTORS):
        with_f = [n for n in out if bool(_levels(n)[i])]
        without = [n for n in out if not _levels(n)[i]]
        if with_f and without:
            effects[f] = {m: float(np.mean([out[n][m] for n in with_f])
                                   - np.mean([out[n][m] for n in without]))
                          for m in MEASURES}  # fmt: skip
    return ExperimentResult(out, effects)


def fly_condition(
    pilot: PitchPilot, n: int, runs: int, seed: int, scale: float, fit: bool = False
) -> dict[str, object]:
    """Fly condition ``n`` of Table 6.3 ``runs`` times; return its measures (one task)."""
    return fly(pilot, motion_system(f"condition-{n}"), runs, seed, scale, fit)


def fly(
    pilot: PitchPilot,
    cfg: MotionSystem,
    runs: int,
    seed: int,
    scale: float,
    fit: bool = False,
    model: str = "reduced",
) -> dict[str, object]:
    """Fly the pitch task through ``cfg`` ``runs`` times; return the measures of Fig 6.5-6.9.

    Variances [deg^2] (mean over runs, per run, and split into target, disturbance and
    remnant parts), crossover frequencies [rad/s] and phase margins [deg] of both loops, and
    with ``fit`` the pilot identified from the first run (closed-loop MLE).
    """
    fd, ft = pitch_task()
    r = simulate_pitch(pilot, cfg, runs, seed, scale, model=model)
    parts = {name: variance_decomposition(getattr(r, name), fd, ft)
             for name in ("e", "u", "theta")}  # fmt: skip
    ol = open_loops(pilot, cfg)
    deg2 = (180 / np.pi) ** 2
    out: dict[str, object] = {
        "var_e": float(np.var(r.e, axis=1).mean() * deg2),
        "var_u": float(np.var(r.u, axis=1).mean() * deg2),
        "var_theta": float(np.var(r.theta, axis=1).mean() * deg2),
        "runs_deg2": {
            k: (np.var(getattr(r, k), axis=1) * deg2).tolist() for k in ("e", "u", "theta")
        },
        "parts_deg2": {k: {c: v * deg2 for c, v in d.items()} for k, d in parts.items()},
        "crossover_d": ol.crossover_d,
        "phase_margin_d": ol.phase_margin_d,
        "crossover_t": ol.crossover_t,
        "phase_margin_t": ol.phase_margin_t,
        "motion_lead_phase_deg": ol.motion_lead_phase_deg,
    }
    if fit:  # the pilot as an experimenter would identify it from the first run (Fig 6.8-6.9)
        est = fit_pitch_pilot(r.ft, r.fd, r.u[0], cfg)
        out["estimated"] = dataclasses.asdict(est.pilot)
        out["vaf_percent"] = est.vaf_percent
    return out


def _levels(n: int) -> tuple[bool, bool, bool]:
    fb, delay, noise = TABLE_6_3[n]
    return (fb is not None, delay > 0.03, bool(noise))
