"""One finding per effect across DOFs: an effect seen with the same parameters in several DOFs.

A delay of the motion software, a gain of the drives or a filter of the IMU usually acts on
every DOF. Findings of one effect in several DOFs are one finding with those DOFs when every
numeric parameter agrees within ``AGREEMENT`` combined standard deviations; its parameters are
the inverse-variance weighted means, its evidence the sum of the BIC improvements, with each
DOF's own evidence and held-out gain kept under ``per_dof``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from twin.chain.extensions import Extension
from twin.diagnose.candidates import numeric_names
from twin.diagnose.select import Finding

#: Parameters agree when they differ by at most this many combined standard deviations.
AGREEMENT = 3.0


def _std(f: Finding, name: str) -> float:
    sd = f.evidence.get("parameter_std", {})
    v = sd.get(name) if isinstance(sd, dict) else None
    return float(v) if isinstance(v, float) and np.isfinite(v) and v > 0 else float("nan")


def agree(a: Finding, b: Finding) -> bool:
    """Whether two findings of one effect have the same parameters within their uncertainty."""
    if a.extension.effect != b.extension.effect:
        return False
    for k in numeric_names(a.extension.effect):
        sa, sb = _std(a, k), _std(b, k)
        if not (np.isfinite(sa) and np.isfinite(sb)):
            return False
        if abs(a.extension.value(k) - b.extension.value(k)) > AGREEMENT * np.hypot(sa, sb):
            return False
    return True


def merged(group: Sequence[Finding]) -> Finding:
    """Return one finding for a group of agreeing findings of one effect."""
    if len(group) == 1:
        return group[0]
    effect = group[0].extension.effect
    pars: dict[str, object] = {}
    std: dict[str, float] = {}
    for k in numeric_names(effect):
        w = np.array([1.0 / _std(f, k) ** 2 for f in group])
        v = np.array([f.extension.value(k) for f in group])
        pars[k] = float(w @ v / w.sum())
        std[k] = float(1.0 / np.sqrt(w.sum()))
    channels = [c for f in group for c in f.extension.parameters.get("channels", ())]  # type: ignore[attr-defined]
    if channels:
        pars["channels"] = tuple(dict.fromkeys(channels))
    dofs = tuple(d for f in group for d in f.extension.dofs)
    evidence = {
        "criterion": group[0].evidence.get("criterion"),
        "delta_bic": float(sum(f.delta_bic for f in group)),
        "parameter_std": std,
        "merged": f"one effect in {len(group)} DOFs: parameters agree within {AGREEMENT:g} "
        "combined standard deviations; values are inverse-variance weighted means",
        "per_dof": {",".join(f.extension.dofs): f.evidence for f in group},
    }
    # held-out figures: the mean over the DOFs of each number they all report
    keys = set.intersection(*(set(f.gain) for f in group))
    gain: dict[str, object] = {
        k: float(np.mean([f.gain[k] for f in group]))  # type: ignore[arg-type]
        for k in sorted(keys)
        if all(isinstance(f.gain[k], float) for f in group)
    }
    gain["held_out"] = "; ".join(sorted({str(f.gain.get("held_out")) for f in group}))
    gain["per_dof"] = {",".join(f.extension.dofs): f.gain for f in group}
    return Finding(Extension(effect, pars, dofs), evidence, gain)


def merge_across_dofs(findings: Sequence[Finding]) -> list[Finding]:
    """Group agreeing findings of each effect over DOFs (greedy, strongest first)."""
    groups: list[list[Finding]] = []
    for f in sorted(findings, key=lambda f: -f.delta_bic):
        for g in groups:
            if all(agree(f, x) and not set(f.extension.dofs) & set(x.extension.dofs) for x in g):
                g.append(f)
                break
        else:
            groups.append([f])
    return sorted((merged(g) for g in groups), key=lambda f: -f.delta_bic)
