"""Stewart-platform kinematics of Appendix A, vectorised over time.

A *pose* is an array ``(..., 6)`` of offsets from the neutral pose in the thesis base frame:
surge x, sway y, heave z [m] (z down) and roll, pitch, yaw [rad] (Eq A.1). Leg lengths are
absolute [m]. Every function accepts any number of leading (time, batch) axes.

Examples
--------
>>> import numpy as np
>>> from twin.platform.geometry import load_geometry
>>> geo = load_geometry("mpi")
>>> pose = np.array([0.0, 0.0, -0.1, 0.0, np.radians(5.0), 0.0])  # 10 cm up, 5 deg nose up
>>> fk = forward(geo, inverse(geo, pose))
>>> bool(np.allclose(fk.pose, pose, atol=1e-7)), fk.iterations <= 5
(True, True)

"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from twin.core.errors import ForwardKinematicsError, OutOfStrokeError, PoseError
from twin.core.frames import DOF_NAMES, angular_motion, euler_rate_matrix, rotation_matrix
from twin.core.results import frame
from twin.platform.geometry import Geometry

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from twin.core.plotting import AxesArg

FloatArray = NDArray[np.float64]

#: Forward-kinematics tolerance on leg lengths [m] (App. A.4).
FK_TOLERANCE = 1e-7


def as_pose(pose: ArrayLike, name: str = "pose") -> FloatArray:
    """Validate a pose array and return it as float.

    Parameters
    ----------
    pose : array_like, shape (..., 6)
        Pose offsets from neutral (m, rad).
    name : str
        What to call the array in error messages.

    Raises
    ------
    PoseError
        If the last axis is not 6 long or any value is NaN or infinite.

    """
    try:
        p = np.asarray(pose, dtype=float)
    except (TypeError, ValueError):
        raise PoseError(f"{name} must be numeric, shape (..., 6)") from None
    if p.ndim == 0 or p.shape[-1] != 6:
        raise PoseError(
            f"{name} must have shape (..., 6) = (surge, sway, heave, roll, pitch, yaw); "
            f"got shape {p.shape}"
        )
    bad = ~np.isfinite(p)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise PoseError(f"{name} holds a non-finite value at index {idx}: poses must be finite")
    return p


def _as_lengths(lengths: ArrayLike) -> FloatArray:
    try:
        q = np.asarray(lengths, dtype=float)
    except (TypeError, ValueError):
        raise PoseError("leg lengths must be numeric, shape (..., 6)") from None
    if q.ndim == 0 or q.shape[-1] != 6:
        raise PoseError(f"leg lengths must have shape (..., 6); got shape {q.shape}")
    if not np.all(np.isfinite(q)):
        raise PoseError("leg lengths must be finite")
    return q


def check_stroke(geo: Geometry, lengths: FloatArray, what: str = "pose") -> None:
    """Raise :class:`OutOfStrokeError` if any leg length lies outside its stroke.

    The message names the first offending sample, the leg, its length and the allowed range.
    """
    low = lengths < geo.leg_min - 1e-12
    high = lengths > geo.leg_max + 1e-12
    bad = low | high
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        leg = idx[-1]
        sample = f" at sample {idx[:-1]}" if len(idx) > 1 else ""
        raise OutOfStrokeError(
            f"{what}{sample} needs leg {leg + 1} at {lengths[idx]:.4f} m, outside its stroke "
            f"[{geo.leg_min[leg]:.4f}, {geo.leg_max[leg]:.4f}] m"
            f" ({int(bad.any(axis=-1).sum())} sample(s) out of stroke)"
        )


def _cabin_gimbals_in_base(geo: Geometry, p: FloatArray) -> FloatArray:
    """T_c^b a_j^c: cabin gimbals rotated into base axes, shape (..., 6, 3)."""
    return np.einsum("...ij,kj->...ki", rotation_matrix(p[..., 3:]), geo.cabin_gimbals)


def leg_vectors(geo: Geometry, pose: ArrayLike) -> FloatArray:
    """Leg vectors l_j^b = c^b + T_c^b a_j^c - b_j^b of Eq A.5, shape (..., 6, 3)."""
    p = as_pose(pose)
    c = geo.neutral_ugp + p[..., :3]
    return c[..., None, :] + _cabin_gimbals_in_base(geo, p) - geo.base_gimbals


def static_leg_forces(
    geo: Geometry, pose: ArrayLike, mass: float, com: ArrayLike, gravity: float = 9.81
) -> FloatArray:
    """Return the leg forces that hold a cabin still at ``pose`` (Eq A.14 at rest).

    Solves sum_j f_j n_j = -m g and sum_j (T a_j) x f_j n_j = -(T c) x m g for the six
    forces along the legs (positive: the leg pushes, extending).

    Parameters
    ----------
    geo : Geometry
        The platform.
    pose : array_like, shape (..., 6)
        Pose offsets from neutral (m, rad).
    mass : float
        Cabin mass [kg].
    com : array_like, shape (3,)
        Its centre of gravity in the cabin frame [m].
    gravity : float
        [m/s^2], along +z of the base frame (z down).

    Returns
    -------
    ndarray, shape (..., 6)
        [N].

    """
    p = as_pose(pose)
    n, moment_arms = _leg_axes(geo, p)
    weight = np.array([0.0, 0.0, mass * gravity])
    c_b = np.einsum("...ij,j->...i", rotation_matrix(p[..., 3:]), np.asarray(com, dtype=float))
    wrench = np.concatenate([np.broadcast_to(weight, c_b.shape), np.cross(c_b, weight)], axis=-1)
    columns = np.concatenate([n, moment_arms], axis=-1)  # (..., 6 legs, 6): row j
    return np.linalg.solve(np.swapaxes(columns, -1, -2), -wrench[..., None])[..., 0]


def _leg_axes(geo: Geometry, p: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Return the unit leg vectors n_j and their moments (T a_j) x n_j about the UGP."""
    L = leg_vectors(geo, p)
    n = L / np.linalg.norm(L, axis=-1, keepdims=True)
    return n, np.cross(_cabin_gimbals_in_base(geo, p), n)


