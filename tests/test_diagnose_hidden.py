"""twin diagnose on data that differ from the twin in more than one way.

The generator (:mod:`twin.diagnose.hidden`) draws, from the seed alone, a platform (MPI or SRS
with their nominal noise), a DOF (any of the six), one or two effects with random parameters
and a recording IMU whose noise is 0.3-3 times the data sheet's (the diagnosis is not told:
it measures it), kept only where the two Table 5.2 runs could reveal the effects (expected BIC
improvement >= 3x the naming threshold, Cramér-Rao sd <= 1/3 of the tolerance, jointly; two
effects only where no other single or pair of linear effects explains them).

Acceptance (slow suite, seeds not tuned): a single effect (any of the eight, motion noise
included) named first with its parameter
(delay +-5 ms, others +-20 %) in >= 95 % of draws; clean runs with mismatched IMU noise: no
dynamic cause in >= 95 %; two effects at once: both named in >= 85 %. The default suite runs
two of the cases that failed before (a quieter IMU, gain + delay) and a clean run with a
quieter IMU; the slow suite the others (resonance + gyro filter, a delay behind the 1 Hz
filter).
"""

from __future__ import annotations

import numpy as np
import pytest

from twin.chain.config import motion_system
from twin.chain.extensions import EFFECTS, Extension
from twin.diagnose.diagnosis import diagnose
from twin.diagnose.hidden import (
    DOFS,
    DRAWN,
    RELATIVE_TOLERANCE,
    TOLERANCE,
    Hidden,
    clean,
    draw,
    record,
    record_runs,
)

#: Effects whose one-seed case runs in the default suite (a quieter-IMU delay case runs there
#: too, below); the rest run in the slow suite.
FAST_EFFECTS: tuple[str, ...] = ()


def _parameter_errors(true: Extension, found: Extension) -> list[str]:
    errors = []
    for name, v in true.parameters.items():
        if name == "channels":
            if tuple(v) != tuple(found.parameters[name]):  # type: ignore[arg-type]
                errors.append(f"channels {found.parameters[name]} for {v}")
            continue
        tol = TOLERANCE.get(name, RELATIVE_TOLERANCE * abs(float(v)))  # type: ignore[arg-type]
        if abs(found.value(name) - float(v)) > tol:  # type: ignore[arg-type]
            errors.append(f"{name} {found.value(name):.4g} for {float(v):.4g} (tol {tol:.3g})")
    return errors


def _held_out_improves(finding) -> bool:
    g = finding.gain
    if "chi2_per_line_before" in g:
        return g["chi2_per_line_after"] < g["chi2_per_line_before"]
    return g["loglik_per_bin_after"] > g["loglik_per_bin_before"]


def check_single(h: Hidden, d) -> list[str]:
    """What is wrong with the diagnosis of one hidden effect (empty: passed)."""
    truth = h.extensions[0]
    if not d.findings:
        return ["no finding"]
    top = d.findings[0]
    if top.extension.effect != truth.effect:
        return [f"named {top.extension.describe()} for {truth.describe()}"]
    errors = _parameter_errors(truth, top.extension)
    if not _held_out_improves(top):
        errors.append(f"held-out error did not fall: {top.gain}")
    return errors


def check_all(h: Hidden, d) -> list[str]:
    """Every hidden effect named (with its parameters: reported, not required)."""
    found = {f.extension.effect for f in d.findings}
    missing = [e.describe() for e in h.extensions if e.effect not in found]
    return [f"missing {m}; named {[f.extension.describe() for f in d.findings]}" for m in missing]


def dynamic_findings(d) -> list[str]:
    """Findings other than motion noise (a clean run must have none)."""
    return [f.extension.describe() for f in d.findings if f.extension.effect != "noise"]


def _diagnose(h: Hidden, tmp_path):
    return diagnose(record(h, tmp_path), seed=h.seed)


#: Draws tried per seed: motion noise is detectable only with a quiet IMU or a large scale.
MAX_REDRAWS = 400


