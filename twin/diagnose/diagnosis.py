"""The diagnosis of recorded runs: the Python entry point of ``twin diagnose``.

Examples
--------
On two recorded run folders (``twin simulate --out`` or ``twin import`` writes them; not run
here, as it needs them)::

    d = diagnose(["out/run1", "out/run2"])
    [f.extension.describe() for f in d.findings]   # ['delay: extra_delay_s 0.065 (heave)']
    d.extended_config.save("mpi-measured.json")

"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from twin.chain.config import MotionSystem
from twin.chain.extensions import Extension
from twin.core.checks import number
from twin.core.errors import SignalError, UsageError
from twin.core.jsonable import plain
from twin.core.plotting import AxesArg, finish, subplots
from twin.core.progress import ProgressFn
from twin.core.results import frame, frd, pick
from twin.diagnose.candidates import DYNAMIC, Model, describe_bound
from twin.diagnose.data import NOISE_REALISATIONS, Case, load_case
from twin.diagnose.detect import smallest_detectable
from twin.diagnose.evidence import lines
from twin.diagnose.merge import merge_across_dofs
from twin.diagnose.nuisance import NoiseJudgement, judge_noise
from twin.diagnose.physical import PhysicalResult, calibrate
from twin.diagnose.physical_vocabulary import merged_config
from twin.diagnose.residuals import (
    MAX_HZ,
    LineRatios,
    PowerTest,
    decomposition,
    line_ratios,
    residual_bands,
    segment,
)
from twin.diagnose.select import (
    BIC_MARGIN,
    Finding,
    Selection,
    describe_alternative,
    name_causes,
    negligible_text,
    same_response_text,
)
from twin.diagnose.sensor_side import decide_side, rule_out_by_noise, ruled_out_text, side_text
from twin.formats.run_checks import check_distinct, read_plausible_run
from twin.formats.runs import RecordedRun

if TYPE_CHECKING:
    import control
    import pandas as pd
    from matplotlib.figure import Figure


@dataclass(eq=False)
class DofReport:
    """What the nominal model gets wrong in one DOF, and what was found.

    Attributes
    ----------
    dof : str
        The DOF.
    lines : LineRatios
        Describing-function ratio measured / nominal.
    extended_lines : LineRatios
        The same against the extended model.
    harmonics : list of PowerTest
        Residual power at harmonics and elsewhere (per run).
    residual_noise : list of PowerTest
        Residual power per octave band (per run), against the measured noise level.
    detectable : dict
        Smallest effects the data could have revealed, per effect.
    noise : NoiseJudgement
        The measured noise: IMU (nuisance) and motion noise (a cause) power factors.
    selection : Selection
        Every set of effects tried, with its fit.
    findings : list of Finding
        Causes named, most important first.
    model : Model
        Nominal + the findings.

    """

    dof: str
    lines: LineRatios
    extended_lines: LineRatios
    harmonics: list[list[PowerTest]]
    residual_noise: list[list[PowerTest]]
    detectable: dict[str, dict[str, object]]
    noise: NoiseJudgement
    selection: Selection
    findings: list[Finding]
    model: Model

    def to_dict(self) -> dict[str, object]:
        """Return the DOF's part of :meth:`Diagnosis.to_dict` (``nominal.dofs.DOF``)."""
        return plain({"dof": self.dof, **self.to_json()})  # type: ignore[return-value]

    def to_frame(self) -> pd.DataFrame:
        """One row per excited line: measured over nominal gain and phase, significance."""
        lo, hi = self.lines.ci_db()
        return frame({
            "frequency_hz": self.lines.f, "ratio_db": self.lines.db, "ratio_deg": self.lines.deg,
            "ratio_db_low": lo, "ratio_db_high": hi, "ratio_deg_ci": self.lines.ci_deg(),
            "statistic": self.lines.statistic, "significant": self.lines.significant,
        })  # fmt: skip

    def to_frd(self) -> control.FrequencyResponseData:
        """Return the measured over nominal describing function at the lines."""
        return frd(self.lines.ratio, self.lines.f, f"{self.dof} measured / nominal")

    def plot(
        self, ax: AxesArg = None, *, path: str | None = None, max_hz: float = MAX_HZ
    ) -> Figure:
        """Plot the describing-function ratio measured / nominal, and the extended model's.

        Parameters
        ----------
        ax : sequence of two Axes, optional
            Where to draw: measured over nominal gain and phase; a new figure by default.
        path : str, optional
            Save the figure here.
        max_hz : float
            Top of the model curve [Hz].

        Returns
        -------
        matplotlib.figure.Figure

        """
        fig, (a1, a2) = subplots(ax, 2, 1, figsize=(7, 6), sharex=True)
        lo, hi = self.lines.ci_db()
        db = self.lines.db
        a1.errorbar(self.lines.f, db, yerr=[db - lo, hi - db], fmt="o",
                    label="measured / nominal (95 % CI)")  # fmt: skip
        a1.plot(
            self.extended_lines.f,
            self.extended_lines.db,
            "s",
            mfc="none",
            label="measured / extended",
        )
        f = np.geomspace(self.lines.f.min() / 2, max_hz, 300)
        h = self.model.linear_response(f)
        a1.semilogx(f, 20 * np.log10(np.abs(h)), "k-", lw=1, label="extended / nominal (model)")
        a1.axhline(0, color="0.6", lw=0.5)
        a1.set_ylabel("magnitude [dB]")
        a1.legend(fontsize=8)
        a2.errorbar(self.lines.f, self.lines.deg, yerr=self.lines.ci_deg(), fmt="o")
        a2.plot(self.extended_lines.f, self.extended_lines.deg, "s", mfc="none")
        a2.semilogx(f, np.degrees(np.angle(h)), "k-", lw=1)
        a2.axhline(0, color="0.6", lw=0.5)
        a2.set_ylabel("phase [deg]")
        a2.set_xlabel("frequency [Hz]")
        a1.set_title(f"{self.dof}: describing function, measured against the models")
        return finish(fig, path, dpi=110)

    def to_json(self) -> dict[str, object]:
        """Return the DOF's part of ``nominal``."""
        return {
            "describing_function_ratio": self.lines.to_json(),
            "harmonics": [[t.to_json() for t in run] for run in self.harmonics],
            "residual_noise": [[t.to_json() for t in run] for run in self.residual_noise],
            "smallest_detectable": self.detectable,
            "noise": {
                **self.noise.fit.to_json(),
                "motion_noise_delta_bic": self.noise.delta_bic,
                "held_out": self.noise.held_out,
            },
            "sets_tried": self.selection.table[:12],
            "singles_tried": [r for r in self.selection.table if len(r["effects"]) == 1],  # type: ignore[arg-type]
            "at_bound": list(self.selection.at_bound),
        }


