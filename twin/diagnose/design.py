"""Design the next run: the measurement that tells the alternatives of a diagnosis apart.

When a diagnosis is ambiguous (several explanations within the selection margin:
:mod:`twin.diagnose.select`), or found nothing and a user asks how to see a smaller effect,
:func:`design_run` chooses one run in the finding's DOF: a multisine of a few lines, their
frequencies and acceleration amplitudes (within the platform's limits:
:func:`twin.chain.signals.check_signal`) and its length (within a time budget), the one whose
expected evidence between the closest two explanations is largest.

The expected evidence of a run between explanations i and j, if i is true, is

    ``E_ij = 2 |H_i(f) - H_j(f)|^2 A^2 / s(f)^2``

(the BIC difference the run adds with both at their fitted parameters: the Kullback-Leibler
divergence of the two complex Gaussians, as :func:`twin.diagnose.detect.expected_delta_bic`;
refitting j on the new run can absorb part of it, so it is an upper bound). H is each
explanation's response at the line, A the acceleration amplitude and s the noise of a
Fourier amplitude over the new window: measured in the diagnosed runs, off their lines, next
to f, and scaled by sqrt(T_old / T_new). Where one of the two has a backlash, whose describing
function depends on the whole motion, the evidence is simulated instead: both runs with one
explanation, the other refitted by the diagnosis's own fit
(:mod:`twin.diagnose.simulated_evidence`), at several amplitudes of the chosen lines.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy import optimize, stats

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

from twin.chain.config import MotionSystem
from twin.chain.extensions import Extension
from twin.chain.signals import (
    WINDOW_S,
    DescribingSignal,
    MultiSine,
    base_frequency,
    check_signal,
    periodic_signal,
    premeasurement_periods,
    single_sine,
)
from twin.core.checks import read_json
from twin.core.errors import DataError, SignalError, SignalLimitError
from twin.core.frames import acceleration_unit, dof_index
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.progress import ProgressFn
from twin.core.results import frame
from twin.diagnose.candidates import (
    extension_at_bounds,
    make_extension,
    numeric_names,
    search_space,
)
from twin.diagnose.data import Case, Channel, load_case
from twin.diagnose.equivalence import SAME_RESPONSE
from twin.diagnose.select import BIC_MARGIN
from twin.diagnose.simulated_evidence import SimulatedEvidence
from twin.formats.runs import write_commands
from twin.measurement.describing_function import fourier_coefficients

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
#: Frequencies tried [Hz] (multiples of 0.05 Hz: whole periods in a window of 20 s).
FREQUENCIES_HZ = (0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 5.0, 7.0, 10.0, 12.0, 15.0, 20.0)
#: Acceleration amplitudes tried, largest first [m/s^2 or rad/s^2]; the largest that the
#: platform's limits allow at a frequency, and a third and a tenth of it.
AMPLITUDES = (3.0, 2.0, 1.0, 0.5, 0.2, 0.1, 0.05)
#: Neighbouring bins on each side of a frequency whose noise is measured.
NOISE_BINS = 5
#: Effects whose response is linear (a transfer function): weighed line by line.
LINEAR_EFFECTS = (
    "delay",
    "gain",
    "platform_filter",
    "resonance",
    "lead",
    "sensor_filter",
    "platform_lag",
)
#: Effects a run can be designed to show (the linear ones, and a backlash by simulation).
DESIGNABLE = (*LINEAR_EFFECTS, "backlash")
#: Default time budget of the designed run [s].
BUDGET_S = 120.0
#: Lines of the designed multisine.
LINES = 3
#: Least position amplitude of a line, in plays of an explanation's backlash: a line within the
#: play moves nothing behind it (a run of such lines shows a platform at rest, which the run
#: checks refuse as an IMU that does not follow its commands).
BEYOND_PLAY = 3.0
#: Expected evidence of a pair beyond which the design seeks no more for it (twice the
#: margin: lines go to the pairs still below it, not to those already told apart).
ENOUGH = 2 * BIC_MARGIN
#: Platform-filter settings a run may be recorded at [Hz], besides the nominal's: those the
#: thesis measured the MPI at (Ch. 4: 1, 5 and 10 Hz; "values up to 10 Hz").
FILTER_SETTINGS_HZ = (5.0, 10.0)
#: Factors tried on the lines' amplitudes, together, until the multisine fits the limits.
SCALES = (1.0, 0.7, 0.5, 0.35, 0.25, 0.18, 0.12, 0.08, 0.05)


@dataclass(frozen=True)
class Explanation:
    """One explanation of the runs: a set of effects with their fitted parameters.

    ``primary``: one of those the runs cannot tell apart (the named set and its
    alternatives); a rival is any other single effect the diagnosis fitted, or any set of
    linear effects among the closest it fitted (``sets_tried``), which the designed run must
    not leave able to mimic them (refitted: :class:`Mimic`).
    """

    label: str
    extensions: tuple[Extension, ...]
    primary: bool = True

    def config(self, nominal: MotionSystem) -> MotionSystem:
        """Return the nominal configuration extended by this explanation."""
        return nominal.replace(extensions=(*nominal.extensions, *self.extensions))


#: The lines chosen at one filter setting: the run, its evidence on the linear pairs (None:
#: none weighed), notes, each line's evidence per pair, and the pairs that respond alike.
_Chosen = tuple[
    DescribingSignal,
    dict[tuple[str, str], float] | None,
    list[str],
    dict[tuple[str, str], FloatArray],
    list[tuple[Explanation, Explanation]],
]


@dataclass(frozen=True)
class Candidate:
    """One candidate run and the evidence it is expected to give."""

    frequency_hz: float
    amplitude: float
    window_s: float
    duration_s: float
    evidence: dict[tuple[str, str], float]

    @property
    def weakest(self) -> float:
        """The least expected evidence over the pairs that matter (see :func:`design_run`)."""
        return min(self.evidence.values(), default=0.0)


@dataclass(frozen=True)
class DesignResult:
    """The designed run, why, and what else was weighed.

    ``setting``: the configuration to record the run at (the diagnosis's nominal, with the
    platform filter ``filter_scale`` times its setting where the design opens it).
    """

    dof: str
    platform: str
    explanations: tuple[Explanation, ...]
    best: Candidate
    candidates: tuple[Candidate, ...]
    signal: DescribingSignal
    source: str
    notes: tuple[str, ...] = field(default_factory=tuple)
    levels: tuple[tuple[float, float, float], ...] = ()
    setting: MotionSystem | None = None
    filter_scale: float = 1.0

    @property
    def filter_changed(self) -> bool:
        """Whether the run is to be recorded at another filter setting than the old runs'."""
        return self.filter_scale != 1.0

    def at_setting(self, config: MotionSystem) -> MotionSystem:
        """Return ``config`` (a truth, the nominal) at the filter setting of the designed run."""
        return config.filter_scaled(self.filter_scale)

    @property
    def decides(self) -> bool:
        """Whether the run is expected to separate every pair by more than the margin."""
        return self.best.weakest > BIC_MARGIN

    def to_frame(self) -> pd.DataFrame:
        """Return the expected evidence, one row per pair (true explanation, other one)."""
        return frame([{"true": i, "other": j, "delta_bic": v}
                      for (i, j), v in self.best.evidence.items()])  # fmt: skip

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Plot the expected evidence of each pair against the naming margin.

        Parameters
        ----------
        ax : Axes, optional
            Where to draw; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        pairs = list(self.best.evidence.items())
        fig, ax = subplots(ax, figsize=(7, 0.4 * len(pairs) + 1.5))
        ax.barh([f"if {i}: against {j}" for (i, j), _ in pairs], [v for _, v in pairs])
        ax.axvline(BIC_MARGIN, color="k", lw=0.8, ls="--", label=f"margin ({BIC_MARGIN:g})")
        ax.set_xscale("symlog", linthresh=BIC_MARGIN)
        ax.set_xlabel("expected evidence of the old runs and the designed one [BIC]")
        ax.tick_params(axis="y", labelsize=7)
        ax.legend(fontsize=8)
        ax.set_title(f"designed run in {self.dof}: {self.best.duration_s:.0f} s", fontsize=9)
        return finish(fig, path)

    def to_dict(self) -> dict[str, object]:
        """Return the design as JSON (``design.json``)."""
        b = self.best
        return {
            "dof": self.dof,
            "platform": self.platform,
            "diagnosis": self.source,
            "explanations": [
                {
                    "label": e.label,
                    "extensions": [x.to_json() for x in e.extensions],
                    "rival": not e.primary,
                }
                for e in self.explanations
            ],
            "run": {
                "signal": "multisine" if len(self.signal.frequencies_hz) > 1 else "single sine",
                "frequencies_hz": [float(f) for f in self.signal.frequencies_hz],
                "amplitudes": [float(a) for a in self.signal.amplitudes],  # type: ignore[union-attr]
                "amplitude_unit": acceleration_unit(self.dof),
                "window_s": b.window_s,
                "duration_s": b.duration_s,
                "filter_break_hz": None if self.setting is None else self.setting.filter_break_hz,
                "filter_changed": self.filter_changed,
                "config": None if self.setting is None else "config.json",
            },
            "expected_evidence": [
                {"true": i, "other": j, "delta_bic": v} for (i, j), v in b.evidence.items()
            ],
            "decides": self.decides,
            "amplitudes_tried": [
                {
                    "peak_motion": p,
                    "motion_unit": position_unit(self.dof),
                    "weakest_delta_bic": w,
                    "chance_to_decide": c,
                }
                for p, w, c in self.levels
            ],
            "margin": BIC_MARGIN,
            "candidates": [
                {
                    "frequency_hz": c.frequency_hz,
                    "amplitude": c.amplitude,
                    "weakest_delta_bic": c.weakest,
                }
                for c in self.candidates
            ],
            "notes": list(self.notes),
        }

    def summary_lines(self) -> list[str]:
        """Return the design as the terminal shows it."""
        b, unit = self.best, acceleration_unit(self.dof)
        weakest = min(b.evidence, key=b.evidence.__getitem__, default=("-", "-"))
        sig = self.signal
        lines = ", ".join(
            f"{f:g} Hz {a:.3g} {unit}"
            for f, a in zip(sig.frequencies_hz, sig.amplitudes, strict=True)
        )  # type: ignore[arg-type]
        at = "" if not self.filter_changed or self.setting is None else \
            f", with the platform filter at {self.setting.filter_break_hz:g} Hz"  # fmt: skip
        out = [
            f"run: {self.dof}, lines {lines}; {b.duration_s:.0f} s ({b.window_s:.0f} s "
            f"measured){at}",
            "expected evidence (BIC) of the old runs and this one, if one explanation is true, "
            "against each other refitted to it:",
        ]
        for (i, j), v in b.evidence.items():
            out.append(f"  if {i}: against {j} {v:.1f}")
        out.append(
            f"expected to decide (every pair above {BIC_MARGIN:g})"
            if self.decides
            else f"not expected to decide within the budget (weakest pair {b.weakest:.1f}, "
            f"below {BIC_MARGIN:g}: if {weakest[0]}, against {weakest[1]}); the evidence grows "
            "with the measured time: about "
            f"{b.window_s * BIC_MARGIN / max(b.weakest, 1e-9):.3g} s of it would be needed"
        )
        return [*out, *(f"note: {n}" for n in self.notes)]


