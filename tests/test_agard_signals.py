"""AGARD-AR-144 input signals (§3.2.3): fades, pre-measurement, sines, steps, limit checks."""

import numpy as np
import pytest

from twin.chain.signals import (
    STEP_PATTERN,
    base_frequency,
    check_signal,
    describing_signal,
    premeasurement_periods,
    single_sine,
    square_steps,
)
from twin.core.errors import SignalError, SignalLimitError


def test_premeasurement_periods_follow_eq_3_3():
    # Eq 3.3: 2 periods below 0.5 Hz, 5 from 0.5 to 2 Hz, 10 from 2 Hz
    assert [premeasurement_periods(f) for f in (0.1, 0.49, 0.5, 1.99, 2.0, 7.1)] == [
        2, 2, 5, 5, 10, 10]  # fmt: skip


def test_single_sine_phases_and_window():
    sig = single_sine("heave", 0.5, 0.2, window_s=10.0)
    fade = 1 / 0.5  # Eq 3.1-3.2: f_f = f / 2, the fade lasts 1 / (2 f_f)
    settle = 5 / 0.5  # Eq 3.3: 5 periods at 0.5 Hz
    assert sig.window == pytest.approx((fade + settle, fade + settle + 10.0))
    acc = sig.commands.at(sig.commands.t, 2)[:, 2]
    t = sig.commands.t
    inside = (t >= sig.window[0]) & (t < sig.window[1])
    assert np.sqrt(2) * acc[inside].std() == pytest.approx(0.2, rel=1e-3)
    # position, velocity and acceleration start and end at rest
    for d in range(3):
        v = sig.commands.at(np.array([0.0, sig.commands.duration]), d)[:, 2]
        assert np.abs(v).max() < 1e-4  # spline end conditions: ~5e-6 m/s^2


def test_describing_signal_with_eq_3_3_premeasurement():
    sig = describing_signal(1, "pitch", settle_s=None)  # lowest frequency 0.1 Hz
    assert sig.window[0] == pytest.approx(10.0 + 20.0)  # fade 1/0.1, two periods of 0.1 Hz
    assert base_frequency(sig.frequencies_hz) == pytest.approx(0.05)


def test_square_steps_return_to_rest_and_follow_the_pattern():
    sig = square_steps("surge", 0.1, 1.0, repeats=2)
    x = sig.commands.values[:, 0]
    assert abs(x[-1]) < 1e-12 and np.abs(x).max() == pytest.approx(0.1)  # A T^2
    t = sig.start_s + (np.arange(16) + 0.5) * 1.0
    assert np.allclose(sig.acceleration(t), 0.1 * np.array(STEP_PATTERN * 2))
    mid = sig.commands.at(t, 2)[:, 0]  # the spline follows the levels between the corners
    assert np.allclose(mid, sig.acceleration(t), atol=2e-3)
    with pytest.raises(SignalError, match="repeats"):
        square_steps("surge", 0.1, 1.0, repeats=0)


def test_check_signal_names_the_limit_it_would_break():
    with pytest.raises(SignalLimitError, match="velocity limit broken by leg"):
        check_signal(single_sine("heave", 0.5, 2.0).commands, "mpi", "big sine")
    with pytest.raises(SignalLimitError, match="stroke"):
        check_signal(square_steps("heave", 1.0, 2.0).commands, "mpi")
    check_signal(describing_signal(2, "heave").commands, "mpi")  # Table 5.2 fits


def test_bad_signals_are_rejected():
    with pytest.raises(SignalError, match="Nyquist"):
        single_sine("pitch", 60.0, 0.1)
    with pytest.raises(SignalError, match="unknown DOF"):
        single_sine("wobble", 1.0, 0.1)
    with pytest.raises(SignalError, match=r"step amplitude .* must be a number in \(0, 100\]"):
        square_steps("heave", -0.1, 1.0)
    with pytest.raises(SignalError, match=r"step length \[s\] must be a number > 0; got nan"):
        square_steps("heave", 0.1, float("nan"))


@pytest.mark.parametrize("tau", [1e-6, 0.004, 0.08, 0.6])
def test_the_step_fits_lag_response_is_lsims_to_the_bit(tau):
    """The threshold fit's first-order lag (Eq 3.7) runs lsim's first-order-hold recursion by
    lfilter: the same values as scipy.signal.lsim, bit for bit, on steps and noise."""
    from scipy import signal

    from twin.agard.threshold import lag_response

    rng = np.random.default_rng(3)
    t = 2.0 + np.arange(3001) * 0.001
    u = np.where(rng.random(t.size) < 0.7, np.sign(np.sin(3 * t)), rng.standard_normal(t.size))
    _, expected, _ = signal.lsim(([1.0], [tau, 1.0]), u, t - t[0])
    assert lag_response(t, u, tau).tobytes() == expected.tobytes()
    with pytest.raises(SignalError, match="equally spaced times; got 3 times unequally"):
        lag_response(t[[0, 1, 3]], u[:3], tau)
