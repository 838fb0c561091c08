"""Full and reduced platforms: IMU at rest, lever arm, determinism, limits."""

import numpy as np
import pytest

from twin.chain.imu import ImuSpec, postprocess, specific_force
from twin.chain.signals import builtin_signal, describing_signal, rest
from twin.chain.simulate import prepare, simulate
from twin.chain.trajectory import Trajectory
from twin.core.errors import ActuatorLimitError, SignalError
from twin.core.frames import rotation_matrix


@pytest.mark.parametrize("model", ["full", "reduced"])
def test_imu_at_rest_reads_minus_g(model):
    sim = simulate("mpi-2008", rest(3.0), model, imu=ImuSpec().ideal())
    acc = sim.imu.accel[len(sim.imu.t) // 3 :]
    assert acc[:, 2].mean() == pytest.approx(-9.81, abs=2e-3)
    assert np.abs(acc[:, :2]).max() < 2e-3
    assert np.abs(sim.imu.gyro).max() < 1e-3
    assert sim.imu.rate_hz == pytest.approx(819.2)


def test_default_imu_noise_and_bias_are_applied():
    sim = simulate("srs", rest(5.0), "reduced", seed=2)
    acc = sim.imu.accel
    assert acc[:, 2].std() == pytest.approx(0.035 * 9.81, rel=0.1)  # ADIS16355 35 mg rms
    assert acc[:, 2].mean() == pytest.approx(-9.81, abs=0.05)


@pytest.mark.parametrize("dof", ["heave", "pitch"])
def test_full_model_specific_force_is_the_second_difference_of_the_cabin_path(dof):
    # ground truth: the second difference of the simulated path of the mount point, at the
    # UGP and off it (MuJoCo's acceleration sensors are not: under implicitfast they miss the
    # implicit damping correction and read ~2.4x too much in heave)
    sig = describing_signal(2, dof)
    r = simulate("mpi-2008", sig.commands, "full").response
    T = rotation_matrix(r.pose[:, 3:])
    dt = r.t[1] - r.t[0]
    for mount in (np.zeros(3), np.array([0.4, -0.3, -0.5])):  # cabin frame, m
        path = r.pose[:, :3] + T @ mount
        a = (path[2:] - 2 * path[1:-1] + path[:-2]) / dt**2
        truth = np.einsum("nji,nj->ni", T[1:-1], a - [0.0, 0.0, 9.81])
        f = specific_force(r, mount)[1:-1]
        err = np.sqrt(np.mean((f - truth)[1000:] ** 2))
        assert err < 0.01 * np.std(truth[1000:], axis=0).max()
    if dof == "pitch":  # the arm matters
        assert np.abs(f - specific_force(r, np.zeros(3))[1:-1]).max() > 0.1
    assert np.abs(r.omega - r.sensor_gyro).max() < 1e-9


def test_seeded_runs_are_bit_identical_and_chunking_changes_only_rounding():
    cmd = describing_signal(2, "heave").commands
    a = simulate("mpi", cmd, "full", seed=5)
    b = simulate("mpi", cmd, "full", seed=5)
    c = simulate("mpi", cmd, "full", seed=6)
    assert np.array_equal(a.imu.accel, b.imu.accel)
    assert np.array_equal(a.response.pose, b.response.pose)
    assert not np.array_equal(a.imu.accel, c.imu.accel)
    run = prepare("mpi", cmd, "full", seed=5)
    chunks = list(run.platform.run(run.platform_input, run.noise_stream(), chunk_s=3.3))
    pose = np.concatenate([ch.pose for ch in chunks])
    # other chunks: the same to rounding (the filters restart their recursions per chunk)
    assert np.abs(pose - a.response.pose).max() < 1e-12


def _sequential(items, submit):
    """Each step finished before the next is submitted (no physics in a thread)."""
    for item in items:
        yield submit(item)()


def test_physics_rolled_in_a_thread_gives_the_same_bits_as_step_by_step(monkeypatch):
    """Run.chunks submits chunk k + 1 before finishing chunk k (the full model's physics rolls
    in a thread meanwhile): the same bits as finishing every chunk first, over five chunks."""
    import twin.chain.simulate as simulate_module

    sig = describing_signal(2, "pitch").commands
    cmd = Trajectory(sig.rate_hz, sig.values[:251])  # 2.5 s
    out = []
    for overlap in (True, False):
        if not overlap:
            monkeypatch.setattr(simulate_module, "overlapped", _sequential)
        run = prepare("mpi", cmd, "full", seed=3)
        run.chunk_s = 0.5
        out.append(run.collect())
    assert out[0].response.t.size == 2501
    for name in ("pose", "legs", "acceleration"):
        assert np.array_equal(getattr(out[0].response, name), getattr(out[1].response, name))
    assert np.array_equal(out[0].imu.accel, out[1].imu.accel)


def test_blas_keeps_to_one_thread_while_the_physics_rolls_and_is_restored_after():
    """A process whose BLAS has two threads (the test workers have one: set it here)."""
    from threadpoolctl import threadpool_info, threadpool_limits

    def blas_threads():
        return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}

    run = prepare("mpi", Trajectory(100.0, np.zeros((101, 6))), "full")
    run.chunk_s = 0.5
    with threadpool_limits(limits=2, user_api="blas"):
        assert blas_threads() == {2}
        during = [blas_threads() for _ in run.chunks()]
        assert blas_threads() == {2}
    assert len(during) == 3 and all(n == {1} for n in during)


