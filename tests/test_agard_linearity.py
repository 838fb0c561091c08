"""AGARD-AR-144 linearity: describing functions at several amplitudes (twin.agard.linearity)."""

import dataclasses
import json

import numpy as np
import pytest

from twin.agard.linearity import (
    LinearitySegment,
    analyse_linearity,
    run_linearity,
    schedule,
)
from twin.agard.session import Session
from twin.chain.signals import single_sine
from twin.chain.simulate import default_imu
from twin.chain.trajectory import Trajectory
from twin.core.errors import SignalError
from twin.measurement.measure import Bench, configure
from twin.platform.actuators import LegPhysics
from twin.platform.geometry import load_geometry
from twin.platform.kinematics import inverse
from twin.platform.platform_physics import PlatformPhysics

#: Total delay of the mpi configuration [s] (platform.toml delay_s, §5.5.2).
MPI_DELAY_S = 0.035


def backlash_df(half_width: float, amplitude: float) -> complex:
    """Describing function of backlash (total width 2 b, unit slope) for a sine of amplitude A.

    Gelb & Vander Velde, Multiple-Input Describing Functions and Nonlinear System Design
    (1968), ch. 2 (backlash), written for b / A = r < 1:
    Re N = (1/pi) [pi/2 + asin(1 - 2r) + 2 (1 - 2r) sqrt(r (1 - r))],
    Im N = -(4/pi) r (1 - r).
    """
    r = half_width / amplitude
    re = (np.pi / 2 + np.arcsin(1 - 2 * r) + 2 * (1 - 2 * r) * np.sqrt(r * (1 - r))) / np.pi
    return complex(re, -4 / np.pi * r * (1 - r))


def brute_force_backlash_df(half_width: float, amplitude: float) -> complex:
    """The same by simulating a backlash over many periods and taking the fundamental."""
    t = np.linspace(0, 4, 400_001)[:-1]  # four periods of a 1 Hz sine
    x = amplitude * np.sin(2 * np.pi * t)
    y = np.empty_like(x)
    v = x[0]
    for i, xi in enumerate(x):
        v = min(max(v, xi - half_width), xi + half_width)
        y[i] = v
    last = t >= 1  # after the first period
    e = np.exp(-2j * np.pi * t[last])
    return complex((y[last] @ e) / (x[last] @ e))


@pytest.mark.parametrize("ratio", [0.1, 0.3, 0.5, 0.8])
def test_the_backlash_formula_matches_a_brute_force_backlash(ratio):
    assert backlash_df(ratio, 1.0) == pytest.approx(brute_force_backlash_df(ratio, 1.0), abs=2e-3)


def heave_leg_ratio(platform: str) -> float:
    """|d leg / d heave| at neutral, by differencing the inverse kinematics (equal for all legs)."""
    geo, dz = load_geometry(platform), 1e-6
    d = (inverse(geo, [0, 0, dz, 0, 0, 0]) - inverse(geo, np.zeros(6))) / dz
    assert np.ptp(np.abs(d)) < 1e-3 * np.abs(d).max()  # heave moves all six legs alike
    return float(np.abs(d).mean())


def bench_with_play(play_m: float) -> Bench:
    """Full mpi without filter and noise, ideal IMU, every leg with ``play_m`` of play."""
    legs = LegPhysics.ideal().replace(play_m=play_m)
    cfg = configure("mpi", break_hz=0, noise=False).replace(physics=PlatformPhysics(legs=legs))
    return Bench(cfg, "full", imu=default_imu("mpi").ideal())


def test_leg_play_gives_the_backlash_describing_function():
    """The model's play is a backlash (twin.platform.actuators.shape_reference: the rod rests
    inside a band of total width play_m and follows at its edges), not a dead zone; in heave
    all six legs see the same play, so the cabin has a backlash of total width
    play / |d leg / d heave|. At 0.5 Hz the linear rest is the 35 ms delay (gain 1)."""
    play, f = 0.01, 0.5
    amplitudes = [0.5, 0.2, 0.1]  # m/s^2: position 51, 20, 10 mm against a 5.5 mm half-width
    r = run_linearity(Session(bench_with_play(play)), "heave", [f], amplitudes)
    b = play / heave_leg_ratio("mpi") / 2
    for a, h in zip(r.amplitudes, r.response, strict=True):
        n = backlash_df(b, a / (2 * np.pi * f) ** 2)
        assert abs(h) == pytest.approx(abs(n), rel=0.02)  # tolerance: 2 % of the gain
        expected_phase = np.degrees(np.angle(n)) - 360 * f * MPI_DELAY_S
        assert np.degrees(np.angle(h)) == pytest.approx(expected_phase, abs=2.0)  # 2 deg
    # the smaller amplitudes' changes are far outside their intervals: not linear
    assert not r.linear[1:].any()
    assert np.all(np.abs(r.gain_change[1:]) > 3 * r.gain_change_ci[1:])


