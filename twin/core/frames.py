"""Frames and rotations of the thesis (Appendix A), and the one place MuJoCo frames enter.

The thesis' frames are x forward, y right, z down (Appendix A.1). MuJoCo's world is z up; the
models put their base and cabin bodies in thesis orientation by a 180 degree rotation about x
(:data:`MJ_FROM_THESIS_QUAT`), so that all model-local coordinates are thesis coordinates. The
functions here are vectorised over any leading axes.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.core.errors import ConfigError

#: Quaternion (w, x, y, z) of the thesis base/cabin frame expressed in MuJoCo's z-up world:
#: a half turn about x maps (x fwd, y right, z down) onto (x fwd, y left, z up).
MJ_FROM_THESIS_QUAT = (0.0, 1.0, 0.0, 0.0)

#: Rotation matrix of :data:`MJ_FROM_THESIS_QUAT` (its own inverse).
MJ_FROM_THESIS = np.diag([1.0, -1.0, -1.0])

DOF_NAMES = ("surge", "sway", "heave", "roll", "pitch", "yaw")
"""Names of the six pose degrees of freedom, in the order of Eq A.1."""


def dof_index(dof: str) -> int:
    """Return the index (0-5) of a DOF name in :data:`DOF_NAMES`.

    Raises
    ------
    ConfigError
        For a name that is not a DOF (the message lists the six).

    Examples
    --------
    >>> dof_index("pitch")
    4

    """
    try:
        return DOF_NAMES.index(dof)
    except ValueError:
        raise ConfigError(f"unknown DOF {dof!r}; expected one of {', '.join(DOF_NAMES)}") from None


def acceleration_unit(dof: str) -> str:
    """Return the acceleration unit of a DOF: ``m/s^2`` (translations) or ``rad/s^2``."""
    return "rad/s^2" if dof_index(dof) >= 3 else "m/s^2"


def rotation_matrix(angles: ArrayLike) -> NDArray[np.float64]:
    """Return T_c^b of Eq A.2 for Euler angles (roll, pitch, yaw) in radians.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        Roll phi, pitch theta, yaw psi [rad].

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rotation from the cabin frame to the base frame.

    Examples
    --------
    >>> import numpy as np
    >>> T = rotation_matrix([0.0, np.pi / 2, 0.0])
    >>> np.round(T @ [1.0, 0.0, 0.0], 12)  # nose up: x_c points up (-z_b)
    array([ 0.,  0., -1.])

    """
    a = np.asarray(angles, dtype=float)
    cf, sf = np.cos(a[..., 0]), np.sin(a[..., 0])
    ct, st = np.cos(a[..., 1]), np.sin(a[..., 1])
    cp, sp = np.cos(a[..., 2]), np.sin(a[..., 2])
    T = np.empty((*a.shape[:-1], 3, 3))
    T[..., 0, 0] = ct * cp
    T[..., 0, 1] = sf * st * cp - cf * sp
    T[..., 0, 2] = cf * st * cp + sf * sp
    T[..., 1, 0] = ct * sp
    T[..., 1, 1] = sf * st * sp + cf * cp
    T[..., 1, 2] = cf * st * sp - sf * cp
    T[..., 2, 0] = -st
    T[..., 2, 1] = sf * ct
    T[..., 2, 2] = cf * ct
    return T


def euler_rate_matrix(angles: ArrayLike) -> NDArray[np.float64]:
    """Return R of Eq A.4, mapping Euler-angle rates to the angular velocity in F^b.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        Roll, pitch, yaw [rad].

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``omega_b = R @ [phi_dot, theta_dot, psi_dot]``.

    """
    a = np.asarray(angles, dtype=float)
    ct, st = np.cos(a[..., 1]), np.sin(a[..., 1])
    cp, sp = np.cos(a[..., 2]), np.sin(a[..., 2])
    R = np.zeros((*a.shape[:-1], 3, 3))
    R[..., 0, 0] = ct * cp
    R[..., 0, 1] = -sp
    R[..., 1, 0] = ct * sp
    R[..., 1, 1] = cp
    R[..., 2, 0] = -st
    R[..., 2, 2] = 1.0
    return R


def angular_motion(
    angles: ArrayLike, rates: ArrayLike, accelerations: ArrayLike | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """Angular velocity and acceleration in base axes from Euler angles and their derivatives.

    ``omega = R eta_dot`` and ``omega_dot = R eta_ddot + R_dot eta_dot`` (Eq A.4), written out
    component by component: several times faster than the matrix products for long arrays.

    Parameters
    ----------
    angles, rates : array_like, shape (..., 3)
        Euler angles [rad] and their rates [rad/s].
    accelerations : array_like, shape (..., 3), optional
        Euler-angle accelerations [rad/s^2].

    Returns
    -------
    omega, omega_dot : ndarray, shape (..., 3)
        In base axes [rad/s, rad/s^2]; ``omega_dot`` is None without ``accelerations``.

    Examples
    --------
    >>> import numpy as np
    >>> eta, rate = np.array([0.1, -0.2, 0.3]), np.array([0.4, 0.5, -0.6])
    >>> w, _ = angular_motion(eta, rate)
    >>> bool(np.allclose(w, euler_rate_matrix(eta) @ rate))
    True

    """
    a = np.asarray(angles, dtype=float)
    r = np.asarray(rates, dtype=float)
    ct, st = np.cos(a[..., 1]), np.sin(a[..., 1])
    cp, sp = np.cos(a[..., 2]), np.sin(a[..., 2])
    fd, td, pd = r[..., 0], r[..., 1], r[..., 2]
    ctcp, ctsp = ct * cp, ct * sp
    omega = np.stack([ctcp * fd - sp * td, ctsp * fd + cp * td, pd - st * fd], axis=-1)
    if accelerations is None:
        return omega, None
    acc = np.asarray(accelerations, dtype=float)
    fdd, tdd, pdd = acc[..., 0], acc[..., 1], acc[..., 2]
    omega_dot = np.stack(
        [
            ctcp * fdd - sp * tdd - (st * cp * td + ctsp * pd) * fd - cp * pd * td,
            ctsp * fdd + cp * tdd + (ctcp * pd - st * sp * td) * fd - sp * pd * td,
            pdd - st * fdd - ct * td * fd,
        ],
        axis=-1,
    )
    return omega, omega_dot


def euler_from_matrix(T: ArrayLike) -> NDArray[np.float64]:
    """Return the Euler angles (roll, pitch, yaw) of a rotation T_c^b (inverse of Eq A.2).

    Parameters
    ----------
    T : array_like, shape (..., 3, 3)
        Rotation from the cabin frame to the base frame.

    Returns
    -------
    ndarray, shape (..., 3)
        Roll, pitch, yaw [rad], pitch in [-pi/2, pi/2].

    Examples
    --------
    >>> import numpy as np
    >>> angles = np.array([0.1, -0.2, 0.3])
    >>> bool(np.allclose(euler_from_matrix(rotation_matrix(angles)), angles))
    True

    """
    m = np.asarray(T, dtype=float)
    roll = np.arctan2(m[..., 2, 1], m[..., 2, 2])
    pitch = -np.arcsin(np.clip(m[..., 2, 0], -1.0, 1.0))
    yaw = np.arctan2(m[..., 1, 0], m[..., 0, 0])
    return np.stack([roll, pitch, yaw], axis=-1)


def matrix_from_quat(q: ArrayLike) -> NDArray[np.float64]:
    """Return the rotation matrices of unit quaternions (w, x, y, z), MuJoCo's order.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Quaternions; they are normalised here.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    """
    a = np.asarray(q, dtype=float)
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    w, x, y, z = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    m = np.empty((*a.shape[:-1], 3, 3))
    m[..., 0, 0] = 1 - 2 * (y * y + z * z)
    m[..., 0, 1] = 2 * (x * y - w * z)
    m[..., 0, 2] = 2 * (x * z + w * y)
    m[..., 1, 0] = 2 * (x * y + w * z)
    m[..., 1, 1] = 1 - 2 * (x * x + z * z)
    m[..., 1, 2] = 2 * (y * z - w * x)
    m[..., 2, 0] = 2 * (x * z - w * y)
    m[..., 2, 1] = 2 * (y * z + w * x)
    m[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return m