def explanations_of(doc: dict, finding: int = 0) -> tuple[str, list[Explanation]]:
    """Return the DOF and the explanations of an ambiguous finding of a ``diagnosis.json``.

    Raises
    ------
    DataError
        No such finding, or one that is not ambiguous (nothing to tell apart).

    """
    findings = doc.get("findings") or []
    if not findings:
        raise DataError(
            "the diagnosis found nothing to tell apart; give --effect NAME (one of "
            f"{', '.join(DESIGNABLE)}) to design the run that would show it "
            "below the size these runs could"
        )
    if not 0 <= finding < len(findings):
        raise DataError(f"the diagnosis has {len(findings)} finding(s); no finding {finding + 1}")
    f = findings[finding]
    alts = f.get("alternatives") or []
    if not f.get("ambiguous") or not alts or not all("parameters" in a for a in alts):
        raise DataError(
            f"finding {finding + 1} ({f['effect']}) is not ambiguous: there is nothing to tell "
            "apart (give --effect NAME to design a run that sees a smaller one)"
        )
    dof = f["dofs"][0]
    members = set(f["evidence"].get("set") or [f["effect"]])
    together = [f] + [
        g
        for g in findings
        if g is not f
        and g["dofs"] == f["dofs"]
        and g["effect"] in members
        and set(g["evidence"].get("set") or [g["effect"]]) == members
    ]  # the named set whole: each member is a finding of its own
    named = tuple(
        Extension.from_json({k: g[k] for k in ("effect", "parameters", "dofs")}) for g in together
    )
    out = [Explanation(" + ".join(x.describe() for x in named), named)]
    for a in alts:
        exts = _extensions(a, dof)
        out.append(Explanation(" + ".join(x.describe() for x in exts), exts))
    tried = doc["nominal"]["dofs"][dof]
    # the set the runs' BIC chose, before the held-out gate or the negligible rule took a
    # member out: the runs did not rule it out, the designed run must tell it from the rest
    ev = f["evidence"]
    support = (
        members
        | set(ev.get("dropped_by_held_out_gate") or [])
        | set(ev.get("dropped_as_negligible") or [])
    )
    whole = [r for r in tried.get("sets_tried", []) if set(r["effects"]) == support]
    if (
        support != members and whole and ("backlash" not in support or whole[0].get("nameable"))
    ):  # a play the runs do not ask for (its search found none) is no explanation
        exts = _extensions(whole[0], dof)
        out.append(Explanation(" + ".join(x.describe() for x in exts), exts))
    have = {tuple(sorted(x.effect for x in e.extensions)) for e in out}
    # what the noise ruled out is no rival (a new run's lines would not revive it)
    have |= {tuple(sorted(a["effects"])) for a in ev.get("ruled_out_by_noise") or []}
    near = [  # the closest sets the diagnosis fitted: a new run may make any of them nameable
        r for r in tried.get("sets_tried", []) if set(r["effects"]) <= set(LINEAR_EFFECTS)
    ]  # fmt: skip
    for r in [*tried.get("singles_tried", []), *near]:
        if tuple(sorted(r["effects"])) in have:
            continue
        if "backlash" in r["effects"] and not r.get("nameable"):
            continue  # a play the runs do not ask for (its search found none): no rival
        exts = _extensions(r, dof)
        out.append(Explanation(" + ".join(x.describe() for x in exts), exts, primary=False))
    return dof, out