def inverse(geo: Geometry, pose: ArrayLike, check: bool = True) -> FloatArray:
    """Inverse position kinematics (Eq A.5-A.6): leg lengths for poses.

    Parameters
    ----------
    geo : Geometry
        The platform.
    pose : array_like, shape (..., 6)
        Pose offsets from neutral (m, rad).
    check : bool
        Raise :class:`OutOfStrokeError` if a leg leaves its stroke (default). With ``False``
        lengths outside the stroke are returned as computed.

    Returns
    -------
    ndarray, shape (..., 6)
        Leg lengths [m].

    """
    lengths = np.linalg.norm(leg_vectors(geo, pose), axis=-1)
    if check:
        check_stroke(geo, lengths)
    return lengths


def jacobian(geo: Geometry, pose: ArrayLike) -> FloatArray:
    """Platform Jacobian J_lx of Eq A.11: leg rates = J_lx @ pose rates (Euler-angle rates).

    Parameters
    ----------
    geo : Geometry
        The platform.
    pose : array_like, shape (..., 6)
        Pose offsets from neutral (m, rad).

    Returns
    -------
    ndarray, shape (..., 6, 6)

    """
    p = as_pose(pose)
    n, moment_arms = _leg_axes(geo, p)
    rot = np.einsum("...kj,...ji->...ki", moment_arms, euler_rate_matrix(p[..., 3:]))
    return np.concatenate([n, rot], axis=-1)


