"""The compiled kernels give the bits of the NumPy expressions they replace (twin.chain.kernels).

Each test spells the NumPy original out (the expression the chain used before the kernel) and
compares bit patterns, signed zeros included, on random data, non-contiguous views and
several runs; tests/test_stored_figures.py compares whole seeded runs.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from twin.chain import kernels
from twin.chain.imu import specific_force
from twin.chain.jets import hermite_eval, hermite_samples
from twin.chain.reduced import ReducedPlatform
from twin.chain.response import GRAVITY_BASE, PlatformResponse
from twin.chain.trajectory import Trajectory, interp_columns
from twin.core.frames import angular_motion, rotation_matrix
from twin.platform.geometry import load_geometry
from twin.platform.kinematics import leg_rates


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal bit patterns (so -0.0 differs from 0.0; a NaN is compared as its bits)."""
    a, b = np.ascontiguousarray(a, float), np.ascontiguousarray(b, float)
    return a.shape == b.shape and bool((a.view(np.int64) == b.view(np.int64)).all())


def _cross(a, b):
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def rigid_motion(pose, rate, acc, T):
    """The NumPy the rigid-cabin kernel replaced: velocities, and omega in cabin axes (Eq A.4)."""
    omega_b, omega_dot_b = angular_motion(pose[:, 3:], rate[:, 3:], acc[:, 3:])
    omega = np.einsum("nji,nj->ni", T, omega_b)
    omega_dot = np.einsum("nji,nj->ni", T, omega_dot_b)
    return rate[:, :3].copy(), acc[:, :3].copy(), omega, omega_dot


def test_same_bits_tells_signed_zeros_apart():
    assert same_bits(np.array([0.0, 1.0]), np.array([0.0, 1.0]))
    assert not same_bits(np.array([0.0]), np.array([-0.0]))
    assert not same_bits(np.array([1.0]), np.array([np.nextafter(1.0, 2.0)]))


@pytest.mark.parametrize("runs", [1, 3])
def test_the_quintic_at_many_points_is_hermite_eval_at_each(runs):
    rng = np.random.default_rng(runs)
    jets = rng.standard_normal((runs, 41, 6, 3))
    jets[:, :3] = -0.0  # zeros of either sign stay what NumPy makes of them
    h = 0.01
    x = np.arange(300) / 7.6  # points between the samples, a rate no multiple of theirs
    k = np.minimum(np.floor(x).astype(int), 39)
    s = x - k
    got = hermite_samples(jets, k, s, h)
    want = hermite_eval(jets[:, k], jets[:, k + 1], s[:, None], h)  # (runs, m, c, 3)
    assert same_bits(got, np.moveaxis(want, -1, 0))
    # one position for all points (a delay's), on a non-contiguous view of the jets
    view = np.concatenate([jets, jets], axis=2)[:, :, ::2]
    got = hermite_samples(view, k, 0.3, h)
    want = hermite_eval(view[:, k], view[:, k + 1], 0.3, h)
    assert same_bits(got, np.moveaxis(want, -1, 0))


