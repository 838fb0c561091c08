"""Name the causes: joint fits of sets of effects, BIC selection, and a held-out gate.

For each analysed DOF the line evidence (:mod:`twin.diagnose.evidence`) is fitted, on top of
the nominal model, with every single dynamic effect and every pair of them (parameters fitted
jointly, :func:`twin.diagnose.candidates.fit_set`); pairs with ``backlash`` are screened on
the plays of its grid (each play is a simulation, shared by all pairs), and those that screen
within ``SCREEN_WINDOW`` of the best set are refined (the play searched, the effects that
shape the motion before it refitted in the chain's order): a screen on a coarse grid, with
the fast form's order, can fall short of the true set by tens of BIC. With chi2 = -log L,

    BIC = 2 chi2 + p ln(n)

(p fitted parameters, n = 2 x the number of lines: real observations). A set can be named when
it beats the nominal model by more than ``BIC_MARGIN`` (10: "very strong" evidence on Kass and
Raftery's scale) *and* every member is needed: the set beats each of its subsets by the margin
(so a pair is named only when both effects are). Of those, the sets within ``OCCAM_WINDOW`` of
the best BIC are equally supported, and the one with the fewest parameters is named. From a
named pair a third effect is added when it improves the BIC by the margin again. This is
forward-backward selection over all pairs: a cause that only looked best alone is replaced when
two others
explain the data better.

Before it, the bound gate: a set with a fitted parameter at an end of its search range
(:func:`twin.diagnose.candidates.at_bounds`: gain 0.1, a 0.1 Hz break, 0.3 s more delay)
explains the runs only beyond what a motion system has: that is a limit reached, not a
measurement, and the values fitted jointly with it are no better. Nothing of the set is named;
the parameters at their bound are reported "at the bound" (:attr:`Selection.at_bound`).

Then the held-out gate: every named effect must improve the data it was not fitted on, on the
evidence it claims to explain: the set is refitted with and without the effect on one half of
the measurement window and scored on the other (two-fold, both ways), or on validation runs;
an effect whose held-out line error (chi2 per line: the describing-function error at the
excited lines, weighted by its uncertainty) does not fall is dropped. Reported per finding,
before -> after (the set without it -> with it): held-out chi2 per line, describing-function
error (mean absolute dB and deg of measured over predicted at the lines) and VAF.

An effect named beside another must also matter: removing it must raise the held-out
describing-function error by at least :data:`MIN_DF_GAIN_DB` or :data:`MIN_DF_GAIN_DEG`
(the set's strongest member, by BIC, is exempt: it is what the runs show). At a designed
run's signal-to-noise ratio (lines known to 0.01 dB) any shape the twin's effects do not
have exactly, a lab's digital filter say, is fitted by small extra effects that cancel each
other (a 3.6 ms delay with a 3.9 ms lead); their joint change of the describing function is
below what the thesis' Bode comparisons resolve (Figs 5.7, 5.9). They are dropped and
reported (``dropped_as_negligible``), not named.

Alternatives (other sets within the margin of the named one) and the correlations of the
jointly fitted parameters are reported, so trade-offs (delay vs lead vs filter) are visible.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import combinations

import numpy as np
from numpy.typing import NDArray

from twin.chain.extensions import Extension
from twin.core.progress import ProgressFn
from twin.diagnose.candidates import DYNAMIC, Model, SetFit, at_bounds, fit_set, numeric_names
from twin.diagnose.data import Case
from twin.diagnose.equivalence import MIN_DF_GAIN_DB, MIN_DF_GAIN_DEG, same_response
from twin.diagnose.evidence import Lines, lines, measured_line_sd

FloatArray = NDArray[np.float64]
#: Most alternatives an ambiguous finding lists (the closest first).
MAX_ALTERNATIVES = 3
#: Largest relative difference of two responses said to be identical (the refit's precision).
IDENTICAL = 1e-6
#: Evidence needed to name a cause [BIC units].
BIC_MARGIN = 10.0
#: Sets whose BIC is within this of the best are equally supported: the one with the fewest
#: parameters is named (a platform filter is a resonance with damping 1; the data cannot
#: prefer the resonance for a better fit of the noise).
OCCAM_WINDOW = 6.0
#: Pairs with backlash screened within this of the best set are refined [BIC units]: the
#: screen's play grid steps by a factor of 2.6 and applies a filter after the play where the
#: chain has it before, which cost a platform filter with a play, at its true values, 59 BIC
#: in a drawn case (SRS roll, 2.1 Hz and 6.8 mrad; refined it is the best set).
SCREEN_WINDOW = 100.0


@dataclass
class Finding:
    """A named cause.

    Attributes
    ----------
    extension : Extension
        Effect, fitted parameters and DOFs.
    evidence : dict
        Criterion, dBIC, chi2, observations, parameter standard deviations and correlations,
        alternatives.
    gain : dict
        Held-out describing-function error, chi2 per line and VAF, before -> after.

    """

    extension: Extension
    evidence: dict[str, object]
    gain: dict[str, object] = field(default_factory=dict)

    @property
    def ambiguous(self) -> bool:
        """Whether other explanations fit the runs as well (within the margin).

        Then this is one of several, not *the* cause (:attr:`evidence` ``alternatives``).
        """
        return bool(self.evidence.get("ambiguous"))

    @property
    def delta_bic(self) -> float:
        """BIC improvement that named it."""
        return float(self.evidence["delta_bic"])  # type: ignore[arg-type]

    def to_json(self) -> dict[str, object]:
        """Return the finding in the fixed JSON vocabulary."""
        e = self.extension.to_json()
        return {
            "effect": e["effect"],
            "parameters": e["parameters"],
            "dofs": e["dofs"],
            "ambiguous": self.ambiguous,
            "alternatives": self.evidence.get("alternatives") or [],
            "same_response": self.evidence.get("same_response") or [],
            "evidence": self.evidence,
            "gain": self.gain,
        }


@dataclass(frozen=True)
class Selection:
    """What :func:`select` decided for one DOF.

    Attributes
    ----------
    fit : SetFit or None
        The named set (None: the nominal model stands).
    delta_bic : dict of str to float
        BIC improvement of each named effect (the set against the set without it).
    table : list of dict
        Every set tried: effects, chi2, parameters, BIC improvement over the nominal model.
    observations : int
        Real observations (2 x lines).
    at_bound : tuple of dict
        Effects of the selected set whose fitted parameters lie at a bound of their search
        (:func:`twin.diagnose.candidates.at_bounds`): reported, never named.
    fits : dict of tuple of str to SetFit
        Every set fitted, by its sorted effects.

    """

    fit: SetFit | None
    delta_bic: dict[str, float]
    table: list[dict[str, object]]
    observations: int
    at_bound: tuple[dict[str, object], ...] = ()
    fits: dict[tuple[str, ...], SetFit] = field(default_factory=dict, repr=False)


def bic_gain(chi2_0: float, chi2_1: float, extra_parameters: int, n: int) -> float:
    """BIC improvement of a model with ``extra_parameters`` more: 2 dchi2 - dp ln n."""
    return 2.0 * (chi2_0 - chi2_1) - extra_parameters * np.log(n)


def select(
    model: Model,
    evidence: Sequence[Lines],
    effects: Sequence[str] = DYNAMIC,
    progress: ProgressFn | None = None,
) -> Selection:
    """Forward-backward selection over all single effects and pairs (see module docstring)."""
    n = 2 * sum(x.size for x in evidence)
    chi0 = model.chi2(evidence)
    fits: dict[tuple[str, ...], SetFit] = {}

    def fit(es: tuple[str, ...], start: dict | None = None, coarse: bool = False) -> SetFit:
        key = tuple(sorted(es))
        if key not in fits:
            if progress:
                progress(f"{model.dof}: fitting {' + '.join(key)}")
            fits[key] = fit_set(key, model, evidence, start, coarse)
        return fits[key]

    def gain_of(es: tuple[str, ...]) -> float:
        f = fits[tuple(sorted(es))]
        return bic_gain(chi0, f.chi2, f.parameters, n)

    singles = [e for e in effects if e != "backlash"]
    for e in singles:
        fit((e,))
    if "backlash" in effects:  # on its grid first; refined only where it helps at all
        fit(("backlash",), coarse=True)
        if gain_of(("backlash",)) > 0:
            fits[("backlash",)] = fit_set(
                ("backlash",), model, evidence, _start(fits[("backlash",)])
            )
    for pair in combinations(effects, 2):
        # pairs with backlash are screened on the plays of its grid (simulated once, for the
        # single fit); those near the best are refined
        fit(pair, coarse="backlash" in pair)
    refined = set()
    if "backlash" in effects:
        best = max(gain_of(k) for k in fits)
        for k in [k for k in fits if "backlash" in k and len(k) > 1]:
            if gain_of(k) >= best - SCREEN_WINDOW:
                fits[k] = fit_set(k, model, evidence, _start(fits[k]))
                refined.add(k)

    def needed(es: tuple[str, ...]) -> dict[str, float]:
        """BIC improvement of each member over the set without it (inf for a single).

        A rest with a backlash that was only screened is refined first, from the set's own
        values too: a refined set against a screened one would make any member look needed
        (a lead at 0 beside a play and a moved filter, whose screen left the play at half).
        """
        f = fits[tuple(sorted(es))]
        out = {}
        for e in es:
            rest = tuple(x for x in es if x != e)
            if rest:
                r = fit(rest)
                key = tuple(sorted(rest))
                if "backlash" in key and len(key) > 1 and key not in refined:
                    own = {k: v for k, v in _start(f).items() if k in key}
                    tries = [fit_set(key, model, evidence, start) for start in (_start(r), own)]
                    fits[key] = r = min(tries, key=lambda x: x.chi2)
                    refined.add(key)
                out[e] = bic_gain(r.chi2, f.chi2, f.parameters - r.parameters, n)
            else:
                out[e] = gain_of(es)
        return out

    def named_ok(k: tuple[str, ...]) -> bool:
        return gain_of(k) > BIC_MARGIN and all(v > BIC_MARGIN for v in needed(k).values())

    def occam() -> tuple[str, ...]:
        """Return the fewest parameters among the nameable sets near the best (none: ())."""
        passing = [k for k in fits if named_ok(k)]
        if not passing:
            return ()
        top = max(gain_of(k) for k in passing)
        near = [k for k in passing if gain_of(k) >= top - OCCAM_WINDOW]
        return min(near, key=lambda k: (fits[k].parameters, -gain_of(k)))

    def refine(chosen: tuple[str, ...]) -> None:
        """Refine a pair with a play that was only screened (a trio is fitted whole)."""
        if "backlash" in chosen and len(chosen) == 2 and chosen not in refined:
            fits[chosen] = fit_set(chosen, model, evidence, _start(fits[chosen]))
            refined.add(chosen)

    def forward(chosen: tuple[str, ...]) -> tuple[str, ...]:
        """Return the pair with a third effect on top where each member is then needed."""
        best = None
        for e in effects:
            if e in chosen or e == "backlash":
                continue
            start = {x.effect: [x.value(k) for k in numeric_names(x.effect)]
                     for x in fits[chosen].extensions}  # fmt: skip
            trio = tuple(sorted((*chosen, e)))
            fits[trio] = fit_set(trio, model, evidence, None)
            if fits[trio].chi2 > fits[chosen].chi2:  # a poor start: from the pair's values
                start[e] = [float(v) for v in fit((e,)).extensions[0].parameters.values()
                            if isinstance(v, float)]  # fmt: skip
                fits[trio] = fit_set(trio, model, evidence, start)
            if all(v > BIC_MARGIN for v in needed(trio).values()) and (
                best is None or gain_of(trio) > gain_of(best)
            ):
                best = trio
        return chosen if best is None else best

    chosen = occam()
    refine(chosen)
    screened = len(refined)
    if len(chosen) == 2:
        chosen = forward(chosen)
        if len(refined) > screened:  # a pair with a play refined only now may be the better
            again = occam()
            if again != chosen and len(again) == 2:
                refine(again)
                again = forward(again)
            chosen = again
    table = [
        {
            "effects": list(k),
            "chi2": fits[k].chi2,
            "delta_bic": gain_of(k),
            "nameable": named_ok(k),
            "parameters": {
                e.effect: {p: e.value(p) for p in numeric_names(e.effect)}
                for e in fits[k].extensions
            },
        }
        for k in sorted(fits, key=lambda k: -gain_of(k))
    ]
    if not chosen:
        return Selection(None, {}, table, n)
    return Selection(fits[chosen], needed(chosen), table, n, fits=fits)


def alternatives(sel: Selection, limit: int | None = 3) -> list[dict[str, object]]:
    """Other explanations whose BIC is within the margin of the named set.

    An alternative is a set that could be named on its own (it beats the nominal model by the
    margin and needs every member) and is neither the named set with effects added (those
    explain nothing more) nor one of its parts (those the named set beat by the margin).
    Each comes with its fitted parameters, its BIC improvement and how far below the named
    set's it lies.
    """
    if sel.fit is None:
        return []
    chosen = set(sel.fit.effects)
    top = next(r["delta_bic"] for r in sel.table if set(r["effects"]) == chosen)  # type: ignore[arg-type]
    out = [
        {
            "effects": r["effects"],
            "parameters": r["parameters"],
            "delta_bic": float(r["delta_bic"]),  # type: ignore[arg-type]
            "delta_bic_below_named": float(top - r["delta_bic"]),  # type: ignore[operator]
        }
        for r in sel.table
        if r.get("nameable")
        and top - r["delta_bic"] < BIC_MARGIN  # type: ignore[operator]
        and not chosen <= set(r["effects"])  # type: ignore[arg-type]
        and not set(r["effects"]) <= chosen  # type: ignore[arg-type]
    ]
    return out if limit is None else out[:limit]


def negligible_text(f: Finding) -> str | None:
    """Return the effects dropped beside a finding as too small to matter (None: none)."""
    small = f.evidence.get("dropped_as_negligible") or []
    if not small:
        return None
    return (
        f"also fitted, not named (too small to matter: without each the held-out describing "
        f"function changes by less than {MIN_DF_GAIN_DB:g} dB and {MIN_DF_GAIN_DEG:g} deg): "
        + ", ".join(small)  # type: ignore[arg-type]
    )


def same_response_text(f: Finding) -> str | None:
    """Return the sets with the named set's very response, in words (None: there are none)."""
    same = f.evidence.get("same_response") or []
    if not same:
        return None
    parts = []
    for alt in same:  # type: ignore[union-attr]
        eq = alt["same_response"]
        parts.append(
            " + ".join(
                e + " " + ", ".join(f"{k} {v:.4g}" for k, v in eq["parameters"][e].items())
                for e in eq["effects"]
            )
            + _apart(eq["max_relative_difference"])
        )
    return (
        "the same response, with more parameters (at no frequency do they differ by "
        f"{MIN_DF_GAIN_DB:g} dB or {MIN_DF_GAIN_DEG:g} deg, the least a named effect changes; "
        "the fewer parameters are named): " + "; ".join(parts)
    )