@dataclass(frozen=True)
class ForwardResult:
    """Result of forward kinematics.

    Attributes
    ----------
    pose : ndarray, shape (..., 6)
        The solved poses.
    iterations : int
        Newton-Raphson iterations used by the slowest sample.
    iterations_per_sample : ndarray of int, shape (...)
        Iterations each sample needed.
    residual : float
        Largest leg-length error left [m].

    """

    pose: FloatArray
    iterations: int
    iterations_per_sample: NDArray[np.int64] = field(repr=False)
    residual: float

    def to_dict(self) -> dict[str, object]:
        """JSON-ready result (poses as nested lists, m and rad)."""
        return {
            "pose": np.asarray(self.pose).tolist(),
            "iterations": int(self.iterations),
            "iterations_per_sample": np.asarray(self.iterations_per_sample).tolist(),
            "residual_m": float(self.residual),
        }

    def to_frame(self) -> pd.DataFrame:
        """One row per solved sample: the pose (m, rad) and the iterations it took."""
        pose = np.atleast_2d(np.asarray(self.pose, dtype=float))
        cols: dict[str, object] = {d: pose[:, k] for k, d in enumerate(DOF_NAMES)}
        cols["iterations"] = np.broadcast_to(self.iterations_per_sample, pose.shape[:1])
        return frame(cols)

    def plot(self, ax: AxesArg = None, *, path: str | None = None) -> Figure:
        """Plot the solved poses per DOF against the sample number (translations and angles).

        Parameters
        ----------
        ax : sequence of two Axes, optional
            Where to draw: translations and angles; a new figure by default.
        path : str, optional
            Save the figure here.

        Returns
        -------
        matplotlib.figure.Figure

        """
        from twin.core.plotting import finish, subplots

        pose = np.asarray(self.pose).reshape(-1, 6)
        fig, (ax_t, ax_r) = subplots(ax, 2, 1, figsize=(6, 5), sharex=True)
        for k, name in enumerate(DOF_NAMES):
            ax = ax_t if k < 3 else ax_r
            ax.plot(pose[:, k] if k < 3 else np.degrees(pose[:, k]), ".-", label=name)
        ax_t.set_ylabel("translation [m]")
        ax_r.set_ylabel("rotation [deg]")
        ax_r.set_xlabel("sample")
        ax_t.legend(fontsize=8)
        ax_r.legend(fontsize=8)
        ax_t.set_title(f"forward kinematics: {self.iterations} iterations, "
                       f"residual {self.residual:.1e} m", fontsize=9)  # fmt: skip
        return finish(fig, path)


def forward(
    geo: Geometry,
    lengths: ArrayLike,
    initial: ArrayLike | None = None,
    tol: float = FK_TOLERANCE,
    max_iter: int = 50,
) -> ForwardResult:
    """Forward kinematics by Newton-Raphson (Eq A.12-A.13), vectorised over samples.

    Parameters
    ----------
    geo : Geometry
        The platform.
    lengths : array_like, shape (..., 6)
        Measured leg lengths [m].
    initial : array_like, shape (..., 6) or (6,), optional
        Initial pose guess (default: neutral). The desired pose is a good guess (App. A.4).
    tol : float
        Largest allowed leg-length error [m] (default 1e-7).
    max_iter : int
        Iteration budget.

    Returns
    -------
    ForwardResult

    Raises
    ------
    OutOfStrokeError
        If a length is outside the leg's stroke: no pose of the real machine has it.
    ForwardKinematicsError
        If some sample does not converge within ``max_iter`` (e.g. inconsistent lengths) or
        meets a singular Jacobian.

    """
    q = _as_lengths(lengths)
    check_stroke(geo, q, what="leg lengths")
    x = np.zeros(q.shape) if initial is None else np.broadcast_to(as_pose(initial), q.shape).copy()
    iters = np.zeros(q.shape[:-1], dtype=np.int64)
    err = q - inverse(geo, x, check=False)
    for _ in range(max_iter):
        active = np.max(np.abs(err), axis=-1) >= tol
        if not active.any():
            break
        try:
            step = np.linalg.solve(jacobian(geo, x[active]), err[active][..., None])[..., 0]
        except np.linalg.LinAlgError:
            raise ForwardKinematicsError(
                "forward kinematics met a singular Jacobian: the lengths are at or near a "
                "singular configuration; give an initial pose closer to the solution"
            ) from None
        x[active] += step
        iters[active] += 1
        err = q - inverse(geo, x, check=False)
    residual = float(np.max(np.abs(err))) if err.size else 0.0
    if residual >= tol or not np.all(np.isfinite(x)):
        worst = tuple(int(i) for i in np.unravel_index(np.argmax(np.abs(err)), err.shape))
        raise ForwardKinematicsError(
            f"forward kinematics did not converge in {max_iter} iterations: leg-length error "
            f"{residual:.3g} m at {worst} (tolerance {tol:g} m); the lengths may be inconsistent "
            "(no pose has them) or the initial guess too far"
        )
    return ForwardResult(
        pose=x, iterations=int(iters.max(initial=0)), iterations_per_sample=iters, residual=residual
    )


