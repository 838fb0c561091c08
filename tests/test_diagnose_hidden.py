"""twin diagnose: hide an effect in a run, require the diagnosis to name it and measure the gain.

The generator (:mod:`twin.diagnose.hidden`) draws, from the seed alone, a platform (MPI or SRS
with their nominal noise), a DOF (heave or pitch) and one effect with random parameters, kept
only where the two Table 5.2 runs could reveal it (expected BIC improvement >= 3x the naming
threshold and Cramér-Rao sd <= 1/3 of the tolerance). The default suite checks one seed per
effect type; the slow suite checks many and states the pass rate. Clean runs, the thesis' own
cases and the command line are in test_diagnose.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from twin.chain.extensions import EFFECTS
from twin.diagnose.diagnosis import diagnose
from twin.diagnose.hidden import RELATIVE_TOLERANCE, TOLERANCE, draw, record


def _check(hidden, d) -> list[str]:
    """Return what is wrong with a diagnosis of a hidden effect (empty: passed)."""
    if not d.findings:
        return ["no finding"]
    top = d.findings[0]
    if top.extension.effect != hidden.extension.effect:
        return [f"named {top.extension.describe()} for {hidden.extension.describe()}"]
    errors = []
    for name, true in hidden.extension.parameters.items():
        if name == "channels":
            if tuple(true) != tuple(top.extension.parameters[name]):
                errors.append(f"channels {top.extension.parameters[name]} for {true}")
            continue
        tol = TOLERANCE.get(name, RELATIVE_TOLERANCE * abs(true))
        if abs(top.extension.value(name) - true) > tol:
            errors.append(f"{name} {top.extension.value(name):.4g} for {true:.4g} (tol {tol:.3g})")
    g = top.gain  # the gain on held-out data is positive whenever a true effect is found
    if not g["loglik_per_bin_after"] > g["loglik_per_bin_before"]:
        errors.append(f"held-out log-likelihood fell: {g}")
    if hidden.extension.effect != "noise" and not g["vaf_after"] > g["vaf_before"]:
        errors.append(f"held-out VAF fell: {g['vaf_before']:.2f} -> {g['vaf_after']:.2f}")
    return errors


def _hidden(seed: int, effect: str, tmp_path):
    h = draw(seed, effect)
    return h, diagnose(record(h, tmp_path), seed=seed)


#: Effects whose diagnosis simulates the twin inside the fit (backlash: non-linear) or many
#: noise realisations (noise): 20-40 s each, so their one-seed case runs with the slow suite
#: (the eight-seed test below covers them too); the extension blocks themselves are tested in
#: test_diagnose_extensions.py and test_chain_stream.py.
SLOW_EFFECTS = ("backlash", "noise")


@pytest.mark.parametrize(
    "effect",
    [pytest.param(e, marks=pytest.mark.slow) if e in SLOW_EFFECTS else e for e in EFFECTS],
)
def test_a_hidden_effect_is_named_and_its_parameter_recovered(effect, tmp_path):
    """One seed per effect type: named first; delay within 5 ms, others within 20 %."""
    h, d = _hidden(1000 * list(EFFECTS).index(effect), effect, tmp_path)
    assert _check(h, d) == [], h


@pytest.mark.slow
def test_hidden_effects_over_many_seeds(tmp_path):
    """Eight seeds per effect type (64 cases): every one named and recovered."""
    failures = []
    for effect in EFFECTS:
        for i in range(1, 9):
            h, d = _hidden(
                1000 * list(EFFECTS).index(effect) + i, effect, tmp_path / f"{effect}{i}"
            )
            failures += [f"{effect} seed {h.seed}: {e}" for e in _check(h, d)]
    assert failures == []


def test_runs_without_signal_design_are_diagnosed_too(tmp_path):
    """A recorded run has no ``signal`` in meta.json: lines and window are inferred."""
    h = draw(7, "gain")
    runs = record(h, tmp_path, with_signal_meta=False)
    d = diagnose(runs, seed=7)
    assert _check(h, d) == []
    assert np.isfinite(d.dofs[h.dof].lines.db).all()
