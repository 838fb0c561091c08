"""The AGARD-AR-144 turn-around bump test (twin.agard.bump): schedule, analysis, physics."""

import json

import numpy as np
import pytest

from twin.agard.bump import analyse_bump, bump_signal, run_bump
from twin.agard.session import Session
from twin.chain.signals import rest
from twin.chain.simulate import default_imu
from twin.core.errors import SignalError, SignalLimitError
from twin.measurement.measure import Bench, Measurement, configure, from_run
from twin.platform.actuators import LegPhysics
from twin.platform.facts import load_model
from twin.platform.geometry import load_geometry
from twin.platform.kinematics import jacobian
from twin.platform.payload import cabin_mass_properties
from twin.platform.platform_physics import PlatformPhysics

HEAVE = 2


def test_schedule_reverses_where_the_profiles_put_it():
    sig = bump_signal("heave", velocities=(0.1, 0.02))
    # rest 1 s, 0 -> v in v/a + ramp = 1.05 s, cruise 0.5 s, then half of the 2.05 s reversal
    first = 1.0 + 1.05 + 0.5 + 2.05 / 2
    # then the other half, the -v stretch (2 x 0.5 + 1.05 s) and half the next reversal
    second = first + 2.05 / 2 + 2.05 + 2.05 / 2
    assert sig.reversals_s[:2] == pytest.approx((first, second), abs=1e-9)
    assert len(sig.reversals_s) == 4
    c = sig.commands
    speed = c.at(np.array(sig.reversals_s), 1)[:, HEAVE]
    acc = c.at(np.array(sig.reversals_s), 2)[:, HEAVE]
    assert np.abs(speed).max() < 1e-6
    assert acc == pytest.approx([-0.1, 0.1, -0.02, 0.02], abs=1e-6)
    # cruising speed mid-way through the first constant-speed stretch
    assert c.at([1.0 + 1.05 + 0.25], 1)[0, HEAVE] == pytest.approx(0.1, abs=1e-6)
    # the series end at rest at neutral; the largest excursion by hand: 0.0525 m to speed,
    # 0.05 m cruising, 0.0049583 m in the first jerk ramp and 0.0475313 m on to zero speed
    assert abs(c.values[-1, HEAVE]) < 1e-12
    assert np.abs(c.values[:, HEAVE]).max() == pytest.approx(0.1549896, abs=2e-5)
    assert not np.any(np.delete(c.values, HEAVE, axis=1))
    assert sig.meta()["kind"] == "bump" and sig.meta()["velocities"] == [0.1, 0.02]


def _synthetic(sig, config, planted=None, noise=1e-3, seed=3):
    """A measurement whose platform follows the commands exactly 25 ms late (the SRS delay)."""
    c = sig.commands
    t = c.t
    commanded = c.at(t, 2)
    measured = np.interp(t - 0.025, t, commanded[:, HEAVE], left=0.0)
    if planted is not None:
        at, depth, width = planted
        measured = measured + depth * np.exp(-0.5 * ((t - at) / width) ** 2)
    measured = measured + np.random.default_rng(seed).normal(0.0, noise, t.size)
    both = np.zeros_like(commanded)
    both[:, HEAVE] = measured
    return Measurement(t, commanded, both, c, "synthetic", config, {"signal": sig.meta()})


def test_analysis_recovers_a_planted_bump():
    config = configure("srs")  # no platform filter, 25 ms delay
    assert config.breaks_hz[HEAVE] is None and config.delays_s[HEAVE] == pytest.approx(0.025)
    sig = bump_signal("heave", velocities=(0.1, 0.02))
    turn = sig.reversals_s[0] + 0.025
    depth, width = 0.03, 0.02  # a dip against the commanded -0.1 m/s^2, 0.1 s after the turn
    m = _synthetic(sig, config, (turn + 0.1, depth, width))
    r = analyse_bump(m)
    assert r.dof == "heave"
    assert [x.t_s for x in r.reversals] == pytest.approx(sig.reversals_s, abs=1e-3)
    assert [x.t_platform_s for x in r.reversals] == pytest.approx(
        [t + 0.025 for t in sig.reversals_s], abs=2e-3)  # fmt: skip
    assert [x.speed for x in r.reversals] == pytest.approx([0.1, 0.1, 0.02, 0.02], rel=1e-3)
    first = r.reversals[0]
    assert first.peak == pytest.approx(depth, abs=4e-3)
    assert first.ratio == pytest.approx(depth / 0.1, abs=0.04)
    assert first.t_peak_s == pytest.approx(0.1, abs=0.011)
    assert first.area == pytest.approx(depth * width * np.sqrt(2 * np.pi), rel=0.15)
    for other in r.reversals[1:]:
        assert abs(other.peak) < 5e-3  # the noise's: 1e-3 rms
    assert r.noise_rms == pytest.approx(1e-3, rel=0.2)


