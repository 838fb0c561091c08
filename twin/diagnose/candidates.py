"""Candidate model extensions: predict a channel with an extension, and fit its parameters.

A *model* of a DOF is the nominal configuration plus a list of extensions
(:class:`twin.chain.extensions.Extension`). Its prediction of a channel is

* the nominal twin's noise-free prediction, re-simulated with the ``backlash`` extension
  when there is one (the only non-linear one: it runs through the twin);
* times the frequency responses of the linear extensions (applied to the whole run in the
  frequency domain: they act on one DOF's command path, or inside the IMU, and commute with
  the reduced platform and the post-processing);
* with a noise spectrum: the nominal one times ``scale^2`` (``noise``) and times
  |H_sensor|^2 (a ``sensor_filter`` filters the sensor's noise with the signal).

Parameters are fitted by maximising the Whittle likelihood of the measured spectrum over the
analysis band (:meth:`twin.diagnose.residuals.Segment.loglik`): a grid over each parameter's
physical range, then a local refinement. Standard deviations come from the curvature of the
log-likelihood (the Cramér-Rao bound).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy import optimize

from twin.chain.extensions import DOF_CHANNEL, EFFECTS, LINEAR, Extension
from twin.diagnose.data import Case, Channel, simulate_measurement
from twin.diagnose.residuals import TAPER_CORRELATION, Segment, line_bins
from twin.errors import SignalError
from twin.frames import dof_index

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


@dataclass
class Model:
    """Nominal configuration + extensions of one DOF, with cached predictions.

    Parameters
    ----------
    case : Case
        What is diagnosed.
    dof : str
        The DOF.
    extensions : list of Extension
        Extensions on top of the nominal configuration.

    """

    case: Case
    dof: str
    extensions: list[Extension] = field(default_factory=list)
    _cache: dict = field(default_factory=dict, repr=False)

    def with_(self, ext: Extension) -> Model:
        """Return this model plus one extension (sharing the simulation cache)."""
        return Model(self.case, self.dof, [*self.extensions, ext], self._cache)

    def base(self, ch: Channel) -> FloatArray:
        """Prediction before the linear extensions (re-simulated if there is backlash)."""
        plays = [e for e in self.extensions if e.effect == "backlash"]
        if not plays:
            return ch.nominal
        key = (ch.run, ch.dof, ch.window, tuple(e.value("play") for e in plays))
        if key not in self._cache:
            cfg = self.case.clean.replace(extensions=(*self.case.clean.extensions, *plays))
            pred = simulate_measurement(
                cfg, ch.commands, ch.t, self.case.model, self.case.seed, self.case.imu.ideal()
            )
            self._cache[key] = pred[:, ch.index]
        return self._cache[key]

    def response(self, f: FloatArray) -> ComplexArray:
        """Product of the linear extensions' responses at ``f`` [Hz]."""
        h = np.ones(np.size(f), dtype=complex)
        nominal_break = self.case.config.breaks_hz[dof_index(self.dof)]
        for e in self.extensions:
            if e.effect in LINEAR:
                h = h * e.response(f, nominal_break)
        return h

    def psd_factor(self, f: FloatArray) -> FloatArray:
        """Factor on the nominal noise spectrum at ``f`` [Hz]."""
        g = np.ones(np.size(f))
        for e in self.extensions:
            if e.effect == "noise":
                g = g * e.value("scale") ** 2
            elif e.effect == "sensor_filter":
                g = g * np.abs(e.response(f)) ** 2
        return g

    def predict(self, ch: Channel) -> FloatArray:
        """Full-length prediction of a channel."""
        return apply_response(self.base(ch), ch.rate_hz, self.response)

    def loglik(self, segments: Sequence[Segment]) -> float:
        """Whittle log-likelihood summed over segments."""
        total = 0.0
        preds: dict[int, FloatArray] = {}
        for seg in segments:
            key = id(seg.channel)
            if key not in preds:
                preds[key] = self.predict(seg.channel)
            total += seg.loglik(preds[key], self.psd_factor(seg.f))
        return total


def apply_response(
    x: FloatArray, rate_hz: float, response: Callable[[FloatArray], ComplexArray]
) -> FloatArray:
    """Filter a whole signal by a frequency response (zero-padded FFT, no wrap-around)."""
    n = x.size
    nfft = 1 << int(np.ceil(np.log2(2 * n)))
    f = np.fft.rfftfreq(nfft, 1.0 / rate_hz)
    return np.fft.irfft(np.fft.rfft(x, nfft) * response(f), nfft)[:n]


@dataclass(frozen=True)
class Space:
    """Where one effect's numeric parameters are searched.

    Attributes
    ----------
    names : tuple of str
        Parameter names (the fixed vocabulary).
    grids : tuple of ndarray
        Coarse grid per parameter.
    bounds : tuple of (float, float)
        Bounds of the refinement.

    """

    names: tuple[str, ...]
    grids: tuple[FloatArray, ...]
    bounds: tuple[tuple[float, float], ...]