def test_without_play_the_gain_and_phase_do_not_change_beyond_their_intervals():
    """Four quantities are checked (gain and phase change at two frequencies): at 95 % each,
    one in five nominal runs would fail somewhere; the 99 % intervals keep the family-wise
    rate near 4 % (Bonferroni: 1 - 0.05 / 4 = 98.75 %)."""
    bench = Bench(configure("mpi"), "full")  # with the Eq 5.10 heave noise and the real IMU
    segs = run_linearity(Session(bench), "heave", [0.5, 1.0], [1.0, 0.3], window_s=20.0)
    assert segs.level == 0.95
    r = dataclasses.replace(segs, level=0.99)
    assert r.linear.all()
    small = r.amplitudes < 1.0
    assert np.all(r.gain_change_ci[small] > 0) and np.all(r.gain_change_ci[small] < 0.1)


def test_default_schedule_is_three_amplitudes_a_decade_apart_scaled_to_the_limits():
    points, skipped = schedule("mpi", "heave")
    assert not skipped
    freqs = sorted({f for f, _ in points})
    assert freqs == [0.2, 0.5, 1.0, 2.0, 5.0]
    for f in freqs:
        amps = sorted((a for g, a in points if g == f), reverse=True)
        assert amps == pytest.approx([amps[0], amps[0] / 10, amps[0] / 100])
        assert amps[0] <= 3.0
    top = {f: max(a for g, a in points if g == f) for f in freqs}
    assert top[0.2] < top[1.0]  # stroke-limited at low frequency


def test_a_point_beyond_the_limits_is_skipped_with_the_reason():
    s = Session(Bench(configure("srs", noise=False), "reduced"))
    r = run_linearity(s, "heave", [0.2], [3.0, 0.3])
    assert r.amplitudes.tolist() == [0.3]
    assert len(r.skipped) == 1 and r.skipped[0].amplitude == 3.0
    assert "would break the srs limits" in r.skipped[0].reason
    assert "skipped" in r.format_table()
    assert json.loads(json.dumps(r.to_dict()))["skipped"][0]["amplitude"] == 3.0


def test_segments_of_one_long_run_give_the_separate_runs_result():
    bench = Bench(configure("srs", noise=False), "reduced", imu=default_imu("srs").ideal())
    sines = [single_sine("pitch", 0.5, 0.4), single_sine("pitch", 1.0, 0.1)]
    values = np.vstack([sines[0].commands.values, sines[1].commands.values[1:]])
    long = Trajectory(100.0, values)
    m = bench.measure(bench.prepare(long, 0, "schedule").collect())
    offset = sines[0].commands.duration
    segments = [
        LinearitySegment(m, *sines[0].window, 0.5, 0.4),
        LinearitySegment(m, sines[1].window[0] + offset, sines[1].window[1] + offset, 1.0, 0.1),
    ]
    joined = analyse_linearity(segments, "pitch")
    alone = [run_linearity(Session(bench), "pitch", [f], [a]) for f, a in ((0.5, 0.4), (1, 0.1))]
    for k, r in enumerate(alone):
        assert joined.response[k] == pytest.approx(r.response[0], abs=1e-3)


@pytest.fixture(scope="module")
def measured():
    s = Session(Bench(configure("srs", noise=False), "reduced"))
    return s.measure(single_sine("roll", 1.0, 0.2), "roll")


@pytest.mark.parametrize(
    ("window", "f", "a", "message"),
    [
        ((5.0, 14.5), 1.0, 0.2, "whole number"),
        ((5.0, 15.0), 1.0, 0.05, "not the stated 0.05"),
        ((-5.0, 22.0), 1.0, 0.2, "within what was measured"),
        ((5.0, 15.0), -1.0, 0.2, "frequency"),
    ],
)
def test_a_bad_segment_is_refused_naming_what_is_wrong(measured, window, f, a, message):
    with pytest.raises(SignalError, match=message):
        analyse_linearity([LinearitySegment(measured, *window, f, a)])


def test_bad_calls_are_refused(measured):
    with pytest.raises(SignalError, match="at least one segment"):
        analyse_linearity([])
    seg = LinearitySegment(measured, *measured.meta["signal"]["window_s"], 1.0, 0.2)
    with pytest.raises(SignalError, match="confidence level"):
        analyse_linearity([seg], level=1.5)
    with pytest.raises(SignalError, match="same frequency and amplitude"):
        analyse_linearity([seg, seg])
    with pytest.raises(SignalError, match="unknown DOF"):
        schedule("mpi", "bounce")


def test_result_outputs(measured, tmp_path):
    seg = LinearitySegment(measured, *measured.meta["signal"]["window_s"], 1.0, 0.2)
    r = analyse_linearity([seg])
    d = json.loads(json.dumps(r.to_dict()))
    assert d["test"] == "linearity" and d["dof"] == "roll" and d["confidence_level"] == 0.95
    assert d["points"][0]["gain_change"] == 0.0  # its own reference
    assert "reference" in r.format_table()
    fig = r.plot(path=str(tmp_path / "lin.png"))
    assert (tmp_path / "lin.png").stat().st_size > 0 and len(fig.axes) == 2