def test_an_error_in_the_physics_thread_reaches_the_caller(monkeypatch):
    import twin.chain.physics as physics

    def broken(*args, **kwargs):
        raise RuntimeError("rollout failed")

    monkeypatch.setattr(physics.rollout, "rollout", broken)
    run = prepare("mpi", Trajectory(100.0, np.zeros((101, 6))), "full")
    run.chunk_s = 0.5
    with pytest.raises(RuntimeError, match="rollout failed"):
        run.collect()


def _too_fast(rate_hz=100.0):
    t = np.arange(0, 6.0, 1 / rate_hz)
    v = np.zeros((t.size, 6))
    v[:, 2] = -0.15 * np.sin(2 * np.pi * 2.0 * t) * np.clip(t - 1, 0, 1)  # 0.15 m at 2 Hz
    return Trajectory(rate_hz, v)


def test_actuator_limits_are_counted_and_applied():
    sim = simulate("mpi-2008", _too_fast(), "full")
    assert sim.limits.samples["velocity"] > 0 and sim.limits.samples["acceleration"] > 0
    assert "leg" in sim.limits.first
    legs = sim.response.legs
    dt = sim.response.t[1] - sim.response.t[0]
    v = np.diff(legs, axis=0) / dt
    assert np.abs(v).max() < 0.3 * 1.1  # Table 5.1 0.3 m/s, with PD tracking error
    quiet = simulate("mpi-2008", describing_signal(1, "heave").commands, "full")
    assert quiet.limits.total == 0


@pytest.mark.parametrize("config", ["mpi-2008", "mpi"])
def test_reduced_model_counts_limits_like_an_exact_check_of_every_sample(config):
    # the reduced platform computes leg rates only where a bound allows a violation; the
    # counts must equal those of checking every sample exactly
    run = prepare(config, _too_fast(), "reduced", seed=2)
    sim = run.collect()
    from twin.chain.limits import LimitReport
    from twin.platform.kinematics import leg_rates

    plat = run.platform
    exact = LimitReport("limit", plat.rate_hz)
    sig = run.platform_input
    state = plat.reset(sig.jets[:, 0], sig.t0, sig.rate_hz, [run.noise_stream()])
    ref = plat._reference(sig.jets, state)  # every platform sample, noise included
    lengths, vel, acc = leg_rates(plat.geometry, ref.pose[0], ref.rate[0], ref.acc[0])
    plat.limits.check(ref.t, lengths, vel, acc, exact)
    assert exact.samples["velocity"] > 0 and exact.samples["acceleration"] > 0
    assert sim.limits.samples == exact.samples
    assert sim.limits.first == exact.first


def test_strict_mode_rejects_commands_beyond_limits():
    with pytest.raises(ActuatorLimitError, match=r"velocity|acceleration"):
        simulate("mpi-2008", _too_fast(), "full", limit_mode="strict")


def test_imu_saturates_and_counts():
    spec = ImuSpec(accel_range=9.0).ideal()
    sim = simulate("srs", rest(1.0), "reduced", imu=spec)
    assert sim.imu.saturated == len(sim.imu.t)
    assert np.abs(sim.imu.accel).max() == pytest.approx(9.0)


