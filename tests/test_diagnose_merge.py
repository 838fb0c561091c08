"""One finding per effect across DOFs (twin.diagnose.merge): synthetic findings, no simulation."""

from __future__ import annotations

import pytest

from twin.chain.extensions import Extension
from twin.diagnose.merge import merge_across_dofs
from twin.diagnose.select import Finding


def _delay(dof: str, value: float, sd: float, dbic: float) -> Finding:
    gain = {"held_out": "halves", "chi2_per_line_before": 4.0, "chi2_per_line_after": 1.0}
    return Finding(
        Extension("delay", {"extra_delay_s": value}, (dof,)),
        {"delta_bic": dbic, "parameter_std": {"extra_delay_s": sd}},
        gain,
    )


def test_agreeing_findings_in_two_dofs_are_one_finding():
    merged = merge_across_dofs(
        [_delay("heave", 0.030, 0.002, 50.0), _delay("pitch", 0.034, 0.001, 80.0)]
    )
    assert len(merged) == 1
    f = merged[0]
    assert set(f.extension.dofs) == {"heave", "pitch"}
    # inverse-variance weights 1/4e-6 and 1/1e-6: (0.030 * 0.25 + 0.034 * 1) / 1.25
    assert f.extension.value("extra_delay_s") == pytest.approx(0.0332, abs=1e-6)
    # combined sd: 1 / sqrt(1 / 0.002^2 + 1 / 0.001^2)
    assert f.evidence["parameter_std"]["extra_delay_s"] == pytest.approx(8.944e-4, rel=1e-3)
    assert f.delta_bic == pytest.approx(130.0)
    assert set(f.gain["per_dof"]) == {"heave", "pitch"}
    assert f.gain["chi2_per_line_after"] == pytest.approx(1.0)


def test_disagreeing_findings_stay_apart():
    merged = merge_across_dofs(
        [_delay("heave", 0.030, 0.001, 50.0), _delay("pitch", 0.045, 0.001, 80.0)]
    )
    assert [f.extension.dofs for f in merged] == [("pitch",), ("heave",)]


def test_a_finding_without_a_standard_deviation_is_not_merged():
    a, b = _delay("heave", 0.030, 0.001, 50.0), _delay("pitch", 0.030, float("nan"), 80.0)
    assert len(merge_across_dofs([a, b])) == 2