def _extensions(row: dict, dof: str) -> tuple[Extension, ...]:
    """Return the extensions of a fitted set as ``diagnosis.json`` lists it."""
    return tuple(
        make_extension(e, list(row["parameters"][e]), list(row["parameters"][e].values()), dof)
        for e in row["effects"]
    )


def detection_explanations(doc: dict, dof: str, effect: str) -> list[Explanation]:
    """Return "nothing" and ``effect`` at the size the runs could just not show (no finding).

    Raises
    ------
    DataError
        For a DOF the diagnosis did not analyse, or an effect without a stated size.

    """
    if effect not in DESIGNABLE:
        raise DataError(
            f"--effect {effect}: the design weighs {', '.join(DESIGNABLE)}; not {effect!r}"
        )
    dofs = doc["nominal"]["dofs"]
    if dof not in dofs:
        raise DataError(f"the diagnosis analysed {', '.join(dofs)}; not {dof}")
    entry = dofs[dof]["smallest_detectable"].get(effect)
    if entry is None:
        raise DataError(
            f"no smallest detectable size of {effect!r} in {dof}; stated for "
            f"{', '.join(dofs[dof]['smallest_detectable'])}"
        )
    values = entry.get("values", [entry.get("value")])
    size = next((v for v in reversed(values) if v is not None), None)
    if size is None:
        raise DataError(f"{effect} in {dof}: no size in its searched range would have shown")
    ext = make_extension(effect, [entry["parameter"]], [size], dof)
    return [Explanation("no effect", ()), Explanation(ext.describe(), (ext,))]


def measured_noise(
    case: Case, dof: str, frequencies: Sequence[float], channels: Sequence[Channel]
) -> tuple[FloatArray, float]:
    """Return the noise of a Fourier amplitude at each frequency, and the window it holds for.

    From each of ``channels`` (diagnosed runs of ``dof``): the residual measured - nominal
    twin, at the :data:`NOISE_BINS` bins on each side of the frequency that are not lines of
    the run (or their 2nd and 3rd harmonics); the root mean square over the runs, for the
    shortest window.

    Raises
    ------
    DataError
        No run of ``dof``.

    """
    if not channels:
        raise DataError(f"the diagnosed runs do not drive {dof}")
    power, windows = np.zeros(len(frequencies)), []
    for ch in channels:
        t0, t1 = ch.window
        df = 1.0 / (t1 - t0)
        lines = np.concatenate([ch.lines_hz * m for m in (1, 2, 3)])
        resid = ch.measured - ch.nominal
        for i, f in enumerate(frequencies):
            k = np.round(f / df) + np.arange(-NOISE_BINS, NOISE_BINS + 1)
            bins = k[k > 0] * df
            bins = bins[np.min(np.abs(bins[:, None] - lines[None, :]), axis=1) > 0.5 * df]
            bins = bins[np.abs(bins - f) > 0.5 * df]
            c = fourier_coefficients(ch.t, resid, bins, ch.window)
            power[i] += float(np.mean(np.abs(c) ** 2))
        windows.append(t1 - t0)
    return np.sqrt(power / len(channels)), min(windows)


def _largest_amplitude(platform: str, dof: str, f: float) -> float | None:
    for a in AMPLITUDES:
        try:
            check_signal(single_sine(dof, f, a).commands, platform)
        except SignalLimitError:
            continue
        return a
    return None


def _multisine(
    platform: str, dof: str, lines: Sequence[tuple[float, float]], budget_s: float
) -> DescribingSignal | None:
    """Return the multisine of ``lines`` (frequency, largest single amplitude) within limits.

    The amplitudes are scaled down together by the first of :data:`SCALES` whose signal the
    platform's limits allow, and the window is the longest whole number of base periods
    the budget leaves after the fades and the settling (None: none fits).
    """
    f = np.array([x[0] for x in lines])
    a = np.array([x[1] for x in lines])
    f_min = float(f.min())
    overhead = 2.0 / f_min + premeasurement_periods(f_min) / f_min
    period = 1.0 / base_frequency(f)
    window = np.floor((budget_s - overhead) / period) * period
    if window < period - 1e-9:
        return None
    for scale in SCALES:
        sig = periodic_signal(
            MultiSine(f, a * scale), dof, window_s=window, label="designed multisine"
        )
        try:
            check_signal(sig.commands, platform)
        except SignalLimitError:
            continue
        return sig
    return None


