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

from twin.chain.kernels import limit_suspects, rigid_cabin
from twin.chain.limits import ActuatorLimits, LimitReport
from twin.chain.response import PlatformResponse
from twin.chain.stepping import Platform, PlatformState, Reference
from twin.platform.facts import load_facts
from twin.platform.geometry import load_geometry
from twin.platform.kinematics import as_pose, leg_rates

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
        """Put the cabin where the reference says; count the limits it would break.

        Attitude, angular motion and leg lengths come from one compiled pass
        (:func:`twin.chain.kernels.rigid_cabin`: the arithmetic of
        :func:`~twin.core.frames.rotation_matrix`, :func:`~twin.core.frames.angular_motion` and
        :func:`~twin.platform.kinematics.leg_rates`, the same bits).
        """
        runs, m = ref.pose.shape[:2]
        pose, rate, acc = (a.reshape(runs * m, 6) for a in (ref.pose, ref.rate, ref.acc))
        pose = as_pose(pose)
        angles = pose[:, 3:]  # cos and sin as rotation_matrix and angular_motion take them
        trig = np.array([f(angles[:, k]) for k in range(3) for f in (np.cos, np.sin)])
        n = pose.shape[0]
        rotation, lengths = np.empty((n, 3, 3)), np.empty((n, 6))
        omega, omega_dot = np.empty((n, 3)), np.empty((n, 3))
        g = self.geometry
        rigid_cabin(pose, rate, acc, trig, g.cabin_gimbals, g.base_gimbals, g.neutral_ugp,
                    rotation, omega, omega_dot, lengths)  # fmt: skip
        motion = (rate[:, :3].copy(), acc[:, :3].copy(), omega, omega_dot)
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
        and l_min the shortest leg (:func:`twin.chain.kernels.limit_suspects`). Samples whose
        bounds stay inside the limits cannot break them; the rest (and any out of stroke) get
        the exact leg velocities and accelerations. The counts equal those of checking every
        sample exactly.
        """
        if t.size == 0:
            return
        lim = self.limits
        suspect = np.empty(t.size, dtype=bool)
        limit_suspects(*motion, lengths, self._radius, lim.max_velocity * 0.999,
                       lim.max_acceleration * 0.999, lim.leg_min, lim.leg_max, suspect)  # fmt: skip
        rows = np.flatnonzero(suspect)
        if rows.size == 0:
            return
        _, vel, lacc = leg_rates(self.geometry, pose[rows], rate[rows], acc[rows], rotation[rows])
        lim.check(t[rows], lengths[rows], vel, lacc, report)