def search_space(effect: str, case: Case, dof: str, channels: Sequence[Channel]) -> Space:
    """Return the physical range searched for each effect (stated in the report)."""
    k = dof_index(dof)
    if effect == "delay":
        lo = -float(case.config.delay_s)
        return Space(("extra_delay_s",), (np.arange(lo, 0.3001, 0.002),), ((lo, 0.3),))
    if effect == "gain":
        return Space(("gain",), (np.geomspace(0.2, 5.0, 81),), ((0.1, 10.0),))
    if effect == "platform_filter":
        return Space(("break_hz",), (np.geomspace(0.2, 30.0, 61),), ((0.1, 50.0),))
    if effect == "resonance":
        return Space(
            ("frequency_hz", "damping"),
            (np.geomspace(0.5, 20.0, 41), np.geomspace(0.05, 1.5, 13)),
            ((0.3, 30.0), (0.02, 3.0)),
        )
    if effect == "lead":
        return Space(("time_constant_s",), (np.arange(0.0, 0.2001, 0.002),), ((0.0, 0.3),))
    if effect == "sensor_filter":
        return Space(("cutoff_hz",), (np.geomspace(0.5, 40.0, 51),), ((0.2, 50.0),))
    if effect == "backlash":
        travel = max(float(np.ptp(ch.commands.values[:, k])) for ch in channels)
        return Space(
            ("play",), (np.geomspace(1e-3, 0.3, 7) * travel,), ((1e-4 * travel, 0.5 * travel),)
        )
    if effect == "noise":
        return Space(("scale",), (np.array([1.0]),), ((0.0, 100.0),))
    raise SignalError(f"unknown effect {effect!r}; expected one of {', '.join(EFFECTS)}")


def make_extension(
    effect: str, names: Sequence[str], values: Sequence[float], dof: str
) -> Extension:
    """Build an extension of ``dof`` from fitted values."""
    pars: dict[str, object] = {n: float(v) for n, v in zip(names, values, strict=True)}
    if effect == "sensor_filter":
        pars["channels"] = (DOF_CHANNEL[dof],)
    return Extension(effect, pars, (dof,))


@dataclass(frozen=True)
class Fit:
    """One candidate fitted on top of a model.

    Attributes
    ----------
    extension : Extension
        The effect with its fitted parameters.
    loglik : float
        Log-likelihood with it.
    std : dict of str to float
        Cramér-Rao standard deviation per parameter (nan where the curvature is not
        positive).

    """

    extension: Extension
    loglik: float
    std: dict[str, float]


def fit_candidate(
    effect: str, model: Model, segments: Sequence[Segment], start: Sequence[float] | None = None
) -> Fit:
    """Fit one effect's parameters on top of ``model`` over ``segments``.

    ``start`` (e.g. the values fitted on other data) replaces the coarse grid by a local
    search around it.
    """
    channels = list({id(s.channel): s.channel for s in segments}.values())
    space = search_space(effect, model.case, model.dof, channels)
    if effect == "noise":
        return _fit_noise(model, segments)

    def cost(x: Sequence[float]) -> float:
        x = np.clip(x, [b[0] for b in space.bounds], [b[1] for b in space.bounds])
        return -model.with_(make_extension(effect, space.names, x, model.dof)).loglik(segments)

    if start is not None:
        x0 = np.asarray(start, dtype=float)
    elif effect == "backlash":
        x0 = _backlash_start(model, segments, space)
    else:
        grid = np.array(np.meshgrid(*space.grids, indexing="ij")).reshape(len(space.names), -1).T
        costs = np.array([cost(x) for x in grid])
        x0 = grid[int(np.argmin(costs))]
    x = _refine(cost, x0, space, effect, 2.0 if start is None else 1.25)
    ext = make_extension(effect, space.names, x, model.dof)
    std = _crlb(cost, x, space)
    return Fit(ext, -cost(x), dict(zip(space.names, std, strict=True)))