def _apart(difference: float) -> str:
    """Say how far apart two responses are: identical (to the refit's precision), or by %."""
    if difference < IDENTICAL:
        return " (identical)"
    return f" (within {100 * difference:.2g} %)"


def below_text(below: float) -> str:
    """Return how far an alternative's BIC lies below the named one's, in words."""
    return f"BIC {abs(below):.1f} {'lower' if below >= 0 else 'higher'}"


def describe_alternative(alt: dict[str, object]) -> str:
    """Return an alternative in words: effects, parameters, BIC and held-out line error."""
    params: dict = alt.get("parameters") or {}  # type: ignore[assignment]
    parts = []
    for e in alt["effects"]:  # type: ignore[attr-defined]
        p = params.get(e) or {}
        parts.append(e + (" " + ", ".join(f"{k} {v:.4g}" for k, v in p.items()) if p else ""))
    text = f"{' + '.join(parts)} ({below_text(alt['delta_bic_below_named'])}"  # type: ignore[arg-type]
    held: dict = alt.get("held_out") or {}  # type: ignore[assignment]
    if held:
        text += (f"; held-out line error {held['chi2_per_line_before']:.2f} -> "
                 f"{held['chi2_per_line_after']:.2f} chi2/line")  # fmt: skip
    return text + ")"