def test_window_picks_a_series_inside_a_longer_run():
    sig = bump_signal("heave", velocities=(0.05, 0.01))
    m = _synthetic(sig, configure("srs"))
    # the 0.01 m/s series starts after the first series' 1 s rest
    start = sig.reversals_s[1] + 4.0
    r = analyse_bump(m, "heave", window=(start, m.t[-1]))
    assert [x.t_s for x in r.reversals] == pytest.approx(sig.reversals_s[2:], abs=1e-3)
    assert {round(x.speed, 4) for x in r.reversals} == {0.01}
    whole = analyse_bump(m, "heave")
    assert len(whole.reversals) == 4


def test_bad_input_names_what_is_allowed():
    with pytest.raises(SignalError, match="unknown DOF 'bounce'"):
        bump_signal("bounce")
    with pytest.raises(SignalError, match="at least one"):
        bump_signal("heave", velocities=())
    with pytest.raises(SignalError, match=r"velocities\[1\]"):
        bump_signal("heave", velocities=(0.1, -0.05))
    with pytest.raises(SignalError, match="one bump acceleration per velocity"):
        bump_signal("heave", velocities=(0.1, 0.05), accelerations=(0.1,))
    with pytest.raises(SignalError, match="jerk ramp"):
        bump_signal("heave", velocities=(0.1,), accelerations=(10.0,))  # v / a = 0.01 s
    with pytest.raises(SignalError, match="list of numbers"):
        bump_signal("heave", velocities="0.1")
    sig = bump_signal("heave", velocities=(0.1,))
    m = _synthetic(sig, configure("srs"))
    with pytest.raises(SignalError, match="no velocity reversal"):
        analyse_bump(m, "heave", window=(0.0, 0.9))  # the rest before the series
    with pytest.raises(SignalError, match="window end"):
        analyse_bump(m, "heave", window=(5.0, 4.0))
    still = Measurement(np.arange(301) / 100, np.zeros((301, 6)), np.zeros((301, 6)),
                        rest(3.0), "rest", configure("srs"), {})  # fmt: skip
    with pytest.raises(SignalError, match="no velocity reversal"):
        analyse_bump(still, "heave")
    # 0.5 m/s reversing at 0.1 m/s^2 needs metres of heave: refused before it is run
    session = Session(Bench(configure("mpi"), "reduced"))
    with pytest.raises(SignalLimitError, match="stroke"):
        run_bump(session, "heave", velocities=(0.5,), accelerations=(0.1,))


def test_nominal_platform_bump_is_at_noise_level(tmp_path):
    """The full MPI model, heave noise and IMU as configured: the default schedule."""
    r = run_bump(Session(Bench(configure("mpi"), "full", seed=0)), "heave")
    assert len(r.reversals) == 10
    assert sorted({round(x.speed, 4) for x in r.reversals}) == [0.005, 0.01, 0.02, 0.05, 0.1]
    assert 0.02 < r.noise_rms < 0.2  # the ADIS16355 after App. C.2.3: ~0.07 m/s^2
    peaks = np.array([abs(x.peak) for x in r.reversals])
    print("nominal |peak| / noise rms:", np.round(peaks / r.noise_rms, 2), r.noise_rms)
    assert peaks.max() < 3.5 * r.noise_rms
    # no trend with speed: noise does not care (a friction bump grows with the acceleration)
    assert abs(r.trend_exponent) < 0.3
    d = json.loads(json.dumps(r.to_dict()))
    assert d["test"] == "turn-around bump" and len(d["reversals"]) == 10
    assert len(d["per_speed"]) == 5 and d["per_speed"][0]["speed"] == 0.1
    table = r.format_table()
    assert "turn-around bump, heave" in table and table.count("\n") >= 13
    png = tmp_path / "bump.png"
    r.plot(path=str(png))
    assert png.stat().st_size > 10_000


def _with_friction(coulomb_n):
    config = configure("mpi", noise=False)  # the heave noise off: the bump alone
    legs = LegPhysics.of_model(load_model("mpi")).replace(coulomb_n=coulomb_n)
    return config.replace(physics=PlatformPhysics(legs=legs))


