"""Name the cause: forward selection of extensions by BIC, and the gain on held-out data.

For each analysed DOF, starting from the nominal model, every effect not yet in the model is
fitted on top of it over the measurement windows of all runs; the one with the largest
improvement of the Bayesian information criterion,

    dBIC = 2 (log L_with - log L_without) - p ln(n),

(p fitted parameters, n = 2 x the number of frequency bins: real observations) is added when
dBIC > ``BIC_MARGIN`` (10: "very strong" evidence on Kass and Raftery's scale), and the search
repeats. A run that the nominal model explains within its noise therefore yields no finding.
Findings are ranked by dBIC, most important first.

The gain of each finding is measured on data not used to fit it: two-fold cross-validation
over the halves of the measurement window (parameters fitted on one half, evaluated on the
other, and the reverse; the mean is reported), or a whole validation run. Reported: VAF of the
measured signal, the describing-function error (mean |dB| and |deg| over the lines, measured
over predicted) and the log-likelihood per bin, before -> after adding the finding (the
findings ranked above it are in both).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from twin.chain.extensions import EFFECTS, Extension
from twin.diagnose.candidates import Fit, Model, fit_candidate
from twin.diagnose.data import Case, Channel
from twin.diagnose.residuals import MAX_HZ, Segment, decomposition, segment

FloatArray = NDArray[np.float64]
#: Evidence needed to name a cause [BIC units].
BIC_MARGIN = 10.0
#: Most findings per DOF.
MAX_FINDINGS = 3


@dataclass
class Finding:
    """A named cause.

    Attributes
    ----------
    extension : Extension
        Effect and fitted parameters.
    evidence : dict
        Criterion, dBIC, log-likelihood gain, observations, parameter standard deviations.
    gain : dict
        Held-out VAF, describing-function error and log-likelihood before -> after.

    """

    extension: Extension
    evidence: dict[str, object]
    gain: dict[str, object] = field(default_factory=dict)

    def to_json(self) -> dict[str, object]:
        """Return the finding in the fixed JSON vocabulary."""
        e = self.extension.to_json()
        return {
            "effect": e["effect"],
            "parameters": e["parameters"],
            "dofs": e["dofs"],
            "evidence": self.evidence,
            "gain": self.gain,
        }


def _needs_backlash(segments: Sequence[Segment]) -> bool:
    """Fit backlash only where the residual has more than noise off the lines (it is slow)."""
    return any(t.significant and t.ratio > 1 for s in segments for t in decomposition(s))


def select(
    case: Case,
    dof: str,
    max_hz: float = MAX_HZ,
    effects: Sequence[str] | None = None,
    progress: Callable[[str], None] | None = None,
) -> tuple[list[Finding], Model]:
    """Forward selection of extensions for one DOF (see module docstring)."""
    channels = case.of(dof)
    segments = [segment(ch, max_hz=max_hz) for ch in channels]
    n_obs = 2 * sum(s.size for s in segments)
    effects = list(effects or EFFECTS)
    if "backlash" in effects and not _needs_backlash(segments):
        effects.remove("backlash")
    model = Model(case, dof)
    ll = model.loglik(segments)
    findings: list[Finding] = []
    while len(findings) < MAX_FINDINGS:
        used = {f.extension.effect for f in findings}
        fits: list[tuple[float, Fit]] = []
        for effect in effects:
            if effect in used:
                continue
            if progress:
                progress(f"{dof}: fitting {effect}")
            fit = fit_candidate(effect, model, segments)
            p = len(EFFECTS[effect]) - (effect == "sensor_filter")  # channels are not fitted
            fits.append((2 * (fit.loglik - ll) - p * np.log(n_obs), fit))
        if not fits:
            break
        dbic, best = max(fits, key=lambda x: x[0])
        if dbic <= BIC_MARGIN:
            break
        findings.append(
            Finding(
                best.extension,
                {
                    "criterion": f"BIC improvement > {BIC_MARGIN:g}",
                    "delta_bic": float(dbic),
                    "log_likelihood_gain": float(best.loglik - ll),
                    "observations": int(n_obs),
                    "parameter_std": best.std,
                    "runner_up": _runner_up(fits, best),
                    "window_s": [list(s.window) for s in segments],
                    "band_hz": [float(min(s.f[0] for s in segments)), float(max_hz)],
                },
            )
        )
        model = model.with_(best.extension)
        ll = best.loglik
    return findings, model


def _runner_up(fits: list[tuple[float, Fit]], best: Fit) -> dict[str, object] | None:
    rest = sorted((f for f in fits if f[1] is not best), key=lambda x: -x[0])
    if not rest:
        return None
    dbic, fit = rest[0]
    return {"effect": fit.extension.effect, "delta_bic": float(dbic)}


# --- gain on held-out data ---------------------------------------------------------------------


def line_amplitudes(
    t: FloatArray, y: FloatArray, f: FloatArray, window: tuple[float, float]
) -> NDArray[np.complex128]:
    """Least-squares complex amplitudes of sines at ``f`` over ``window`` (any length)."""
    sel = (t >= window[0] - 1e-9) & (t < window[1] - 1e-9)
    tt = t[sel]
    a = np.hstack([np.sin(2 * np.pi * np.outer(tt, f)), np.cos(2 * np.pi * np.outer(tt, f))])
    a = np.hstack([a, np.ones((tt.size, 1))])
    c, *_ = np.linalg.lstsq(a, y[sel], rcond=None)
    m = f.size
    return c[:m] + 1j * c[m : 2 * m]


def scores(model: Model, ch: Channel, seg: Segment) -> dict[str, float]:
    """VAF [%], describing-function error (mean |dB|, |deg|) and log-likelihood per bin."""
    pred = model.predict(ch)
    sel = seg.mask
    y = ch.measured[sel]
    vaf = 100 * (1 - np.var(y - pred[sel]) / np.var(y))
    r = line_amplitudes(ch.t, ch.measured, ch.lines_hz, seg.window) / line_amplitudes(
        ch.t, pred, ch.lines_hz, seg.window
    )
    return {
        "vaf": float(vaf),
        "df_error_db": float(np.mean(np.abs(20 * np.log10(np.abs(r))))),
        "df_error_deg": float(np.mean(np.abs(np.degrees(np.angle(r))))),
        "loglik_per_bin": model.loglik([seg]) / seg.size,
    }


def _refit(
    case: Case, dof: str, findings: Sequence[Finding], segments: Sequence[Segment]
) -> list[Model]:
    """Models with the first 0..m findings, parameters refitted on ``segments``."""
    model = Model(case, dof)
    models = [model]
    for f in findings:
        ext = f.extension
        start = [v for k, v in ext.parameters.items() if k != "channels"]
        fit = fit_candidate(ext.effect, model, segments, start=start)
        model = model.with_(fit.extension)
        models.append(model)
    return models


def _mean(rows: list[dict[str, float]]) -> dict[str, float]:
    return {k: float(np.mean([r[k] for r in rows])) for k in rows[0]}


def held_out_gain(
    case: Case,
    dof: str,
    findings: Sequence[Finding],
    max_hz: float = MAX_HZ,
    validation: Case | None = None,
    model: Model | None = None,
) -> list[dict[str, object]]:
    """Gain of each finding on data not used to fit it (see module docstring)."""
    if not findings:
        return []
    if validation is not None:
        models = (
            _models_of(model, len(findings))
            if model
            else _refit(case, dof, findings, [segment(c, max_hz=max_hz) for c in case.of(dof)])
        )
        tests = [(models, ch, segment(ch, max_hz=max_hz)) for ch in validation.of(dof)]
        held_out = "validation run(s)"
    else:
        tests = []
        for ch in case.of(dof):
            a, b = ch.halves()
            for fit_w, test_w in ((a, b), (b, a)):
                models = _refit(case, dof, findings, [segment(ch, fit_w, max_hz)])
                tests.append((models, ch, segment(ch, test_w, max_hz)))
        held_out = "other half of the measurement window (two-fold)"
    if not tests:
        return [{"held_out": "no validation channel of this DOF"} for _ in findings]
    out = []
    for i in range(len(findings)):
        before = _mean([scores(ms[i], ch, seg) for ms, ch, seg in tests])
        after = _mean([scores(ms[i + 1], ch, seg) for ms, ch, seg in tests])
        out.append(
            {
                "held_out": held_out,
                "vaf_before": before["vaf"],
                "vaf_after": after["vaf"],
                "df_error_db_before": before["df_error_db"],
                "df_error_db_after": after["df_error_db"],
                "df_error_deg_before": before["df_error_deg"],
                "df_error_deg_after": after["df_error_deg"],
                "loglik_per_bin_before": before["loglik_per_bin"],
                "loglik_per_bin_after": after["loglik_per_bin"],
            }
        )
    return out


def _models_of(model: Model, m: int) -> list[Model]:
    """Return the nested models of a selected model (first 0..m extensions)."""
    return [Model(model.case, model.dof, model.extensions[:i], model._cache) for i in range(m + 1)]
