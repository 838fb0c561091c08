"""Chapter 6: the pitch task through the eight motion conditions of Table 6.3 (pilot fixed)."""

import numpy as np
import pytest

from twin.chain.config import motion_system
from twin.pilot.experiment import run_experiment
from twin.pilot.forcing import pitch_task
from twin.pilot.pitch import PitchPilot, open_loops, simulate_pitch


def test_forcing_functions_follow_table_6_2():
    fd, ft = pitch_task()
    assert np.degrees(np.sqrt(ft.variance)) ** 2 == pytest.approx(0.4, rel=0.01)  # §6.3.1
    assert fd.omega_rad_s.size == ft.omega_rad_s.size == 10
    assert np.allclose(fd.bins() * 2 * np.pi / 81.92, fd.omega_rad_s)  # whole periods


def test_felt_motion_is_the_filtered_delayed_attitude():
    """Noise-free condition 7 (1 Hz, 35 ms): the felt attitude equals Eq 5.11 applied to the
    simulated one within 1 % at the forcing lines up to 5 rad/s (above, theta is small and the
    start-up transient of the aircraft's integrator leaks into the window)."""
    r = simulate_pitch(PitchPilot(), "condition-7", runs=1)
    n = r.theta.shape[1]
    fd, ft = pitch_task()
    k = np.concatenate([fd.bins(), ft.bins()])
    k = k[k * 2 * np.pi / 81.92 < 5.0]
    ratio = np.fft.rfft(r.theta_felt[0])[k] / np.fft.rfft(r.theta[0])[k]
    w = 2 * np.pi * k / 81.92
    expected = motion_system("condition-7").frequency_response(w / (2 * np.pi))[:, 4]
    assert np.abs(ratio / expected - 1).max() < 0.01
    assert n == 8192


def test_the_1_hz_filter_dominates_delay_and_noise():
    """§6.4 with the pilot fixed: the 1 Hz filter costs the felt motion more than 30 deg of
    lead at the disturbance crossover and has a larger effect than the 10 ms delay or the noise
    on the lead, the disturbance phase margin and the error variance; performance gets worse
    with the filter (sigma^2(e) up), as the thesis found."""
    r = run_experiment(runs=4, seed=3)
    f, d, n = (r.effects[k] for k in ("filter", "delay", "noise"))
    assert f["motion_lead_phase_deg"] < -30
    for m in ("motion_lead_phase_deg", "phase_margin_d", "var_e"):
        assert abs(f[m]) > 3 * abs(d[m]) and abs(f[m]) > 3 * abs(n[m]), m
    assert f["var_e"] > 0
    for c in r.conditions.values():  # the disturbance loop crosses over above the target loop
        assert c["crossover_d"] > c["crossover_t"]
        assert c["phase_margin_d"] < c["phase_margin_t"]


def test_open_loops_without_motion_lead_lose_phase_margin():
    lead = open_loops(PitchPilot(), motion_system("condition-1"))
    filtered = open_loops(PitchPilot(), motion_system("condition-5"))
    assert filtered.phase_margin_d < lead.phase_margin_d