def _bump(config, velocities=(0.1,)):
    imu = default_imu("mpi").ideal()  # the physics, not the sensor's noise
    return run_bump(Session(Bench(config, "full", seed=0, imu=imu)), "heave", velocities)


def test_friction_bump_grows_with_friction_and_obeys_the_servo_bound():
    """Coulomb friction F on all six legs, reversing at 0.1 m/s and 0.1 m/s^2 in heave.

    Textbook: friction flipping sign at the reversal changes the heave force by
    2 F_dof, F_dof = F sum_j |J_j,heave|. On a rigid mass that is an acceleration step of
    2 F_dof / M; but the legs' PD (Eq 5.9) feeds back the leg speed with K_d per leg, a
    damping C = K_d sum_j J_j,heave^2 in heave, far above what the mass needs: the servo takes
    the force up by a speed error dv = 2 F_dof / C, during which the platform dwells (its
    acceleration falls towards zero). So the bump's area is dv, taken back by the position
    loop with time constant K_d / K_p = 3.5 s (at most 1 - exp(-1 / 3.5) = 25 % within the
    1 s window), and its depth is at most the commanded acceleration: far below 2 F_dof / M.
    """
    model = load_model("mpi")
    j = jacobian(load_geometry("mpi"), np.zeros(6))[:, HEAVE]
    kd = np.array(model.numeric("leg_kd").data[:6])
    kp = np.array(model.numeric("leg_kp").data[:6])
    mass, _ = cabin_mass_properties(model)
    assert kd / kp == pytest.approx(np.full(6, 3.5))  # 73 500 / 21 000
    keep = np.exp(-1.0 / 3.5)
    nominal = _bump(_with_friction(0.0))
    nominal_peak = max(abs(x.peak) for x in nominal.reversals)
    assert nominal_peak < 1e-3  # the expected motion (filter, delay) is right: ratio < 1 %
    peaks, areas = [], []
    for f in (50.0, 100.0, 200.0):
        r = _bump(_with_friction(f))
        f_dof = f * np.abs(j).sum()
        dv = 2 * f_dof / (kd @ j**2)
        step = 2 * f_dof / mass
        for x in r.reversals:
            # the dwell opposes the commanded acceleration
            assert np.sign(x.peak) == -np.sign(x.acceleration)
            assert np.sign(x.area) == -np.sign(x.acceleration)
            assert keep * dv < abs(x.area) < 1.05 * dv
            assert x.ratio <= 1.0
            assert abs(x.peak) < 0.05 * step
        print(f"F {f:g} N: dv {dv:.3e} m/s, 2 F_dof / M {step:.2f} m/s^2; areas "
              f"{[round(x.area, 5) for x in r.reversals]}, peaks "
              f"{[round(x.peak, 4) for x in r.reversals]}")  # fmt: skip
        peaks.append(np.mean([abs(x.peak) for x in r.reversals]))
        areas.append(np.mean([abs(x.area) for x in r.reversals]))
    assert peaks[0] > 20 * nominal_peak
    assert np.all(np.diff(peaks) > 0) and np.all(np.diff(areas) > 0)


def test_one_leg_friction_makes_a_bump():
    legs = np.zeros(6)
    legs[0] = 400.0
    one = _bump(_with_friction(legs))
    nominal = _bump(_with_friction(0.0))
    peak = np.mean([abs(x.peak) for x in one.reversals])
    print("one leg 400 N: |peak|", peak, "nominal", max(abs(x.peak) for x in nominal.reversals))
    assert peak > 20 * max(abs(x.peak) for x in nominal.reversals)


def test_a_recorded_run_gives_the_same_bumps(tmp_path):
    """The run folder a session writes, read back and analysed: the same reversals and bumps."""
    imu = default_imu("mpi").ideal()
    session = Session(Bench(_with_friction(100.0), "full", seed=0, imu=imu), out=tmp_path)
    live = run_bump(session, "heave", velocities=(0.1,))
    recorded = analyse_bump(from_run(tmp_path / "runs" / "00-bump-heave"))
    assert recorded.dof == "heave"
    assert [x.t_s for x in recorded.reversals] == pytest.approx(
        [x.t_s for x in live.reversals], abs=1e-6)  # fmt: skip
    # the IMU written to imu.csv and read back: the same peaks to the file's precision
    assert [x.peak for x in recorded.reversals] == pytest.approx(
        [x.peak for x in live.reversals], rel=0.02)  # fmt: skip
    assert abs(recorded.reversals[0].peak) > 10 * recorded.noise_rms