def test_postprocess_differentiates_rates_like_appendix_c():
    # App. C.2.3: S-G (order 9, 69 points) differentiator + 201-tap 15 Hz FIR, 100 Hz out
    sig = describing_signal(2, "pitch")  # up to 7.1 Hz: inside the filters' flat band
    sim = simulate("srs", sig.commands, "reduced", imu=ImuSpec().ideal())
    out = postprocess(sim.imu)
    assert out.t[1] - out.t[0] == pytest.approx(0.01)
    r = sim.response
    inside = (out.t > sig.window[0]) & (out.t < sig.window[1])
    for got, true in (
        (out.angular_acceleration[:, 1], r.omega_dot[:, 1]),
        (out.gyro[:, 1], r.omega[:, 1]),
        (out.accel[:, 0], specific_force(r, np.zeros(3))[:, 0]),
    ):
        ref = np.interp(out.t, r.t, true)[inside]
        err = got[inside] - ref
        assert np.sqrt(np.mean(err**2)) < 0.02 * np.sqrt(np.mean(ref**2))


def test_builtin_signal_names():
    assert builtin_signal("rest-2").duration == pytest.approx(2.0)
    with pytest.raises(SignalError, match="built-in signals are"):
        builtin_signal("multisine1-wobble")


def test_the_full_platform_takes_another_integration_step():
    """For convergence studies (bench/table_5_5_timestep.py): the step and the loop-closure
    time constant (two steps) follow; out-of-range steps are refused."""
    from twin.chain.physics import FullPlatform

    p = FullPlatform("mpi", timestep_s=5e-4)
    assert p.rate_hz == pytest.approx(2000.0)
    assert np.allclose(p.model.eq_solref[:, 0], 1e-3)
    for bad in (0.0, float("nan"), 0.01):
        with pytest.raises(SignalError, match="timestep"):
            FullPlatform("mpi", timestep_s=bad)


@pytest.mark.parametrize("model", ["reduced", "full"])
def test_motion_read_by_several_imus_equals_a_simulation_per_imu(model):
    """Without heave noise the motion is simulated once and read by each (seed, IMU): the bits
    of one simulation per pair (the diagnosis' IMU-noise realisations and its prediction)."""
    sig = describing_signal(2, "pitch").commands
    cmd = Trajectory(sig.rate_hz, sig.values[:301])  # 3 s
    spec = ImuSpec()
    readings = [(4, spec.ideal()), (5, spec), (6, spec.with_noise(2.0))]
    run = prepare("srs", cmd, model, 4)
    run.chunk_s = 1.0  # several chunks
    shared = run.read_by_imus(readings)
    for (seed, imu), got in zip(readings, shared, strict=True):
        alone = prepare("srs", cmd, model, seed, imu)
        alone.chunk_s = 1.0
        want = alone.collect()
        assert got.seed == seed and got.imu_spec == imu
        assert np.array_equal(got.imu.accel, want.imu.accel)
        assert np.array_equal(got.imu.gyro, want.imu.gyro)
        assert np.array_equal(got.response.pose, want.response.pose)
    assert not np.array_equal(shared[1].imu.accel, shared[2].imu.accel)
    with pytest.raises(SignalError, match="heave noise"):
        prepare("mpi", cmd, model, 1).read_by_imus(readings)
    with pytest.raises(SignalError, match="at least one"):
        prepare("srs", cmd, model, 1).read_by_imus([])


def test_a_full_platform_without_leg_forces_moves_the_same():
    """leg_forces=False (a diagnosis' predictions) drops the forces only: the same motion bits."""
    from twin.chain.physics import FullPlatform

    sig = describing_signal(1, "heave")
    cmd = Trajectory(sig.commands.rate_hz, sig.commands.values[:400])
    with_forces = simulate("srs", cmd, "full", seed=4)
    without = simulate("srs", cmd, "full", seed=4, platform=FullPlatform("srs", leg_forces=False))
    assert without.response.leg_force is None and with_forces.response.leg_force is not None
    for name in ("pose", "acceleration", "omega", "omega_dot", "legs", "leg_velocity"):
        assert np.array_equal(getattr(with_forces.response, name), getattr(without.response, name))
    assert np.array_equal(with_forces.imu.accel, without.imu.accel)
    assert np.array_equal(with_forces.imu.gyro, without.imu.gyro)
