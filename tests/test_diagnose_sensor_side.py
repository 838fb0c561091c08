"""A sensor filter or a platform lag: the same lines, told apart by the sensor's own noise.

A first-order filter inside the IMU and a first-order lag of the platform (Eq 5.11's t_m: a
heavier cabin behind the same PD) give the same describing function; only a filter in the
sensor filters the sensor's noise. Runs are drawn with either truth (and, from the full
MuJoCo model, with a heavier cabin); the diagnosis must name the right side.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from twin.chain.config import motion_system
from twin.chain.extensions import Extension
from twin.diagnose.diagnosis import diagnose
from twin.diagnose.hidden import record_runs
from twin.diagnose.select import MAX_ALTERNATIVES, Finding
from twin.diagnose.sensor_side import platform_reading, rule_out_by_noise, ruled_out_text
from twin.platform.payload import Payload
from twin.platform.platform_physics import PlatformPhysics

CHANNEL = {"pitch": "q", "roll": "p", "heave": "az"}


def _named(d) -> list[tuple[str, str | None]]:
    return [(f.extension.effect, f.evidence.get("side", {}).get("verdict")) for f in d.findings]


@pytest.mark.parametrize(("dof", "cutoff_hz"), [
    ("pitch", 3.0), pytest.param("roll", 8.0, marks=pytest.mark.slow)])  # fmt: skip
def test_a_platform_lag_is_named_as_the_platforms_not_as_a_sensor_filter(dof, cutoff_hz,
                                                                        tmp_path):  # fmt: skip
    srs = motion_system("srs")
    lag = 1 / (2 * np.pi * cutoff_hz)
    truth = srs.replace(extensions=(Extension("platform_lag", {"lag_s": lag}, (dof,)),))
    d = diagnose(record_runs(truth, srs, dof, tmp_path, 3))
    assert _named(d) == [("platform_lag", "platform")]
    f = d.findings[0]
    assert f.extension.value("lag_s") == pytest.approx(lag, rel=0.1)
    assert f.extension.dofs == (dof,)
    assert f.evidence["side"]["noise_evidence_platform_over_sensor"] > 10  # BIC margin
    assert d.extended_config.of("platform_lag")  # the extended model carries it


@pytest.mark.parametrize(("dof", "cutoff_hz"), [
    ("pitch", 3.0), pytest.param("roll", 8.0, marks=pytest.mark.slow)])  # fmt: skip
def test_a_sensor_filter_stays_the_sensors(dof, cutoff_hz, tmp_path):
    srs = motion_system("srs")
    filt = Extension("sensor_filter", {"cutoff_hz": cutoff_hz, "channels": (CHANNEL[dof],)}, ())
    d = diagnose(record_runs(srs.replace(extensions=(filt,)), srs, dof, tmp_path, 4))
    assert _named(d) == [("sensor_filter", "sensor")]
    assert d.findings[0].evidence["side"]["noise_evidence_platform_over_sensor"] < -10


@pytest.mark.slow
@pytest.mark.parametrize("seed", [5, 6, 7])
def test_a_heavier_cabin_in_full_physics_is_never_named_a_sensor_filter(seed, tmp_path):
    """The MPI's cabin 60 % heavier, simulated and diagnosed with the full MuJoCo model: pitch
    lags more (Table 5.5's t_m = 12.4 ms grows with the inertia by about 7 ms), which the
    lines alone read as a 20 Hz filter on the gyro. Named: the platform lag, or (where the
    noise cannot tell: less than an octave of noise above 20 Hz in the band) the filter with
    the lag beside it as equally likely; never a filter the noise confirms."""
    mpi = motion_system("mpi")
    heavy = mpi.replace(physics=PlatformPhysics(payload=Payload.scaling("mpi", 1.6)))
    d = diagnose(record_runs(heavy, mpi, "pitch", tmp_path, seed, model="full"), model="full")
    assert ("sensor_filter", "sensor") not in _named(d)
    lags = [f.extension for f in d.findings if f.extension.effect == "platform_lag"]
    for lag in lags:
        assert lag.dofs == ("pitch",) and 0.005 < lag.value("lag_s") < 0.05


def test_the_platform_reading_has_the_sensor_filters_line_response():
    sensor = Extension("sensor_filter", {"cutoff_hz": 5.0, "channels": ("q",)}, ())
    platform = platform_reading(sensor, "pitch")
    f = np.array([0.1, 1.0, 5.0, 12.0])
    assert np.allclose(platform.response(f), sensor.response(f), rtol=1e-12)
    cfg = motion_system("srs").replace(extensions=(platform,))
    h = cfg.response_at_hz(f)[:, 4] / motion_system("srs").response_at_hz(f)[:, 4]
    assert np.allclose(h, sensor.response(f), rtol=1e-9)  # the chain's block is the same lag


def _finding(verdict: str, alternatives: list[dict], ambiguous: bool = True) -> Finding:
    sensor = Extension("sensor_filter", {"cutoff_hz": 5.0, "channels": ("q",)}, ("pitch",))
    side = {"verdict": verdict, "noise_evidence_platform_over_sensor": -240.0}
    evidence = {"delta_bic": 900.0, "set": ["sensor_filter"], "side": side,
                "alternatives": alternatives, "ambiguous": ambiguous}  # fmt: skip
    return Finding(sensor, evidence)


def _alt(below: float = 6.7, **parameters) -> dict:
    return {"effects": sorted(parameters), "parameters": parameters, "delta_bic_below_named": below}


DELAY_RESONANCE = _alt(8.0, delay={"extra_delay_s": 0.03},
                       resonance={"frequency_hz": 6.0, "damping": 0.7})  # fmt: skip


@pytest.mark.parametrize(
    ("verdict", "alternatives", "ambiguous"),
    [
        ("undecided", [DELAY_RESONANCE], True),  # the noise cannot tell
        ("platform", [DELAY_RESONANCE], True),
        ("sensor", [DELAY_RESONANCE], False),  # alternatives beside a finding not ambiguous
        ("sensor", [DELAY_RESONANCE] * MAX_ALTERNATIVES, True),  # others may not be weighed
        ("sensor", [_alt(delay={"extra_delay_s": 0.0}, sensor_filter={"cutoff_hz": 6.0})], True),
        ("sensor", [_alt(backlash={"play": 0.002})], True),  # its own off-line power
    ],
)
def test_what_the_noise_leaves_alone(verdict, alternatives, ambiguous):
    """Nothing is ruled out (nor a model needed) where the noise cannot or should not decide."""
    f = _finding(verdict, alternatives, ambiguous)
    (g,) = rule_out_by_noise(None, [f])  # type: ignore[arg-type]
    assert g is f and ruled_out_text(g) is None


def test_a_filtered_noise_rules_out_an_alternative_outside_the_sensor(tmp_path):
    """Delay + resonance may match a 3 Hz gyro filter's lines; not the noise it filtered."""
    srs = motion_system("srs")
    filt = Extension("sensor_filter", {"cutoff_hz": 3.0, "channels": ("q",)}, ())
    d = diagnose(record_runs(srs.replace(extensions=(filt,)), srs, "pitch", tmp_path, 4))
    report = d.dofs["pitch"]
    (named,) = report.findings
    inside = _alt(3.0, gain={"gain": 0.98}, sensor_filter={"cutoff_hz": 3.2})
    f = replace(named, evidence={**named.evidence, "ambiguous": True,
                                 "alternatives": [DELAY_RESONANCE, inside]})  # fmt: skip
    (g,) = rule_out_by_noise(report.model, [f])
    assert g.ambiguous and g.evidence["alternatives"] == [inside]  # the other filter stays
    (gone,) = g.evidence["ruled_out_by_noise"]
    assert gone["effects"] == ["delay", "resonance"]
    assert gone["noise_evidence_against"] > 10  # its own, beyond the BIC margin
    text = ruled_out_text(g)
    assert text is not None and "delay extra_delay_s 0.03 + resonance" in text
