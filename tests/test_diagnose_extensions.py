"""Model extensions (the fixed vocabulary of twin diagnose) as blocks of the twin."""

from __future__ import annotations

import json

import numpy as np
import pytest

from twin.agard.df import run_df
from twin.agard.session import Session
from twin.chain.config import load_config, motion_system
from twin.chain.extensions import EFFECTS, Extension, backlash
from twin.chain.simulate import default_imu
from twin.core.errors import SignalError, UnknownPlatformError
from twin.measurement.measure import Bench

LINEAR_CASES = [
    Extension("delay", {"extra_delay_s": 0.04}, ("heave",)),
    Extension("gain", {"gain": 1.2}, ("heave",)),
    Extension("platform_filter", {"break_hz": 3.0}, ("heave",)),
    Extension("resonance", {"frequency_hz": 6.0, "damping": 0.3}, ("heave",)),
    Extension("lead", {"time_constant_s": 0.023}, ("heave",)),
    Extension("sensor_filter", {"cutoff_hz": 4.0, "channels": ("az",)}, ()),
    Extension("platform_lag", {"lag_s": 0.02}, ("heave",)),
]


def test_vocabulary_is_the_fixed_set_of_effects():
    assert dict(EFFECTS) == {
        "delay": ("extra_delay_s",), "gain": ("gain",), "platform_filter": ("break_hz",),
        "resonance": ("frequency_hz", "damping"), "lead": ("time_constant_s",),
        "sensor_filter": ("cutoff_hz", "channels"), "backlash": ("play",),
        "platform_lag": ("lag_s",), "noise": ("scale",),
        "imu_alignment": ("roll_rad", "pitch_rad", "yaw_rad"),
    }  # fmt: skip


@pytest.mark.parametrize(
    ("effect", "pars", "dofs", "match"),
    [
        ("wobble", {}, (), "unknown effect 'wobble'"),
        ("delay", {"delay": 0.1}, (), "unknown parameter 'delay'.*allowed: extra_delay_s"),
        ("delay", {}, (), "takes parameters extra_delay_s; got none"),
        ("gain", {"gain": -1.0}, (), r"gain must be a number in \[0.001, 1000\]; got -1.0"),
        ("gain", {"gain": float("nan")}, (), "must be a number"),
        ("gain", {"gain": "2"}, (), "must be a number"),
        ("gain", {"gain": 1e300}, (), r"in \[0.001, 1000\]"),
        ("platform_filter", {"break_hz": 1e300}, (), r"break_hz must be a number in \[0.01, 10"),
        ("delay", {"extra_delay_s": [0.1]}, (), "extra_delay_s must be a number"),
        ("resonance", {"frequency_hz": 5.0, "damping": 0.0}, (), r"damping must be a number in"),
        ("sensor_filter", {"cutoff_hz": 4.0, "channels": ("qq",)}, (), "channels must be"),
        ("sensor_filter", {"cutoff_hz": 4.0, "channels": "q"}, (), "channels must be"),
        ("backlash", {"play": -0.1}, (), r"play must be a number in \[0, 10\]"),
        ("gain", {"gain": 1.1}, ("yaw_rate",), "unknown DOF 'yaw_rate'"),
    ],
)
def test_bad_extensions_are_refused(effect, pars, dofs, match):
    with pytest.raises(SignalError, match=match):
        Extension(effect, pars, dofs)


def test_backlash_is_a_dead_band():
    x = np.concatenate([np.linspace(0, 1, 11), np.linspace(1, -1, 21)])
    y = backlash(x, 0.2)
    assert np.all(np.abs(x - y) <= 0.1 + 1e-12)  # never further than half the play
    # on reversal the output stays put until the input has travelled the whole play
    top = int(np.argmax(x))  # x = 1.0, 1.0, 0.9, 0.8 (held: 0.2 travelled), 0.7 (moves)
    assert np.allclose(y[top : top + 4], 0.9)
    assert y[top + 4] == pytest.approx(0.8)


def test_simulated_extensions_match_their_frequency_responses():
    """Each linear extension, simulated by the twin (reduced, quiet IMU), changes the
    describing function by its analytic response at the Table 5.2 lines: within 0.05 dB and
    0.5 deg."""
    base = motion_system("srs")
    imu = default_imu("srs").ideal()
    nominal = run_df(Session(Bench(base, "reduced", imu=imu)), "heave", signals=(2,))
    f = nominal.frequencies_hz
    for ext in LINEAR_CASES:
        ms = base.replace(extensions=(ext,))
        res = run_df(Session(Bench(ms, "reduced", imu=imu)), "heave", signals=(2,))
        # against the nominal run: the IMU post-processing's own response cancels
        model = ms.response_at_hz(f)[:, 2] / base.response_at_hz(f)[:, 2]
        err = res.response / nominal.response / model
        assert np.abs(20 * np.log10(np.abs(err))).max() < 0.05, ext.effect
        assert np.abs(np.degrees(np.angle(err))).max() < 0.5, ext.effect


def test_noise_extension_scales_the_noise():
    quiet = motion_system("mpi")
    loud = quiet.replace(extensions=(Extension("noise", {"scale": 2.0}, ()),))
    assert loud.noise_scale == 2.0
    a, b = quiet.noise_block().generate(5.0, 1), loud.noise_block().generate(5.0, 1)
    assert np.allclose(b.acceleration, 2 * a.acceleration)


def test_configuration_file_round_trip(tmp_path):
    ms = motion_system("mpi").replace(name="mpi-measured", extensions=tuple(LINEAR_CASES[:2]))
    path = ms.save(tmp_path / "mpi-measured.json")
    back = motion_system(str(path))
    assert back.extensions == ms.extensions
    assert back.to_meta() == ms.to_meta()
    assert load_config(path).platform == "mpi"


@pytest.mark.parametrize(
    ("content", "error", "match"),
    [
        ("not json", SignalError, "not valid JSON"),
        (json.dumps({"format": "other"}), SignalError, "not a twin-config/1 file"),
        (json.dumps({"format": "twin-config/1", "platform": "x"}), UnknownPlatformError,
         "unknown platform"),
        (
            json.dumps({"format": "twin-config/1", "platform": "mpi",
                        "platform_config": {"delay_s": 0.1}}),
            SignalError,
            "lacks 'filter_break_hz'",
        ),
        (
            json.dumps({
                "format": "twin-config/1", "platform": "mpi",
                "platform_config": {"filter_break_hz": 1.0, "delay_s": 0.035, "noise": True,
                                    "extensions": [{"effect": "wobble", "parameters": {}}]},
            }),
            SignalError,
            "unknown effect",
        ),
    ],
)  # fmt: skip
def test_malformed_configuration_files_are_refused(tmp_path, content, error, match):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(error, match=match):
        motion_system(str(path))


def test_the_demo_s_measured_configuration_loads():
    """`make demo` simulates notebooks/data/srs-imu-filtered.json as a "measured" SRS."""
    from pathlib import Path

    path = Path(__file__).parents[1] / "notebooks" / "data" / "srs-imu-filtered.json"
    ms = motion_system(str(path))
    assert load_config(path).platform == "srs"
    (filt,) = ms.of("sensor_filter")
    assert filt.value("cutoff_hz") == pytest.approx(3.0)
