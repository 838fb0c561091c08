"""What a run could have revealed: expected evidence, Cramér-Rao bounds, smallest effects.

For a true set of effects (line prediction Y_t) on top of a model (Y_0) the expected chi2
gain is ``sum |Y_t - Y_0|^2 / sd^2`` over the lines (the Kullback-Leibler divergence of the two
complex Gaussians), so the expected BIC improvement of naming them is

    ``2 sum |Y_t - Y_0|^2 / sd^2 + p - p ln(n)``

(+p: the fitted parameters' own expected gain). An effect is *detectable* when that exceeds
``BIC_MARGIN``; :func:`smallest_detectable` states, per effect, the size at which it does (e.g.
"a delay above 27 ms would have been found"), so that "no finding" has a meaning. The Fisher
information of the same likelihood gives the smallest standard deviation any unbiased fit of
the parameters can reach (:func:`fisher_std`).

For the ``noise`` effect the same holds on the off-line bins with the Whittle likelihood:
per bin S_t / S_0 - 1 - ln(S_t / S_0).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy import optimize

from twin.chain.extensions import DOF_CHANNEL, Extension
from twin.core.frames import dof_index
from twin.diagnose.candidates import Model, make_extension, numeric_names, search_space
from twin.diagnose.evidence import Lines
from twin.diagnose.nuisance import off_line
from twin.diagnose.residuals import TAPER_CORRELATION, Segment
from twin.diagnose.select import BIC_MARGIN


def _on_top(model: Model, exts: Sequence[Extension]) -> Model:
    for e in exts:
        model = model.with_(e)
    return model


def expected_delta_bic(base: Model, exts: Sequence[Extension], evidence: Sequence[Lines]) -> float:
    """Return the expected BIC improvement of adding ``exts`` to ``base`` if they are true."""
    true = _on_top(base, exts)
    gain = sum(
        float(np.sum(np.abs(true.line_prediction(x) - base.line_prediction(x)) ** 2 / x.sd**2))
        for x in evidence
    )
    p = sum(len(numeric_names(e.effect)) for e in exts)
    n = 2 * sum(x.size for x in evidence)
    return 2 * gain + p - p * np.log(n)


def expected_noise_delta_bic(
    scale: float, segments: Sequence[Segment], imu_known: bool = False
) -> float:
    """Return the expected BIC improvement of naming motion noise ``scale`` x the nominal.

    The IMU's noise level is a nuisance fitted in both models, so the evidence is what the
    motion noise adds that a rescaled IMU noise cannot mimic: the Kullback-Leibler divergence
    of the true spectrum from the best nominal-motion-noise spectrum with the IMU factor free
    (``imu_known``: held at its value).
    """
    parts = []
    for seg in segments:
        keep = off_line(seg)
        shape = seg.shape_psd
        sm, si = seg.scales[0] * shape[0][keep], seg.scales[1] * shape[1][keep]
        parts.append((scale**2 * sm + si, sm, si))
    bins = sum(p[0].size for p in parts)

    def kl(log_b: float) -> float:
        total = 0.0
        for st, sm, si in parts:
            r = st / np.maximum(sm + np.exp(log_b) * si, 1e-300)
            total += float(np.sum(r - 1 - np.log(r)))
        return total

    if imu_known:
        return 2 * kl(0.0) / TAPER_CORRELATION + 1 - np.log(bins / TAPER_CORRELATION)
    best = optimize.minimize_scalar(kl, bounds=(np.log(1e-3), np.log(1e3)), method="bounded")
    return 2 * float(best.fun) / TAPER_CORRELATION + 1 - np.log(bins / TAPER_CORRELATION)


def fisher_std(
    base: Model, exts: Sequence[Extension], evidence: Sequence[Lines]
) -> dict[str, float]:
    """Return the Cramér-Rao standard deviation of every numeric parameter of ``exts``.

    The parameters are fitted jointly, ``exts`` true on ``base``; keys ``effect.parameter``.
    """
    names = [(i, k) for i, e in enumerate(exts) for k in numeric_names(e.effect)]
    x = np.array([exts[i].value(k) for i, k in names])
    h = np.maximum(np.abs(x) * 1e-3, 1e-6)
    cols = []
    for j, (i, k) in enumerate(names):
        parts = []
        for sign in (1, -1):
            e = exts[i]
            v = [e.value(n) + (sign * h[j] if n == k else 0.0) for n in numeric_names(e.effect)]
            moved = make_extension(e.effect, numeric_names(e.effect), v, base.dof)
            moved = Extension(moved.effect, {**e.parameters, **moved.parameters}, e.dofs)
            m = _on_top(base, [*exts[:i], moved, *exts[i + 1 :]])
            parts.append(np.concatenate([m.line_prediction(x) / x.sd for x in evidence]))
        cols.append((parts[0] - parts[1]) / (2 * h[j]))
    jac = np.array(cols).T
    fim = 2 * np.real(jac.conj().T @ jac)
    try:
        cov = np.linalg.inv(fim)
    except np.linalg.LinAlgError:
        return {f"{exts[i].effect}.{k}": float("inf") for i, k in names}
    d = np.diag(cov)
    return {
        f"{exts[i].effect}.{k}": float(np.sqrt(v)) if v > 0 else float("inf")
        for (i, k), v in zip(names, d, strict=True)
    }


#: Relative precision of a smallest detectable size, of its distance from no effect (so a
#: delay of a few microseconds on quiet data is found as well as one of 30 ms).
SIZE_RTOL = 1e-3


def _threshold(excess, origin: float, to: float) -> float | None:
    """Where ``excess`` crosses zero from ``origin`` (no effect) towards ``to``; None if never.

    ``excess`` is negative at ``origin``; the crossing is found to :data:`SIZE_RTOL` of its
    distance from ``origin``, however close to it.
    """
    if excess(to) < 0:
        return None
    step = to - origin
    d = optimize.brentq(lambda d: excess(origin + d), 1e-9 * np.sign(step), step, xtol=1e-12,
                        rtol=SIZE_RTOL)  # fmt: skip
    return origin + float(d)


def _decimals(distance: float, least: int) -> int:
    """Return the decimals that show two significant digits of ``distance`` (>= ``least``)."""
    if distance == 0 or not np.isfinite(distance):
        return least
    return max(least, 1 - int(np.floor(np.log10(abs(distance)))))


def _delay_text(seconds: float) -> str:
    """Return a delay (signed) in ms, or in µs below 1 ms: two significant digits at least."""
    value, unit = (seconds * 1e3, "ms") if abs(seconds) >= 1e-3 else (seconds * 1e6, "µs")
    return f"{value:+.{_decimals(value, 0)}f} {unit}"


def _lead_text(seconds: float) -> str:
    """Return a lead time constant as :func:`_delay_text` does, without the sign."""
    return _delay_text(seconds).lstrip("+")


def _gain_text(gain: float) -> str:
    """Return a gain: three decimals, or as many as show two significant digits of gain - 1."""
    return f"{gain:.{_decimals(gain - 1, 3)}f}"


def _scale_text(scale: float) -> str:
    """Return a noise scale: two decimals, or as many as show two significant digits of it - 1."""
    return f"{scale:.{_decimals(scale - 1, 2)}f}"


def smallest_detectable(
    base: Model,
    evidence: Sequence[Lines],
    segments: Sequence[Segment] = (),
    imu_known: bool = False,
) -> dict[str, object]:
    """Per effect, the smallest size the runs would have shown (expected dBIC = the margin).

    Returns a dict of entries ``{"parameter", "values" or "value", "statement"}``: delay and
    gain on both sides of "no effect"; lead upwards; platform filter, sensor filter and
    resonance (damping 0.3) by the highest break/cut-off/mode frequency that would still show;
    platform lag upwards; backlash by the smallest play (on its search grid, interpolated:
    :func:`_smallest_play`); motion noise on both sides where the configuration has it.
    """
    dof = base.dof

    def excess_of(effect: str, name: str, extra: dict | None = None):
        def excess(v: float) -> float:
            e = Extension(effect, {name: float(v), **(extra or {})}, (dof,))
            return expected_delta_bic(base, [e], evidence) - BIC_MARGIN

        return excess

    out: dict[str, object] = {}
    d = excess_of("delay", "extra_delay_s")
    lo_d = -0.999 * float(base.case.config.delay_s)
    less = _threshold(d, 0.0, lo_d) if lo_d < -1e-6 else None
    more = _threshold(d, 0.0, 0.3)
    out["delay"] = {
        "parameter": "extra_delay_s",
        "values": [less, more],
        "statement": _both("delay", less, more, _delay_text),
    }
    g = excess_of("gain", "gain")
    lo_g, hi_g = _threshold(g, 1.0, 0.1), _threshold(g, 1.0, 10.0)
    out["gain"] = {
        "parameter": "gain",
        "values": [lo_g, hi_g],
        "statement": _both("gain", lo_g, hi_g, _gain_text),
    }
    for effect, name, what in (("lead", "time_constant_s", "lead"),
                               ("platform_lag", "lag_s", "platform lag")):  # fmt: skip
        size = _threshold(excess_of(effect, name), 0.0, 0.3)
        out[effect] = {
            "parameter": name,
            "value": size,
            "statement": f"no {what} up to 300 ms would have been found"
            if size is None
            else f"a {what} above {_lead_text(size)} would have been found",
        }
    for effect, name, extra, what in (
        ("platform_filter", "break_hz", None, "a platform filter (2nd order) breaking"),
        ("sensor_filter", "cutoff_hz", {"channels": (DOF_CHANNEL[dof],)},
         "a sensor filter cutting off"),
        ("resonance", "frequency_hz", {"damping": 0.3}, "a resonance (damping 0.3)"),
    ):  # fmt: skip
        ex = excess_of(effect, name, extra)
        nominal = base.nominal_break if effect == "platform_filter" else None
        f = _highest_frequency(ex, 200.0 if nominal is None else nominal * 0.999)
        out[effect] = {
            "parameter": name,
            "value": f,
            "statement": f"{what} below {f:.3g} Hz would have been found"
            if f is not None
            else f"no {effect.replace('_', ' ')} above 0.1 Hz would have been found",
        }
    out["backlash"] = _smallest_play(base, evidence)
    if segments and any(s.source_psd[0].any() for s in segments):

        def nx(scale: float) -> float:
            return expected_noise_delta_bic(scale, segments, imu_known) - BIC_MARGIN

        lo_n, hi_n = _threshold(nx, 1.0, 0.01), _threshold(nx, 1.0, 30.0)
        out["noise"] = {
            "parameter": "scale",
            "values": [lo_n, hi_n],
            "statement": _both("motion noise scale", lo_n, hi_n, _scale_text),
        }
    return out


def _smallest_play(base: Model, evidence: Sequence[Lines]) -> dict[str, object]:
    """Return the smallest backlash play the runs would have shown (its entry).

    Each play is a simulation: the expected evidence is taken at the plays of the backlash's
    search grid (simulated side by side, or already by its fit) and the crossing of the
    margin interpolated between them in log(play).
    """
    channels = list({id(x.channel): x.channel for x in evidence}.values())
    grid = search_space("backlash", base.case, base.dof, channels).grids[0]
    base.prefetch([float(p) for p in grid], channels)
    excess = np.array([
        expected_delta_bic(base, [make_extension("backlash", ["play"], [p], base.dof)],
                           evidence) - BIC_MARGIN
        for p in grid
    ])  # fmt: skip
    above = np.flatnonzero(excess >= 0)
    unit = "mm" if dof_index(base.dof) < 3 else "mrad"
    if above.size == 0:
        play, statement = None, (f"no backlash up to {grid[-1] * 1e3:.3g} {unit} of play "
                                 "would have been found")  # fmt: skip
    else:
        i = int(above[0])
        if i == 0:
            play = float(grid[0])
        else:  # linear in log(play) between the last grid play below the margin and the first above
            u0, u1, e0, e1 = np.log(grid[i - 1]), np.log(grid[i]), excess[i - 1], excess[i]
            play = float(np.exp(u0 + (u1 - u0) * (-e0) / (e1 - e0)))
        statement = f"a backlash above {play * 1e3:.3g} {unit} of play would have been found"
    return {"parameter": "play", "value": play, "statement": statement,
            "grid": [float(p) for p in grid]}  # fmt: skip


def _highest_frequency(excess, top: float, bottom: float = 0.1) -> float | None:
    """Highest frequency in [bottom, top] at which ``excess`` (larger below) is still >= 0."""

    def g(u: float) -> float:
        return excess(float(np.exp(u)))

    lo, hi = np.log(bottom), np.log(top)
    if g(lo) <= 0:
        return None
    if g(hi) > 0:
        return top
    return float(np.exp(optimize.brentq(g, lo, hi, xtol=1e-4)))


def _both(what: str, lo: float | None, hi: float | None, fmt) -> str:
    parts = []
    if lo is not None:
        parts.append(f"below {fmt(lo)}")
    if hi is not None:
        parts.append(f"above {fmt(hi)}")
    if not parts:
        return f"no {what} in the searched range would have been found"
    return f"a {what} {' or '.join(parts)} would have been found"
