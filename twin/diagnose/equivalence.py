"""Explanations with the same response: one a special case of another.

Some sets of effects hold others as special cases of their parameters:

- a ``resonance`` damped at 1 is a ``platform_filter`` where the configuration has none (both
  a critically damped pair of poles, Eq 5.1's form);
- a ``lead`` cancelling one pole of a critically damped ``resonance`` leaves a first-order lag: a
  ``sensor_filter`` (or a ``platform_lag``) on the driven DOF's line;
- a ``lead`` cancelling one of a ``platform_filter``'s poles (where the configuration has no
  filter) does the same.

When an alternative, refitted to the named set's response over every frequency a run could
use, matches it to within :data:`SAME_RESPONSE`, the two differ nowhere by as much as the
smallest effect the diagnosis names (:data:`MIN_DF_GAIN_DB`, :data:`MIN_DF_GAIN_DEG`: below
what the thesis' Bode comparisons resolve); a designed run at a very high signal-to-noise
ratio might still rank them, but not by a difference that matters to the motion. The BIC's
count of parameters ranks them, and the alternative is the named response said with more
parameters, not a rival cause. (A moved MPI filter, 1/(1 + s/w)^2 at 0.79 Hz instead of
1 Hz, and a lead with a first-order filter differ by 0.15 % at most, 0.013 dB.) The
diagnosis then reports it beside the finding as the same response (:func:`same_response`),
and :mod:`twin.diagnose.design` does not design for it.

Responses are compared as the factor the effects multiply the nominal line response by
(:meth:`twin.chain.extensions.Extension.response`), the same for every channel of the DOF.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy import optimize

from twin.chain.extensions import LINEAR, Extension
from twin.diagnose.candidates import (
    BEFORE_BACKLASH,
    make_extension,
    numeric_names,
    search_space,
)
from twin.diagnose.data import Case, Channel

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: Least rise of the held-out describing-function error (mean over the lines) when an effect
#: named beside another is removed, in dB or in degrees, for it to be named
#: (:mod:`twin.diagnose.select`).
MIN_DF_GAIN_DB = 0.1
MIN_DF_GAIN_DEG = 0.5
#: Largest relative difference of two responses that are the same response [-]: a complex
#: ratio within it changes no line by :data:`MIN_DF_GAIN_DB` nor :data:`MIN_DF_GAIN_DEG`
#: (0.87 %: the phase bound, sin 0.5 deg, is the tighter).
SAME_RESPONSE = min(10 ** (MIN_DF_GAIN_DB / 20) - 1, float(np.sin(np.radians(MIN_DF_GAIN_DEG))))
#: Frequencies the responses are compared at [Hz]: every frequency a run of the design uses
#: (:data:`twin.diagnose.design.FREQUENCIES_HZ`) and beyond.
FREQUENCIES_HZ = np.geomspace(0.05, 50.0, 120)


def relative_response(
    extensions: Sequence[Extension],
    f: FloatArray,
    nominal_break_hz: float | None,
    filter_scales: Sequence[float] = (1.0,),
) -> ComplexArray:
    """Return the factor a set of linear extensions multiplies a DOF's response by at ``f``.

    At each filter setting of ``filter_scales`` (times the nominal's), one after the other.
    """
    parts = []
    for k in filter_scales:
        out = np.ones(np.shape(f), dtype=complex)
        for ext in extensions:
            out = out * ext.response(f, nominal_break_hz, k)
        parts.append(out)
    return np.concatenate(parts)


def same_response(
    named: Sequence[Extension],
    effects: Sequence[str],
    parameters: Mapping[str, Mapping[str, float]],
    case: Case,
    dof: str,
    channels: Sequence[Channel],
) -> dict[str, object] | None:
    """Return the alternative refitted to the named set's response, if it is the same.

    Parameters
    ----------
    named : sequence of Extension
        The named set, at its fitted parameters.
    effects : sequence of str
        The alternative's effects.
    parameters : mapping
        The alternative's fitted parameters (effect -> name -> value): where the refit starts.
    case, dof, channels
        What is diagnosed (the alternative is refitted within its search's bounds,
        :func:`twin.diagnose.candidates.search_space`).

    Returns
    -------
    dict or None
        ``effects``, ``parameters`` (refitted) and ``max_relative_difference`` where the
        difference is at most :data:`SAME_RESPONSE` at every frequency of
        :data:`FREQUENCIES_HZ`; None otherwise. Two sets that each hold a backlash are
        compared with the alternative's play set to the named one: they are the same
        response when their linear effects are, on each side of the play apart (what shapes
        the motion before it, and the delay, which commutes with it; what acts after it): the
        same motion then reaches the same play.

    """
    plays = [e for e in named if e.effect == "backlash"]
    if not plays and "backlash" not in effects:
        return _same_linear(named, effects, parameters, case, dof, channels)
    if len(plays) != 1 or list(effects).count("backlash") != 1:
        return None
    params: dict[str, dict[str, float]] = {"backlash": {"play": plays[0].value("play")}}
    worst = 0.0
    for side in (_before_play, lambda e: not _before_play(e)):
        mine = [e for e in named if e.effect != "backlash" and side(e.effect)]
        theirs = [e for e in effects if e != "backlash" and side(e)]
        if not mine and not theirs:
            continue
        if not mine or not theirs:
            return None
        eq = _same_linear(mine, theirs, parameters, case, dof, channels)
        if eq is None:
            return None
        params |= eq["parameters"]  # type: ignore[arg-type]
        worst = max(worst, float(eq["max_relative_difference"]))  # type: ignore[arg-type]
    return {"effects": list(effects), "parameters": params, "max_relative_difference": worst}


def _before_play(effect: str) -> bool:
    """Whether a linear effect acts on the motion before a backlash (or commutes with it)."""
    return effect in (*BEFORE_BACKLASH, "delay")


def _same_linear(
    named: Sequence[Extension],
    effects: Sequence[str],
    parameters: Mapping[str, Mapping[str, float]],
    case: Case,
    dof: str,
    channels: Sequence[Channel],
) -> dict[str, object] | None:
    """:func:`same_response` of linear sets (None where a set is not linear)."""
    if any(e.effect not in LINEAR for e in named) or any(e not in LINEAR for e in effects):
        return None
    nominal_break = case.clean.filter_break_hz
    f = FREQUENCIES_HZ
    settings = sorted({ch.filter_scale for ch in channels}) or [1.0]  # each run's setting
    target = relative_response(named, f, nominal_break, settings)
    slots, x0, lo, hi = [], [], [], []
    for effect in effects:
        names = list(numeric_names(effect))
        bounds = search_space(effect, case, dof, channels).bounds
        given = parameters.get(effect) or {}
        for name, (b_lo, b_hi) in zip(names, bounds, strict=True):
            width = b_hi - b_lo
            x0.append(float(np.clip(given.get(name, (b_lo + b_hi) / 2), b_lo + 1e-9 * width,
                                    b_hi - 1e-9 * width)))  # fmt: skip
            lo.append(b_lo)
            hi.append(b_hi)
        slots.append((effect, names))

    def extensions(theta: FloatArray) -> list[Extension]:
        out, i = [], 0
        for effect, names in slots:
            out.append(make_extension(effect, names, theta[i : i + len(names)], dof))
            i += len(names)
        return out

    def residual(theta: FloatArray) -> FloatArray:
        r = relative_response(extensions(theta), f, nominal_break, settings) / target - 1.0
        return np.concatenate([r.real, r.imag])

    fit = optimize.least_squares(residual, np.array(x0), bounds=(lo, hi), max_nfev=400)
    exts = extensions(fit.x)
    diff = float(np.max(np.abs(relative_response(exts, f, nominal_break, settings) / target - 1.0)))
    if diff > SAME_RESPONSE:
        return None
    return {
        "effects": list(effects),
        "parameters": {e.effect: {n: e.value(n) for n in numeric_names(e.effect)} for e in exts},
        "max_relative_difference": diff,
    }
