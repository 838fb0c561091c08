"""Chapter 6's experiment flown by a population of adaptive simulated subjects, with its ANOVA.

Each subject (seeded) has its own limitations - visual and motion delays, a resting
neuromuscular frequency and damping, and how well it perceives motion (the felt rate's
observation noise relative to its visual one; people's vestibular thresholds differ
by factors of several) - and its own priorities (control weight r, observation-noise ratio),
drawn around the values of :mod:`twin.pilot.models.adapt`. In every Table 6.3
condition the subject adapts its equalisation (K_v, t_lead, t_lag, K_m) and its neuromuscular
tuning (omega_nm, zeta_nm; the resting one is where the search starts, and what is flown when
only the equalisation adapts) to the motion system (:func:`twin.pilot.models.adapt.adapt`, from the
standard starts and its previous condition's) and
then flies it ``REPETITIONS`` times (the thesis recorded five per condition, §6.3.4) with an
imperfect adaptation: in each repetition every adapted parameter is off by a log-normal factor
(``ADAPTATION_SD``), as a person's control behaviour varies from run to run; a repetition whose
loop is unstable or costs more than ``MAX_COST_RATIO`` times the adapted one is a run where
control was lost and is flown again. The measures per subject and condition follow the
thesis' procedure: var(e) and var(u) are the repetitions' own (frequency domain,
:func:`twin.pilot.models.adapt.predict`), averaged; the pilot model identified on the averaged data
is approximated by the repetitions' average pilot (geometric mean of each parameter), and
its crossover frequencies and phase margins (:func:`twin.pilot.models.pitch.open_loops`), K_v, K_m,
t_lead, t_lag, omega_nm and zeta_nm are the measures. (:mod:`twin.pilot.studies.identified` measures
them as the thesis did instead: the repetitions flown in the time domain and the model
identified from them, tau_m included.) (Each repetition flown as its own
measure, a single near-unstable draw dominated a subject's cell and the 1 Hz filter's effect
on var(e) was lost in some populations.) Both the redraw and its fallback (after
``MAX_REDRAWS`` failed draws the adapted pilot itself) narrow the spread within a subject,
which can raise the F values.

The statistics are the thesis' (§6.4, Tables 6.4-6.7): a repeated-measures ANOVA per measure
(statsmodels ``AnovaRM``, within-subject factors filter x delay x noise), F, p and the
direction of each main effect (mean at the second level - 1 Hz filter, 35 ms, noise on -
minus the first), beside the thesis' F and directions.

Assumptions (stated, not from the thesis): the spreads of :data:`SUBJECT_SPREAD` and the
adaptation noise (the motion perception's and the visual delay's spreads are settings,
:class:`twin.pilot.studies.spread.Spread`, chosen from profiles against Tables 6.4-6.7, docs); the
cost J = var(e) + r var(u) and the observation-noise remnant of :mod:`twin.pilot.models.adapt`;
where the subjects adapt their visual delay too (``adapted`` with ``"tau_v"``), the speed-accuracy
trade-off of :func:`twin.pilot.models.adapt.visual_noise_ratio`. What to keep in mind when reading
the F values: the motion noise of Eq 5.10 changes the predicted var(e) by parts per million, so the
noise factor is nearly inert in this model (its "no effect" agrees with the thesis by
construction); behind the filter the adapted loop's gain falls slowly through 0 dB (about -0.5
in log-log between 1 and 3 rad/s), so the target crossover moves much with small parameter
changes (with K_m = 0 the target and disturbance loops coincide), and a few subjects cross over
higher behind the filter; a population finds the effect about as often as the thesis' own F
predicts (a replication over populations: :mod:`twin.pilot.studies.replication`). With only the
equalisation adapted (``adapted=EQUALISATION``, the model before the neuromuscular tuning
adapted) the filter's effect on var(u) went either way (24 of 45 subjects lower), so no
population showed it; with the tuning adapted it is lower for 43 of 45 (subjects who all
perceived motion as well as vision and differed by 30 ms in visual delay,
``Spread(0, 0.03)``). ``bench/pilot_adaptive.py`` prints
both models side by side.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import stats

from twin.core.errors import SignalError
from twin.core.progress import ProgressFn
from twin.core.results import frame
from twin.core.tasks.engine import Engine, using
from twin.core.thesis import TABLE_6_3, TABLES_6_4_TO_6_7
from twin.pilot.models.adapt import (
    ADAPTED,
    CONTROL_WEIGHT,
    EQUALISATION,
    NOISE_RATIO,
    SPEED_ACCURACY,
    STARTS,
    Adapted,
    Performance,
    Task,
    adapt,
    adapted_names,
    performance,
    stable,
)
from twin.pilot.models.pitch import PitchPilot, open_loops
from twin.pilot.studies.spread import DEFAULT_SPREAD, VISUAL_DELAY_SD, Spread, checked

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from twin.core.plotting import AxesArg

FloatArray = NDArray[np.float64]

#: Factors of Table 6.3 and their levels (first, second).
FACTORS = {"filter": ("none", "1 Hz"), "delay": ("25 ms", "35 ms"), "noise": ("off", "on")}
#: Measures of the JSON contract, in the order printed.
MEASURES = (
    "crossover_disturbance_rad_s",
    "crossover_target_rad_s",
    "phase_margin_disturbance_deg",
    "phase_margin_target_deg",
    "var_u",
    "var_e",
    "k_m",
    "k_v",
)
#: Measures compared with the thesis: the contract's, the lead-lag pair (Table 6.6), the
#: neuromuscular tuning and the visual delay (Table 6.7; each compared where it is adapted).
COMPARED = (*MEASURES, "t_lead", "t_lag", "omega_nm", "zeta_nm", "tau_v")
#: Subject spread: parameter -> (mean, sd) for limitations; log-normal sd for the priorities.
#: The visual delay's sd and the motion perception's spread are settings (:class:`Spread`):
#: :func:`subjects` takes tau_v's sd from its ``spread``, the one here is the default's.
SUBJECT_SPREAD = {
    "tau_v": (0.30, VISUAL_DELAY_SD),
    "tau_m": (0.20, 0.03),
    "omega_nm": (11.0, 1.5),
    "zeta_nm": (0.25, 0.05),
    "weight": (CONTROL_WEIGHT, 0.3),
    "noise_ratio": (NOISE_RATIO, 0.3),
}
#: Run-to-run variation of the adapted parameters (log-normal sd).
ADAPTATION_SD = 0.1
#: Repetitions flown per subject and condition (the thesis recorded five once performance was
#: stable, §6.3.4, and identified its model on their average).
REPETITIONS = 5
#: Cost, relative to the adapted pilot's, beyond which a repetition counts as control lost.
MAX_COST_RATIO = 1.5
#: Draws of that variation tried for a stable loop before the adapted pilot is flown as is.
MAX_REDRAWS = 20


@dataclass(frozen=True)
class Subject:
    """A simulated subject: its limitations and priorities.

    Attributes
    ----------
    number : int
        Subject number (from 1).
    limitations : PitchPilot
        Delays and resting neuromuscular system (the equalisation, and the neuromuscular
        tuning where it adapts, are only where the search starts).
    weight, noise_ratio : float
        r of the cost and observation-noise ratio of the remnant.
    motion_noise : float
        The felt rate's observation-noise ratio relative to ``noise_ratio``
        (:func:`twin.pilot.models.adapt.adapt`; 1: motion perceived as well as vision).

    """

    number: int
    limitations: PitchPilot
    weight: float
    noise_ratio: float
    motion_noise: float = 1.0


def subjects(n: int, seed: int = 0, spread: Spread = DEFAULT_SPREAD) -> list[Subject]:
    """Draw ``n`` subjects from ``seed`` (:data:`SUBJECT_SPREAD`, and ``spread``).

    ``spread`` sets how much they differ in motion perception and visual delay
    (:class:`twin.pilot.studies.spread.Spread`). Each subject's draws are standard normal deviates
    scaled by the spreads, so subjects of one seed under other spreads are the same people,
    more or less alike (``Spread(motion=0)``: every subject perceives motion as well as
    vision, the other draws unchanged).
    """
    if n < 2:
        raise SignalError(f"an ANOVA needs at least 2 subjects; got {n}")
    spread = checked(spread)
    sds = {**SUBJECT_SPREAD, "tau_v": (SUBJECT_SPREAD["tau_v"][0], spread.visual_delay)}
    rng = np.random.default_rng(np.random.SeedSequence([seed, 14]))
    # the motion perception from its own stream: the other draws are those of subjects
    # drawn before it was part of a subject (tag 16 with two entries; the identified runs'
    # [seed, 16, subject, condition, repetition] are other streams)
    motion = np.random.default_rng(np.random.SeedSequence([seed, 16]))
    out = []
    for i in range(n):
        lim = {k: float(max(rng.normal(*sds[k]), 0.3 * sds[k][0]))
               for k in ("tau_v", "tau_m", "omega_nm", "zeta_nm")}  # fmt: skip
        w, nr = (float(sds[k][0] * np.exp(rng.normal(0, sds[k][1])))
                 for k in ("weight", "noise_ratio"))  # fmt: skip
        mn = float(np.exp(motion.normal(0, spread.motion)))
        out.append(Subject(i + 1, dataclasses.replace(PitchPilot(), **lim), w, nr, mn))
    return out


def levels(condition: int) -> dict[str, int]:
    """Factor levels (0 first, 1 second) of a Table 6.3 condition."""
    fb, delay, noise = TABLE_6_3[condition]
    return {"filter": int(fb is not None), "delay": int(delay > 0.03), "noise": int(noise)}


def fly_subject(
    subject: Subject,
    seed: int = 0,
    adapted: tuple[str, ...] = ADAPTED,
    run_to_run_sd: float = ADAPTATION_SD,
) -> list[dict[str, float]]:
    """Adapt ``subject`` to every condition and return its measures (one row per condition).

    ``adapted`` names the parameters the subject adapts (:func:`twin.pilot.models.adapt.adapt`);
    ``run_to_run_sd`` is their run-to-run variation (log-normal sd, :data:`ADAPTATION_SD`).
    """
    rows = []
    for n, task, a, flown in flown_conditions(subject, seed, adapted, run_to_run_sd):
        perf = [x for _, x in flown]
        # the thesis identified its model on the repetitions' average: the average pilot (its
        # log-parameters' mean); var(e) and var(u) are the runs' own, averaged
        pilot = dataclasses.replace(a.pilot, **{
            k: float(np.exp(np.mean([np.log(getattr(r, k)) for r, _ in flown])))
            if getattr(a.pilot, k) > 0 else 0.0 for k in a.adapted})  # fmt: skip
        rows.append(condition_row(subject, n, pilot, task,
                                  float(np.mean([x.var_e for x in perf])),
                                  float(np.mean([x.var_u for x in perf]))))  # fmt: skip
    return rows


#: The pilot parameters in a row of :func:`fly_subject` (in this order).
ROW_PARAMETERS = ("k_m", "k_v", "t_lead", "t_lag", "omega_nm", "zeta_nm", "tau_v")


def condition_row(
    subject: Subject,
    condition: int,
    pilot: PitchPilot,
    task: Task,
    var_e: float,
    var_u: float,
    parameters: tuple[str, ...] = ROW_PARAMETERS,
) -> dict[str, float]:
    """Return one subject's measures in one condition, as the ANOVA takes them.

    ``pilot`` is the subject's model there (its open loops give the crossovers and phase
    margins), ``var_e`` and ``var_u`` are in rad^2 (the row holds deg^2), ``parameters``
    are the pilot's parameters the row holds.
    """
    loops = open_loops(pilot, task.config)
    deg2 = (180 / np.pi) ** 2
    return {
        "subject": subject.number, "condition": condition, **levels(condition),
        "crossover_disturbance_rad_s": loops.crossover_d,
        "crossover_target_rad_s": loops.crossover_t,
        "phase_margin_disturbance_deg": loops.phase_margin_d,
        "phase_margin_target_deg": loops.phase_margin_t,
        "var_u": var_u * deg2, "var_e": var_e * deg2,
        **{k: getattr(pilot, k) for k in parameters},
    }  # fmt: skip


def flown_conditions(
    subject: Subject,
    seed: int = 0,
    adapted: tuple[str, ...] = ADAPTED,
    run_to_run_sd: float = ADAPTATION_SD,
) -> Iterator[tuple[int, Task, Adapted, list[tuple[PitchPilot, Performance]]]]:
    """Yield, per Table 6.3 condition in order, the subject's adaptation and its repetitions.

    Each item is (condition, task, the adapted pilot, the ``REPETITIONS`` repetitions: each
    one's pilot and performance); the arguments are :func:`fly_subject`'s.
    """
    rng = np.random.default_rng(np.random.SeedSequence([seed, 15, subject.number]))
    previous = None
    for n in TABLE_6_3:
        task = Task.pitch(f"condition-{n}")
        starts = [dataclasses.replace(subject.limitations,
                                      **dict(zip(EQUALISATION, x, strict=True)))
                  for x in STARTS] + ([previous] if previous is not None else [])  # fmt: skip
        a = adapt(task, subject.limitations, subject.weight, subject.noise_ratio, starts, adapted,
                  subject.motion_noise)  # fmt: skip
        previous = a.pilot
        yield n, task, a, [_repetition(a, subject, task, rng, run_to_run_sd)
                           for _ in range(REPETITIONS)]  # fmt: skip


def _repetition(
    adapted: Adapted, subject: Subject, task: Task, rng: np.random.Generator, sd: float
) -> tuple[PitchPilot, Performance]:
    """One repetition: the adapted pilot off by the run-to-run variation, and its performance.

    A draw whose loop is unstable or costs more than ``MAX_COST_RATIO`` times the adapted
    pilot's is a run where control was lost; as in the experiment, it is flown again.
    """
    best = adapted.performance.cost
    for _ in range(MAX_REDRAWS):
        noisy = {k: getattr(adapted.pilot, k) * float(np.exp(rng.normal(0, sd)))
                 for k in adapted.adapted}  # fmt: skip
        pilot = dataclasses.replace(adapted.pilot, **noisy)
        if stable(pilot, task):
            perf = performance(
                pilot,
                task,
                subject.limitations,
                subject.weight,
                subject.noise_ratio,
                adapted.adapted,
                subject.motion_noise,
            )
            if perf.cost <= MAX_COST_RATIO * best:
                return pilot, perf
    return adapted.pilot, adapted.performance


def filter_effect(
    subject: Subject, adapted: tuple[str, ...] = ADAPTED
) -> dict[str, tuple[float, float]]:
    """Adapt ``subject`` to conditions 1 and 5: the 1 Hz filter's effect, no run-to-run variation.

    Returns
    -------
    dict
        measure -> (value in condition 1, SRS; value in condition 5, 1 Hz filter), for var(e)
        and var(u) [deg^2], both crossovers and phase margins and the adapted parameters.

    """
    out: dict[str, list[float]] = {}
    deg2 = (180 / np.pi) ** 2
    for n in (1, 5):
        a = adapt(Task.pitch(f"condition-{n}"), subject.limitations, subject.weight,
                  subject.noise_ratio, adapted=adapted,
                  motion_noise=subject.motion_noise)  # fmt: skip
        d = a.to_dict()
        values = {"var_e": a.performance.var_e * deg2, "var_u": a.performance.var_u * deg2,
                  **{m: d[m] for m in MEASURES if m in d},
                  **{k: getattr(a.pilot, k) for k in a.adapted}}  # fmt: skip
        for m, v in values.items():
            out.setdefault(m, []).append(float(v))
    return {m: (v[0], v[1]) for m, v in out.items()}


def anova(
    rows: list[dict[str, float]], measures: tuple[str, ...] = COMPARED
) -> dict[str, dict[str, dict[str, object]]]:
    """Repeated-measures ANOVA (statsmodels ``AnovaRM``) of every measure's main effects.

    Returns
    -------
    dict
        ``{MEASURE: {FACTOR: {"F", "p", "df", "direction", "mean_first", "mean_second"}}}``.

    """
    import pandas as pd  # statsmodels' own dependency; imported only here (slow import)
    from statsmodels.stats.anova import AnovaRM

    df = pd.DataFrame(rows)
    out: dict[str, dict[str, dict[str, object]]] = {}
    for m in measures:
        if df.groupby("subject")[m].std().max() == 0:
            raise SignalError(f"{m} does not vary over the conditions within any subject: "
                              "no ANOVA (was it adapted?)")  # fmt: skip
        table = AnovaRM(df, m, "subject", within=list(FACTORS)).fit().anova_table
        out[m] = {}
        for f in FACTORS:
            first, second = (float(df.loc[df[f] == k, m].mean()) for k in (0, 1))
            out[m][f] = {
                "F": float(table.loc[f, "F Value"]),
                "p": float(table.loc[f, "Pr > F"]),
                "df": [int(table.loc[f, "Num DF"]), int(table.loc[f, "Den DF"])],
                "direction": "+" if second > first else "-",
                "mean_first": first,
                "mean_second": second,
            }
    return out


@dataclass(frozen=True)
class PopulationResult:
    """Measures of every subject in every condition and their ANOVA.

    Attributes
    ----------
    rows : list of dict
        One row per subject and condition (measures, levels, adapted parameters).
    anova : dict
        :func:`anova`'s result.
    seed : int
        The seed.
    adapted : tuple of str
        The parameters the subjects adapted.
    run_to_run_sd : float
        Their run-to-run variation (log-normal sd).
    identified : float or None
        None: the pilot-model measures are the flown pilots' own (:func:`fly_subject`); a
        number: identified from the runs, as the thesis did, with a passive feedthrough of
        that relative size (0: none; :mod:`twin.pilot.studies.identified`).
    spread : Spread
        How the subjects differ in motion perception and visual delay (:func:`subjects`).

    """

    rows: list[dict[str, float]]
    anova: dict[str, dict[str, dict[str, object]]]
    seed: int
    adapted: tuple[str, ...] = ADAPTED
    run_to_run_sd: float = ADAPTATION_SD
    identified: float | None = None
    spread: Spread = DEFAULT_SPREAD

    def agreement(self) -> dict[str, dict[str, bool]]:
        """Per measure and factor, whether the prediction agrees with the thesis.

        Where the thesis found an effect (p < 0.05, Tables 6.4-6.7): same direction and
        p < 0.05; where it found none: p >= 0.05.
        """
        out: dict[str, dict[str, bool]] = {}
        for m in self.anova:
            out[m] = {}
            for f, (_, direction) in TABLES_6_4_TO_6_7[m].items():
                got = self.anova[m][f]
                if direction is None:
                    out[m][f] = bool(got["p"] >= 0.05)
                else:
                    out[m][f] = bool(got["p"] < 0.05 and got["direction"] == direction)
        return out

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: ``anova`` (the contract), ``thesis``, ``agreement``, ``rows``."""
        thesis = {m: {f: {"F": v[0], "direction": v[1]} for f, v in by.items()}
                  for m, by in TABLES_6_4_TO_6_7.items() if m in self.anova}  # fmt: skip
        return {"anova": self.anova, "thesis": thesis, "agreement": self.agreement(),
                "subjects": len({r["subject"] for r in self.rows}), "seed": self.seed,
                "adapted": list(self.adapted), "run_to_run_sd": self.run_to_run_sd,
                "identified": self.identified, **self.spread.to_dict(),
                "rows": self.rows}  # fmt: skip

    def format_table(self) -> str:
        """Plain-text table: predicted F, p, direction beside the thesis' F and direction."""
        agree = self.agreement()
        how = ""
        if self.identified is not None:
            how = "; the pilot model identified from the runs (MLE)"
            if self.identified:
                how += f", each with a passive feedthrough {self.identified:g}"
        lines = [
            f"Chapter 6 predicted by {len({r['subject'] for r in self.rows})} adaptive "
            f"subjects (seed {self.seed}; adapting {', '.join(self.adapted)}; run-to-run "
            f"variation {self.run_to_run_sd:.0%}; {self.spread.describe()}{how}); "
            "repeated-measures ANOVA, main effects",
            f"{'measure':30s} {'factor':6s} {'F':>8s} {'p':>7s} dir | thesis F  dir  agrees",
        ]
        for m in self.anova:
            for f in FACTORS:
                a = self.anova[m][f]
                tf, td = TABLES_6_4_TO_6_7[m][f]
                lines.append(
                    f"{m:30s} {f:6s} {a['F']:8.2f} {a['p']:7.4f} {a['direction']:>3s} | "
                    f"{tf:8.2f} {td or 'ns':>4s}  {'yes' if agree[m][f] else 'NO'}"
                )
        return "\n".join(lines)

    def to_frame(self) -> pd.DataFrame:
        """One row per subject and condition: the measures (:attr:`rows`)."""
        return frame(self.rows)

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Predicted vs thesis main effects: signed F per measure and factor.

        Parameters
        ----------
        ax : sequence of three Axes, optional
            Where to draw: one per factor; a new figure by default.
        path : str, optional
            Where to save the figure.

        Returns
        -------
        matplotlib.figure.Figure

        """
        from twin.core.plotting import finish

        measures = list(self.anova)
        fig, axes = effect_axes(measures, 4.5, ax=ax)
        y = np.arange(len(measures))
        for ax, f in zip(axes, FACTORS, strict=True):
            pred = [signed_f(self.anova[m][f]["F"], self.anova[m][f]["direction"])
                    for m in measures]  # fmt: skip
            th = [signed_f(*TABLES_6_4_TO_6_7[m][f]) for m in measures]
            ax.barh(y + 0.2, signed_log(pred), 0.4, label="twin")
            ax.barh(y - 0.2, signed_log(th), 0.4, label="thesis")
        axes[0].legend(fontsize=8)
        den = self.anova[measures[0]]["filter"]["df"][1]
        fig.suptitle(f"Chapter 6 main effects: adaptive simulated subjects (F(1,{den}) = "
                     f"{stats.f.ppf(0.95, 1, den):.2f} is p = 0.05) vs Tables 6.4-6.7 (F(1,8) = "
                     f"5.32 is p = 0.05; thesis directions only where significant)",
                     fontsize=9)  # fmt: skip
        return finish(fig, path, dpi=110)

    def plot_conditions(self, path: str | None = None):
        """Plot the measures per condition as Fig 6.5-6.9: mean and 95 % CI over subjects."""
        from twin.pilot.studies.condition_figure import Panel, plot_conditions, samples_by_condition

        measures = (
            ("var_e", "var(e) (Fig 6.5a)", "deg^2"), ("var_u", "var(u) (Fig 6.5b)", "deg^2"),
            ("crossover_disturbance_rad_s", "disturbance crossover (Fig 6.7)", "rad/s"),
            ("phase_margin_disturbance_deg", "disturbance phase margin (Fig 6.7)", "deg"),
            ("crossover_target_rad_s", "target crossover (Fig 6.7)", "rad/s"),
            ("phase_margin_target_deg", "target phase margin (Fig 6.7)", "deg"),
            ("k_v", "K_v (Fig 6.8)", "-"), ("k_m", "K_m (Fig 6.9)", "s"),
            ("t_lead", "T_lead (Fig 6.8)", "s"), ("t_lag", "T_lag (Fig 6.8)", "s"),
            ("omega_nm", "omega_nm (Fig 6.9)", "rad/s"), ("zeta_nm", "zeta_nm (Fig 6.9)", "-"),
        )  # fmt: skip
        if "tau_v" in self.adapted or self.identified is not None:
            measures = (*measures, ("tau_v", "tau_v (Fig 6.9a)", "s"))
        if self.identified is not None:  # the fit's own: tau_m and how well the model fits
            measures = (*measures, ("tau_m", "tau_m (Fig 6.9b)", "s"),
                        ("chi2_per_dof", "fit chi-square per dof", "-"))  # fmt: skip
        panels = [Panel(title, f"{title.split(' (')[0]} [{unit}]",
                        samples_by_condition(self.rows, key))
                  for key, title, unit in measures]  # fmt: skip
        n = len({r["subject"] for r in self.rows})
        how = "" if self.identified is None else ", the pilot model identified from the runs"
        return plot_conditions(
            panels,
            f"Table 6.3 conditions flown by {n} adaptive simulated subjects (seed {self.seed}"
            f"{how}): mean and 95 % CI over subjects, as Fig 6.5-6.9",
            path,
        )


def signed_f(f: float, direction: str | None) -> float:
    """F with the sign of its effect's direction (``"-"`` negative; ``"+"`` or None positive)."""
    return -float(f) if direction == "-" else float(f)


def signed_log(f: ArrayLike) -> FloatArray:
    """``sign(F) log10(1 + |F|)``: F values from 0.1 to 500 of either sign on one axis."""
    a = np.asarray(f, dtype=float)
    return np.sign(a) * np.log10(1 + np.abs(a))


def effect_axes(
    measures: list[str],
    height: float,
    xlabel: str = "sign(effect) log10(1 + F)",
    ax: AxesArg = None,
) -> tuple[Any, Any]:
    """Return a figure with one axis per factor of :data:`FACTORS`, measures down the side.

    Parameters
    ----------
    measures : list of str
        The measures, top to bottom.
    height : float
        Figure height [in].
    xlabel : str
        What the x axes show (:func:`signed_log` of F by default); they share one scale.
    ax : sequence of Axes, optional
        One Axes per factor to draw on; a new figure by default.

    Returns
    -------
    (matplotlib.figure.Figure, array of matplotlib.axes.Axes)

    """
    from twin.core.plotting import subplots

    fig, axes = subplots(
        ax, 1, len(FACTORS), figsize=(13, height), sharey=True, sharex=True, panels="one per factor"
    )
    for ax, f in zip(axes, FACTORS, strict=True):
        ax.axvline(0, color="k", lw=0.5)
        ax.set_title(f"{f} ({FACTORS[f][1]} vs {FACTORS[f][0]})", fontsize=9)
        ax.set_xlabel(xlabel, fontsize=8)
    axes[0].set_yticks(np.arange(len(measures)), measures, fontsize=8)
    return fig, axes


def run_population(
    n_subjects: int = 6,
    seed: int = 0,
    progress: ProgressFn | None = None,
    scheduler: Engine | str | None = None,
    adapted: tuple[str, ...] = ADAPTED,
    run_to_run_sd: float = ADAPTATION_SD,
    spread: Spread = DEFAULT_SPREAD,
) -> PopulationResult:
    """Fly the eight conditions with ``n_subjects`` adaptive subjects and run the ANOVA.

    Each subject is a task (:mod:`twin.core.tasks`): its randomness comes from its own seed, so the
    result is the same whatever runs the subjects (``scheduler``; default this process).
    ``adapted`` names the parameters the subjects adapt (:data:`twin.pilot.models.adapt.ADAPTED`;
    ``EQUALISATION`` keeps each subject's neuromuscular system, and its measures out of the
    ANOVA); ``run_to_run_sd`` is their run-to-run variation (log-normal sd, 0 to 1);
    ``spread`` how they differ in motion perception and visual delay (:func:`subjects`).

    Raises
    ------
    SignalError
        A run-to-run variation out of range.
    TypeError
        A ``spread`` that is not a :class:`~twin.pilot.studies.spread.Spread`.
    TaskError
        When a subject failed (named with its number and seed).

    """
    adapted = checked_settings(adapted, run_to_run_sd, spread)
    tasks = population_tasks(n_subjects, seed, adapted, run_to_run_sd, spread)
    with using(scheduler) as engine:
        flown = engine.map(fly_subject, *tasks, "subjects", progress).values()
    return population_result(flown, seed, adapted, run_to_run_sd, spread)


def checked_settings(
    adapted: tuple[str, ...], run_to_run_sd: float, spread: Spread = DEFAULT_SPREAD
) -> tuple[str, ...]:
    """Check a population's settings before any subject flies; return the adapted names.

    Raises
    ------
    SignalError
        A run-to-run variation out of [0, 1] (or NaN), or a bad choice of adapted names.
    TypeError
        A ``spread`` that is not a :class:`~twin.pilot.studies.spread.Spread`.

    """
    if not 0 <= run_to_run_sd <= 1:  # also refuses NaN
        raise SignalError(f"run-to-run variation must be a log-normal sd in [0, 1]; "
                          f"got {run_to_run_sd}")  # fmt: skip
    checked(spread)
    return adapted_names(adapted)


def population_tasks(
    n_subjects: int,
    seed: int,
    adapted: tuple[str, ...],
    run_to_run_sd: float,
    spread: Spread,
) -> tuple[list[tuple], list[dict[str, int]]]:
    """Arguments of :func:`fly_subject` per subject of population ``seed``, and their names."""
    subs = subjects(n_subjects, seed, spread)
    return ([(s, seed, adapted, run_to_run_sd) for s in subs],
            [{"subject": s.number, "seed": seed} for s in subs])  # fmt: skip


def population_result(
    flown: list[list[dict[str, float]]],
    seed: int,
    adapted: tuple[str, ...],
    run_to_run_sd: float,
    spread: Spread,
) -> PopulationResult:
    """Assemble the subjects' rows (:func:`fly_subject`'s, in subject order) and their ANOVA."""
    rows = [row for r in flown for row in r]
    return PopulationResult(rows, anova(rows, compared(adapted)), seed, adapted, run_to_run_sd,
                            spread=checked(spread))  # fmt: skip


def compared(adapted: tuple[str, ...]) -> tuple[str, ...]:
    """Return the measures compared with the thesis when the subjects adapt ``adapted``.

    Parameters
    ----------
    adapted : tuple of str
        What the subjects adapt (:func:`twin.pilot.models.adapt.adapted_names`).

    Returns
    -------
    tuple of str
        Those of :data:`COMPARED` that are not pilot parameters, and the parameters adapted.

    """
    return tuple(m for m in COMPARED if m not in (*ADAPTED, *SPEED_ACCURACY) or m in adapted)