def _backlash_start(model: Model, segments: Sequence[Segment], space: Space) -> FloatArray:
    """Return a start for the play: distortion power matched, or the grid's best.

    The likelihood is often too narrow in the play for a coarse grid (the kinks must line up
    in time), but the power a play adds off the excited lines grows smoothly with it: the
    play that matches the measured excess power there (over the nominal noise, log-log
    interpolation of the grid) is a start near the peak. Where that power is not monotonic
    (large plays) the grid's best point is the better start: both are returned, and the
    refinement scans near each.
    """
    grid = space.grids[0]
    excess, predicted = 0.0, np.zeros(grid.size)
    for seg in segments:
        ch = seg.channel
        off = np.ones(seg.size, dtype=bool)
        k = line_bins(seg, ch.lines_hz)
        for j in (-1, 0, 1):
            off[np.clip(k[k >= 0] + j, 0, seg.size - 1)] = False
        base = seg.spectrum(model.predict(ch))
        noise = seg.noise_psd * model.psd_factor(seg.f)
        excess += float(np.sum(np.abs(seg.measured - base)[off] ** 2 - noise[off]))
        for i, p in enumerate(grid):
            pred = model.with_(make_extension("backlash", ["play"], [p], model.dof)).predict(ch)
            predicted[i] += float(np.sum(np.abs(seg.spectrum(pred) - base)[off] ** 2))
    logp = np.log(np.maximum.accumulate(np.maximum(predicted, 1e-300)))
    matched = float(np.exp(np.interp(np.log(max(excess, 1e-300)), logp, np.log(grid))))
    # where the distortion power is not monotonic in the play (large plays), the grid's best
    # point is the better start: return both
    ll = [model.with_(make_extension("backlash", ["play"], [v], model.dof)).loglik(segments)
          for v in grid]  # fmt: skip
    return np.array([matched, grid[int(np.argmax(ll))]])


def _refine(
    cost: Callable, x0: FloatArray, space: Space, effect: str, span: float = 2.0
) -> FloatArray:
    """Refine a start value: bounded 1-D search, Nelder-Mead in log space for two parameters.

    ``span`` is the factor around the start scanned for ``backlash``.
    """
    if len(space.names) == 1:
        g = space.grids[0]
        i = int(np.argmin(np.abs(g - x0[0])))
        lo = g[max(i - 1, 0)] if g.size > 1 else space.bounds[0][0]
        hi = g[min(i + 1, g.size - 1)] if g.size > 1 else space.bounds[0][1]
        if effect == "backlash":  # the likelihood is narrow in the play: scan near x0 in
            # steps of 10 %, then refine within one step
            steps = 2 * round(np.log(span) / np.log(1.1)) + 1
            local = np.concatenate([np.geomspace(v / span, v * span, steps) for v in x0])
            best = local[int(np.argmin([cost([v]) for v in local]))]
            r = optimize.minimize_scalar(
                lambda u: cost([np.exp(u)]), bounds=(np.log(best / 1.1), np.log(best * 1.1)),
                method="bounded", options={"xatol": 0.005},
            )  # fmt: skip
            return np.array([np.exp(r.x)])
        lo, hi = max(min(lo, x0[0]), space.bounds[0][0]), min(max(hi, x0[0]), space.bounds[0][1])
        r = optimize.minimize_scalar(lambda u: cost([u]), bounds=(lo, hi), method="bounded",
                                     options={"xatol": 1e-6 * max(1.0, abs(hi))})  # fmt: skip
        return np.array([r.x])
    r = optimize.minimize(
        lambda u: cost(np.exp(u)), np.log(x0), method="Nelder-Mead",
        options={"xatol": 1e-4, "fatol": 1e-3, "maxiter": 400},
    )  # fmt: skip
    return np.clip(np.exp(r.x), [b[0] for b in space.bounds], [b[1] for b in space.bounds])


def _crlb(cost: Callable, x: FloatArray, space: Space) -> list[float]:
    """Return standard deviations from a finite-difference Hessian of -log L."""
    n = x.size
    h = np.maximum(np.abs(x) * 1e-3, 1e-6)
    hess = np.empty((n, n))
    f0 = cost(x)
    for i in range(n):
        for j in range(i, n):
            ei, ej = np.eye(n)[i] * h[i], np.eye(n)[j] * h[j]
            if i == j:
                v = (cost(x + ei) - 2 * f0 + cost(x - ei)) / h[i] ** 2
            else:
                v = (
                    cost(x + ei + ej) - cost(x + ei - ej) - cost(x - ei + ej) + cost(x - ei - ej)
                ) / (4 * h[i] * h[j])
            hess[i, j] = hess[j, i] = v
    try:
        cov = np.linalg.inv(hess)
        d = np.diag(cov)
        return [float(np.sqrt(v)) if v > 0 else float("nan") for v in d]
    except np.linalg.LinAlgError:
        return [float("nan")] * n


def _fit_noise(model: Model, segments: Sequence[Segment]) -> Fit:
    """Noise scale in closed form: scale^2 = mean(|Y_m - Y_p|^2 / S) over all bins."""
    ratios, bins = 0.0, 0
    for seg in segments:
        r = seg.measured - seg.spectrum(model.predict(seg.channel))
        ratios += float(np.sum(np.abs(r) ** 2 / (seg.noise_psd * model.psd_factor(seg.f))))
        bins += seg.size
    c2 = ratios / bins
    ext = make_extension("noise", ("scale",), [np.sqrt(c2)], model.dof)
    # var(c^2) = c^4 / bins (exponential periodogram): sd(c) = c / (2 sqrt(bins))
    std = {"scale": float(np.sqrt(c2) / (2 * np.sqrt(bins / TAPER_CORRELATION)))}
    return Fit(ext, model.with_(ext).loglik(segments), std)