@dataclass(frozen=True)
class LineSet:
    """Lines a set of runs measures: frequency, acceleration amplitude, noise of the amplitude.

    ``scale``: each line's platform-filter setting over the nominal's (None: the nominal's).
    """

    f: FloatArray
    amplitude: FloatArray
    noise: FloatArray
    scale: FloatArray | None = None

    @property
    def scales(self) -> FloatArray:
        """Each line's filter setting over the nominal's."""
        return np.ones(self.f.size) if self.scale is None else self.scale

    def __add__(self, other: LineSet) -> LineSet:
        return LineSet(
            *(
                np.concatenate([a, b])
                for a, b in zip(
                    (self.f, self.amplitude, self.noise, self.scales),
                    (other.f, other.amplitude, other.noise, other.scales),
                    strict=True,
                )
            )
        )

    def evidence(self, hi: ComplexArray, hj: ComplexArray) -> float:
        """Return ``2 sum |H_i - H_j|^2 A^2 / s^2``: the BIC difference if i is true."""
        return float(2 * np.sum(np.abs(hi - hj) ** 2 * self.amplitude**2 / self.noise**2))


def old_lines(case: Case, dof: str) -> LineSet:
    """Return the lines the diagnosed runs measured (their noise off the lines, next to them)."""
    parts = []
    for ch in case.of(dof):
        f = np.asarray(ch.lines_hz, dtype=float)
        u = fourier_coefficients(ch.t, ch.commands.at(ch.t, 2)[:, dof_index(dof)], f, ch.window)
        noise, _ = measured_noise(case, dof, f, [ch])
        parts.append(LineSet(f, np.abs(u), noise, np.full(f.size, ch.filter_scale)))
    out = parts[0]
    for p in parts[1:]:
        out = out + p
    return out