# --- the held-out gate -------------------------------------------------------------------------


def _start(fit: SetFit) -> dict[str, list[float]]:
    return {e.effect: [e.value(k) for k in numeric_names(e.effect)] for e in fit.extensions}


def _scores(model: Model, x: Lines) -> dict[str, float]:
    """chi2 per line, describing-function error and VAF of a model on held-out lines."""
    pred = model.line_prediction(x)
    r = x.measured / pred
    ch = x.channel
    sel = (ch.t >= x.window[0] - 1e-9) & (ch.t < x.window[1] - 1e-9)
    y = ch.measured[sel]
    vaf = 100 * (1 - np.var(y - model.predict(ch)[sel]) / np.var(y))
    return {
        "chi2_per_line": x.chi2(pred) / x.size,
        "df_error_db": float(np.mean(np.abs(20 * np.log10(np.abs(r))))),
        "df_error_deg": float(np.mean(np.abs(np.degrees(np.angle(r))))),
        "vaf": float(vaf),
    }


def _mean(rows: list[dict[str, float]]) -> dict[str, float]:
    return {k: float(np.mean([r[k] for r in rows])) for k in rows[0]}


def folds(
    case: Case, dof: str, validation: Case | None = None, max_hz: float = np.inf
) -> tuple[list[tuple[list[Lines], list[Lines]]], str]:
    """Return fitting and held-out evidence: window halves both ways, or validation runs.

    Validation runs are used for a DOF when they drive it.
    """
    channels = case.of(dof)
    if validation is not None and validation.of(dof):
        fit_on = [lines(c, max_hz=max_hz) for c in channels]
        test_on = [lines(c, max_hz=max_hz) for c in validation.of(dof)]
        return [(fit_on, test_on)], "validation run(s)"
    out = []
    for i in (0, 1):
        fit_on, test_on = [], []
        for c in channels:
            halves = c.halves()
            full_sd = measured_line_sd(c)
            fit_on.append(lines(c, halves[i], full_sd, max_hz))
            test_on.append(lines(c, halves[1 - i], full_sd, max_hz))
        out.append((fit_on, test_on))
    return out, "other half of the measurement window (two-fold)"