def held_text(g: dict[str, object]) -> str:
    """Return a finding's held-out gain (before -> after) in words."""
    if "chi2_per_line_before" in g and "df_error_db_before" not in g:
        return (
            f"line error {g['chi2_per_line_before']:.2f} -> "
            f"{g['chi2_per_line_after']:.2f} chi2/line, every channel"
        )
    if "chi2_per_line_before" in g:
        return (
            f"line error {g['chi2_per_line_before']:.2f} -> {g['chi2_per_line_after']:.2f}"
            f" chi2/line, DF error {g['df_error_db_before']:.2f} -> "
            f"{g['df_error_db_after']:.2f} dB, {g['df_error_deg_before']:.1f} -> "
            f"{g['df_error_deg_after']:.1f} deg, VAF {g['vaf_before']:.1f} -> "
            f"{g['vaf_after']:.1f} %"
        )
    return (
        f"log-likelihood per bin {g['loglik_per_bin_before']:.3f} -> "
        f"{g['loglik_per_bin_after']:.3f}"
    )


@dataclass(eq=False)
class Diagnosis:
    """Result of :func:`diagnose`.

    Attributes
    ----------
    case : Case
        Runs, nominal configuration and model.
    dofs : dict of str to DofReport
        Per analysed DOF.
    runs : list of str
        Run folders.
    validation : list of str
        Validation run folders (empty: held-out halves were used).
    max_hz : float
        Top of the analysis band.
    notes : list of str
        What reading the runs did to them (:attr:`twin.formats.runs.RecordedRun.notes`).
    physical : PhysicalResult or None
        The physical causes weighed on the full model (``physics=True``; None: not weighed).

    """

    case: Case
    dofs: dict[str, DofReport]
    runs: list[str]
    validation: list[str]
    max_hz: float
    notes: list[str] = field(default_factory=list)
    physical: PhysicalResult | None = None

    @property
    def chain_findings(self) -> list[Finding]:
        """The signal chain's findings per DOF (an effect found alike in several DOFs: one)."""
        return merge_across_dofs([f for r in self.dofs.values() for f in r.findings])

    @property
    def findings(self) -> list[Finding]:
        """Every finding, most important (largest BIC improvement) first.

        A physical cause that explains the runs at least as well as the chain's findings
        replaces them (they are listed as its alternative when the two are within the margin);
        chain findings that do not beat the full nominal by the margin on every channel are
        not named where the physics was weighed; the motion noise, which no physical cause
        explains, stays.
        """
        chain = self.chain_findings
        p = self.physical
        if p is None:
            return chain
        noise = [f for f in chain if f.extension.effect == "noise"]
        if p.finding is not None and p.preferred:
            return [p.finding, *noise]
        return chain if p.chain_supported else noise

    @property
    def at_bound(self) -> list[dict[str, object]]:
        """Effects whose fitted parameters lie at a search bound: reported, not findings."""
        return [b for r in self.dofs.values() for b in r.selection.at_bound]

    @property
    def extended_config(self) -> MotionSystem:
        """The nominal configuration with every finding added."""
        cfg = self.case.config
        found = self.findings
        if not found:
            return cfg
        exts = [f.extension for f in found if isinstance(f.extension, Extension)]
        causes = [f.extension for f in found if not isinstance(f.extension, Extension)]
        names = "+".join(sorted({e.effect for e in (*exts, *causes)}))
        return merged_config(cfg, causes).replace(  # type: ignore[arg-type]
            name=f"{cfg.name}+{names}",
            extensions=(*merged_config(cfg, causes).extensions, *exts),  # type: ignore[arg-type]
            description=f"{cfg.name} extended by twin diagnose of {', '.join(self.runs)}",
        )

    def summary_lines(self) -> list[str]:
        """Return the findings as the terminal shows them (and the recording's text)."""
        out: list[str] = []
        for note in self.notes:
            out.append(f"note: {note}")
        for b in self.at_bound:
            out.append(f"at the bound: {describe_bound(b)}")
        if not self.findings and not self.at_bound:
            out.append(
                "no finding: the runs agree with the nominal model within their noise; they "
                "could have shown:"
            )
            for line in self.statements():
                out.append(f"  {line}")
        elif not self.findings:
            out.append("no finding within the search bounds")
        shown: list[tuple[object, ...]] = []
        for i, f in enumerate(self.findings, 1):
            held = held_text(f.gain)
            if f.ambiguous:
                key = (tuple(f.extension.dofs), tuple(f.evidence.get("set") or ()))
                if key in shown:  # another member of an ambiguous set: listed with it
                    continue
                shown.append(key)
                members = [
                    g
                    for g in self.findings
                    if g.ambiguous
                    and (tuple(g.extension.dofs), tuple(g.evidence.get("set") or ())) == key
                ]
                vs = f.evidence.get("held_out_against_nominal") or {}
                held = (
                    f"line error {vs['chi2_per_line_before']:.2f} -> "
                    f"{vs['chi2_per_line_after']:.2f} chi2/line"
                    if vs
                    else held
                )
                out.append(
                    f"{i}. the runs cannot tell these apart (within BIC {BIC_MARGIN:g}); none is "
                    "named as the cause:"
                )
                out.append(
                    f"   - {' + '.join(g.extension.describe() for g in members)}  (BIC "
                    f"+{f.delta_bic:.0f}; held-out {held})"
                )
                for alt in f.evidence.get("alternatives") or []:
                    out.append(f"   - {describe_alternative(alt)}")
            else:
                out.append(
                    f"{i}. {f.extension.describe()}  (BIC +{f.delta_bic:.0f}; held out: {held})"
                )
            key = ("same", tuple(f.extension.dofs), tuple(f.evidence.get("set") or ()))
            if key not in shown:  # once per named set
                shown.append(key)
                for text in (same_response_text(f), negligible_text(f), ruled_out_text(f)):
                    if text is not None:
                        out.append(f"   {text}")
            side = f.evidence.get("side")
            if side is not None and side["verdict"] == "undecided":
                out.append(f"   {side_text(side)}")
            if f.evidence.get("preference"):
                out.append(f"   {f.evidence['preference']}")
            if not f.ambiguous:  # physical rivals listed on the finding without the flag
                for alt in f.evidence.get("alternatives") or []:
                    out.append(
                        f"   as likely (within BIC {BIC_MARGIN:g}): {describe_alternative(alt)}"
                    )
        if self.physical is not None:
            p = self.physical
            if not p.chain_supported:
                out.append(
                    f"not named: {p.chain['describe']} (BIC {p.chain['delta_bic']:+.1f} on every "
                    f"channel, the leg logs included where the runs have them; below "
                    f"{BIC_MARGIN:g})"
                )
            elif p.preferred and p.chain is not None:
                out.append(
                    f"replaced by the physical cause: {p.chain['describe']} (BIC "
                    f"{p.chain['delta_bic']:+.1f} on every channel)"
                )
            for e in p.table:
                if e["at_bound"] and e["delta_bic"] > BIC_MARGIN:
                    out.append(
                        f"at the bound (physical, not named): {e['describe']} (BIC "
                        f"{e['delta_bic']:+.1f})"
                    )
            for what, gain in p.weak():
                out.append(f"weak support, not named: {what} (BIC {gain:+.1f})")
        return out

    def statements(self) -> list[str]:
        """Return what the runs could have shown, per DOF and effect (what "no finding" means)."""
        chain = [
            f"{dof}: {entry['statement']}"
            for dof, r in self.dofs.items()
            for entry in r.detectable.values()
        ]
        physical = self.physical.statements() if self.physical is not None else []
        return chain + [f"physics: {s}" for s in physical]

    def _document(self) -> dict[str, object]:
        """Return the ``--json`` document: ``findings`` and ``nominal`` (numpy values)."""
        return {
            "findings": [f.to_json() for f in self.findings],
            "at_bound": [{**b, "describe": describe_bound(b)} for b in self.at_bound],
            "nominal": {
                "platform": self.case.config.platform,
                "platform_config": self.case.config.to_meta(),
                "filter_scales": list(self.case.filter_scales),
                "model": self.case.model,
                "runs": self.runs,
                "run_paths": [str(Path(r).resolve()) for r in self.runs],
                "validation_runs": self.validation,
                "notes": self.notes,
                "band_hz": [None, self.max_hz],
                "criterion": "joint fits of every effect and pair of effects on the excited "
                "lines, uncertainty from the measurement's own noise; a set is named when its "
                f"BIC and each member's improve by > {BIC_MARGIN:g} and each member improves "
                "the held-out line error",
                "dofs": {d: r.to_json() for d, r in self.dofs.items()},
                "physical": self.physical.to_json() if self.physical is not None else None,
            },
            "extended_config": self.extended_config.to_meta(),
        }

    def to_dict(self) -> dict[str, object]:
        """Return the ``--json`` document (``findings``, ``nominal``, ``extended_config``).

        Numbers are plain Python ones and non-finite values null, ready for ``json.dumps``.
        """
        return plain(self._document())  # type: ignore[return-value]

    def to_frame(self) -> pd.DataFrame:
        """One row per finding: effect, DOFs, parameters, BIC improvement, ambiguity."""
        import pandas as pd

        rows = [{"effect": f["effect"], "dofs": ",".join(f["dofs"]),
                 "parameters": f["parameters"], "delta_bic": f["evidence"].get("delta_bic"),
                 "ambiguous": f["ambiguous"]}
                for f in self.to_dict()["findings"]]  # type: ignore[union-attr]  # fmt: skip
        return pd.DataFrame(rows, columns=["effect", "dofs", "parameters", "delta_bic",
                                           "ambiguous"])  # fmt: skip

    def to_frd(self, dof: str | None = None) -> control.FrequencyResponseData:
        """One DOF's measured over nominal describing function (:meth:`DofReport.to_frd`).

        ``dof`` may be left out where one DOF was analysed.
        """
        return self.dofs[pick(dof, self.dofs, "the diagnosis")].to_frd()

    def plot(
        self, ax: AxesArg = None, *, path: str | None = None, dof: str | None = None
    ) -> Figure:
        """Plot one DOF's describing-function ratios (see :meth:`DofReport.plot`).

        Parameters
        ----------
        ax : sequence of two Axes, optional
            Where to draw: measured over nominal gain and phase; a new figure by default.
        path : str, optional
            Save the figure here.
        dof : str, optional
            Which analysed DOF (default the first).

        Returns
        -------
        matplotlib.figure.Figure

        """
        if dof is not None and dof not in self.dofs:
            raise UsageError(f"{dof!r} was not analysed; analysed: {', '.join(self.dofs)}")
        return self.dofs[dof or next(iter(self.dofs))].plot(ax, path=path, max_hz=self.max_hz)