@pytest.mark.parametrize(
    "effect",
    [e if e in FAST_EFFECTS else pytest.param(e, marks=pytest.mark.slow) for e in DRAWN],
)
def test_a_hidden_effect_is_named_whatever_the_imu_noise(effect, tmp_path):
    """One seed per effect type, IMU noise 0.3-3x nominal: named first with its parameter."""
    h = draw(1000 * list(EFFECTS).index(effect), effect, max_redraws=MAX_REDRAWS)
    assert check_single(h, _diagnose(h, tmp_path)) == [], h


@pytest.mark.slow
def test_motion_noise_is_named_when_the_imu_noise_is_known(tmp_path):
    """Motion noise (Eq 5.10, the MPI's heave) with the IMU's noise known (``imu_noise``, as a
    recording at rest gives it): named with its scale within 20 % in 5 draws of 5."""
    failures = []
    for i in range(5):
        h = draw(7000 + i, "noise", imu_noise=(0.3, 3.0), imu_known=True, max_redraws=200)
        d = diagnose(record(h, tmp_path / str(i)), seed=h.seed, imu_noise=h.imu_noise)
        failures += [f"seed {h.seed}: {e}" for e in check_single(h, d)]
    assert failures == []


@pytest.mark.parametrize("imu_noise", [0.3, pytest.param(3.0, marks=pytest.mark.slow)])
def test_clean_runs_with_another_imu_name_no_dynamic_cause(imu_noise, tmp_path):
    """A quieter and a noisier IMU than the data sheet, nothing else: no dynamic cause, and the
    IMU's noise is measured (within 25 %)."""
    h = clean(int(imu_noise * 10), imu_noise, dofs=DOFS)
    d = _diagnose(h, tmp_path)
    assert dynamic_findings(d) == []
    measured = d.dofs[h.dof].noise.fit.to_json()["imu_noise_scale"]
    assert measured == pytest.approx(imu_noise, rel=0.25)


# --- the cases that failed before, made by code other than the generator's draw -----------------


def _runs(truth_exts, nominal: str, dof: str, imu_noise: float, tmp_path, seed: int = 5):
    nom = motion_system(nominal)
    h = Hidden(seed, nom, dof, tuple(truth_exts), imu_noise)
    return h, record_runs(h.truth, nom, dof, tmp_path, seed, imu=h.imu)


def test_a_quiet_imu_and_a_heave_delay_is_a_delay_not_a_sensor_filter(tmp_path):
    """Before: +30 ms in heave with a quieter IMU was named a 3.1 Hz sensor filter."""
    ext = Extension("delay", {"extra_delay_s": 0.030}, ("heave",))
    h, runs = _runs([ext], "srs", "heave", 0.3, tmp_path)
    d = diagnose(runs, seed=5)
    assert check_single(h, d) == []
    assert dynamic_findings(d) == [d.findings[0].extension.describe()]


def _assert_named_with_parameters(exts: list[Extension], tmp_path) -> None:
    """SRS heave runs with ``exts``: every one named, each parameter within tolerance."""
    h, runs = _runs(exts, "srs", "heave", 1.0, tmp_path)
    d = diagnose(runs, seed=5)
    assert check_all(h, d) == []
    found = {f.extension.effect: f.extension for f in d.findings}
    for e in exts:
        assert _parameter_errors(e, found[e.effect]) == []


@pytest.mark.slow
def test_a_gain_before_a_backlash_leaves_the_play_as_it_is(tmp_path):
    """The chain applies a gain *before* the backlash; fitted in the other order a gain of 1.4
    made a 3 mm play read 2.07 mm. Both within the hidden-effect tolerance (20 %)."""
    _assert_named_with_parameters(
        [Extension("gain", {"gain": 1.4}, ("heave",)),
         Extension("backlash", {"play": 0.003}, ("heave",))], tmp_path)  # fmt: skip


def test_gain_and_delay_in_heave_are_both_named(tmp_path):
    """Before: gain 0.9 + 25 ms in heave: neither was found."""
    _assert_named_with_parameters(
        [Extension("gain", {"gain": 0.9}, ("heave",)),
         Extension("delay", {"extra_delay_s": 0.025}, ("heave",))], tmp_path)  # fmt: skip


