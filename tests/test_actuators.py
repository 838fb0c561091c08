"""The actuators' physics: friction, play, lag, force limits and gain per leg; leg forces.

The nominal platforms keep the thesis' ideal actuators (Fig 5.4: nothing but the PD of Eq 5.9),
so their runs are unchanged (tests/test_stored_figures.py). Each effect is checked against what
it must do physically: the legs carry the cabin's weight at rest, friction and play cost the
faulty leg tracking accuracy and grow with their size, a lag delays the leg by its time
constant, a force limit caps the force, and a diverging run stops with one clear error.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from twin.chain.config import motion_system
from twin.chain.physics import FullPlatform
from twin.chain.simulate import simulate
from twin.chain.trajectory import Trajectory
from twin.core.errors import ConfigError, ModelFileError, PhysicsDivergedError
from twin.core.frames import rotation_matrix
from twin.platform.actuators import TOML_KEYS, LegPhysics, ReferenceState, shape_reference
from twin.platform.build import read_build_parameters
from twin.platform.facts import PLATFORMS, model_dir
from twin.platform.kinematics import leg_vectors

G = 9.81


def _heave(seconds: float = 6.0, amplitude: float = 0.02, hz: float = 0.5) -> Trajectory:
    """A faded heave sine (reverses the legs every half period)."""
    t = np.arange(round(seconds * 100) + 1) / 100.0
    v = np.zeros((t.size, 6))
    v[:, 2] = amplitude * np.sin(2 * np.pi * hz * t) * np.clip(t / 1.5, 0, 1)
    return Trajectory(100.0, v)


def _run(platform: str, physics: LegPhysics | None = None, commands: Trajectory | None = None):
    cfg = motion_system(platform).override(None, 0.0, False)  # no filter, delay or noise
    plat = FullPlatform(platform, physics=physics)
    return simulate(cfg, commands or _heave(), "full", seed=0, platform=plat)


@pytest.mark.parametrize("platform", PLATFORMS)
def test_the_nominal_actuators_are_the_thesis_ideal_ones_from_build_toml(platform):
    built = read_build_parameters(model_dir(platform) / "build.toml").actuators
    read = FullPlatform(platform).physics
    assert read.is_ideal() and built.is_ideal()
    assert read.to_dict() == built.to_dict()


def test_leg_forces_at_rest_carry_the_cabins_weight():
    """At rest the six leg forces along the legs hold the cabin: their vertical parts add up to
    m g and their moments about the centre of gravity to zero, whether the static-force
    feedback K_s or the PD carries the weight (MuJoCo's own tendon force with K_s = 0)."""
    rest = Trajectory(100.0, np.zeros((201, 6)))
    for ks in (None, 0.0):
        plat = FullPlatform("mpi")
        cabin = plat.model.body("cabin")
        if ks is not None:
            plat.model.body_gravcomp[cabin.id] = ks
            plat._cabin = (plat._cabin[0], plat._cabin[1], ks)
        sim = simulate(motion_system("mpi").override(None, 0.0, False), rest, "full", seed=0,
                       platform=plat)  # fmt: skip
        f = sim.response.leg_force[-1]
        legs = leg_vectors(plat.geometry, sim.response.pose[-1])
        n = legs / np.linalg.norm(legs, axis=-1, keepdims=True)
        total = (f[:, None] * n).sum(axis=0)  # force of the legs on the cabin, base axes
        mass = float(cabin.mass[0])
        assert total[2] == pytest.approx(-mass * G, rel=2e-3)  # z down: the legs push up
        assert np.abs(total[:2]).max() < 1e-3 * mass * G
        # moments about the UGP: the legs' at their cabin gimbals balance the weight's at the
        # centre of gravity (the cabin frame's com turned into base axes)
        pose = sim.response.pose[-1]
        ugp = plat.geometry.neutral_ugp + pose[:3]
        gimbals = legs + plat.geometry.base_gimbals - ugp
        com = rotation_matrix(pose[3:]) @ np.array(cabin.ipos)
        torque = np.cross(gimbals, f[:, None] * n).sum(axis=0) + np.cross(com, [0, 0, mass * G])
        assert np.abs(torque).max() < 2e-3 * mass * G * np.abs(gimbals).max()


@pytest.mark.parametrize("what", ["coulomb_n", "play_m"])
def test_friction_and_play_in_one_leg_cost_that_leg_tracking_monotonically(what):
    sizes = {"coulomb_n": (0.0, 400.0, 1600.0), "play_m": (0.0, 0.001, 0.004)}[what]
    nominal = _run("mpi")
    errors = []
    for size in sizes:
        values = np.zeros(6)
        values[1] = size  # leg 2
        physics = LegPhysics.ideal().replace(**{what: values})
        sim = _run("mpi", physics)
        diff = sim.response.legs - nominal.response.legs
        errors.append(np.sqrt(np.mean(diff**2, axis=0)))
    leg2 = [e[1] for e in errors]
    assert leg2[0] == 0.0 and leg2[0] < leg2[1] < leg2[2]
    assert errors[2][1] == max(errors[2])  # the faulty leg is the one that is off most
    if what == "play_m":  # a dead band of 4 mm leaves the rod up to half of it behind
        worst = np.abs(_run("mpi", LegPhysics.ideal().replace(play_m=[0, 0.004, 0, 0, 0, 0]))
                       .response.legs[:, 1] - nominal.response.legs[:, 1]).max()  # fmt: skip
        assert 0.0015 < worst < 0.003


def test_a_servo_lag_delays_its_leg_by_its_time_constant():
    lag = 0.02
    nominal = _run("mpi", commands=_heave(hz=0.3))
    slow = _run("mpi", LegPhysics.ideal().replace(lag_s=[0, 0, 0, 0, lag, 0]),
                commands=_heave(hz=0.3))  # fmt: skip
    t = nominal.response.t
    keep = t > 2.0
    a, b = nominal.response.legs[keep, 4], slow.response.legs[keep, 4]
    shifts = np.arange(0, 60)  # 0-60 ms at 1 kHz: the shift that best maps one on the other
    misfit = [np.mean((a[: a.size - s] - b[s:]) ** 2) for s in shifts]
    assert shifts[int(np.argmin(misfit))] / 1000.0 == pytest.approx(lag, abs=0.003)


@pytest.mark.parametrize("tau", [0.00125, 0.02])
def test_a_servo_lags_rate_reference_is_the_lagged_rate_even_near_the_physics_step(tau):
    # a 2 Hz sine of 10 mm through 1 / (1 + tau s): its rate reference must have the amplitude
    # w |H(jw)| = w A / sqrt(1 + (w tau)^2) (computed here by hand), also where tau is close
    # to the 1 ms step (where (u - y) / tau lost a third of it and a lag of 1.25 ms moved a leg
    # more than one of 20 ms)
    h, w, amp = 1e-3, 2 * np.pi * 2.0, 0.01
    t = np.arange(0.0, 2.0, h)
    u = amp * np.sin(w * t)[:, None] * np.ones(6)
    ud = amp * w * np.cos(w * t)[:, None] * np.ones(6)
    physics = LegPhysics.ideal().replace(lag_s=np.full(6, tau))
    y, yd = shape_reference(physics, h, u, ud, ReferenceState(np.zeros(6), np.zeros(6)))
    expected = amp / np.sqrt(1 + (w * tau) ** 2)
    assert np.abs(y[1000:, 0]).max() == pytest.approx(expected, rel=1e-3)
    assert np.abs(yd[1000:, 0]).max() == pytest.approx(w * expected, rel=1e-3)


def test_a_shorter_servo_lag_moves_its_leg_less():
    nominal = _run("mpi")
    off = []
    for lag in (0.00125, 0.005, 0.02):
        sim = _run("mpi", LegPhysics.ideal().replace(lag_s=[0, 0, lag, 0, 0, 0]))
        off.append(np.sqrt(np.mean((sim.response.legs[:, 2] - nominal.response.legs[:, 2]) ** 2)))
    assert off[0] < off[1] < off[2]


def test_a_force_limit_caps_the_force_and_is_counted():
    nominal = _run("mpi", commands=_heave(amplitude=0.05, hz=1.5))
    peak = np.abs(nominal.response.leg_force).max()
    limit = 0.9 * peak
    sim = _run("mpi", LegPhysics.ideal().replace(force_limit_n=limit),
               commands=_heave(amplitude=0.05, hz=1.5))  # fmt: skip
    assert np.abs(sim.response.leg_force).max() < limit * 1.03  # the static share moves a little
    assert sim.limits.force_samples > 0 and "force limit" in sim.limits.first
    over = np.abs(sim.response.leg_force) >= 1.01 * limit  # beyond the static share's drift
    assert over.any(axis=-1).sum() <= sim.limits.force_samples
    assert nominal.limits.force_samples == 0


def test_a_leg_gain_factor_scales_that_legs_pd_and_reads_back():
    physics = LegPhysics.ideal().replace(gain=[1, 1, 0.5, 1, 1, 1])
    plat = FullPlatform("srs", physics=physics)
    kp = [plat.model.actuator(f"leg{j}_position").gainprm[0] for j in range(1, 7)]
    kd = [plat.model.actuator(f"leg{j}_velocity").gainprm[0] for j in range(1, 7)]
    assert kp[2] == pytest.approx(kp[0] / 2) and kd[2] == pytest.approx(kd[0] / 2)
    assert plat.physics.gain.tolist() == [1, 1, 0.5, 1, 1, 1]
    physics.apply(plat.model)  # applying again does not compound
    assert plat.model.actuator("leg3_position").gainprm[0] == pytest.approx(kp[2])


def test_a_diverging_run_stops_with_one_clear_error():
    plat = FullPlatform("mpi")
    data = mujoco.MjData(plat.model)
    states = np.zeros((1, 3, 5))
    states[0, :, 0] = [1.0, 1.001, 1.002]
    states[0, 2, 3] = np.nan
    with pytest.raises(PhysicsDivergedError, match=r"mpi model diverged at t = 1\.002 s"):
        plat._check_finite(states, np.zeros((1, 3, 1)), data)
    data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number = 1
    with pytest.raises(PhysicsDivergedError, match="MuJoCo warned: badqacc"):
        plat._check_finite(np.zeros((1, 2, 5)), np.zeros((1, 2, 1)), data)


def test_actuator_tables_are_checked():
    with pytest.raises(ConfigError, match="unknown key 'frictoin'"):
        LegPhysics.from_table({"frictoin": 1.0}, "physics")
    with pytest.raises(ConfigError, match=r"gain\[2\] must be a number in \[0.01, 100\]"):
        LegPhysics.from_table({"gain": [1, 1, 0, 1, 1, 1]}, "physics")
    with pytest.raises(ModelFileError, match="one number or a list of 6"):
        LegPhysics.from_table({"play": [0.0, 0.0]}, "build.toml [actuators]", TOML_KEYS,
                              ModelFileError)  # fmt: skip


def test_full_runs_write_leg_forces_and_reduced_runs_do_not(tmp_path):
    from twin.cli.main import main
    from twin.formats.runs import read_run

    for model in ("full", "reduced"):
        out = tmp_path / model
        assert main(["simulate", "mpi", "--signal", "rest-2", "--model", model, "--quiet",
                     "--out", str(out)]) == 0  # fmt: skip
        run = read_run(out)
        if model == "full":
            assert run.forces is not None and run.forces.shape == run.actuators.shape
            assert np.allclose(run.forces[:, 0], run.actuators[:, 0])
            assert (run.forces[:, 1:] > 0).all()  # at rest every leg pushes
        else:
            assert run.forces is None and not (out / "forces.csv").exists()


# --- a payload on the cabin ---------------------------------------------------------------------


def test_a_payload_scales_the_cabin_and_the_leg_forces_it_must_carry():
    from twin.platform.facts import load_model
    from twin.platform.payload import Payload, cabin_mass_properties

    nominal_mass, nominal_com = cabin_mass_properties(load_model("srs"))
    heavy = Payload.scaling("srs", 1.6).model("srs")
    mass, com = cabin_mass_properties(heavy)
    assert mass == pytest.approx(1.6 * nominal_mass) and np.allclose(com, nominal_com)
    rest = Trajectory(100.0, np.zeros((101, 6)))
    cfg = motion_system("srs").override(None, 0.0, False)
    forces = [simulate(cfg, rest, "full", seed=0, platform=FullPlatform("srs", payload=p))
              .response.leg_force[-1] for p in (None, Payload.scaling("srs", 1.6))]  # fmt: skip
    assert forces[1] == pytest.approx(1.6 * forces[0], rel=2e-3)


def test_a_heavier_cabin_lags_more_in_pitch_as_table_5_5s_t_m_grows_with_inertia():
    """MPI pitch: t_m = 12.4 ms (Table 5.5) = I / (K_d sum r^2); twice the inertia adds about
    as much again (a first-order lag delays a slow sine by about its time constant)."""
    from twin.platform.payload import Payload

    t = np.arange(601) / 100.0
    v = np.zeros((t.size, 6))
    v[:, 4] = 0.02 * np.sin(2 * np.pi * 0.5 * t) * np.clip(t / 1.5, 0, 1)
    cmd = Trajectory(100.0, v)
    cfg = motion_system("mpi").override(None, 0.0, False)
    pitch = [simulate(cfg, cmd, "full", seed=0, platform=FullPlatform("mpi", payload=p))
             .response.pose[2000:, 4] for p in (None, Payload.scaling("mpi", 2.0))]  # fmt: skip
    shifts = np.arange(0, 40)
    misfit = [np.mean((pitch[0][: pitch[0].size - s] - pitch[1][s:]) ** 2) for s in shifts]
    assert shifts[int(np.argmin(misfit))] / 1000.0 == pytest.approx(0.0124, rel=0.35)


def test_payloads_are_checked():
    from twin.platform.payload import Payload

    with pytest.raises(ConfigError, match="payload mass_kg must be a number > 0"):
        Payload.of(0.0)
    with pytest.raises(ConfigError, match="position_m must lie within 5 m"):
        Payload.of(10.0, (0, 0, 9))
    with pytest.raises(ConfigError, match="payload factor must be a number in"):
        Payload.scaling("mpi", 0.5)
    with pytest.raises(ConfigError, match="more than 10 times"):
        Payload.of(1e6).model("mpi")


# --- physics in a configuration -----------------------------------------------------------------


def test_a_configurations_physics_reaches_the_full_model_and_round_trips(tmp_path, capsys):
    import json

    from twin.chain.config import load_config
    from twin.cli.main import main
    from twin.formats.runs import read_run

    physics = {"legs": {"coulomb_n": [0, 800, 0, 0, 0, 0]},
               "payload": {"mass_kg": 150.0, "position_m": [0.3, 0.0, -0.5],
                           "inertia": [20.0, 30.0, 20.0]}}  # fmt: skip
    cfg = motion_system("mpi").to_meta() | {"physics": physics}
    path = tmp_path / "calibrated.json"
    path.write_text(json.dumps({"format": "twin-config/1", "platform": "mpi",
                                "platform_config": cfg}))  # fmt: skip
    ms = load_config(path)
    assert ms.physics.legs.coulomb_n.tolist() == [0, 800, 0, 0, 0, 0]
    assert ms.physics.payload.mass_kg == 150.0
    again = load_config(ms.save(tmp_path / "again.json"))
    assert again.to_meta() == ms.to_meta()
    runs = {}
    for name, config in (("nominal", "mpi"), ("calibrated", str(path))):
        out = tmp_path / name
        assert main(["simulate", config, "--signal", "multisine1-heave", "--quiet", "--out",
                     str(out)]) == 0  # fmt: skip
        runs[name] = read_run(out)
    assert runs["calibrated"].meta["platform_config"]["physics"] == again.to_meta()["physics"]
    static = runs["calibrated"].forces[:50, 1:].sum() / runs["nominal"].forces[:50, 1:].sum()
    mass = float(FullPlatform("mpi").model.body("cabin").mass[0])
    assert static == pytest.approx((mass + 150.0) / mass, rel=0.01)  # the legs carry it
    capsys.readouterr()
    assert main(["simulate", str(path), "--signal", "rest-1", "--model", "reduced",
                 "--out", str(tmp_path / "r")]) == 2  # fmt: skip
    assert "needs the full model" in capsys.readouterr().err


def test_a_configurations_physics_is_strict():
    from twin.chain.config import MotionSystem

    base = motion_system("mpi").to_meta()
    for physics, message in (
        ({"leg": {}}, "unknown key 'leg'"),
        ({"legs": {"coulomb": 1}}, "unknown key 'coulomb'"),
        ({"legs": {"play_m": 1.0}}, r"play_m\[0\] must be a number in \[0, 0.1\]"),
        ({"payload": {"position_m": [0, 0, 0]}}, "lacks 'mass_kg'"),
        ({"payload": {"mass_kg": 1e9}}, "more than 10 times"),
        ([1, 2], "must be an object"),
    ):
        with pytest.raises(ConfigError, match=message):
            MotionSystem.from_meta("mpi", base | {"physics": physics})
