"""Inverse/forward kinematics, Jacobian and leg rates (Appendix A)."""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from twin.core.errors import ForwardKinematicsError, OutOfStrokeError, PoseError
from twin.core.frames import euler_rate_matrix, rotation_matrix
from twin.platform.geometry import load_geometry
from twin.platform.kinematics import (
    actuator_trajectory,
    forward,
    inverse,
    jacobian,
    leg_rates,
    workspace,
)

GEOS = {p: load_geometry(p) for p in ("mpi", "srs")}
WS = {p: workspace(g) for p, g in GEOS.items()}


def pose_in_workspace(platform):
    """Poses with each DOF inside its single-DOF range (combined poses may leave the stroke)."""
    ranges = list(WS[platform].values())
    return st.tuples(*[st.floats(0.95 * r.min, 0.95 * r.max) for r in ranges]).map(np.array)


@pytest.mark.parametrize("platform", ["mpi", "srs"])
def test_fk_of_ik_returns_the_pose_within_tolerance(platform):
    @settings(max_examples=150, deadline=None)
    @given(pose_in_workspace(platform))
    def check(pose):
        geo = GEOS[platform]
        lengths = inverse(geo, pose, check=False)
        assume(np.all(lengths >= geo.leg_min) and np.all(lengths <= geo.leg_max))
        fk = forward(geo, lengths)
        assert np.abs(inverse(geo, fk.pose, check=False) - lengths).max() < 1e-7
        assert np.allclose(fk.pose, pose, atol=1e-6)
        assert fk.iterations <= 12

    check()


def test_fk_from_the_desired_pose_takes_two_or_three_iterations():
    # App. A.4: 2-3 iterations when the initial guess is the desired pose
    geo = GEOS["mpi"]
    pose = np.array([0.1, -0.05, 0.08, 0.1, -0.12, 0.3])
    lengths = inverse(geo, pose)
    fk = forward(geo, lengths, initial=pose + 1e-3)
    assert 1 <= fk.iterations <= 3
    assert fk.residual < 1e-7


def test_fk_is_vectorised_over_a_trajectory():
    geo = GEOS["srs"]
    t = np.linspace(0, 2, 201)
    pose = np.column_stack([0.3 * np.sin(t), 0.2 * np.cos(t), 0.1 * t, 0.1 * np.sin(3 * t),
                            0.05 * t, -0.2 * np.sin(t)])  # fmt: skip
    fk = forward(geo, inverse(geo, pose))
    assert fk.pose.shape == (201, 6)
    assert fk.iterations_per_sample.shape == (201,)
    assert np.allclose(fk.pose, pose, atol=1e-6)


@pytest.mark.parametrize("platform", ["mpi", "srs"])
def test_jacobian_matches_finite_differences_of_ik(platform):
    geo = GEOS[platform]
    rng = np.random.default_rng(7)
    for _ in range(20):
        pose = rng.uniform(-1, 1, 6) * [0.1, 0.1, 0.1, 0.2, 0.2, 0.3]
        J = jacobian(geo, pose)
        h = 1e-6
        fd = np.column_stack([
            (inverse(geo, pose + h * e, check=False) - inverse(geo, pose - h * e, check=False))
            / (2 * h)
            for e in np.eye(6)
        ])  # fmt: skip
        assert np.allclose(J, fd, atol=1e-7)


def test_euler_rate_matrix_gives_the_angular_velocity_of_the_rotation():
    # Eq A.4: skew(omega) = T_dot T^T
    rng = np.random.default_rng(3)
    eta, eta_dot = rng.uniform(-0.5, 0.5, 3), rng.uniform(-1, 1, 3)
    h = 1e-6
    Td = (rotation_matrix(eta + h * eta_dot) - rotation_matrix(eta - h * eta_dot)) / (2 * h)
    W = Td @ rotation_matrix(eta).T
    omega = np.array([W[2, 1], W[0, 2], W[1, 0]])
    assert np.allclose(omega, euler_rate_matrix(eta) @ eta_dot, atol=1e-8)


def test_leg_velocities_and_accelerations_match_differentiated_lengths():
    geo = GEOS["mpi"]
    w = 2 * np.pi * np.array([0.3, 0.5, 0.7, 0.4, 0.6, 0.2])
    amp = np.array([0.1, 0.08, 0.06, 0.15, 0.12, 0.3])
    t = np.linspace(0, 3, 30001)
    pose = amp * np.sin(np.outer(t, w))
    rate = amp * w * np.cos(np.outer(t, w))
    acc = -amp * w**2 * np.sin(np.outer(t, w))
    lengths, vel, accel = leg_rates(geo, pose, rate, acc)
    dt = t[1] - t[0]
    fd_vel = np.gradient(lengths, dt, axis=0)
    fd_acc = np.gradient(fd_vel, dt, axis=0)
    assert np.allclose(vel[2:-2], fd_vel[2:-2], atol=1e-6)
    assert np.allclose(accel[5:-5], fd_acc[5:-5], atol=1e-4)
    # the sampled-trajectory helper agrees with the exact derivatives
    traj = actuator_trajectory(geo, t, pose)
    assert np.allclose(traj.velocities, vel, atol=1e-5)
    assert np.allclose(traj.accelerations[5:-5], accel[5:-5], atol=1e-3)


def test_limit_violations_name_the_limit_leg_and_time():
    geo = GEOS["mpi"]
    t = np.linspace(0, 2, 2001)
    w = 2 * np.pi * 2.0
    pose = np.zeros((t.size, 6))
    pose[:, 2] = 0.05 * np.sin(w * t)  # 0.63 m/s, 7.9 m/s^2 in heave
    found = actuator_trajectory(geo, t, pose).limit_violations(geo, 0.3, 2.0)
    assert any(v.startswith("velocity limit broken by leg") for v in found)
    assert any(v.startswith("acceleration limit broken by leg") for v in found)
    assert not any("stroke" in v for v in found)
    slow = pose * 0.01
    assert actuator_trajectory(geo, t, slow).limit_violations(geo, 0.3, 2.0) == []


@pytest.mark.parametrize(
    ("pose", "match"),
    [
        ([0, 0, np.nan, 0, 0, 0], r"non-finite value at index \(2,\)"),
        ([0, 0, 0, 0, 0], r"shape \(\.\.\., 6\)"),
        ("abc", "numeric"),
    ],
)
def test_bad_poses_raise_pose_error(pose, match):
    with pytest.raises(PoseError, match=match):
        inverse(GEOS["mpi"], pose)


def test_out_of_stroke_pose_names_the_leg_and_its_range():
    with pytest.raises(OutOfStrokeError, match=r"needs leg \d at .* outside its stroke"):
        inverse(GEOS["mpi"], [0, 0, -0.4, 0, 0, 0])  # 40 cm up: more than half the stroke


def test_fk_rejects_lengths_outside_the_stroke():
    geo = GEOS["mpi"]
    with pytest.raises(OutOfStrokeError, match="leg lengths"):
        forward(geo, geo.neutral_lengths + 0.3)


def test_fk_reports_non_convergence():
    geo = GEOS["mpi"]
    lengths = inverse(geo, [0.1, 0, 0, 0, 0, 0.5])
    with pytest.raises(ForwardKinematicsError, match="did not converge in 1 iterations"):
        forward(geo, lengths, max_iter=1)


def test_fk_rejects_nan_lengths():
    with pytest.raises(PoseError, match="finite"):
        forward(GEOS["mpi"], [np.nan] * 6)