@pytest.mark.slow
def test_a_resonance_and_a_gyro_filter_in_pitch_are_both_named(tmp_path):
    """Before: a 7 Hz resonance + a 5 Hz gyro filter in pitch was named a 44 ms delay."""
    exts = [
        Extension("resonance", {"frequency_hz": 7.0, "damping": 0.2}, ("pitch",)),
        Extension("sensor_filter", {"cutoff_hz": 5.0, "channels": ("q",)}, ("pitch",)),
    ]
    h, runs = _runs(exts, "srs", "pitch", 1.0, tmp_path)
    d = diagnose(runs, seed=5)
    assert check_all(h, d) == []
    corr = d.findings[0].evidence["correlation"]
    assert len(corr["labels"]) == 3 and np.shape(corr["matrix"]) == (3, 3)


@pytest.mark.slow
def test_a_delay_behind_the_1_hz_filter_is_found_or_said_undetectable(tmp_path):
    """Before: 20 ms behind the 1 Hz filter gave no finding and no statement of what size of
    delay the run could have shown. Now: either the delay is named within 5 ms, or the report
    says the smallest detectable delay, and it is above 20 ms."""
    nominal = motion_system("mpi").replace(filter_break_hz=1.0)
    ext = Extension("delay", {"extra_delay_s": 0.020}, ("heave",))
    runs = record_runs(nominal.replace(extensions=(ext,)), nominal, "heave", tmp_path, 6)
    d = diagnose(runs, seed=6)
    doc = d.to_dict()
    detectable = doc["nominal"]["dofs"]["heave"]["smallest_detectable"]["delay"]
    assert "would have been found" in detectable["statement"]
    if d.findings:
        assert d.findings[0].extension.effect == "delay"
        assert d.findings[0].extension.value("extra_delay_s") == pytest.approx(0.02, abs=0.005)
    else:
        assert detectable["values"][1] is None or detectable["values"][1] > 0.020


# --- acceptance rates over many draws (slow) ----------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("effect", DRAWN)
def test_single_effect_acceptance_rate(effect, tmp_path):
    """20 draws per effect type (any DOF, IMU noise 0.3-3x, not told to the diagnosis): named
    first with its parameter in at least 19 (95 %). Motion noise exists in the MPI's heave
    only; with the IMU's level unknown it is told from the IMU's noise by its shape below
    1 Hz, so the drawing rule admits it only large or behind a quiet IMU."""
    failures = []
    for i in range(1, 21):
        h = draw(1000 * list(EFFECTS).index(effect) + i, effect, max_redraws=MAX_REDRAWS)
        failures += [
            f"seed {h.seed} {h.dof}: {e}" for e in check_single(h, _diagnose(h, tmp_path / str(i)))
        ]
    print(f"{effect}: {20 - len(failures)} of 20 named first with the parameter", failures)
    assert len(failures) <= 1, failures


@pytest.mark.slow
def test_clean_acceptance_rate(tmp_path):
    """40 clean draws (any DOF, IMU noise 0.3-3x): a dynamic cause named in at most 2 (5 %)."""
    bad = {}
    for seed in range(200, 240):
        h = clean(seed, (0.3, 3.0), dofs=DOFS)
        found = dynamic_findings(_diagnose(h, tmp_path / str(seed)))
        if found:
            bad[seed] = found
    print(f"clean: a dynamic cause named in {len(bad)} of 40", bad)
    assert len(bad) <= 2, bad


@pytest.mark.slow
@pytest.mark.parametrize("block", range(2))
def test_two_effect_acceptance_rate(block, tmp_path):
    """2 x 20 draws of two effects at once (any pair the detectability rule admits): both named
    in at least 17 of each 20 (85 %)."""
    failures = {}  # per draw: a draw with both effects missing is one miss, not two
    for i in range(20):
        h = draw(5000 + 100 * block + i, count=2)
        errors = check_all(h, _diagnose(h, tmp_path / str(i)))
        if errors:
            failures[f"seed {h.seed} {h.dof}"] = errors
    print(f"two effects, block {block}: both named in {20 - len(failures)} of 20", failures)
    assert len(failures) <= 3, failures