def held_out(
    model: Model, fit: SetFit, folds_: list[tuple[list[Lines], list[Lines]]]
) -> dict[str, dict[str, float]]:
    """Held-out scores of the set with and without each member (refitted on each fold)."""
    start = _start(fit)
    out: dict[str, dict[str, float]] = {}
    for e in fit.effects:
        rest = tuple(x for x in fit.effects if x != e)
        before, after = [], []
        for fit_on, test_on in folds_:
            # coarse: a backlash play is held at its full-data value (each play is a
            # simulation); the linear parameters are refitted on the fold
            m1 = fit_set(fit.effects, model, fit_on, start, coarse=True).model(model)
            m0 = model
            if rest:
                without = fit_set(rest, model, fit_on, {k: start[k] for k in rest}, coarse=True)
                m0 = without.model(model)
            before += [_scores(m0, x) for x in test_on]
            after += [_scores(m1, x) for x in test_on]
        b, a = _mean(before), _mean(after)
        out[e] = {f"{k}_before": b[k] for k in b} | {f"{k}_after": a[k] for k in a}
    return out


def _negligible(gains: dict[str, dict[str, float]], delta: dict[str, float]) -> list[str]:
    """Members of a set, but its strongest, whose removal hardly changes the held-out DF."""
    if len(gains) < 2:
        return []
    strongest = max(gains, key=lambda e: delta.get(e, -np.inf))
    return [
        e for e, v in gains.items()
        if e != strongest
        and v["df_error_db_before"] - v["df_error_db_after"] < MIN_DF_GAIN_DB
        and v["df_error_deg_before"] - v["df_error_deg_after"] < MIN_DF_GAIN_DEG
    ]  # fmt: skip


