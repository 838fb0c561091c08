"""The reduced platform (Eq 5.11): a rigid cabin that follows its (filtered, delayed) input.

Together with the blocks of :mod:`twin.chain.config` in front of it this is the thesis'
reduced MPI model, H = 1 / (1 + s / (2 pi f_b))^2 e^{-tau s}, plus the Eq 5.10 noise. What it
leaves out, by construction: the platform's own first-order lag (t_m of Table 5.5, a few ms),
parasitic motion in the undriven DOFs, the static sag of K_s, leg dynamics, and actuator
saturation (limits are counted, never applied).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from twin.chain.limits import ActuatorLimits, LimitReport
from twin.chain.response import PlatformResponse, rigid_motion
from twin.chain.stepping import Platform, PlatformState, Reference
from twin.frames import rotation_matrix
from twin.platform.facts import load_facts
from twin.platform.geometry import load_geometry
from twin.platform.kinematics import leg_rates

FloatArray = NDArray[np.float64]


class ReducedPlatform(Platform):
    """A rigid cabin that follows its input exactly: with the blocks in front, Eq 5.11.

    Produces the same :class:`PlatformResponse` as :class:`~twin.chain.physics.FullPlatform`.
    Being analytic it is evaluated where it is looked at: by default at the IMU rate of
    ``platform.toml`` (819.2 Hz), so each IMU sample is an exact evaluation; give ``rate_hz``
    (e.g. the full model's 1 kHz, or a closed loop's own rate) to sample it elsewhere. Leg
    lengths come from the inverse kinematics, and actuator limits are counted at that rate
    (never limited: the reduced model has no actuators to saturate).

    Parameters
    ----------
    platform : str
        ``"mpi"`` or ``"srs"`` (for the geometry and limits).
    rate_hz : float, optional
        Output rate [Hz]; the platform's IMU rate by default.
    limit_mode : str
        ``"limit"`` (count only) or ``"strict"`` (raise on any limit).

    """

    kind = "reduced"

    def __init__(self, platform: str, rate_hz: float | None = None, limit_mode: str = "limit"):
        self.platform = platform
        self.geometry = load_geometry(platform)
        facts = load_facts(platform)
        self.limits = ActuatorLimits.of(self.geometry, facts, limit_mode)
        self.own_lag_s = np.zeros(6)
        self.rate_hz = float(rate_hz or facts.imu_rate_hz)
        self._radius = float(np.linalg.norm(self.geometry.cabin_gimbals, axis=1).max())

    def _advance(self, ref: Reference, state: PlatformState) -> PlatformResponse:
        """Put the cabin where the reference says; count the limits it would break."""
        runs, m = ref.pose.shape[:2]
        flat = [a.reshape(runs * m, 6) for a in (ref.pose, ref.rate, ref.acc)]
        pose, rate, acc = flat
        rotation = rotation_matrix(pose[:, 3:])  # once, for the legs, the motion and the IMU
        lengths, _, _ = leg_rates(self.geometry, pose, rotation=rotation)
        motion = rigid_motion(pose, rate, acc, rotation)
        self._check_limits(np.tile(ref.t, runs), pose, rate, acc, lengths, motion, rotation,
                           state.report)  # fmt: skip
        shaped = [x.reshape(runs, m, -1) for x in (*motion, lengths)]
        return PlatformResponse(ref.t, ref.command, ref.pose.copy(), *shaped,
                                rotation=rotation.reshape(runs, m, 3, 3))  # fmt: skip

    def _check_limits(
        self,
        t: FloatArray,
        pose: FloatArray,
        rate: FloatArray,
        acc: FloatArray,
        lengths: FloatArray,
        motion: tuple[FloatArray, ...],
        rotation: FloatArray,
        report: LimitReport,
    ) -> None:
        """Count limit violations, computing leg rates only where a bound says they may occur.

        Per sample, |l_dot| <= |c_dot| + |omega| r and |l_ddot| <= |c_ddot| + (|omega_dot| +
        |omega|^2) r + (|c_dot| + |omega| r)^2 / l_min, with r the largest cabin-gimbal radius
        and l_min the shortest leg. Samples whose bounds stay inside the limits cannot break
        them; the rest (and any out of stroke) get the exact leg velocities and accelerations.
        The counts equal those of checking every sample exactly.
        """
        if t.size == 0:
            return
        velocity, acceleration, omega, omega_dot = motion
        w = _norm(omega)
        v_bound = _norm(velocity) + w * self._radius
        a_bound = (
            _norm(acceleration)
            + (_norm(omega_dot) + w**2) * self._radius
            + v_bound**2 / lengths.min(axis=1)
        )
        lim = self.limits
        suspect = (v_bound > lim.max_velocity * 0.999) | (a_bound > lim.max_acceleration * 0.999)
        suspect |= ((lengths < lim.leg_min) | (lengths > lim.leg_max)).any(axis=1)
        rows = np.flatnonzero(suspect)
        if rows.size == 0:
            return
        _, vel, lacc = leg_rates(self.geometry, pose[rows], rate[rows], acc[rows], rotation[rows])
        lim.check(t[rows], lengths[rows], vel, lacc, report)


def _norm(v: FloatArray) -> FloatArray:
    """Row norms of an (n, 3) array (faster than numpy.linalg.norm for short rows)."""
    return np.sqrt(v[:, 0] ** 2 + v[:, 1] ** 2 + v[:, 2] ** 2)