def leg_rates(
    geo: Geometry,
    pose: ArrayLike,
    pose_rate: ArrayLike | None = None,
    pose_acc: ArrayLike | None = None,
    rotation: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray | None, FloatArray | None]:
    """Leg lengths, velocities and accelerations from a pose and its exact derivatives.

    Uses l_dot = n . L_dot and l_ddot = n . L_ddot + ``(|L_dot|^2 - l_dot^2) / l``, with
    L_dot = c_dot + omega x T a and L_ddot = c_ddot + omega_dot x T a + omega x (omega x T a),
    omega = R eta_dot (Eq A.4, A.8).

    Parameters
    ----------
    geo : Geometry
        The platform.
    pose : array_like, shape (..., 6)
        Pose offsets from neutral (m, rad).
    pose_rate : array_like, shape (..., 6), optional
        Its time derivative (Euler-angle rates for the rotations); leg velocities are
        returned only if given.
    pose_acc : array_like, shape (..., 6), optional
        Second derivative; leg accelerations are returned only if given (with ``pose_rate``).
    rotation : ndarray, shape (..., 3, 3), optional
        T_c^b of the poses if already computed (:func:`twin.core.frames.rotation_matrix`).

    Returns
    -------
    lengths, velocities, accelerations : ndarray, shape (..., 6)
        ``velocities`` and ``accelerations`` are None when their inputs were not given.

    """
    p = as_pose(pose)
    # Component by component, each array (6, ...) with the legs first so that the long axis
    # is the last (the same products and sums as over (..., 6), several times faster);
    # 3x faster than einsum/cross.
    T = rotation_matrix(p[..., 3:]) if rotation is None else rotation
    shape = (6,) + (1,) * (p.ndim - 1)  # a gimbal coordinate per leg, against (...)
    A = [geo.cabin_gimbals[:, j].reshape(shape) for j in range(3)]
    B = [geo.base_gimbals[:, j].reshape(shape) for j in range(3)]
    ab = [sum(T[..., i, j] * A[j] for j in range(3)) for i in range(3)]
    L = [(geo.neutral_ugp[i] + p[..., i]) + ab[i] - B[i] for i in range(3)]
    length = np.sqrt(L[0] ** 2 + L[1] ** 2 + L[2] ** 2)
    if pose_rate is None:
        return _legs_last(length), None, None
    inv = 1.0 / length
    pd = np.broadcast_to(as_pose(pose_rate, "pose_rate"), p.shape)
    pdd = None if pose_acc is None else np.broadcast_to(as_pose(pose_acc, "pose_acc"), p.shape)
    n = [Li * inv for Li in L]
    w_b, wd_b = angular_motion(p[..., 3:], pd[..., 3:], None if pdd is None else pdd[..., 3:])
    w = [w_b[..., i] for i in range(3)]
    w_x_a = _cross(w, ab)
    Ld = [pd[..., i] + w_x_a[i] for i in range(3)]
    ld = n[0] * Ld[0] + n[1] * Ld[1] + n[2] * Ld[2]
    if pdd is None:
        return _legs_last(length), _legs_last(ld), None
    wd = [wd_b[..., i] for i in range(3)]
    wd_x_a, w_x_w_x_a = _cross(wd, ab), _cross(w, w_x_a)
    Ldd = [pdd[..., i] + wd_x_a[i] + w_x_w_x_a[i] for i in range(3)]
    ldd = n[0] * Ldd[0] + n[1] * Ldd[1] + n[2] * Ldd[2]
    ldd += (Ld[0] ** 2 + Ld[1] ** 2 + Ld[2] ** 2 - ld**2) * inv
    return _legs_last(length), _legs_last(ld), _legs_last(ldd)


