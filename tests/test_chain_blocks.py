"""Motion-system blocks: filter (Eq 5.1), delay, resonance (Eq 5.12/5.13), noise (Eq 5.10)."""

import numpy as np
import pytest

from twin.chain.config import config_names, motion_system
from twin.chain.delay import Delay
from twin.chain.filter import PlatformFilter
from twin.chain.noise import MotionNoise
from twin.chain.resonance import Resonance
from twin.chain.signals import describing_signal
from twin.core.errors import SignalError, UnknownPlatformError
from twin.core.thesis import NOISE_SIGMA, TABLE_6_3
from twin.measurement.describing_function import describing_function


def _df(block, dof="heave", signal=2):
    sig = describing_signal(signal, dof)
    out = block(sig.commands)
    k = 2 if dof == "heave" else 4
    h = describing_function(
        sig.commands.t, sig.commands.values[:, k], out.values[:, k], sig.frequencies_hz, sig.window
    )
    return sig.frequencies_hz, h, block.response_at_hz(sig.frequencies_hz)[:, k]


@pytest.mark.parametrize("fb", [1.0, 5.0, 10.0])
def test_filter_matches_eq_5_1_within_0_05_db_and_0_5_deg(fb):
    # Eq 5.1 at the break frequencies measured in §5.5.2 (1, 5, 10 Hz), commands at 100 Hz
    _f, h, ref = _df(PlatformFilter(fb))
    assert np.abs(20 * np.log10(np.abs(h / ref))).max() < 0.05
    assert np.abs(np.angle(h / ref, deg=True)).max() < 0.5


def test_filter_is_minus_6_db_at_break():
    h = PlatformFilter(1.0).response_at_hz([1.0])[0, 0]
    assert 20 * np.log10(abs(h)) == pytest.approx(-6.0206, abs=1e-3)


@pytest.mark.parametrize("tau", [0.035, 0.0123])
def test_delay_phase_is_minus_360_f_tau_within_0_2_deg(tau):
    f, h, _ = _df(Delay(tau), "pitch")
    assert np.abs(np.angle(h * np.exp(2j * np.pi * f * tau), deg=True)).max() < 0.2
    assert np.abs(np.abs(h) - 1).max() < 2e-3


def test_resonance_is_1_plus_t_s_in_heave_and_pitch_only():
    for dof, tc in (("heave", 0.023), ("pitch", 0.027)):  # Eq 5.12, Eq 5.13
        f, h, _ref = _df(Resonance(), dof)
        assert np.allclose(h, 1 + 2j * np.pi * f * tc, rtol=2e-3)
    sig = describing_signal(1, "roll")
    assert np.allclose(Resonance()(sig.commands).values, sig.commands.values, rtol=0, atol=1e-15)


def test_noise_sigma_within_5_percent_of_thesis():
    # §5.4.4: Eq 5.10 on unit-variance white noise at 819.2 Hz has sigma = 4.230e-2 m/s^2
    full = MotionNoise(highpass_hz=None).generate(600.0, seed=11).acceleration
    assert full.std() == pytest.approx(NOISE_SIGMA, rel=0.05)
    cut = MotionNoise(highpass_hz=1.0).generate(600.0, seed=11)  # SRS version: none below 1 Hz
    assert cut.acceleration.std() == pytest.approx(NOISE_SIGMA, rel=0.05)
    spec = np.abs(np.fft.rfft(cut.acceleration))
    f = np.fft.rfftfreq(cut.acceleration.size, 1 / 819.2)
    # 4th-order high-pass at 1 Hz: below 0.5 Hz at least 24 dB under the 2-10 Hz level
    assert spec[f < 0.5].mean() < spec[(f > 2) & (f < 10)].mean() / 16
    assert np.abs(cut.position).max() < 1e-3  # sub-millimetre heave (§5.6.2.3)


def test_noise_is_seeded():
    a = MotionNoise().generate(10.0, seed=3)
    b = MotionNoise().generate(10.0, seed=3)
    c = MotionNoise().generate(10.0, seed=4)
    assert np.array_equal(a.position, b.position)
    assert not np.array_equal(a.position, c.position)


def test_named_configurations():
    mpi = motion_system("mpi")
    assert (mpi.platform, mpi.filter_break_hz, mpi.delay_s, mpi.noise) == ("mpi", 1.0, 0.035, True)
    old = motion_system("mpi-2008")
    assert (old.filter_break_hz, old.delay_s, old.noise) == (1.0, 0.100, False)
    srs = motion_system("srs")
    assert (srs.platform, srs.filter_break_hz, srs.delay_s, srs.noise) == (
        "srs",
        None,
        0.025,
        False,
    )
    for n, (fb, delay, noise) in TABLE_6_3.items():  # Table 6.3
        c = motion_system(f"condition-{n}")
        assert (c.platform, c.filter_break_hz, c.delay_s, c.noise) == ("srs", fb, delay, noise)
    assert len(config_names()) == 11


def test_full_model_delay_block_leaves_out_the_platform_lag():
    ms = motion_system("mpi")
    lag = np.array([0.006, 0.006, 0.001, 0.013, 0.013, 0.015])
    delay = next(b for b in ms.blocks(lag) if isinstance(b, Delay))
    assert np.allclose(delay.per_dof, 0.035 - lag)


def test_bad_blocks_are_rejected():
    with pytest.raises(SignalError, match=r"break frequency must be in \[0.01, 1000\] Hz"):
        PlatformFilter(-1.0)
    with pytest.raises(SignalError, match=r"break frequency must be in \[0.01, 1000\] Hz"):
        PlatformFilter(1e300)
    with pytest.raises(SignalError, match=r"delay must be in \[0, 10\] s"):
        Delay(float("nan"))
    with pytest.raises(SignalError, match=r"delay must be in \[0, 10\] s"):
        Delay(1e300)
    with pytest.raises(SignalError, match="high-pass"):
        MotionNoise(highpass_hz=500.0)
    with pytest.raises(UnknownPlatformError, match="condition-1"):
        motion_system("condition-9")


def test_noise_stream_does_not_depend_on_chunking():
    whole = MotionNoise().generate(20.0, seed=8)
    stream = MotionNoise().stream(8)
    parts = [stream.take(n) for n in (1, 999, 4096, whole.acceleration.size - 5096)]
    for name in ("acceleration", "velocity", "position"):
        joined = np.concatenate([getattr(p, name) for p in parts])
        assert np.array_equal(joined, getattr(whole, name))