def _poses(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    pose = rng.normal(0, [0.1, 0.1, 0.1, 0.3, 0.3, 0.6], (n, 6))
    rate, acc = rng.standard_normal((n, 6)), rng.standard_normal((n, 6)) * 5
    pose[:4] = 0.0  # at neutral: zero angles and products
    signed = rng.choice([0.0, -0.0], (2, 300, 6))  # at rest: products zero of either sign
    rate[-300:], acc[-300:] = signed
    return pose, rate, acc


def test_the_rigid_cabin_is_rotation_motion_and_legs_of_numpy():
    geo = load_geometry("srs")
    pose, rate, acc = _poses(2000)
    wide = np.concatenate([pose, rate], axis=1)[:, :6]  # a strided view, as the chain passes
    angles = wide[:, 3:]
    trig = np.array([f(angles[:, k]) for k in range(3) for f in (np.cos, np.sin)])
    n = len(pose)
    rot, lengths = np.empty((n, 3, 3)), np.empty((n, 6))
    omega, omega_dot = np.empty((n, 3)), np.empty((n, 3))
    kernels.rigid_cabin(wide, rate, acc, trig, geo.cabin_gimbals, geo.base_gimbals,
                        geo.neutral_ugp, rot, omega, omega_dot, lengths)  # fmt: skip
    T = rotation_matrix(wide[:, 3:])
    assert same_bits(rot, T)
    _, _, w, wd = rigid_motion(wide, rate, acc, T)
    assert same_bits(omega, w) and same_bits(omega_dot, wd)
    assert same_bits(lengths, leg_rates(geo, wide, rotation=T)[0])


def test_limit_suspects_are_the_samples_whose_bounds_reach_a_limit():
    platform = ReducedPlatform("mpi")
    lim = platform.limits
    pose, rate, acc = _poses(5000, seed=2)
    scale = np.geomspace(1e-3, 1.0, len(pose))[:, None]  # from quiet to beyond the limits
    pose, rate, acc = pose * scale, rate * scale, acc * scale
    T = rotation_matrix(pose[:, 3:])
    lengths = leg_rates(platform.geometry, pose, rotation=T)[0]
    velocity, acceleration, omega, omega_dot = rigid_motion(pose, rate, acc, T)

    def norm(v):
        return np.sqrt(v[:, 0] ** 2 + v[:, 1] ** 2 + v[:, 2] ** 2)

    r = platform._radius
    w = norm(omega)
    v_bound = norm(velocity) + w * r
    a_bound = norm(acceleration) + (norm(omega_dot) + w**2) * r + v_bound**2 / lengths.min(axis=1)
    want = (v_bound > lim.max_velocity * 0.999) | (a_bound > lim.max_acceleration * 0.999)
    want |= ((lengths < lim.leg_min) | (lengths > lim.leg_max)).any(axis=1)
    got = np.empty(len(pose), dtype=bool)
    kernels.limit_suspects(velocity, acceleration, omega, omega_dot, lengths, r,
                           lim.max_velocity * 0.999, lim.max_acceleration * 0.999,
                           lim.leg_min, lim.leg_max, got)  # fmt: skip
    assert 0 < want.sum() < len(want), "the data reach some limits and not others"
    np.testing.assert_array_equal(got, want)


def test_the_specific_force_is_the_einsum_and_cross_products_of_numpy():
    pose, rate, acc = _poses(3000, seed=3)
    T = rotation_matrix(pose[:, 3:])
    velocity, acceleration, omega, omega_dot = rigid_motion(pose, rate, acc, T)
    # at rest in free fall (a = g), turning at zero rate: every product a zero of either sign
    zeros = np.random.default_rng(7).choice([0.0, -0.0], (400, 3, 3))
    acceleration[-400:] = zeros[:, 0]
    acceleration[-400:, 2] = GRAVITY_BASE[2]
    omega[-400:], omega_dot[-400:] = zeros[:, 1], zeros[:, 2]
    z = np.zeros((len(pose), 6))
    resp = PlatformResponse(np.arange(len(pose)) / 100.0, pose, pose, velocity, acceleration,
                            omega, omega_dot, z, rotation=T)  # fmt: skip
    mount = np.array([0.4, -0.2, 1.1])
    f = np.einsum("nji,nj->ni", T, acceleration - GRAVITY_BASE)
    want = f + _cross(omega_dot, mount) + _cross(omega, _cross(omega, mount))
    assert same_bits(specific_force(resp, mount), want)


def test_the_sensor_errors_are_numpy_bias_noise_and_clip():
    rng = np.random.default_rng(4)
    values = rng.standard_normal((4000, 6)) * 3
    values[5, 2] = np.nan
    bias, sd = rng.standard_normal(6) * 0.1, np.array([0.3, 0.3, 0.3, 0.01, 0.01, 0.01])
    noise = rng.standard_normal(values.shape)
    limit = np.array([5.0, 5.0, 5.0, 2.0, 2.0, 2.0])
    want = values + bias
    want += noise * sd
    hit = np.abs(want) > limit
    want = np.clip(want, -limit, limit)
    got = values.copy()
    count = kernels.sensor_errors(got, bias, noise, sd, limit)
    assert same_bits(got, want)
    assert count == int(hit.any(axis=1).sum()) > 0


def test_the_cubic_jets_are_the_splines_own_derivatives():
    rng = np.random.default_rng(5)
    t = np.arange(50) / 100.0
    y = rng.standard_normal((50, 6))
    tr = Trajectory(100.0, y)
    at = np.sort(rng.uniform(-0.05, 0.55, 400))  # held before and after the samples
    got = tr.derivatives(at, 2)
    spline = CubicSpline(t, y, axis=0)
    inside = np.clip(at, 0.0, 0.49)
    for d in range(3):
        want = spline(inside, d)
        if d:
            want[(at < 0) | (at > 0.49)] = 0.0
        np.testing.assert_allclose(got[d], want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    # the Horner form, bit for bit (the value; one segment per point)
    i = np.minimum((inside * 100).astype(int), 48)
    tau = (inside - spline.x[i])[:, None]
    c3, c2, c1, c0 = spline.c[:, i]
    assert same_bits(got[0], ((c3 * tau + c2) * tau + c1) * tau + c0)
    assert len(tr.derivatives(at, 0)) == 1


def test_interp_columns_on_the_sample_times_takes_the_samples():
    rng = np.random.default_rng(6)
    grid = np.arange(100) / 819.2
    values = rng.standard_normal((100, 6))
    got = interp_columns(grid[10:60], grid, values)
    assert same_bits(got, values[10:60])
    got[0, 0] = 99.0  # a copy, not a view of the samples
    assert values[10, 0] != 99.0
    # with a repeated time the last of the equal samples is taken, as numpy.interp does
    dup = np.insert(grid, 20, grid[19])
    vdup = np.insert(values, 20, values[19] + 1.0, axis=0)
    want = np.column_stack([np.interp(grid[10:30], dup, vdup[:, k]) for k in range(6)])
    assert same_bits(interp_columns(grid[10:30], dup, vdup), want)
    between = grid[10:30] + 0.3 / 819.2
    want = np.column_stack([np.interp(between, grid, values[:, k]) for k in range(6)])
    assert same_bits(interp_columns(between, grid, values), want)


def test_the_quintic_refuses_an_interval_outside_the_samples():
    jets = np.zeros((1, 30, 6, 3))
    with pytest.raises(IndexError, match=r"0\.\.28"):
        hermite_samples(jets, np.array([29]), np.array([0.5]), 0.01)
    with pytest.raises(IndexError, match=r"got -1\.\.3"):
        hermite_samples(jets, np.array([-1, 3]), np.array([0.5, 0.5]), 0.01)


def test_a_kernel_pickles_as_its_name():
    import pickle

    again = pickle.loads(pickle.dumps(kernels.sensor_errors))
    assert again is kernels.sensor_errors


def _limit_loop(lim, dt, x, xd, broken, state):
    """The NumPy loop the compiled limiter replaced (ActuatorLimits._limit before the kernel)."""
    a, vmax = lim.max_acceleration, lim.max_velocity
    y, yd = x.copy(), xd.copy()
    pos, vel = state.length.copy(), state.velocity.copy()
    k, n = 0, len(x)
    active = state.active
    while k < n:
        if not active:
            nxt = np.flatnonzero(broken[k:])
            if nxt.size == 0:
                break
            k += int(nxt[0])
            pos, vel = (y[k - 1], yd[k - 1]) if k > 0 else (pos, vel)
            active = True
        e = x[k] - pos
        correction = np.sign(e) * np.minimum(np.abs(e) / dt, np.sqrt(2 * a * np.abs(e)))
        v = np.clip(xd[k] + correction, vel - a * dt, vel + a * dt)
        v = np.clip(v, -vmax, vmax)
        new = np.clip(pos + v * dt, lim.leg_min, lim.leg_max)
        v = (new - pos) / dt
        y[k], yd[k] = new, v
        pos, vel = new, v
        if np.all(np.abs(x[k] - new) < 1e-7) and np.all(np.abs(xd[k] - v) <= a * dt):
            active = False
        k += 1
    state.length, state.velocity, state.active = y[-1].copy(), yd[-1].copy(), active
    return y, yd


def _leg_references(rng, n, lim):
    """Leg references that jump (a play), leave the stroke, rest and hold; some signed zeros."""
    t = np.arange(n) / 1000.0
    mid = 0.5 * (lim.leg_min + lim.leg_max)
    span = 0.5 * (lim.leg_max - lim.leg_min)
    phase = 2 * np.pi * rng.uniform(0.2, 3.0, 6) * t[:, None] + rng.uniform(0, 6, 6)
    x = mid + span * np.sin(phase)
    x *= 1 + 0.15 * (rng.uniform(size=(n, 1)) < 0.01)  # jumps, some beyond the stroke
    x += np.cumsum(rng.normal(0, 2e-4, (n, 6)), axis=0)
    xd = np.gradient(x, 1e-3, axis=0)
    x[n // 2 : n // 2 + 400] = x[n // 2]  # a rest the limiter rejoins in
    xd[n // 2 : n // 2 + 400] = rng.choice([0.0, -0.0], (400, 6))
    return x, xd


@pytest.mark.parametrize("platform", ["mpi", "srs"])
def test_the_compiled_limiter_is_the_numpy_loop(platform):
    from copy import deepcopy

    from twin.chain.limits import ActuatorLimits, LimiterState
    from twin.platform.facts import load_facts

    geo = load_geometry(platform)
    lim = ActuatorLimits.of(geo, load_facts(platform))
    rng = np.random.default_rng(8)
    dt = 1e-3
    limited = 0
    for trial in range(6):
        x, xd = _leg_references(rng, 3000, lim)
        broken = rng.uniform(size=len(x)) < (0.002 if trial % 2 else 0.05)
        broken[0] = trial == 2
        state = LimiterState(x[0] + rng.normal(0, 1e-3, 6), rng.normal(0, 0.05, 6), trial > 3)
        mine, ref = deepcopy(state), deepcopy(state)
        for chunk in np.array_split(np.arange(len(x)), 4):  # carried between chunks
            got = lim._limit(dt, x[chunk], xd[chunk], broken[chunk], mine)
            want = _limit_loop(lim, dt, x[chunk], xd[chunk], broken[chunk], ref)
            assert same_bits(got[0], want[0]) and same_bits(got[1], want[1])
            assert same_bits(mine.length, ref.length) and same_bits(mine.velocity, ref.velocity)
            assert mine.active == ref.active
            limited += int((got[0] != x[chunk]).any(axis=1).sum())
    assert limited > 1000, "the references were limited for a good share of the samples"


@pytest.mark.parametrize("max_acceleration", [3.0, 0.0])  # 0: the clips meet zeros of both signs
def test_the_compiled_limiter_keeps_numpys_nans_and_signed_zeros(max_acceleration):
    from copy import deepcopy

    from twin.chain.limits import ActuatorLimits, LimiterState

    legs = np.full(6, 1.0)
    lim = ActuatorLimits(legs * 0.5, legs * 2.0, 0.5, max_acceleration)
    rng = np.random.default_rng(9)
    dt = 1e-3
    x = rng.choice([1.0, 1.0 + 1e-9, 0.4, 2.5, np.nan], (400, 6))
    xd = rng.choice([0.0, -0.0, 0.003, -0.003, 1.0, np.nan], (400, 6))
    broken = rng.uniform(size=400) < 0.1
    for active in (False, True):
        state = LimiterState(rng.choice([1.0, 3.0], 6), rng.choice([0.0, -0.0, 0.003], 6), active)
        mine, ref = deepcopy(state), deepcopy(state)
        got = lim._limit(dt, x, xd, broken, mine)
        want = _limit_loop(lim, dt, x, xd, broken, ref)
        for g, w in zip(got, want, strict=True):
            nan = np.isnan(w)
            assert (np.isnan(g) == nan).all() and same_bits(g[~nan], w[~nan])
        assert mine.active == ref.active
