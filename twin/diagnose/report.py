"""The diagnosis report folder: Markdown summary, JSON, figures and a Rerun recording.

Written to a temporary folder and renamed when complete, so a failure leaves nothing.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np

from twin.core.lifecycle import replacing_dir
from twin.diagnose.candidates import describe_bound
from twin.diagnose.diagnosis import Diagnosis, DofReport
from twin.diagnose.physical import SOURCE_TEXT, PhysicalResult
from twin.diagnose.residual_figure import plot_residual
from twin.diagnose.select import describe_alternative, negligible_text, same_response_text
from twin.diagnose.sensor_side import ruled_out_text, side_text

#: What a payload's factor means, with and without the legs' forces among the evidence.
PAYLOAD_IMU = ("The factor is on the cabin's mass and inertia together: from the IMU alone a "
               "heavier cabin is a slower one behind the same PD, and mass, inertia and the PD's "
               "damping trade off, so one factor is what these runs identify (the centre of "
               "gravity is held at the cabin's). Leg forces (forces.csv) would see the mass "
               "itself.")  # fmt: skip
PAYLOAD_FORCES = ("The factor is on the cabin's mass and inertia together (the centre of "
                  "gravity held at the cabin's); the leg forces (forces.csv) carry the mass "
                  "directly, which the IMU cannot tell from inertia: what each source "
                  "contributed, below, shows how much the factor rests on them.")  # fmt: skip
HALVES = "the other half of the measurement window (two-fold)"


def _fmt(v: object) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, list | tuple):
        return ", ".join(_fmt(x) for x in v)
    return str(v)


def _pm(std: object, k: str) -> str:
    v = std.get(k) if isinstance(std, dict) else None
    return f" ± {v:.2g}" if isinstance(v, float) and np.isfinite(v) else ""


def summary(d: Diagnosis) -> str:
    """Return the Markdown summary."""
    cfg = d.case.config
    out = [
        "# Diagnosis",
        "",
        f"- runs: {', '.join(d.runs)}",
        f"- nominal: `{cfg.name}` on the {cfg.platform} platform ({d.case.model} model); "
        f"filter {f'{cfg.filter_break_hz:g} Hz' if cfg.filter_break_hz else 'none'}, "
        f"delay {cfg.delay_s * 1e3:.1f} ms, "
        f"noise {'on' if cfg.noise else 'off'}"
        + "".join(
            f"; {run} recorded with the filter at {hz:g} Hz"
            for run, hz in d.case.settings_hz.items()
        ),
        f"- evidence: the excited lines up to {d.max_hz:g} Hz, their uncertainty from the "
        "measurement's own noise (neighbouring bins); every effect and pair of effects fitted "
        "jointly; a set is named when its BIC and each member's improve by more than 10 and "
        "each member lowers the held-out line error",
        "- gain measured on: "
        + ("validation runs " + ", ".join(d.validation) if d.validation else HALVES),
        "",
        "## Findings",
        "",
    ]
    if not d.findings and not d.at_bound:
        out += [
            "No finding: the runs are consistent with the nominal model within their noise.",
            "",
        ]
    elif not d.findings:
        out += ["No finding within the search bounds (see below).", ""]
    for i, f in enumerate(d.findings, 1):
        std = f.evidence.get("parameter_std", {})
        pars = ", ".join(
            f"{k} = {_fmt(v)}" + _pm(std, k) for k, v in f.extension.parameters.items()
        )
        g = {k: v for k, v in f.gain.items() if isinstance(v, float)}
        nan = float("nan")

        def pair(key: str, fmt: str, g: dict = g, nan: float = nan) -> str:
            a, b = g.get(f"{key}_before", nan), g.get(f"{key}_after", nan)
            return f"{a:{fmt}} → {b:{fmt}}"

        one_of = "**ambiguous**, one of several explanations: " if f.ambiguous else ""
        out += [
            f"{i}. {one_of}**{f.extension.effect}** in {', '.join(f.extension.dofs)}: {pars} "
            f"(BIC improvement {f.evidence['delta_bic']:.1f})",
        ]
        if "chi2_per_line_before" in g and "df_error_db_before" not in g:
            out.append(
                f"   - held out ({f.gain.get('held_out')}): line error χ²/line "
                f"{pair('chi2_per_line', '.2f')}"
            )
        elif "chi2_per_line_before" in g:
            out.append(
                f"   - held out ({f.gain.get('held_out')}): line error χ²/line "
                f"{pair('chi2_per_line', '.2f')}, DF error {pair('df_error_db', '.2f')} dB, "
                f"{pair('df_error_deg', '.1f')} deg, VAF {pair('vaf', '.1f')} %"
            )
        elif "loglik_per_bin_before" in g:
            out.append(f"   - held out: log-likelihood per bin {pair('loglik_per_bin', '.3f')}")
        if f.evidence.get("preference"):
            out.append(f"   - {f.evidence['preference']}")
        if "side" in f.evidence:
            out.append(f"   - {side_text(f.evidence['side'])}")
        for text in (same_response_text(f), negligible_text(f), ruled_out_text(f)):
            if text is not None:
                out.append(f"   - {text}")
        alts = f.evidence.get("alternatives") or []
        if alts:
            out.append(
                "   - as well supported (within the margin), so none is named as the cause: "
                if f.ambiguous
                else "   - within the margin: "
            )
            out[-1] += "; ".join(describe_alternative(a) for a in alts)
    out.append("")
    if d.at_bound:
        out += ["## At the bound (not findings)", ""]
        out += [f"- {describe_bound(b)}" for b in d.at_bound]
        out.append("")
    if d.notes:
        out += ["## Notes on the runs", "", *[f"- {n}" for n in d.notes], ""]
    if d.physical is not None:
        out += _physical_section(d.physical)
    for dof, r in d.dofs.items():
        out += _dof_section(dof, r)
    return "\n".join(out) + "\n"


def _physical_section(p: PhysicalResult) -> list[str]:
    """Return the physical causes weighed on the full model: candidates, sources, detectability."""
    out = [
        "## Physical causes (full model)",
        "",
        f"One cause at a time (a payload, one leg's gain, lag, friction or play, the IMU's "
        f"alignment), fitted by {p.simulations} simulations of the full MuJoCo model on every "
        f"channel the runs have: {', '.join(SOURCE_TEXT.get(s, s) for s in p.sources)} "
        f"({p.observations} observations).",
        "",
        "| candidate | BIC improvement | held-out χ² (fit on one half, scored on the other) "
        "| at the bound |",
        "|---|---|---|---|",
    ]
    for e in p.table:
        held = "; ".join(f"{a:.1f} → {b:.1f}" for a, b in e["held_out_chi2"].values())  # type: ignore[union-attr]
        out.append(f"| {e['describe']} | {float(e['delta_bic']):.1f} | {held} | "  # type: ignore[arg-type]
                   f"{'yes' if e['at_bound'] else 'no'} |")  # fmt: skip
    out.append("")
    if p.chain is not None:
        out.append(f"The chain's findings ({p.chain['describe']}), simulated on the full model "
                   f"and scored on the same channels: BIC improvement "
                   f"{float(p.chain['delta_bic']):.1f}.")  # type: ignore[arg-type]  # fmt: skip
    if not p.chain_supported:
        out.append("They do not beat the nominal by 10 on every channel: not named.")
    weak = p.weak()
    if weak:
        out.append("Support below the margin (not named): " + "; ".join(
            f"{d} (BIC +{b:.1f})" for d, b in weak) + ".")  # fmt: skip
    if p.finding is not None:
        f = p.finding
        verdict = "named" if p.preferred else "not named: the chain's findings explain more"
        out.append(f"Physical cause: {f.extension.describe()} ({verdict}).")
        if f.extension.effect == "payload":
            out.append(PAYLOAD_FORCES if "forces" in p.sources else PAYLOAD_IMU)
        out += ["", "What each source contributed (fall of χ² with the cause):", ""]
        for s, v in f.evidence["sources"].items():  # type: ignore[union-attr]
            out.append(f"- {SOURCE_TEXT.get(s, s)}: {v['chi2_nominal']:.1f} → "
                       f"{v['chi2_fitted']:.1f}")  # fmt: skip
    else:
        out.append("No physical cause beats the nominal model by the margin.")
    out += ["", "The figures and the recording show each DOF's signal-chain model; the physical "
            "fit is the table above."]  # fmt: skip
    out += ["", "What these runs could have shown of the physics (expected BIC improvement > "
            "10, linearised at each probe; where a log's noise sits at its floor, 1 um or 1 N, "
            "the floor sets it):", "", *[f"- {s}" for s in p.statements()], ""]  # fmt: skip
    return out


def _dof_section(dof: str, r: DofReport) -> list[str]:
    lo, hi = r.lines.ci_db()
    out = [
        f"## {dof}: measured / nominal",
        "",
        "| f [Hz] | ratio [dB] | 95 % CI [dB] | phase [deg] | ± [deg] | significant "
        "| smallest detectable [dB / deg] |",
        "|---|---|---|---|---|---|---|",
    ]
    ci = r.lines.ci_deg()
    for i, f in enumerate(r.lines.f):
        out.append(
            f"| {f:.2f} | {r.lines.db[i]:+.2f} | {lo[i]:+.2f} … {hi[i]:+.2f} "
            f"| {r.lines.deg[i]:+.1f} | "
            f"{ci[i]:.1f} | {'**yes**' if r.lines.significant[i] else 'no'} | "
            f"{r.lines.min_db[i]:.2f} / {r.lines.min_deg[i]:.1f} |"
        )
    out += ["", "Residual power against the measured noise level (per run):", ""]
    for run, (h, n) in enumerate(zip(r.harmonics, r.residual_noise, strict=True)):
        tests = ", ".join(
            f"{t.name} ×{t.ratio:.2f} (p={t.p_value:.2g}{', significant' if t.significant else ''})"
            for t in [*h, *n]
            if t.bins
        )
        out.append(f"- run {run + 1}: {tests}")
    nz = r.noise.fit.to_json()
    motion = nz["motion_noise_scale"]
    out += [
        "",
        f"Measured noise over the nominal model's (amplitude): IMU ×{nz['imu_noise_scale']:.2f} "
        "(a sensor property, not a cause)"
        + (f", motion noise ×{motion:.2f}" if motion is not None else ""),
        "",
        "What these runs could have shown (expected BIC improvement > 10):",
        "",
        *[f"- {entry['statement']}" for entry in r.detectable.values()],
        "",
    ]
    return out


def _figures(d: Diagnosis, folder: Path) -> None:
    for dof, r in d.dofs.items():
        r.plot(path=str(folder / f"df_{dof}.png"), max_hz=d.max_hz)
        plot_residual(d, dof, str(folder / f"residual_{dof}.png"))


#: Writes a diagnosis' recording to a path (:func:`twin.viz.record.diagnosis.record_diagnosis`).
Recording = Callable[[Diagnosis, Path], object]


def write_report(
    d: Diagnosis, out: str | Path, figures: bool = True, recording: Recording | None = None
) -> Path:
    """Write ``summary.md``, ``diagnosis.json``, figures and ``diagnosis.rrd`` to ``out``.

    Parameters
    ----------
    d : Diagnosis
        What is reported.
    out : str or Path
        The report folder (replaced whole, or left as it was).
    figures : bool
        Draw ``df_<dof>.png`` and ``residual_<dof>.png``.
    recording : callable, optional
        Writes ``diagnosis.rrd`` (called with ``d`` and the file's path); none without.

    """
    out = Path(out)
    with replacing_dir(out, "diagnosis.json") as tmp:
        (tmp / "summary.md").write_text(summary(d), encoding="utf-8")
        (tmp / "diagnosis.json").write_text(
            json.dumps(d.to_dict(), indent=2) + "\n", encoding="utf-8"
        )
        if figures:
            _figures(d, tmp)
        if recording is not None:
            recording(d, tmp / "diagnosis.rrd")
    return out