def _legs_last(x: FloatArray) -> FloatArray:
    """Return a (6, ...) array of leg values as (..., 6), C-contiguous."""
    return np.ascontiguousarray(np.moveaxis(x, 0, -1))


def _cross(u: list[FloatArray], v: list[FloatArray]) -> list[FloatArray]:
    """Cross product of two vectors given as lists of their three components."""
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


@dataclass(frozen=True)
class ActuatorTrajectory:
    """Leg lengths, velocities and accelerations along a pose trajectory.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s].
    lengths, velocities, accelerations : ndarray, shape (n, 6)
        Per leg [m, m/s, m/s^2].

    """

    t: FloatArray
    lengths: FloatArray
    velocities: FloatArray
    accelerations: FloatArray

    def limit_violations(
        self, geo: Geometry, max_velocity: float, max_acceleration: float
    ) -> list[str]:
        """Describe every actuator limit the trajectory breaks (empty if none).

        Parameters
        ----------
        geo : Geometry
            For the stroke limits.
        max_velocity, max_acceleration : float
            Actuator limits [m/s, m/s^2] (Table 5.1; ``twin.platform.facts.load_facts``).

        """
        out = []
        speed, accel = np.abs(self.velocities), np.abs(self.accelerations)
        checks = (  # label, value, excess over the limit, limit per leg, unit
            ("stroke (short end)", self.lengths, geo.leg_min - self.lengths, geo.leg_min, "m"),
            ("stroke (long end)", self.lengths, self.lengths - geo.leg_max, geo.leg_max, "m"),
            ("velocity", speed, speed - max_velocity, np.full(6, max_velocity), "m/s"),
            ("acceleration", accel, accel - max_acceleration, np.full(6, max_acceleration),
             "m/s^2"),
        )  # fmt: skip
        for label, value, excess, limit, unit in checks:
            broken = excess > 1e-12
            if broken.any():
                i, leg = np.unravel_index(np.argmax(excess), excess.shape)
                out.append(
                    f"{label} limit broken by leg {leg + 1} at t = {self.t[i]:.3f} s: "
                    f"{value[i, leg]:.4g} {unit} against a limit of {limit[leg]:.4g} {unit} "
                    f"({int(broken.any(axis=1).sum())} sample(s))"
                )
        return out


