"""The noise of a measurement, judged on its own: motion noise (a cause) and IMU noise (a nuisance).

Off the excited lines (and the two bins the Hann taper spreads each over) the residual
measured - model is noise. Its spectrum is modelled as

    ``S(f) = (a S_motion(f) + b S_imu(f)) |H_sensor(f)|^2``,

the nominal spectra of the configuration's motion noise (Eq 5.10) and of the IMU's own noise
(:mod:`twin.diagnose.data` keeps them apart; smoothed over a third of an octave,
:attr:`~twin.diagnose.residuals.Segment.shape_psd`, because the two are told apart by their
shapes only), with power factors ``a`` and ``b`` fitted by the
Whittle likelihood. ``b`` is the IMU's noise power relative to the data sheet (a better or
worse IMU than the ADIS16355's nominal figures): a property of the sensor, reported, never a
cause. ``a`` is the motion noise; where the configuration has motion noise in the DOF it is
named as the ``noise`` effect (``scale`` = sqrt(a), an amplitude factor) when a free ``a``
improves the BIC by more than the margin over a = 1 (``b`` free in both) and its held-out
likelihood improves too: ``a`` fitted on one half of the window (of every run at once),
carried to the other halves, against a = 1 there, with ``b`` refitted on those halves in both
(a nuisance is fitted wherever it is used; only the claim is held out).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import optimize

from twin.diagnose.candidates import Model
from twin.diagnose.residuals import TAPER_CORRELATION, Segment, line_bins, segment

FloatArray = NDArray[np.float64]


def off_line(seg: Segment) -> NDArray[np.bool_]:
    """Bins of a segment away from the excited lines (each line and its two neighbours)."""
    keep = np.ones(seg.size, dtype=bool)
    k = line_bins(seg, seg.channel.lines_hz)
    for j in (-1, 0, 1):
        keep[np.clip(k[k >= 0] + j, 0, seg.size - 1)] = False
    return keep


@dataclass(frozen=True)
class NoiseFit:
    """Power factors of the noise sources fitted to a measurement's residual.

    Attributes
    ----------
    motion : float or None
        Power factor ``a`` on the motion noise (None: the configuration has none here).
    imu : float
        Power factor ``b`` on the IMU's noise (1: the data sheet).
    std : dict of str to float
        Standard deviations of the power factors.
    loglik : float
        Whittle log-likelihood of the residual (off-line bins).
    bins : int
        Off-line bins used.

    """

    motion: float | None
    imu: float
    std: dict[str, float]
    loglik: float
    bins: int

    @property
    def scales(self) -> tuple[float, float]:
        """Power factors (motion, IMU) for :meth:`Segment.scaled`."""
        return (1.0 if self.motion is None else self.motion, self.imu)

    def to_json(self) -> dict[str, object]:
        """Amplitude factors (square roots of the power factors) with their meaning."""
        return {
            "imu_noise_scale": float(np.sqrt(self.imu)),
            "motion_noise_scale": None if self.motion is None else float(np.sqrt(self.motion)),
            "power_factor_std": self.std,
            "off_line_bins": self.bins,
            "meaning": "measured noise amplitude over the nominal noise model's, per source; the "
            "IMU's is a nuisance (a sensor property), not a cause",
        }


def _terms(model: Model, segments: Sequence[Segment]) -> list[tuple[FloatArray, ...]]:
    """Per segment, at the off-line bins: ``|R|^2`` and the two source spectra."""
    out = []
    for seg in segments:
        keep = off_line(seg)
        r = seg.measured - seg.spectrum(model.predict(seg.channel))
        h2 = model.psd_factor(seg.f)  # a sensor filter filters every noise it measures
        shape = seg.shape_psd
        sm, si = shape[0] * h2, shape[1] * h2
        out.append((np.abs(r[keep]) ** 2, sm[keep], si[keep]))
    return out


def _loglik(terms: list[tuple[FloatArray, ...]], a: float, b: float) -> float:
    total = 0.0
    for r2, sm, si in terms:
        s = np.maximum(a * sm + b * si, 1e-30)
        total -= float(np.sum(r2 / s + np.log(s)))
    return total / TAPER_CORRELATION


def fit_noise(
    model: Model,
    segments: Sequence[Segment],
    motion_fixed: float | None = None,
    imu_fixed: float | None = None,
) -> NoiseFit:
    """Fit the power factors (``motion_fixed`` / ``imu_fixed``: hold that factor)."""
    terms = _terms(model, segments)
    has_motion = any(t[1].any() for t in terms)
    bins = sum(t[0].size for t in terms)
    if imu_fixed is not None:
        b = float(imu_fixed)
        if not has_motion or motion_fixed is not None:
            a = 1.0 if motion_fixed is None else motion_fixed
            return NoiseFit(a if has_motion else None, b, {}, _loglik(terms, a, b), bins)
        r = optimize.minimize_scalar(lambda u: -_loglik(terms, float(np.exp(u)), b),
                                     bounds=(np.log(1e-4), np.log(1e4)), method="bounded",
                                     options={"xatol": 1e-5})  # fmt: skip
        a = float(np.exp(r.x))
        return NoiseFit(a, b, {"motion": _std(terms, a, b)["motion_alone"]}, -float(r.fun), bins)
    if not has_motion or motion_fixed is not None:
        a = 1.0 if motion_fixed is None else motion_fixed

        def cost1(u: float) -> float:
            return -_loglik(terms, a, float(np.exp(u)))

        r = optimize.minimize_scalar(cost1, bounds=(np.log(1e-4), np.log(1e4)), method="bounded",
                                     options={"xatol": 1e-5})  # fmt: skip
        b = float(np.exp(r.x))
        sd = b / np.sqrt(bins / TAPER_CORRELATION)
        return NoiseFit(None if not has_motion else a, b, {"imu": float(sd)}, -r.fun, bins)

    def cost(u: FloatArray) -> float:
        return -_loglik(terms, float(np.exp(u[0])), float(np.exp(u[1])))

    best = min(
        (
            optimize.minimize(
                cost,
                np.log(x0),
                method="Nelder-Mead",
                options={"xatol": 1e-5, "fatol": 1e-6, "maxiter": 600},
            )
            for x0 in ((1.0, 1.0), (0.3, 3.0), (3.0, 0.3))
        ),
        key=lambda r: r.fun,
    )
    a, b = (float(v) for v in np.exp(best.x))
    std = _std(terms, a, b)
    return NoiseFit(a, b, std, -float(best.fun), bins)


def _std(terms: list[tuple[FloatArray, ...]], a: float, b: float) -> dict[str, float]:
    """Cramér-Rao standard deviations of the two power factors (Whittle Fisher information)."""
    fim = np.zeros((2, 2))
    for _, sm, si in terms:
        s = np.maximum(a * sm + b * si, 1e-30)
        g = np.stack([sm / s, si / s])
        fim += g @ g.T
    fim /= TAPER_CORRELATION
    alone = float(1 / np.sqrt(fim[0, 0])) if fim[0, 0] > 0 else float("nan")
    try:
        cov = np.linalg.inv(fim)
        return {"motion": float(np.sqrt(cov[0, 0])), "imu": float(np.sqrt(cov[1, 1])),
                "motion_alone": alone}  # fmt: skip
    except np.linalg.LinAlgError:
        return {"motion": float("nan"), "imu": float("nan"), "motion_alone": alone}


@dataclass(frozen=True)
class NoiseJudgement:
    """The noise of one DOF: the fit, and whether motion noise differs from the nominal.

    Attributes
    ----------
    fit : NoiseFit
        Both factors free (motion fixed at 1 where the configuration has none).
    delta_bic : float or None
        BIC improvement of a free motion factor over the nominal one (None: no motion noise).
    held_out : dict
        Held-out log-likelihood per bin with the nominal and the fitted motion factor.
    named : bool
        Whether the motion noise is named as the ``noise`` effect.

    """

    fit: NoiseFit
    delta_bic: float | None
    held_out: dict[str, float]
    named: bool


def judge_noise(
    model: Model, margin: float, max_hz: float, imu_noise: float | None = None
) -> NoiseJudgement:
    """Fit the noise of ``model``'s DOF and decide whether the motion noise is a cause.

    ``imu_noise``: the IMU's noise over the data sheet's (amplitude) when it is known, e.g.
    from a recording at rest; None fits it (a nuisance), which leaves the motion noise only as
    separable as the two spectra's shapes allow.
    """
    channels = model.case.of(model.dof)
    segs = [segment(c, max_hz=max_hz) for c in channels]
    known = None if imu_noise is None else float(imu_noise) ** 2
    free = fit_noise(model, segs, imu_fixed=known)
    if free.motion is None:
        return NoiseJudgement(free, None, {}, False)
    nominal = fit_noise(model, segs, motion_fixed=1.0, imu_fixed=known)
    dbic = 2 * (free.loglik - nominal.loglik) - np.log(free.bins / TAPER_CORRELATION)
    rows = []
    for i in (0, 1):
        # two-fold over the window as the chain's held-out gate (select.folds): the claim (the
        # motion factor, a property of the DOF) is fitted on half i of every run at once and
        # carried to the other halves; the nuisance (the IMU's factor, unless known) is
        # refitted there for both, as it is everywhere. One run's half alone holds too few
        # bins below 1 Hz, where the shapes differ, to fit the claim (0 to 50 for a true 28)
        a = [segment(c, c.halves()[i], max_hz) for c in channels]
        b = [segment(c, c.halves()[1 - i], max_hz) for c in channels]
        claimed = fit_noise(model, a, imu_fixed=known).scales[0]
        f0 = fit_noise(model, b, motion_fixed=1.0, imu_fixed=known)
        f1 = fit_noise(model, b, motion_fixed=claimed, imu_fixed=known)
        rows.append((f0.loglik / f0.bins, f1.loglik / f1.bins))
    before, after = (float(np.mean(v)) for v in zip(*rows, strict=True))
    held = {"loglik_per_bin_before": before, "loglik_per_bin_after": after}
    return NoiseJudgement(free, float(dbic), held, bool(dbic > margin and after > before))