class Mimic:
    """Refits one explanation so that its lines match another's (the rival at its best)."""

    def __init__(self, case: Case, dof: str, expl: Explanation) -> None:
        self.nominal, self.k, self.expl = case.clean, dof_index(dof), expl
        self.case, self.channels = case, case.of(dof)
        channels = self.channels
        self.slots: list[tuple[str, list[str], list[float], list[tuple[float, float]]]] = []
        for ext in expl.extensions:
            names = numeric_names(ext.effect)
            space = search_space(ext.effect, case, dof, channels)
            self.slots.append(
                (ext.effect, list(names), [ext.value(n) for n in names], list(space.bounds))
            )
        self.dof = dof

    @property
    def start(self) -> FloatArray:
        """Return the parameters the diagnosis fitted, in slot order."""
        return np.array([v for _, _, values, _ in self.slots for v in values])

    def response(
        self, theta: FloatArray, f: FloatArray, scale: FloatArray | float = 1.0
    ) -> ComplexArray:
        """Return the explanation's response at ``f`` with parameters ``theta``.

        ``scale``: the filter setting over the nominal's, of all lines or of each.
        """
        exts, i = [], 0
        for effect, names, _, _ in self.slots:
            exts.append(make_extension(effect, names, theta[i : i + len(names)], self.dof))
            i += len(names)
        cfg = self.nominal.replace(extensions=(*self.nominal.extensions, *exts))
        f = np.asarray(f, dtype=float)
        scale = np.broadcast_to(np.asarray(scale, dtype=float), f.shape)
        out = np.empty(f.shape, dtype=complex)
        for k in np.unique(scale):
            at = scale == k
            out[at] = cfg.filter_scaled(float(k)).response_at_hz(f[at])[:, self.k]
        return out

    def fit(self, target: ComplexArray, lines: LineSet) -> FloatArray:
        """Return the parameters whose response is nearest ``target`` at ``lines``."""
        lo = np.array([b[0] for *_, bounds in self.slots for b in bounds])
        hi = np.array([b[1] for *_, bounds in self.slots for b in bounds])
        w = lines.amplitude / lines.noise

        def residual(theta: FloatArray) -> FloatArray:
            r = (self.response(theta, lines.f, lines.scales) - target) * w
            return np.concatenate([r.real, r.imag])

        if not self.slots:  # nothing to refit: the nominal response
            return np.empty(0)
        x0 = np.clip(self.start, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
        return optimize.least_squares(residual, x0, bounds=(lo, hi), max_nfev=200).x

    def at_bound(self, theta: FloatArray) -> bool:
        """Return whether a refit lies at an end of a parameter's search (no explanation)."""
        exts, i = [], 0
        for effect, names, _, _ in self.slots:
            exts.append(make_extension(effect, names, theta[i : i + len(names)], self.dof))
            i += len(names)
        return any(extension_at_bounds(x, self.case, self.dof, self.channels) for x in exts)

    def evidence(self, target: ComplexArray, lines: LineSet) -> float | None:
        """Return the least evidence against this explanation when ``target`` is true.

        None where the best mimic lies at the bound of its search: then it is no explanation
        (the diagnosis reports such a fit at the bound and never names it).
        """
        theta = self.fit(target, lines)
        if self.at_bound(theta):
            return None
        return lines.evidence(target, self.response(theta, lines.f, lines.scales))


#: Peak motions tried for a run where a backlash is among the explanations, in plays (besides
#: the largest the limits allow): a play shows in a motion of a few plays and hides in a large
#: one, while the other pairs' evidence grows with the amplitude; the simulations weigh both.
#: (Each line alone may then move less than :data:`BEYOND_PLAY` plays: it is the lines' sum,
#: four plays and more at its peaks, that moves through the play.)
PLAYS_TRIED = (16.0, 8.0, 4.0)


#: Runs whose chance of separating every pair is within this of the likeliest run's are as
#: likely: of them, the smallest motion is kept (where a play shows most).
AS_LIKELY = 0.01


def deciding_chance(evidence: Iterable[float]) -> float:
    """Return the chance that a run separates every pair by more than the margin.

    A pair's BIC difference, with its expected value ``E`` (noise-free), is about normal with
    standard deviation ``2 sqrt(E)`` (twice a chi-square difference whose mean is ``E / 2``
    and variance ``E``), so it passes the margin with probability ``Phi((E - margin) /
    (2 sqrt(E)))``; the pairs taken as independent.
    """
    e = np.maximum(np.asarray(list(evidence), dtype=float), 1e-12)
    return float(np.prod(stats.norm.cdf((e - BIC_MARGIN) / (2 * np.sqrt(e)))))


def lines_kept(
    options: Sequence[tuple[DescribingSignal, dict[tuple[str, str], float]]],
) -> int:
    """Return the index of the run to keep of ``options``, ordered most lines first.

    The likeliest to separate every pair (:func:`deciding_chance`) or, of those within
    :data:`AS_LIKELY` of it, the one with the most lines: more of the band seen. (So where none
    is likely to decide, the most lines: nothing then speaks for fewer, and the band they cover
    may show what no explanation foresaw.) An option without evidence (every rival's refit at
    a bound: no explanation left) decides.

    Examples
    --------
    >>> lines_kept([("three lines", {("a", "b"): 8.0}), ("one", {("a", "b"): 12.0})])
    1
    >>> lines_kept([("three lines", {("a", "b"): 60.0}), ("one", {("a", "b"): 90.0})])
    0
    >>> lines_kept([("three lines", {("a", "b"): 0.1}), ("one", {("a", "b"): 0.5})])
    0

    """
    chances = [deciding_chance(ev.values()) for _, ev in options]
    return next(n for n, c in enumerate(chances) if c >= max(chances) - AS_LIKELY)


def position_unit(dof: str) -> str:
    """Return the unit of a DOF's motion: m or rad."""
    return "m" if dof_index(dof) < 3 else "rad"


def play_of(expls: Sequence[Explanation]) -> float:
    """Return the largest play of a backlash among the ambiguous explanations (0: none)."""
    return max((x.value("play") for e in expls if e.primary for x in e.extensions
                if x.effect == "backlash"), default=0.0)  # fmt: skip


def peak_position(sig: DescribingSignal, dof: str) -> float:
    """Return the largest commanded excursion of a run in ``dof`` [m or rad]."""
    return float(np.max(np.abs(sig.commands.values[:, dof_index(dof)])))


def amplitude_levels(sig: DescribingSignal, dof: str, play: float) -> list[float]:
    """Return the factors on a run's amplitudes to try: 1, and those of :data:`PLAYS_TRIED`.

    Only factors below 1 are kept (a peak motion of ``k`` plays that the largest run exceeds).
    """
    peak = peak_position(sig, dof)
    if play <= 0 or peak <= 0:
        return [1.0]
    return [1.0, *(k * play / peak for k in PLAYS_TRIED if k * play < peak)]


def scaled(
    sig: DescribingSignal, dof: str, factor: float, window_s: float | None = None
) -> DescribingSignal:
    """Return the same multisine with every amplitude times ``factor``.

    Its measurement window is ``window_s`` (default: the same as ``sig``'s).
    """
    ms = MultiSine(np.asarray(sig.frequencies_hz), np.asarray(sig.amplitudes) * factor)
    window = sig.window[1] - sig.window[0] if window_s is None else window_s
    return periodic_signal(ms, dof, window_s=window, label=sig.label)


#: Chance to decide (:func:`deciding_chance`) a run is shortened to: the designed run is the
#: shortest whole number of base periods whose expected evidence still reaches it.
SURE = 0.95


def shortest_window(evidence: Iterable[float], window_s: float, period_s: float) -> float:
    """Return the shortest window that still decides with chance :data:`SURE` (or the whole).

    The evidence of the new run grows with its measured time: each pair's is taken as
    proportional to the window (the old runs' share, which does not shrink, left out: the
    window returned is never too short). Where the whole window's chance is below
    :data:`SURE`, the whole window is returned (the budget is the limit). Never shorter than
    Table 5.2's window of :data:`twin.chain.signals.WINDOW_S` (20 s), in whole base periods.

    Examples
    --------
    >>> shortest_window([400.0, 60.0], 100.0, 10.0)  # 60 -> 30 at 50 s: sure (24 is not)
    50.0
    >>> shortest_window([1e5], 100.0, 10.0)  # never below 20 s
    20.0
    >>> shortest_window([12.0], 100.0, 10.0)  # not sure to decide: the whole budget
    100.0

    """
    e = np.asarray(list(evidence), dtype=float)
    if not e.size or deciding_chance(e) < SURE:  # nothing weighed, or not sure: the budget
        return window_s
    first = max(1, int(np.ceil(WINDOW_S / period_s - 1e-9)))
    for k in range(first, int(np.floor(window_s / period_s + 1e-9)) + 1):
        if deciding_chance(e * k * period_s / window_s) >= SURE:
            return k * period_s
    return window_s


def design_run(
    case: Case,
    expls: Sequence[Explanation],
    dof: str,
    budget_s: float = BUDGET_S,
    max_hz: float = np.inf,
    progress: ProgressFn | None = None,
    source: str = "",
    shortest: bool = False,
    filter_settings_hz: Sequence[float] = FILTER_SETTINGS_HZ,
) -> DesignResult:
    """Choose the multisine within ``budget_s`` that best tells ``expls`` apart.

    For every ordered pair (i true, j another explanation, i one of the ambiguous ones), j
    is refitted to i's lines over the diagnosed runs' lines and every frequency of
    :data:`FREQUENCIES_HZ` within the band (:class:`Mimic`): what j can still not mimic at a
    frequency is that line's evidence. The run's :data:`LINES` lines are chosen one by one,
    each the one that most raises the weakest pair's evidence; the multisine's amplitudes are
    scaled together to the platform's limits and every pair refitted again on the old and
    the new lines. Pairs whose responses are the same at every frequency (a sensor filter and
    a platform lag) cannot be told apart by any run's lines: they are left to the noise.

    A pair with a backlash has no line-by-line evidence (its response depends on the whole
    motion): it is simulated and refitted (:class:`SimulatedEvidence`) with the chosen lines
    at the largest amplitude and at :data:`PLAYS_TRIED` plays of peak motion
    (:func:`amplitude_levels`). The run kept is the one likeliest to separate every pair
    (:func:`deciding_chance`) or, of runs within :data:`AS_LIKELY` of it, the smallest motion:
    a stated preference, where a play shows most. Where only pairs with a play on one side
    are left, their linear parts guide the lines. Before the amplitudes are tried, the
    multisine of the lines chosen is weighed, on the linear pairs, against those of its first
    two lines and its first line (:func:`lines_kept`): scaled as a whole to the limits, a line
    added can cost the others more evidence than it brings (where only pairs with a play are
    left, the lines chosen are kept). With ``shortest``, the run kept is then shortened to the
    fewest whole base periods (at least 20 s) still expected to decide with a chance of
    :data:`SURE` (:func:`shortest_window`); a run not expected to decide keeps the budget.
    Off by default: on a hold-out the project does not see, a 15 ms delay that a 120 s run
    decided stayed ambiguous after the 22 s run this chose (the expected evidence is a
    model's, and a run at the margin of it has none to spare).

    Where the platform has a filter (not moved by an extension of the nominal: a setting
    would then name another break than the one set), the lines are chosen and weighed at the
    nominal setting
    and at each of ``filter_settings_hz`` above it (the thesis' Ch. 4 settings of the MPI by
    default; empty: the nominal's only, for a platform whose filter cannot be changed);
    another setting is kept only where its chance to decide (on the linear pairs) beats the
    nominal's by more than :data:`AS_LIKELY` (a lower one first, of settings as likely). The
    run is then to be recorded at that setting (:attr:`DesignResult.setting`).

    Raises
    ------
    SignalError
        For a budget too short for any frequency's fades, settling and one period.

    """
    nominal = case.clean
    platform = nominal.platform
    freqs = np.array([f for f in FREQUENCIES_HZ if f <= max_hz])
    noise, t_old = measured_noise(case, dof, freqs, case.of(dof))
    # a line that moves less than a few times the play of a backlash among the explanations
    # to tell apart shows only that nothing moves
    play = play_of(expls)
    tops, keep = [], []
    for f in freqs:
        top = _largest_amplitude(platform, dof, float(f))
        if top is not None and top / (2 * np.pi * f) ** 2 < BEYOND_PLAY * play:
            top = None
        if top is not None and _multisine(platform, dof, [(float(f), top)], budget_s):
            tops.append(top)
            keep.append(True)
        else:
            keep.append(False)
    freqs, noise = freqs[keep], noise[keep]
    if not freqs.size:
        raise SignalError(
            f"a budget of {budget_s:g} s is too short for any sine in {dof} "
            "(fades, settling and one period), or none fits the limits"
            + (f" with a motion beyond {BEYOND_PLAY:g} x the backlash's play" if play else "")
        )
    window = budget_s / 2  # for ranking; the run's own window is used for its evidence
    band = LineSet(freqs, np.array(tops), noise * np.sqrt(t_old / window))
    past = old_lines(case, dof)
    mimics = {id(e): Mimic(case, dof, e) for e in expls}

    def response(e: Explanation, f: FloatArray, scale: FloatArray | float = 1.0) -> ComplexArray:
        return mimics[id(e)].response(mimics[id(e)].start, f, scale)

    def nonlinear(e: Explanation) -> bool:
        return any(x.effect == "backlash" for x in e.extensions)

    def effects(e: Explanation) -> set[str]:
        return {x.effect for x in e.extensions}

    # i true, j refitted to it; j holding all of i's effects mimics it exactly (the BIC's
    # penalty on its extra parameters decides those, not any run's lines); a pair with a
    # backlash is weighed by simulation (SimulatedEvidence)
    pairs, simulated = [], []
    for i in expls:
        for j in expls:
            if i is j or not i.primary or effects(i) <= effects(j):
                continue
            (simulated if nonlinear(i) or nonlinear(j) else pairs).append((i, j))

    # the lines are chosen on linear responses: a pair whose explanations both hold a backlash
    # by their linear parts (the play common to both), then weighed whole by simulation; a
    # pair with a play on one side only has no linear stand-in (the play may be the
    # difference) unless no other pair has one: then its linear parts are the guide (the
    # play's share of the response fades as the motion grows; the amplitudes tried and the
    # simulations weigh the rest)
    def linear_part(e: Explanation) -> Explanation:
        return Explanation(e.label, tuple(x for x in e.extensions if x.effect != "backlash"),
                           e.primary)  # fmt: skip

    def stand_ins(both: bool) -> list[tuple[Explanation, Explanation]]:
        out = [(linear_part(i), linear_part(j)) for i, j in simulated
               if (nonlinear(i) and nonlinear(j)) == both]  # fmt: skip
        return [(i, j) for i, j in out if not effects(i) <= effects(j)]

    def noise_of(cand: DescribingSignal) -> FloatArray:
        w = cand.window[1] - cand.window[0]
        return np.interp(np.log(cand.frequencies_hz), np.log(freqs), noise) * np.sqrt(t_old / w)

    def line_evidence(
        cand: DescribingSignal, scale: float, same: list[tuple[Explanation, Explanation]]
    ) -> dict[tuple[str, str], float]:
        f_c = np.asarray(cand.frequencies_hz, dtype=float)
        both = past + LineSet(f_c, np.asarray(cand.amplitudes), noise_of(cand),
                              np.full(f_c.size, scale))  # fmt: skip
        out = {}
        for i, j in pairs:
            if (i, j) not in same:
                v = mimics[id(j)].evidence(response(i, both.f, both.scales), both)
                if v is not None:  # left out: j's refit lies at a bound (no explanation)
                    out[i.label, j.label] = v
        return out

    def choose(scale: float) -> _Chosen:
        """Choose the lines of a run at filter setting ``scale`` x the nominal's; weigh them."""
        at = LineSet(band.f, band.amplitude, band.noise, np.full(band.f.size, scale))
        per_line: dict[tuple[str, str], FloatArray] = {}
        same: list[tuple[Explanation, Explanation]] = []
        everything = past + at

        def weigh_lines(to_weigh: list[tuple[Explanation, Explanation]]) -> None:
            mimics.update({id(e): Mimic(case, dof, e) for pair in to_weigh for e in pair})
            for n, (i, j) in enumerate(to_weigh):
                if progress:
                    progress("design: refitting each explanation to the others", n, len(to_weigh))
                theta = mimics[id(j)].fit(response(i, everything.f, everything.scales), everything)
                if mimics[id(j)].at_bound(theta):
                    continue  # j mimics i only at the edge of what it can be: not an explanation
                hi = response(i, at.f, scale)
                d = hi - mimics[id(j)].response(theta, at.f, scale)
                e = 2 * np.abs(d) ** 2 * at.amplitude**2 / at.noise**2
                if np.max(np.abs(d / hi)) < SAME_RESPONSE:  # the same response
                    if (i, j) in pairs:
                        same.append((i, j))
                else:
                    per_line[i.label, j.label] = e

        weigh_lines([*pairs, *stand_ins(both=True)])
        if not per_line:
            weigh_lines(stand_ins(both=False))
        chosen: list[int] = []

        def score_of(sums: Sequence[float]) -> tuple[float, float]:
            """Pairs brought past twice the margin count no more; then the weakest pair."""
            return (sum(min(x, ENOUGH) for x in sums), min(sums, default=0.0))

        def score(lines_: list[int]) -> tuple[float, float]:
            if not per_line:  # only pairs that need simulating: the lines the noise favours
                return (float(np.sum(at.amplitude[lines_] / at.noise[lines_])), 0.0)
            return score_of([float(v[lines_].sum()) for v in per_line.values()])

        for _ in range(min(LINES, freqs.size)):
            best = max((k for k in range(freqs.size) if k not in chosen),
                       key=lambda k: score([*chosen, k]))  # fmt: skip
            chosen.append(best)
        # the lines chosen, then fewer of them: each multisine is scaled as a whole to the
        # limits, so a line added can cost the others more than it brings
        options: list[DescribingSignal] = []
        for n in range(len(chosen), 0, -1):
            s = _multisine(platform, dof, [(float(freqs[k]), tops[k])
                                           for k in sorted(chosen[:n])], budget_s)  # fmt: skip
            if s is not None:  # the first line alone fits (each kept frequency was tried alone)
                options.append(s)
        sig, known, note = options[0], None, []
        if len(options) > 1 and any(p not in same for p in pairs):
            weighed = [(s, line_evidence(s, scale, same)) for s in options]
            sig, known = weighed[lines_kept(weighed)]
            if sig is not options[0]:
                note.append(
                    f"{len(sig.frequencies_hz)} of the {len(options[0].frequencies_hz)} lines "
                    "chosen: their multisine, scaled as a whole to the limits, is likelier to "
                    "decide (chance " + ", ".join(f"{deciding_chance(ev.values()):.2f}"
                                                 for _, ev in weighed) + " with "
                    + ", ".join(str(len(s.frequencies_hz)) for s, _ in weighed) + " lines)"
                )  # fmt: skip
        if known is None and any(p not in same for p in pairs):
            known = line_evidence(sig, scale, same)
        return sig, known, note, per_line, same

    # at the nominal filter setting, and, where the platform has a filter, at the settings
    # the thesis measured the MPI at (Ch. 4): a filter opened lets the lines through
    nominal_hz = case.config.breaks_hz[dof_index(dof)]
    scales = [1.0]
    if nominal_hz is not None and pairs and not case.config.of("platform_filter"):
        scales += [hz / nominal_hz for hz in sorted(filter_settings_hz)
                   if hz > nominal_hz * (1 + 1e-9)]  # fmt: skip
    chosen_runs = [choose(k) for k in scales]
    at_setting = [deciding_chance((r[1] or {}).values()) for r in chosen_runs]
    pick = next(n for n, c in enumerate(at_setting) if c >= max(at_setting) - AS_LIKELY)
    scale = scales[pick]
    sig, known, kept_note, per_line, same = chosen_runs[pick]
    if pick:
        kept_note.append(
            f"record this run with the platform filter set to {nominal_hz * scale:g} Hz "
            f"(nominal {nominal_hz:g} Hz; the thesis' Ch. 4 measured the MPI at 1, 5 and "
            "10 Hz): at the nominal setting the filter hides the lines that tell the "
            "explanations apart (chance to decide " + ", ".join(
                f"{c:.2f} at {nominal_hz * k:g} Hz" for k, c in zip(scales, at_setting, strict=True)
            ) + "); twin design writes the setting as config.json: import the run with "
            "--config config.json, then diagnose the old runs and the new one without --config"
        )  # fmt: skip
    w_new = sig.window[1] - sig.window[0]
    noise_new = noise_of(sig)
    sim = SimulatedEvidence(case, dof, max_hz) if simulated else None
    levels = [1.0] if sim is None else amplitude_levels(sig, dof, play)
    runs = []
    for n, factor in enumerate(levels):
        cand = sig if factor == 1.0 else scaled(sig, dof, factor)
        evidence = dict(known) if factor == 1.0 and known is not None \
            else line_evidence(cand, scale, same)  # fmt: skip
        if sim is not None:
            if progress:
                progress("design: simulating each explanation at each amplitude", n, len(levels))
            lines_new = sim.candidate(cand, noise_new, f"designed run x{factor!r}", scale)
            for i, j in simulated:
                v = sim.evidence(i.extensions, j.extensions, lines_new)
                if v is not None:
                    evidence[i.label, j.label] = v
        # a pair left out is one whose refit lies at a bound: no explanation, decided
        runs.append((min(evidence.values(), default=0.0), n, cand, evidence))
    # the run most likely to separate every pair; of runs as likely, the smallest motion
    chances = [deciding_chance(r[3].values()) for r in runs]
    likely = [r for r, c in zip(runs, chances, strict=True) if c >= max(chances) - AS_LIKELY]
    _, n_best, sig, evidence = max(likely, key=lambda r: r[1])
    # no longer than it needs to be: the shortest window still sure to decide
    period = 1.0 / base_frequency(np.asarray(sig.frequencies_hz))
    decided = shortest and bool(evidence) and min(evidence.values()) > BIC_MARGIN
    w_short = shortest_window(evidence.values(), w_new, period) if decided else w_new
    shortened = w_short < w_new - 1e-9
    if shortened:
        evidence = {k: v * w_short / w_new for k, v in evidence.items()}
        sig, w_new = scaled(sig, dof, 1.0, w_short), w_short
    run = Candidate(
        float(sig.frequencies_hz.min()),
        float(np.max(sig.amplitudes)),
        float(w_new),
        sig.commands.duration,
        evidence,
    )
    notes = [
        f"{i.label} and {j.label} respond alike at every frequency: no run's lines tell "
        "them apart, the measured noise does (a run at rest, at the IMU's full rate)"
        for i, j in same
        if i.primary and j.primary and expls.index(i) < expls.index(j)
    ] + kept_note
    tried = tuple((peak_position(r[2], dof), r[0], c) for r, c in zip(runs, chances, strict=True))
    if sim is not None:
        notes.append(
            "a backlash among the explanations or their rivals: its pairs simulated and "
            "refitted at "
            f"{len(levels)} amplitude(s) of the lines (peak motion "
            + ", ".join(f"{p:.3g}" for p, *_ in tried)
            + f" {position_unit(dof)}; the chance that every pair passes the margin "
            + ", ".join(f"{c:.2f}" for *_, c in tried)
            + f"): the run is the one at {tried[n_best][0]:.3g}, the smallest motion of those "
            f"within {AS_LIKELY:g} of the likeliest"
        )
    if shortest and w_new < WINDOW_S - 1e-9:
        notes.append(
            f"the budget of {budget_s:g} s leaves {w_new:.3g} s measured, under Table 5.2's "
            f"{WINDOW_S:g} s: nothing to shorten"
        )
    if shortened:
        notes.append(
            f"shortened to {sig.commands.duration:.0f} s ({w_new:.0f} s measured; budget "
            f"{budget_s:g} s): the fewest whole base periods, at least {WINDOW_S:g} s, expected "
            f"to decide with a chance of {SURE:g} or more; the evidence above is scaled with "
            "the measured time, the old runs' share too (a lower bound), and the amplitudes "
            "tried are weighed at the whole budget"
        )
    singles = tuple(
        Candidate(float(f), float(a), window, 0.0, {k: float(v[n]) for k, v in per_line.items()})
        for n, (f, a) in enumerate(zip(freqs, tops, strict=True))
    )
    setting = case.config  # the configuration to record the run at
    if scale != 1.0:
        setting = case.config.filter_scaled(scale)
        setting = setting.replace(
            name=f"{case.config.name}-fb{setting.filter_break_hz:g}",
            description=f"{case.config.name} with the platform filter set to "
            f"{setting.filter_break_hz:g} Hz: the setting of a designed run",
        )
    return DesignResult(dof, platform, tuple(expls), run, singles, sig, source, tuple(notes),
                        tried, setting, scale)  # fmt: skip


def design_from(
    folder: str | Path,
    finding: int = 0,
    effect: str | None = None,
    dof: str | None = None,
    budget_s: float = BUDGET_S,
    progress: ProgressFn | None = None,
    shortest: bool = False,
    keep_filter: bool = False,
) -> DesignResult:
    """Design the next run of a diagnosis folder (``twin diagnose --out``'s).

    Parameters
    ----------
    folder : str or Path
        Holds ``diagnosis.json``; its runs must still be where it says.
    finding : int
        The ambiguous finding to resolve (0: the first).
    effect : str, optional
        Instead: design the run that best shows ``effect`` at the size the runs could just
        not show.
    dof : str, optional
        With ``effect``: the DOF (default the first the diagnosis analysed).
    budget_s : float
        Longest run [s].
    progress : callable, optional
        Called with what is being done.
    shortest : bool
        Shorten the run to the fewest base periods expected to decide (see :func:`design_run`).
    keep_filter : bool
        Keep the platform filter at the diagnosed runs' setting (a platform whose filter
        cannot be changed); by default the thesis' 5 and 10 Hz are weighed too.

    Raises
    ------
    DataError
        A folder without ``diagnosis.json``, a finding that is not ambiguous, an effect
        without a stated size.

    """
    path = Path(folder) / "diagnosis.json"
    if not path.exists():
        raise DataError(f"{folder}: no diagnosis.json; give a folder twin diagnose wrote")
    doc = read_json(path, "a diagnosis.json written by twin diagnose")
    nominal = MotionSystem.from_meta(doc["nominal"]["platform"], doc["nominal"]["platform_config"])  # type: ignore[index]
    if effect is not None:
        dof = dof or next(iter(doc["nominal"]["dofs"]))  # type: ignore[index]
        expls = detection_explanations(doc, dof, effect)  # type: ignore[arg-type]
    else:
        dof, expls = explanations_of(doc, finding)  # type: ignore[arg-type]
    case = load_case(
        _run_paths(doc["nominal"], path),
        nominal,
        doc["nominal"]["model"],
        dofs=[dof],  # type: ignore[index]
        realisations=2,
        progress=progress,
        filter_scales=doc["nominal"].get("filter_scales"),  # type: ignore[union-attr]
    )
    band = doc["nominal"].get("band_hz") or [None, None]  # type: ignore[union-attr]
    max_hz = float(band[1]) if band[1] is not None else np.inf
    return design_run(case, expls, dof, budget_s, max_hz, progress, str(path), shortest,
                      () if keep_filter else FILTER_SETTINGS_HZ)  # fmt: skip


def _run_paths(nominal: dict, path: Path) -> list[str]:
    """Return the diagnosed runs' folders (absolute where the diagnosis wrote them so)."""
    runs = nominal.get("run_paths") or nominal["runs"]
    missing = [r for r in runs if not Path(r).is_dir()]
    if missing:
        raise DataError(
            f"{path}: the diagnosed run {missing[0]} is not there (it must be to "
            "measure its noise); run twin design where twin diagnose ran, or move "
            "the runs back"
        )
    return list(runs)


def write_design(result: DesignResult, out: Path) -> None:
    """Write ``design.json``, ``commands.csv`` (twin-run/1) and ``schedule.toml`` into ``out``.

    And ``config.json`` (``twin-config/1``): the configuration to record the run at, for
    ``twin import --config`` (the diagnosis's nominal, at another filter setting where the
    design asks for one).
    """
    if result.setting is not None:
        result.setting.save(out / "config.json")
    (out / "design.json").write_text(
        json.dumps(result.to_dict(), indent=2) + "\n", encoding="utf-8"
    )
    write_commands(out / "commands.csv", result.signal.commands)
    sig = result.signal
    f = [float(x) for x in sig.frequencies_hz]
    position = [float(a) / (2 * np.pi * x) ** 2 for a, x in zip(sig.amplitudes, f, strict=True)]  # type: ignore[arg-type]
    at = [] if result.setting is None or not result.filter_changed else [
        f"# record with the platform filter set to {result.setting.filter_break_hz:g} Hz "
        "(config.json)"
    ]  # fmt: skip
    schedule = "\n".join(
        [
            *at,
            'schedule = "twin-schedule/1"',
            f'name = "designed run in {result.dof}"',
            "",
            "[[move]]",
            'kind = "sines"',
            f'dof = "{result.dof}"',
            f"frequencies_hz = {f!r}",
            f"amplitudes = {position!r}",
            f"phases_deg = {[180.0] * len(f)!r}",
            f"fade_s = {1.0 / min(f)!r}",
            f"duration_s = {sig.commands.duration!r}",
            "",
        ]
    )
    (out / "schedule.toml").write_text(schedule, encoding="utf-8")
