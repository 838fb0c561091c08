"""What a run could have revealed: expected evidence and Cramér-Rao bounds of an effect.

For a true model (prediction Y_t, noise spectrum S_t) and the nominal one (Y_0, S_0) the
expected log-likelihood gain per bin is the Kullback-Leibler divergence of two complex
Gaussians,

    E[log L_t - log L_0] = |Y_t - Y_0|^2 / S_0 + S_t / S_0 - 1 - ln(S_t / S_0),

so the expected BIC improvement of naming the effect is 2 sum(...) - p ln(n) (+ p for the
fitted parameters' own gain). An effect is *detectable in principle* when that exceeds
``BIC_MARGIN`` with room to spare; a clean bill of health excludes exactly the effects whose
expected improvement is well above it. The Fisher information of the same likelihood gives
the smallest standard deviation any unbiased fit of the parameters can reach.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy import optimize

from twin.chain.extensions import EFFECTS, Extension
from twin.diagnose.candidates import Model, make_extension
from twin.diagnose.residuals import TAPER_CORRELATION, Segment
from twin.diagnose.select import BIC_MARGIN


def _spectra(model: Model, seg: Segment) -> tuple[np.ndarray, np.ndarray]:
    return seg.spectrum(model.predict(seg.channel)), seg.noise_psd * model.psd_factor(seg.f)


def expected_delta_bic(base: Model, ext: Extension, segments: Sequence[Segment]) -> float:
    """Return the expected BIC improvement of adding ``ext`` to ``base`` if it is true."""
    true = base.with_(ext)
    kl = 0.0
    for seg in segments:
        y0, s0 = _spectra(base, seg)
        yt, st = _spectra(true, seg)
        r = st / s0
        kl += float(np.sum(np.abs(yt - y0) ** 2 / s0 + r - 1 - np.log(r)))
    p = sum(1 for k in EFFECTS[ext.effect] if k != "channels")
    n = 2 * sum(s.size for s in segments)
    return 2 * kl / TAPER_CORRELATION + p - p * np.log(n)


def fisher_std(base: Model, ext: Extension, segments: Sequence[Segment]) -> dict[str, float]:
    """Cramér-Rao standard deviation of each numeric parameter of ``ext`` (true on ``base``)."""
    names = [k for k in EFFECTS[ext.effect] if k != "channels"]
    x = np.array([ext.value(k) for k in names])
    h = np.maximum(np.abs(x) * 1e-4, 1e-7)
    grads_y, grads_s = [], []
    for i in range(x.size):
        parts = []
        for sign in (1, -1):
            v = x.copy()
            v[i] += sign * h[i]
            e = make_extension(ext.effect, names, v, base.dof)
            e = Extension(e.effect, {**e.parameters, **_fixed(ext)}, ext.dofs)
            parts.append([_spectra(base.with_(e), s) for s in segments])
        grads_y.append([(a[0] - b[0]) / (2 * h[i]) for a, b in zip(*parts, strict=True)])
        grads_s.append([(a[1] - b[1]) / (2 * h[i]) for a, b in zip(*parts, strict=True)])
    s = [_spectra(base.with_(ext), seg)[1] for seg in segments]
    fim = np.zeros((x.size, x.size))  # divided by TAPER_CORRELATION below
    for i in range(x.size):
        for j in range(x.size):
            fim[i, j] = sum(
                float(np.sum(2 * np.real(np.conj(gi) * gj) / sk + si * sj / sk**2))
                for gi, gj, si, sj, sk in zip(
                    grads_y[i], grads_y[j], grads_s[i], grads_s[j], s, strict=True
                )
            )
    try:
        cov = np.linalg.inv(fim / TAPER_CORRELATION)
    except np.linalg.LinAlgError:
        return {k: float("inf") for k in names}
    return {
        k: float(np.sqrt(c)) if c > 0 else float("inf")
        for k, c in zip(names, np.diag(cov), strict=True)
    }


def _fixed(ext: Extension) -> dict[str, object]:
    return {k: v for k, v in ext.parameters.items() if k == "channels"}


def smallest_detectable(base: Model, segments: Sequence[Segment]) -> dict[str, object]:
    """Per one-parameter effect, the parameter values the data would have flagged.

    For ``delay``, ``gain``, ``lead`` and ``noise``: the value on each side of "no effect"
    whose expected BIC improvement is ``BIC_MARGIN`` (None if not reached within the search
    range); for ``sensor_filter``: the cut-off frequency below which a first-order filter
    would have been named.
    """
    out: dict[str, object] = {}
    dof = base.dof

    def crossing(effect: str, name: str, a: float, b: float) -> float | None:
        def excess(v: float) -> float:
            e = make_extension(effect, [name], [v], dof)
            return expected_delta_bic(base, e, segments) - BIC_MARGIN

        if excess(b) < 0:
            return None
        return float(optimize.brentq(excess, a, b, xtol=1e-6 * max(abs(a), abs(b), 1e-3)))

    def near(effect: str, name: str, v0: float, far: float) -> float | None:
        """Threshold between v0 (no effect) and far (a large effect)."""
        lo, hi = (v0 + 1e-9 * (far - v0), far)
        return crossing(effect, name, lo, hi) if far != v0 else None

    out["delay_s"] = [near("delay", "extra_delay_s", 0.0, -0.9 * base.case.config.delay_s or -1e-3),
                      near("delay", "extra_delay_s", 0.0, 0.3)]  # fmt: skip
    out["gain"] = [near("gain", "gain", 1.0, 0.2), near("gain", "gain", 1.0, 5.0)]
    out["lead_time_constant_s"] = near("lead", "time_constant_s", 0.0, 0.3)
    out["noise_scale"] = [near("noise", "scale", 1.0, 0.2), near("noise", "scale", 1.0, 5.0)]
    out["sensor_filter_cutoff_hz"] = crossing_filter(base, segments, "sensor_filter", "cutoff_hz")
    return out


def crossing_filter(
    base: Model, segments: Sequence[Segment], effect: str, name: str
) -> float | None:
    """Highest cut-off/break frequency [Hz] at which a filter would still be flagged."""
    dof = base.dof

    def excess(logf: float) -> float:
        e = make_extension(effect, [name], [float(np.exp(logf))], dof)
        return expected_delta_bic(base, e, segments) - BIC_MARGIN

    a, b = np.log(0.1), np.log(200.0)
    if excess(a) < 0:
        return None
    if excess(b) > 0:
        return float(np.exp(b))
    return float(np.exp(optimize.brentq(excess, a, b, xtol=1e-4)))