def actuator_trajectory(
    geo: Geometry,
    t: ArrayLike,
    pose: ArrayLike,
    pose_rate: ArrayLike | None = None,
    pose_acc: ArrayLike | None = None,
) -> ActuatorTrajectory:
    """Actuator lengths, velocities and accelerations for a sampled pose trajectory.

    Derivatives not given are taken from the samples (second-order finite differences,
    :func:`numpy.gradient`); give analytic ones when you have them.

    Parameters
    ----------
    geo : Geometry
        The platform.
    t : array_like, shape (n,)
        Strictly increasing sample times [s].
    pose : array_like, shape (n, 6)
        Pose offsets from neutral (m, rad).
    pose_rate : array_like, shape (n, 6), optional
        First time derivative of ``pose``.
    pose_acc : array_like, shape (n, 6), optional
        Second time derivative of ``pose``.

    Returns
    -------
    ActuatorTrajectory

    """
    tt = np.asarray(t, dtype=float)
    p = as_pose(pose)
    if tt.ndim != 1 or p.ndim != 2 or p.shape[0] != tt.size:
        raise PoseError(f"t must be (n,) and pose (n, 6); got {tt.shape} and {p.shape}")
    if tt.size < 3 or not np.all(np.diff(tt) > 0) or not np.all(np.isfinite(tt)):
        raise PoseError("t must hold at least 3 finite, strictly increasing times")
    pd = np.gradient(p, tt, axis=0, edge_order=2) if pose_rate is None else pose_rate
    pdd = np.gradient(pd, tt, axis=0, edge_order=2) if pose_acc is None else pose_acc
    lengths, vel, acc = leg_rates(geo, p, pd, pdd)
    return ActuatorTrajectory(t=tt, lengths=lengths, velocities=vel, accelerations=acc)


@dataclass(frozen=True)
class DofRange:
    """Excursion range of one degree of freedom about neutral (App. B.3).

    Attributes
    ----------
    dof : str
        ``surge``, ``sway``, ``heave``, ``roll``, ``pitch`` or ``yaw``.
    min, max : float
        Most negative and most positive excursion [m or rad].
    min_leg, max_leg : int
        The leg (1-6) whose stroke ends each side.
    min_end, max_end : str
        Which end of that leg's stroke: ``"short"`` or ``"long"``.

    """

    dof: str
    min: float
    max: float
    min_leg: int
    max_leg: int
    min_end: str
    max_end: str

    @property
    def rotational(self) -> bool:
        """True for roll, pitch and yaw."""
        return self.dof in DOF_NAMES[3:]

    @property
    def span(self) -> float:
        """``max - min``."""
        return self.max - self.min


def _excursion(geo: Geometry, dof: int, sign: float, bound: float) -> tuple[float, int, str]:
    """Largest excursion along one DOF direction before any leg leaves its stroke."""
    s = np.linspace(0.0, bound, 4001)
    pose = np.zeros((s.size, 6))
    pose[:, dof] = sign * s

    def margin(lengths: FloatArray) -> FloatArray:
        return np.minimum(lengths - geo.leg_min, geo.leg_max - lengths).min(axis=-1)

    m = margin(inverse(geo, pose, check=False))
    out = np.flatnonzero(m < 0)
    if out.size == 0:
        return float(bound), 0, "none"
    k = out[0]

    def f(x: float) -> float:
        p = np.zeros(6)
        p[dof] = sign * x
        return float(margin(inverse(geo, p, check=False)))

    edge = brentq(f, s[k - 1], s[k], xtol=1e-12)
    p = np.zeros(6)
    p[dof] = sign * edge
    lengths = inverse(geo, p, check=False)
    short, long_ = lengths - geo.leg_min, geo.leg_max - lengths
    leg = int(np.argmin(np.minimum(short, long_)))
    return float(edge), leg + 1, "short" if short[leg] < long_[leg] else "long"


def workspace(geo: Geometry) -> dict[str, DofRange]:
    """Workspace per degree of freedom (App. B.3): each DOF alone, the others at neutral.

    The range ends where the first leg reaches an end of its stroke.

    Parameters
    ----------
    geo : Geometry
        The platform.

    Returns
    -------
    dict of str to DofRange
        Keyed ``surge, sway, heave, roll, pitch, yaw``; translations in m, rotations in rad.

    """
    out = {}
    reach = 4.0 * float(np.max(geo.stroke))
    for k, dof in enumerate(DOF_NAMES):
        bound = reach if k < 3 else np.radians(89.0)
        lo, lo_leg, lo_end = _excursion(geo, k, -1.0, bound)
        hi, hi_leg, hi_end = _excursion(geo, k, 1.0, bound)
        out[dof] = DofRange(dof, -lo, hi, lo_leg, hi_leg, lo_end, hi_end)
    return out