def check_options(max_hz: float, imu_noise: float | None = None) -> None:
    """Refuse a band or an IMU noise factor :func:`diagnose` cannot use, before any work.

    Parameters
    ----------
    max_hz : float
        Top of the analysis band [Hz]: in (0.5, 45].
    imu_noise : float, optional
        The IMU's noise over the data sheet's: in [0.001, 1000].

    Raises
    ------
    SignalError
        Naming the parameter (``max_hz``, ``imu_noise``) and its range.

    """
    if imu_noise is not None:  # a factor on the data sheet's noise densities
        number(imu_noise, "imu_noise (factor on the data sheet)", lo=1e-3, hi=1e3,
               error=SignalError)  # fmt: skip
    if not np.isfinite(max_hz) or not 0.5 < max_hz <= 45.0:
        raise SignalError(
            f"max_hz must be in (0.5, 45] Hz (below the 50 Hz Nyquist frequency of the 100 Hz "
            f"grid); got {max_hz}"
        )


def diagnose(
    runs: Sequence[str | Path | RecordedRun],
    config: str | MotionSystem | None = None,
    model: str = "reduced",
    validate: Sequence[str | Path | RecordedRun] = (),
    max_hz: float = MAX_HZ,
    seed: int = 0,
    dofs: Sequence[str] | None = None,
    realisations: int = NOISE_REALISATIONS,
    progress: ProgressFn | None = None,
    imu_noise: float | None = None,
    physics: bool = False,
) -> Diagnosis:
    """Diagnose recorded runs against the nominal twin.

    Parameters
    ----------
    runs : sequence of path or RecordedRun
        ``twin-run/1`` folders (same platform), e.g. Table 5.2's two multi-sines, or those
        runs already read (:func:`twin.formats.runs.read_run`; what a task on a cluster is given).
    config : str or MotionSystem, optional
        Nominal configuration; ``meta.json``'s by default.
    model : str
        ``"reduced"`` (default) or ``"full"``.
    validate : sequence of path
        Runs used only to measure the gain (else the halves of the measurement window).
    max_hz : float
        Top of the analysis band [Hz].
    seed : int
        Seed of the simulated noise realisations.
    dofs : sequence of str, optional
        DOFs to analyse (the driven ones by default).
    realisations : int
        Noise realisations per run for the nominal noise spectrum.
    progress : callable, optional
        Called with a message at each step.
    imu_noise : float, optional
        The recording IMU's noise over the data sheet's (amplitude) when known, e.g. from a
        recording at rest; by default it is fitted as a nuisance.
    physics : bool
        Also weigh the physical causes (a payload, one leg's gain, lag, friction or play, the
        IMU's alignment) by simulating the full model on every channel the runs have
        (:mod:`twin.diagnose.physical`; about 25 simulations per run), against the chain's
        findings. It implies ``model="full"``: every cause is then weighed against the full
        model's nominal.

    Raises
    ------
    RunFormatError
        A run that is malformed or implausible (:func:`twin.formats.runs.read_run`), or one given
        twice, among the runs or between them and the validation runs.

    """
    check_options(max_hz, imu_noise)
    model = "full" if physics else model
    recs, vals = [read_plausible_run(r) for r in runs], [read_plausible_run(r) for r in validate]
    check_distinct([*recs, *vals])
    case = load_case(recs, config, model, seed, dofs, realisations, progress)
    val = None
    if vals:
        val = load_case(vals, case.config, model, seed + 1, None, realisations, progress,
                        own_filter=config is None)  # fmt: skip
    reports = {}
    for i, dof in enumerate(case.dofs):
        if progress:
            progress("diagnosis [DOFs]", i, len(case.dofs))
        channels = case.of(dof)
        base = Model(case, dof)
        effects = tuple(e for e in DYNAMIC if e not in case.unidentifiable)
        findings, fitted, sel = name_causes(case, dof, base, val, effects, progress, max_hz)
        fitted, findings = decide_side(fitted, findings, imu_noise)  # sensor or platform
        findings = rule_out_by_noise(fitted, findings, imu_noise)  # what the noise rules out
        if progress:
            progress(f"{dof}: noise")
        noise = judge_noise(fitted, BIC_MARGIN, max_hz, imu_noise)
        if noise.named:
            findings.append(_noise_finding(dof, noise))
        segs = [segment(c, max_hz=max_hz).scaled(noise.fit.scales) for c in channels]
        # what motion noise would have been found: relative to the nominal motion noise, on
        # top of the IMU noise the measurement shows
        nominal_motion = [s.scaled((1.0, noise.fit.imu)) for s in segs]
        preds = [fitted.predict(c) for c in channels]
        detectable = smallest_detectable(
            fitted, [lines(c, max_hz=max_hz) for c in channels], nominal_motion,
            imu_noise is not None,
        )  # fmt: skip
        for effect, why in case.unidentifiable.items():
            detectable[effect] = {"statement": f"{effect}: {why}", "identifiable": False}
        reports[dof] = DofReport(
            dof,
            line_ratios(channels),
            line_ratios(channels, preds),
            [decomposition(s) for s in segs],
            [residual_bands(s, p) for s, p in zip(segs, preds, strict=True)],
            detectable,
            noise,
            sel,
            findings,
            fitted,
        )
        if progress:
            progress("diagnosis [DOFs]", i + 1, len(case.dofs))
    notes = [n for r in (*recs, *vals) for n in r.notes]
    d = Diagnosis(case, reports, _names(runs), _names(validate), max_hz, notes)
    if physics:
        if progress:
            progress("physical causes (full model)")
        d.physical = calibrate(case.config, case.runs, case.imu, seed, max_hz, progress,
                               case.filter_scales)  # fmt: skip
        chain = [f for f in d.chain_findings if f.extension.effect != "noise"]
        extended = case.config.replace(extensions=(*case.config.extensions,
                                                   *(f.extension for f in chain)))  # fmt: skip
        per_dof = [
            f for r in reports.values() for f in r.findings if f.extension.effect != "noise"
        ]  # annotated: merged ones are made anew
        d.physical.weigh(extended if chain else None, chain, per_dof)
    return d


def _names(runs: Sequence[str | Path | RecordedRun]) -> list[str]:
    return [str(r.path if isinstance(r, RecordedRun) else r) for r in runs]


def _noise_finding(dof: str, noise: NoiseJudgement) -> Finding:
    """Return the motion noise named as the ``noise`` effect (amplitude factor)."""
    a = float(noise.fit.motion or 1.0)
    scale = float(np.sqrt(a))
    return Finding(
        Extension("noise", {"scale": scale}, (dof,)),
        {
            "criterion": f"BIC improvement > {BIC_MARGIN:g} of a free motion-noise power "
            "factor (the IMU's noise fitted in both, or held at the given level); held-out "
            "likelihood per bin rises",
            "delta_bic": float(noise.delta_bic or 0.0),
            "parameter_std": {"scale": float(noise.fit.std["motion"] / (2 * scale))},
            "imu_noise_scale": float(np.sqrt(noise.fit.imu)),
        },
        {"held_out": "other half of the measurement window (two-fold)", **noise.held_out},
    )
