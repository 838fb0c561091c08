"""Candidate model extensions: predict a channel with extensions, and fit sets of them jointly.

A *model* of a DOF is the nominal configuration plus a list of extensions
(:class:`twin.chain.extensions.Extension`). Its prediction of a channel is the nominal twin's
noise-free prediction (re-simulated with the ``backlash`` extension when there is one: the
only non-linear effect, it runs through the twin) times the frequency responses of the linear
extensions (they act on one DOF's command path, or inside the IMU, and commute with the
reduced platform and the post-processing). At the excited lines that is H(f) P(f).

A *set* of effects is fitted jointly (:func:`fit_set`) by least squares on the standardised
line residuals (:mod:`twin.diagnose.evidence`): positive parameters in log space, every start
of a coarse grid per effect and of the effects fitted one on top of the other, the best kept.
The play of ``backlash`` is an outer one-dimensional search (each value is a simulation).
That fast form applies the linear effects after the backlash; the chain applies gain, filter,
resonance and lead before it, so a fitted set with backlash and one of those is refitted in
the chain's order (:meth:`Model.anchored`: the backlash simulated behind them, the play
searched around the fast fit's play times their mean gain over the lines' motion, then again
behind the values each pass fitted, until a pass gains little). Standard
deviations and correlations come from the Jacobian at the optimum (Fisher information 2 J^T J
of the log-likelihood -chi2); with backlash, whose column costs two simulations per run, when
first asked for (a named set's). Plays known in advance (the grid, the first two of the
search, those of the chain-order parabola and of the Jacobian) are simulated side by side
(:meth:`Model.prefetch`): the same values, in about half the time on two cores.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy import optimize

from twin.chain.extensions import DOF_CHANNEL, EFFECTS, LINEAR, Extension
from twin.core.errors import SignalError
from twin.core.frames import dof_index
from twin.core.threads import concurrently
from twin.diagnose.data import Case, Channel
from twin.diagnose.evidence import Lines
from twin.formats.run_checks import MAX_EXTRA_DELAY_S
from twin.measurement.measure import simulate_measurement

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
#: The effects fitted to the lines: every one that changes the deterministic response but
#: ``platform_lag``, whose line response is a ``sensor_filter``'s on the DOF's own channel: the
#: two are told apart by the noise (a sensor filter filters the sensor's noise too), after the
#: lines have named one of them (:mod:`twin.diagnose.sensor_side`); and ``imu_alignment``,
#: which has no response of one DOF (it leaks each DOF into the other channels: it is fitted
#: across all six, not line by line in one).
DYNAMIC = tuple(e for e in EFFECTS if e not in ("noise", "platform_lag", "imu_alignment"))
#: Parameters searched in log space (positive, scale-like).
_LOG = {"gain", "break_hz", "frequency_hz", "damping", "cutoff_hz", "play"}


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
    anchor: tuple[Extension, ...] = ()
    _cache: dict = field(default_factory=dict, repr=False)

    def with_(self, ext: Extension) -> Model:
        """Return this model plus one extension (sharing the simulation cache)."""
        return Model(self.case, self.dof, [*self.extensions, ext], self.anchor, self._cache)

    def anchored(self, anchor: Sequence[Extension]) -> Model:
        """Return this model with ``anchor`` simulated in the chain's order with the backlash.

        The chain applies the command-side linear effects (delay, gain, filter, resonance,
        lead) *before* the backlash; the fast form applies them after it, which is exact for
        a delay only (a gain g before a play p acts as a play p / g after it). An anchored
        model simulates the backlash behind ``anchor`` and applies the linear extensions as
        their responses relative to the anchor's, so near the anchor it is the chain's order.
        """
        return Model(self.case, self.dof, list(self.extensions), tuple(anchor), self._cache)

    def base(self, ch: Channel) -> FloatArray:
        """Prediction before the linear extensions (re-simulated if there is backlash)."""
        key = self._base_key(ch)
        if key is None:
            return ch.nominal
        if key not in self._cache:
            self._cache[key] = self._simulate_base(ch)
        return self._cache[key]

    def _base_key(self, ch: Channel) -> tuple | None:
        """Cache key of :meth:`base` of a channel (None: no backlash, the nominal's)."""
        plays = tuple(e.value("play") for e in self.extensions if e.effect == "backlash")
        if not plays:
            return None
        return (ch.run, ch.dof, ch.window, ch.filter_scale, plays,
                tuple((e.effect, repr(e.parameters), e.dofs) for e in self.anchor))  # fmt: skip

    def _simulate_base(self, ch: Channel) -> FloatArray:
        """Simulate the channel with the backlash (behind the anchor): :meth:`base`'s value."""
        plays = [e for e in self.extensions if e.effect == "backlash"]
        exts = (*self.case.clean.extensions, *self.anchor, *plays)
        cfg = self.case.config_of(ch, self.case.clean.replace(extensions=exts))
        pred = simulate_measurement(
            cfg, ch.commands, ch.t, self.case.model, self.case.seed, self.case.imu.ideal()
        )
        return pred[:, ch.index]

    def prefetch(self, plays: Sequence[float], channels: Sequence[Channel]) -> None:
        """Simulate this model with each of several plays side by side, into the cache.

        Fills what :meth:`base` of ``self.with_(backlash play)`` gives for each play and
        channel (the same values: each is a simulation of its own, run by
        :func:`twin.core.threads.concurrently`). A simulation that fails is left out: the
        :meth:`base` that needs it runs it again and raises where it did before.
        """
        jobs: dict[tuple, Callable[[], FloatArray]] = {}
        for play in plays:
            m = self.with_(make_extension("backlash", ["play"], [play], self.dof))
            for ch in channels:
                key = m._base_key(ch)
                if key is not None and key not in self._cache and key not in jobs:
                    jobs[key] = functools.partial(m._simulate_base, ch)
        if len(jobs) < 2:
            return
        outcomes = concurrently(list(jobs.values()), return_exceptions=True)
        for key, value in zip(jobs, outcomes, strict=True):
            if not isinstance(value, BaseException):
                self._cache[key] = value

    @property
    def nominal_break(self) -> float | None:
        """The nominal configuration's filter break in this DOF [Hz] (None: no filter)."""
        return self.case.config.breaks_hz[dof_index(self.dof)]

    def response(self, f: FloatArray, filter_scale: float = 1.0) -> ComplexArray:
        """Product of the linear extensions' responses at ``f`` [Hz] (those not simulated).

        ``filter_scale``: the run's filter setting over the nominal's (:class:`Channel`).
        """
        h = self.linear_response(f, filter_scale)
        if self.anchor and any(e.effect == "backlash" for e in self.extensions):
            for e in self.anchor:  # simulated with the backlash already (see anchored)
                h = h / e.response(f, self.nominal_break, filter_scale)
        return h

    def linear_response(self, f: FloatArray, filter_scale: float = 1.0) -> ComplexArray:
        """Product of the linear extensions' responses at ``f`` [Hz], whatever the anchor.

        What the extensions multiply the nominal response by (the anchor only says which of
        them are simulated with the backlash: :meth:`response` leaves those out).
        """
        h = np.ones(np.size(f), dtype=complex)
        for e in self.extensions:
            if e.effect in LINEAR:
                h = h * e.response(f, self.nominal_break, filter_scale)
        return h

    def psd_factor(self, f: FloatArray) -> FloatArray:
        """Factor on the measured noise spectrum at ``f`` [Hz] (a sensor filter's)."""
        g = np.ones(np.size(f))
        for e in self.extensions:
            if e.effect == "sensor_filter":
                g = g * np.abs(e.response(f)) ** 2
        return g

    def predict(self, ch: Channel) -> FloatArray:
        """Full-length prediction of a channel."""
        return apply_response(
            self.base(ch),
            ch.rate_hz,
            functools.partial(self.response, filter_scale=ch.filter_scale),
        )

    def line_prediction(self, lines: Lines) -> ComplexArray:
        """Predicted amplitudes at the lines: H(f) times the (re-simulated) base's."""
        if any(e.effect == "backlash" for e in self.extensions):
            ch = lines.channel
            key = ("lines", id(self.base(ch)), lines.window)
            if key not in self._cache:
                self._cache[key] = lines.amplitudes(self.base(ch))
            base = self._cache[key]
        else:
            base = lines.nominal
        return base * self.response(lines.f, lines.channel.filter_scale)

    def chi2(self, evidence: Sequence[Lines]) -> float:
        """Sum over the evidence of ``|Y - Yhat|^2 / sd^2`` (minus the log-likelihood)."""
        return sum(x.chi2(self.line_prediction(x)) for x in evidence)


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


#: Largest damping of a ``resonance`` searched: a mode. Above 1 the pair of poles is real, two
#: lags rather than a mode, and the vocabulary says lags as filters (``platform_filter``,
#: ``sensor_filter``, ``platform_lag``); at 1 it is the critically damped pair of Eq 5.1's
#: filter (:mod:`twin.diagnose.equivalence`). Reaching it is therefore a physical end of the
#: effect, not a search limit (:func:`extension_at_bounds` does not report it).
MAX_DAMPING = 1.0


def search_space(effect: str, case: Case, dof: str, channels: Sequence[Channel]) -> Space:
    """Return the physical range searched for each effect (stated in the report)."""
    k = dof_index(dof)
    if effect == "delay":
        lo, hi = -float(case.config.delay_s), MAX_EXTRA_DELAY_S
        return Space(("extra_delay_s",), (np.arange(lo, hi + 1e-4, 0.002),), ((lo, hi),))
    if effect == "gain":
        return Space(("gain",), (np.geomspace(0.2, 5.0, 81),), ((0.1, 10.0),))
    if effect == "platform_filter":
        return Space(("break_hz",), (np.geomspace(0.2, 30.0, 61),), ((0.1, 50.0),))
    if effect == "resonance":
        return Space(
            ("frequency_hz", "damping"),
            (np.geomspace(0.5, 20.0, 41), np.geomspace(0.05, MAX_DAMPING, 12)),
            ((0.3, 30.0), (0.02, MAX_DAMPING)),
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
    if effect == "platform_lag":  # the platform reading of a sensor filter's cut-off range
        return Space(("lag_s",), (1 / (2 * np.pi * np.geomspace(0.5, 40.0, 51)),),
                     ((1 / (2 * np.pi * 50.0), 1 / (2 * np.pi * 0.2)),))  # fmt: skip
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


Statistics = tuple[dict[str, dict[str, float]], dict[str, object]]


def _computed_already() -> Statistics:
    """Stand in for a fit's statistics function where they are computed already."""
    raise AssertionError("the statistics were computed when the fit was made or pickled")


@dataclass(frozen=True)
class SetFit:
    """A set of effects fitted jointly on top of a model.

    Attributes
    ----------
    extensions : tuple of Extension
        The effects with their fitted parameters.
    chi2 : float
        ``sum |Y - Yhat|^2 / sd^2`` with them.
    std : dict of str to dict of str to float
        Standard deviation per effect and parameter (nan where not identifiable).
    correlation : dict
        ``labels`` ("effect.parameter") and the correlation ``matrix`` of all parameters.

    Notes
    -----
    ``std`` and ``correlation`` come from the constructor's ``_statistics`` when first asked
    for (:meth:`of` gives them computed): with ``backlash`` their Jacobian costs two
    simulations per run, and only a named set's are reported. ``anchor``: the effects the
    backlash was simulated behind (the chain's order, :meth:`Model.anchored`); a model of the
    set is :meth:`model`.

    """

    extensions: tuple[Extension, ...]
    chi2: float
    _statistics: Callable[[], Statistics] = field(repr=False, compare=False)
    _computed: list[Statistics] = field(default_factory=list, repr=False, compare=False)
    anchor: tuple[Extension, ...] = ()

    @classmethod
    def of(
        cls,
        extensions: tuple[Extension, ...],
        chi2: float,
        std: dict[str, dict[str, float]],
        correlation: dict[str, object],
        anchor: tuple[Extension, ...] = (),
    ) -> SetFit:
        """Return a fit with its statistics computed already."""
        return cls(extensions, chi2, _computed_already, [(std, correlation)], anchor)

    def model(self, base: Model) -> Model:
        """Return ``base`` with this set, in the order it was fitted in (:attr:`anchor`)."""
        m = base.anchored(self.anchor) if self.anchor else base
        for x in self.extensions:
            m = m.with_(x)
        return m

    def __getstate__(self) -> dict[str, object]:
        """Pickle with the statistics computed (a task's result travels without closures)."""
        state = dict(self.__dict__)
        state["_computed"] = [self._statistics_once()]
        state["_statistics"] = _computed_already
        return state

    @property
    def std(self) -> dict[str, dict[str, float]]:
        """Standard deviation per effect and parameter (nan where not identifiable)."""
        return self._statistics_once()[0]

    @property
    def correlation(self) -> dict[str, object]:
        """``labels`` ("effect.parameter") and the correlation ``matrix`` of all parameters."""
        return self._statistics_once()[1]

    def _statistics_once(self) -> Statistics:
        if not self._computed:
            self._computed.append(self._statistics())
        return self._computed[0]

    @property
    def effects(self) -> tuple[str, ...]:
        """Effect names, in the set's order."""
        return tuple(e.effect for e in self.extensions)

    @property
    def parameters(self) -> int:
        """Number of fitted numeric parameters."""
        return sum(len(numeric_names(e.effect)) for e in self.extensions)


def numeric_names(effect: str) -> tuple[str, ...]:
    """Return the fitted (numeric) parameter names of an effect."""
    return tuple(k for k in EFFECTS[effect] if k != "channels")


#: A fitted parameter within this share of its search range of an end (log scale for the
#: scale-like ones) is at the bound: the data ask for more than the search allows, so the
#: value is a limit reached, not a measurement (on garbage: gain 0.1, break 0.1 Hz, 0.3 s).
AT_BOUND_SHARE = 1e-3


def at_bounds(fit: SetFit, model: Model, evidence: Sequence[Lines]) -> list[dict[str, object]]:
    """Return the fitted parameters of a set that lie at an end of their search range.

    Returns
    -------
    list of dict
        ``effect``, ``dofs``, ``parameter``, ``value``, ``bound`` ("lower" or "upper"),
        ``search`` ([low, high]) and ``set`` (the effects fitted with it), one per parameter
        at a bound.

    """
    channels = list({id(x.channel): x.channel for x in evidence}.values())
    out: list[dict[str, object]] = []
    for ext in fit.extensions:
        for entry in extension_at_bounds(ext, model.case, model.dof, channels):
            out.append({**entry, "set": list(fit.effects)})
    return out


def extension_at_bounds(
    ext: Extension, case: Case, dof: str, channels: Sequence[Channel]
) -> list[dict[str, object]]:
    """Return the parameters of one fitted extension at an end of their search range."""
    out: list[dict[str, object]] = []
    space = search_space(ext.effect, case, dof, channels)
    for name, (lo, hi) in zip(space.names, space.bounds, strict=True):
        u, ends = _searched(name, ext.value(name)), (_searched(name, lo), _searched(name, hi))
        for side, end in zip(("lower", "upper"), ends, strict=True):
            if name == "damping" and side == "upper":
                continue  # critically damped: a filter's pair of poles, not a search limit
            if abs(u - end) <= AT_BOUND_SHARE * (ends[1] - ends[0]):
                out.append({"effect": ext.effect, "dofs": [dof], "parameter": name,
                            "value": ext.value(name), "bound": side,
                            "search": [float(lo), float(hi)]})  # fmt: skip
    return out


def _searched(name: str, value: float) -> float:
    """Return a parameter on the scale it is searched on (log for the scale-like ones)."""
    return float(np.log(value)) if name in _LOG else float(value)


def describe_bound(entry: dict[str, object]) -> str:
    """Say that a parameter lies at its bound (:func:`at_bounds`) and is not a finding."""
    lo, hi = entry["search"]  # type: ignore[misc]
    dofs = ", ".join(entry["dofs"])  # type: ignore[arg-type]
    others = [e for e in entry.get("set", []) if e != entry["effect"]]  # type: ignore[attr-defined]
    jointly = f", nor {' and '.join(others)} fitted with it" if others else ""
    return (
        f"{entry['effect']} in {dofs}: {entry['parameter']} {entry['value']:.4g} at the "
        f"{entry['bound']} bound of its search ({lo:.4g} to {hi:.4g}): not a finding{jointly} "
        "(the runs ask for what no motion system has: check their units, axes and clock)"
    )


class _Layout:
    """Map between the parameters of a set of linear effects and one unconstrained vector."""

    def __init__(self, effects: Sequence[str], case: Case, dof: str, channels: Sequence[Channel]):
        self.effects = tuple(effects)
        self.dof = dof
        self.spaces = [search_space(e, case, dof, channels) for e in self.effects]
        self.names = [(e, n) for e, sp in zip(self.effects, self.spaces, strict=True)
                      for n in sp.names]  # fmt: skip
        self.log = np.array([n in _LOG for _, n in self.names])
        lo = np.array([b[0] for sp in self.spaces for b in sp.bounds])
        hi = np.array([b[1] for sp in self.spaces for b in sp.bounds])
        self.lo, self.hi = self.to_u(np.where(self.log, np.maximum(lo, 1e-12), lo)), self.to_u(hi)

    def to_u(self, x: FloatArray) -> FloatArray:
        x = np.asarray(x, dtype=float)
        return np.where(self.log, np.log(np.maximum(x, 1e-300)), x)

    def to_x(self, u: FloatArray) -> FloatArray:
        return np.where(self.log, np.exp(u), u)

    def extensions(self, u: FloatArray) -> list[Extension]:
        x = self.to_x(np.clip(u, self.lo, self.hi))
        out, i = [], 0
        for e, sp in zip(self.effects, self.spaces, strict=True):
            out.append(make_extension(e, sp.names, x[i : i + len(sp.names)], self.dof))
            i += len(sp.names)
        return out


def _grid_best(effect: str, model: Model, evidence: Sequence[Lines], layout: _Layout) -> FloatArray:
    """Best point of an effect's coarse grid on top of ``model`` (physical values)."""
    sp = layout.spaces[layout.effects.index(effect)]
    grid = np.array(np.meshgrid(*sp.grids, indexing="ij")).reshape(len(sp.names), -1).T
    base = [model.line_prediction(x) for x in evidence]
    costs = []
    for g in grid:
        ext = make_extension(effect, sp.names, g, model.dof)
        h = [ext.response(x.f, model.nominal_break, x.channel.filter_scale) for x in evidence]
        costs.append(sum(x.chi2(b * hh) for x, b, hh in zip(evidence, base, h, strict=True)))
    return grid[int(np.argmin(costs))]


def _fit_linear(
    effects: Sequence[str],
    model: Model,
    evidence: Sequence[Lines],
    start: dict[str, Sequence[float]] | None = None,
) -> tuple[list[Extension], float, FloatArray, _Layout]:
    """Fit linear effects jointly on top of ``model``: extensions, chi2, Jacobian, layout."""
    channels = list({id(x.channel): x.channel for x in evidence}.values())
    layout = _Layout(effects, model.case, model.dof, channels)
    base = [model.line_prediction(x) for x in evidence]

    def resid(u: FloatArray) -> FloatArray:
        exts = layout.extensions(u)
        out = []
        for x, b in zip(evidence, base, strict=True):
            h = np.ones(x.size, dtype=complex)
            for e in exts:
                h = h * e.response(x.f, model.nominal_break, x.channel.filter_scale)
            out.append(x.residuals(b * h))
        return np.concatenate(out)

    starts = []
    if start is not None:
        starts.append(np.concatenate([np.asarray(start[e], dtype=float) for e in effects]))
    else:
        singles = {e: _grid_best(e, model, evidence, layout) for e in effects}
        starts.append(np.concatenate([singles[e] for e in effects]))
        for order in (effects, effects[::-1]) if len(effects) > 1 else ():
            current, vals = model, {}
            for e in order:
                vals[e] = _grid_best(e, current, evidence, layout)
                sp = layout.spaces[layout.effects.index(e)]
                current = current.with_(make_extension(e, sp.names, vals[e], model.dof))
            starts.append(np.concatenate([vals[e] for e in effects]))
    best = None
    for x0 in starts:
        u0 = np.clip(layout.to_u(x0), layout.lo + 1e-9, layout.hi - 1e-9)
        sol = optimize.least_squares(resid, u0, bounds=(layout.lo, layout.hi), x_scale="jac")
        if best is None or sol.cost < best.cost:
            best = sol
    assert best is not None
    return layout.extensions(best.x), 2 * float(best.cost), best.jac, layout


def _statistics(
    jac: FloatArray, names: Sequence[tuple[str, str]], x: FloatArray, log: NDArray[np.bool_]
) -> tuple[dict[str, dict[str, float]], dict[str, object]]:
    """Return standard deviations and correlations from the Jacobian of the residuals."""
    fim = 2 * jac.T @ jac
    try:
        cov = np.linalg.pinv(fim, rcond=1e-12)
    except np.linalg.LinAlgError:
        cov = np.full(fim.shape, np.nan)
    sd_u = np.sqrt(np.maximum(np.diag(cov), 0))
    sd = np.where(log, x * sd_u, sd_u)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(sd_u, sd_u)
    std: dict[str, dict[str, float]] = {}
    for (e, n), v in zip(names, sd, strict=True):
        std.setdefault(e, {})[n] = float(v) if np.isfinite(v) and v > 0 else float("nan")
    labels = [f"{e}.{n}" for e, n in names]
    return std, {"labels": labels, "matrix": np.round(corr, 3).tolist()}


def fit_set(
    effects: Sequence[str],
    model: Model,
    evidence: Sequence[Lines],
    start: dict[str, Sequence[float]] | None = None,
    coarse: bool = False,
) -> SetFit:
    """Fit a set of effects jointly on top of ``model`` over the line evidence.

    Parameters
    ----------
    effects : sequence of str
        Effects of :data:`DYNAMIC` (at most one ``backlash``).
    model : Model
        What they are added to (the nominal model, or one with findings of other DOFs).
    evidence : sequence of Lines
        The lines they are fitted on.
    start : dict, optional
        Values per effect to start from (e.g. fitted on other data): a local search only.
    coarse : bool
        With ``backlash``: screen (the play on its grid or at its start only, no refinement).

    """
    effects = tuple(effects)
    linear = tuple(e for e in effects if e != "backlash")
    if "backlash" not in effects:
        exts, chi2, jac, layout = _fit_linear(linear, model, evidence, start)
        x = np.array([e.value(n) for e in exts for n in numeric_names(e.effect)])
        std, corr = _statistics(jac, layout.names, x, layout.log)
        return SetFit.of(tuple(exts), chi2, std, corr)
    return _fit_with_backlash(linear, model, evidence, start, coarse)


#: Command-side linear effects that change what reaches the backlash (a delay does not).
BEFORE_BACKLASH = ("gain", "platform_filter", "resonance", "lead")
#: Log step of the play around its chain-order start (:func:`_parabola`).
ANCHOR_STEP = 1.1
#: Passes of the chain-order refit, each anchored at the shaping effects the last one fitted
#: (the anchor is the effects' values the backlash is simulated behind: a refit that moves
#: them moves what reaches the play, so the next pass simulates behind the new values).
ANCHOR_PASSES = 4
#: A pass that lowers chi2 by less than this is the last one.
ANCHOR_TOLERANCE = 0.5
_Memo = dict[float, tuple[float, list[Extension], FloatArray | None, object]]


def _profile(
    linear: tuple[str, ...],
    model: Model,
    evidence: Sequence[Lines],
    start: dict[str, Sequence[float]] | None,
    memo: _Memo,
) -> Callable[[float], float]:
    """chi2 of the best linear effects behind a given play (memoised: each is a simulation)."""

    def profile(play: float) -> float:
        if play not in memo:
            ctx = model.with_(make_extension("backlash", ["play"], [play], model.dof))
            if linear:
                exts, chi2, jac, layout = _fit_linear(linear, ctx, evidence, start)
                memo[play] = (chi2, exts, jac, layout)
            else:
                memo[play] = (ctx.chi2(evidence), [], None, None)
        return memo[play][0]

    return profile


#: Tolerance of the bounded search of the play [log units] (:func:`_refine`).
PLAY_XATOL = 0.03


def _refine(
    profile: Callable[[float], float],
    lo: float,
    hi: float,
    space: Space,
    prefetch: Callable[[list[float]], None] | None = None,
) -> None:
    """Bounded search of the play in [lo, hi] (log scale) within the effect's bounds.

    ``prefetch``: called first with the search's first two plays (:func:`_brent_start`),
    which do not depend on the profile, to simulate them side by side.
    """
    lo, hi = max(lo, space.bounds[0][0]), min(max(hi, lo * 1.0001), space.bounds[0][1])
    a, b = np.log(lo), np.log(hi)
    if prefetch is not None:
        prefetch([float(np.exp(u)) for u in _brent_start(a, b, PLAY_XATOL)])
    r = optimize.minimize_scalar(lambda u: profile(float(np.exp(u))), bounds=(a, b),
                                 method="bounded", options={"xatol": PLAY_XATOL})  # fmt: skip
    profile(float(np.exp(r.x)))


def _brent_start(a: float, b: float, xatol: float) -> tuple[float, float]:
    """Return the first two points SciPy's bounded Brent search evaluates in [a, b].

    The golden-section point of the interval, then a golden-section step from it into the
    wider side (the first step has no parabola to take), in SciPy's arithmetic: neither
    depends on the function. (Should SciPy change its search, the plays simulated ahead are
    simply not the ones asked for: the result stays the search's.)
    """
    golden, sqrt_eps = 0.5 * (3.0 - np.sqrt(5.0)), np.sqrt(2.2e-16)
    x1 = a + golden * (b - a)
    e = a - x1 if x1 >= 0.5 * (a + b) else b - x1
    rat = golden * e
    tol1 = sqrt_eps * np.abs(x1) + xatol / 3.0
    return x1, x1 + (np.sign(rat) + (rat == 0)) * np.maximum(np.abs(rat), tol1)


def _amplitude_ratio(
    shaping: Sequence[Extension], evidence: Sequence[Lines], model: Model
) -> float:
    """Mean gain of ``shaping`` over the lines, weighted by their motion's power (exact for a gain).

    A play p behind the effects in the fast order acts roughly as p times this in the
    chain's order: the start of the chain-order search. A play acts on the motion (position),
    so each line weighs by its position power, ``|acceleration|^2 / (2 pi f)^4``: the low lines
    that make the excursion, not the high ones whose acceleration is large but whose motion is
    small (a filter that halves only those leaves the play as it is).
    """
    num = den = 0.0
    for x in evidence:
        w = np.abs(x.nominal) ** 2 / (2 * np.pi * x.f) ** 4
        h = np.ones(x.size, dtype=complex)
        for e in shaping:
            h = h * e.response(x.f, model.nominal_break, x.channel.filter_scale)
        num += float(np.sum(w * np.log(np.maximum(np.abs(h), 1e-12))))
        den += float(np.sum(w))
    return float(np.exp(num / den)) if den > 0 else 1.0


def _parabola(
    profile: Callable[[float], float],
    centre: float,
    space: Space,
    prefetch: Callable[[list[float]], None] | None = None,
) -> None:
    """Three plays around ``centre`` (log steps of ANCHOR_STEP) and the parabola's vertex.

    ``prefetch``: called with the three plays first (to simulate them side by side).
    """
    lo_b, hi_b = space.bounds[0]
    centre = float(np.clip(centre, lo_b * ANCHOR_STEP, hi_b / ANCHOR_STEP))
    u = np.log(centre) + np.log(ANCHOR_STEP) * np.array([-1.0, 0.0, 1.0])
    plays = [float(np.exp(v)) for v in u]
    if prefetch is not None:
        prefetch(plays)
    c = np.array([profile(p) for p in plays])
    curvature = c[0] - 2 * c[1] + c[2]
    if curvature > 0:
        shift = 0.5 * (c[0] - c[2]) / curvature  # in steps, kept within twice the bracket
        profile(float(np.exp(u[1] + np.clip(shift, -2.0, 2.0) * np.log(ANCHOR_STEP))))


def _chain_order_start(
    linear: tuple[str, ...],
    model: Model,
    evidence: Sequence[Lines],
    start: dict[str, Sequence[float]],
    play: float,
    memo: _Memo,
) -> tuple[Model, _Memo]:
    """Return the model and memo of the better order for a start's play: fast or chain.

    A start from a refined fit may hold the chain's order (its play behind its shaping
    effects, :meth:`Model.anchored`): held at that play, it is evaluated both ways.
    """
    shaping = [make_extension(e, numeric_names(e), v, model.dof)
               for e, v in start.items() if e in BEFORE_BACKLASH]  # fmt: skip
    if not shaping:
        return model, memo
    anchored, memo_a = model.anchored(shaping), {}
    inner = {e: v for e, v in start.items() if e != "backlash"} or None
    try:
        _profile(linear, anchored, evidence, inner, memo_a)(play)
    except SignalError:  # the chain cannot run them: the fast order stands
        return model, memo
    return (anchored, memo_a) if memo_a[play][0] < memo[play][0] else (model, memo)


def _fit_with_backlash(
    linear: tuple[str, ...],
    model: Model,
    evidence: Sequence[Lines],
    start: dict[str, Sequence[float]] | None,
    coarse: bool = False,
) -> SetFit:
    """Backlash (outer search over the play, each a simulation) plus linear effects (inner).

    ``coarse``: no refinement of the play (the grid, or the start's play, only): a screening
    fit whose simulations are shared by every set with backlash.
    """
    channels = list({id(x.channel): x.channel for x in evidence}.values())
    space = search_space("backlash", model.case, model.dof, channels)
    inner_start = {e: v for e, v in (start or {}).items() if e != "backlash"} or None
    memo: _Memo = {}
    profile = _profile(linear, model, evidence, inner_start, memo)
    if start is not None and "backlash" in start:
        centre = float(start["backlash"][0])
        lo, hi = centre / 2.0, centre * 2.0
        if coarse:
            profile(centre)
            model, memo = _chain_order_start(linear, model, evidence, start, centre, memo)
    else:
        grid = space.grids[0]
        model.prefetch([float(p) for p in grid], channels)
        costs = [profile(float(p)) for p in grid]
        i = int(np.argmin(costs))
        lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    if not coarse:
        _refine(profile, lo, hi, space, lambda plays: model.prefetch(plays, channels))
    play = min(memo, key=lambda p: memo[p][0])  # the best play evaluated
    chi2, exts, jac, layout = memo[play]
    ext_b = make_extension("backlash", ["play"], [play], model.dof)
    if coarse:  # a screening fit: no statistics (they would cost two simulations per run)
        nan = float("nan")
        std = {e.effect: dict.fromkeys(numeric_names(e.effect), nan) for e in (ext_b, *exts)}
        return SetFit.of((ext_b, *exts), chi2, std, {"labels": [], "matrix": []}, model.anchor)
    base, centre = model, None
    for _ in range(ANCHOR_PASSES):  # the chain's order: these shape what reaches the backlash
        shaping = [e for e in exts if e.effect in BEFORE_BACKLASH]  # (Model.anchored)
        if not shaping:
            break
        anchored = base.anchored(shaping)
        centre = play * _amplitude_ratio(shaping, evidence, base) if centre is None else play
        fitted = {e.effect: [e.value(n) for n in numeric_names(e.effect)] for e in exts}
        memo_a: _Memo = {}
        profile_a = _profile(linear, anchored, evidence, fitted, memo_a)
        try:
            ahead = functools.partial(anchored.prefetch, channels=channels)
            _parabola(profile_a, centre, space, ahead)
        except SignalError:  # the chain cannot run them (a pole beyond the commands' Nyquist
            break  # frequency): the fit so far stands
        play_a = min(memo_a, key=lambda p: memo_a[p][0], default=None)
        if play_a is None or memo_a[play_a][0] > chi2:
            break
        gain = chi2 - memo_a[play_a][0]
        model, play = anchored, play_a
        chi2, exts, jac, layout = memo_a[play_a]
        ext_b = make_extension("backlash", ["play"], [play], model.dof)
        if gain < ANCHOR_TOLERANCE:
            break
    stats = functools.partial(_backlash_statistics, model, evidence, play, exts, jac, layout)
    # the statistics when asked for (a named set)
    return SetFit((ext_b, *exts), chi2, stats, anchor=model.anchor)


def _backlash_statistics(
    model: Model,
    evidence: Sequence[Lines],
    play: float,
    exts: Sequence[Extension],
    jac: FloatArray | None,
    layout: _Layout | None,
) -> Statistics:
    """Return the standard deviations and correlations of a fit with backlash.

    The play's column of the Jacobian is a central difference with the linear effects held
    (two simulations per run); the linear effects' columns are ``jac`` (``layout``'s).
    """
    channels = list({id(x.channel): x.channel for x in evidence}.values())
    col = []
    model.prefetch([play * k for k in (1.01, 1 / 1.01)], channels)
    for k in (1.01, 1 / 1.01):
        m = model.with_(make_extension("backlash", ["play"], [play * k], model.dof))
        for e in exts:
            m = m.with_(e)
        col.append(np.concatenate([x.residuals(m.line_prediction(x)) for x in evidence]))
    dplay = ((col[0] - col[1]) / (2 * np.log(1.01)))[:, None]
    names = [("backlash", "play")]
    log = [True]
    if layout is not None:
        names += list(layout.names)
        log += list(layout.log)
        jac = np.hstack([dplay, jac])
    else:
        jac = dplay
    x = np.array([play] + [e.value(n) for e in exts for n in numeric_names(e.effect)])
    return _statistics(jac, names, x, np.array(log))