def rival_explanations(
    sel: Selection, base: Model, evidence: Sequence[Lines],
    folds_: list[tuple[list[Lines], list[Lines]]], same: list[dict[str, object]],
) -> list[dict[str, object]]:  # fmt: skip
    """Return the alternatives (:func:`alternatives`) that pass the named set's gates too.

    An alternative must not sit at a bound of its search and must lower the held-out line
    error as the named set does (each with its held-out figures). One with as many parameters
    or more whose response, refitted, is the named set's
    (:func:`twin.diagnose.equivalence.same_response`) is no rival: it is set aside in
    ``same``, the list given, with its refitted parameters.
    """
    out = []
    channels = list({id(x.channel): x.channel for x in evidence}.values())
    named = sel.fit.extensions if sel.fit is not None else ()
    for alt in alternatives(sel, limit=None):
        key = tuple(sorted(alt["effects"]))  # type: ignore[call-overload]
        if key in sel.fits and at_bounds(sel.fits[key], base, evidence):
            continue
        params: dict = alt["parameters"]  # type: ignore[assignment]
        if sum(len(numeric_names(e)) for e in key) >= sel.fit.parameters:  # type: ignore[union-attr]
            eq = same_response(named, key, params, base.case, base.dof, channels)
            if eq is not None:
                same.append({**alt, "same_response": eq})
                continue
        start = {e: list(p.values()) for e, p in alt["parameters"].items()}  # type: ignore[union-attr]
        held = held_out_set(base, key, start, folds_)
        if held["chi2_per_line_after"] < held["chi2_per_line_before"]:
            out.append({**alt, "held_out": held})
        if len(out) == MAX_ALTERNATIVES:
            break
    return out


def held_out_set(
    model: Model, effects: Sequence[str], start: dict[str, list[float]],
    folds_: list[tuple[list[Lines], list[Lines]]],
) -> dict[str, float]:  # fmt: skip
    """Held-out chi2 per line of the nominal model and of a set refitted on each fold."""
    before, after = [], []
    for fit_on, test_on in folds_:
        m1 = fit_set(tuple(sorted(effects)), model, fit_on, start, coarse=True).model(model)
        before += [_scores(model, x) for x in test_on]
        after += [_scores(m1, x) for x in test_on]
    return {"chi2_per_line_before": _mean(before)["chi2_per_line"],
            "chi2_per_line_after": _mean(after)["chi2_per_line"]}  # fmt: skip


def name_causes(
    case: Case,
    dof: str,
    base: Model,
    validation: Case | None = None,
    effects: Sequence[str] = DYNAMIC,
    progress: ProgressFn | None = None,
    max_hz: float = np.inf,
) -> tuple[list[Finding], Model, Selection]:
    """Select, gate on held-out data, and return the findings of one DOF with the model."""
    evidence = [lines(c, max_hz=max_hz) for c in case.of(dof)]
    sel = select(base, evidence, effects, progress)
    if sel.fit is None:
        return [], base, sel
    fold_list, how = folds(case, dof, validation, max_hz)
    fit, delta = sel.fit, dict(sel.delta_bic)
    chi0, n = base.chi2(evidence), sel.observations
    dropped: list[str] = []
    negligible: list[str] = []
    while True:  # drop what the held-out data do not support, re-check what is left
        edge = at_bounds(fit, base, evidence)
        if edge:  # a limit reached: the set explains the runs only beyond what is searched
            return [], base, Selection(None, {}, sel.table, n, tuple(edge))
        gains = held_out(base, fit, fold_list)
        g = {e: (gains[e]["chi2_per_line_before"], gains[e]["chi2_per_line_after"]) for e in gains}
        bad = [e for e in fit.effects if not g[e][1] < g[e][0]]
        small = [e for e in _negligible(gains, delta) if e not in bad]
        if not bad and not small:
            break
        dropped += bad
        negligible += small
        bad += small
        keep = tuple(e for e in fit.effects if e not in bad)
        if not keep:
            return [], base, Selection(None, {}, sel.table, n)
        fit = fit_set(keep, base, evidence, {k: v for k, v in _start(fit).items() if k in keep})
        delta = {}
        for e in keep:
            rest = tuple(x for x in keep if x != e)
            ref = fit_set(rest, base, evidence, {k: _start(fit)[k] for k in rest}) if rest else None
            extra = fit.parameters - (ref.parameters if ref else 0)
            delta[e] = bic_gain(ref.chi2 if ref else chi0, fit.chi2, extra, n)
        if min(delta.values()) <= BIC_MARGIN:  # what is left is not named on its own
            return [], base, Selection(None, {}, sel.table, n)
    model = fit.model(base)
    same: list[dict[str, object]] = []
    # the alternatives of what is named, measured against its support: where the held-out
    # data took a member out, the set left as refitted; where only effects too small to matter
    # were left out, the set they were fitted in (they are part of the same explanation)
    if fit is sel.fit:
        named = sel
    else:
        support = fit if dropped else sel.fit
        gain = bic_gain(chi0, support.chi2, support.parameters, n)
        table = [r | {"delta_bic": gain} if set(r["effects"]) == set(fit.effects) else r
                 for r in sel.table]  # type: ignore[arg-type]  # fmt: skip
        named = Selection(fit, delta, table, n, fits=sel.fits)
    rivals = rival_explanations(named, base, evidence, fold_list, same)
    # an ambiguous set is compared with its alternatives as they are: each against the nominal
    against_nominal = held_out_set(base, fit.effects, _start(fit), fold_list) if rivals else {}
    findings = []
    for ext in fit.extensions:
        e = ext.effect
        findings.append(
            Finding(
                ext,
                {
                    "criterion": f"BIC improvement > {BIC_MARGIN:g} for the set and for each "
                    "member; held-out line error falls",
                    "delta_bic": float(delta.get(e, np.nan)),
                    "set": list(fit.effects),
                    "chi2_nominal": float(base.chi2(evidence)),
                    "chi2_extended": float(fit.chi2),
                    "observations": int(sel.observations),
                    "parameter_std": fit.std.get(e, {}),
                    "correlation": fit.correlation,
                    "alternatives": rivals,
                    "ambiguous": bool(rivals),
                    "same_response": same,
                    "held_out_against_nominal": against_nominal,
                    "dropped_by_held_out_gate": dropped,
                    "dropped_as_negligible": negligible,
                    "window_s": [list(c.window) for c in case.of(dof)],
                    "lines_hz": sorted({float(f) for c in case.of(dof) for f in c.lines_hz}),
                },
                {"held_out": how, **gains[e]},
            )
        )
    findings.sort(key=lambda f: -f.delta_bic)
    return findings, model, sel
