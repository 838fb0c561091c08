"""The result type every platform returns: cabin motion sampled at the platform rate."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: Gravity vector in the thesis base frame (z down) [m/s^2].
GRAVITY_BASE = np.array([0.0, 0.0, 9.81])


@dataclass(frozen=True, eq=False)
class PlatformResponse:
    """Cabin motion of a platform run (full or reduced), uniformly sampled.

    A platform stepped for several runs at once returns arrays with a leading runs axis
    (``(runs, n, ...)``; ``t`` stays ``(n,)``); :meth:`run` takes one of them.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s].
    command : ndarray, shape (n, 6)
        The platform's input: the pose reference after the motion-system blocks and noise.
    pose : ndarray, shape (n, 6)
        UGP pose offsets from neutral (m, rad), thesis base frame.
    velocity, acceleration : ndarray, shape (n, 3)
        UGP linear velocity and acceleration (gravity not included), base-frame axes.
    omega, omega_dot : ndarray, shape (n, 3)
        Angular velocity (p, q, r) and its derivative, cabin axes.
    legs : ndarray, shape (n, 6)
        Leg lengths [m].
    sensor_gyro : ndarray, shape (n, 3), or None
        MuJoCo's own gyro at the model's ``imu`` site (full model only), thesis cabin axes;
        it equals ``omega``. (MuJoCo's accelerometer is not in the models: under
        ``implicitfast`` it misses the implicit damping correction; the IMU's specific force
        is :func:`twin.chain.imu.specific_force` of the motion.)
    leg_force, leg_velocity : ndarray, shape (n, 6), or None
        Each actuator's force along its leg [N]: the PD of Eq 5.9 (after its force limit)
        plus the share of the cabin's weight the static-force feedback K_s carries; positive
        extends. And the leg's extension rate [m/s] (full model only).
    rotation : ndarray, shape (n, 3, 3), or None
        T_c^b of ``pose`` (Eq A.2) where the platform has computed it already (the reduced
        platform), so that the IMU does not compute it again; None otherwise (and in the
        chunks of :meth:`twin.chain.simulate.Run.chunks`, which keep no copy of it). A
        response made from another with a new ``pose`` must set it to None.

    """

    t: FloatArray
    command: FloatArray
    pose: FloatArray
    velocity: FloatArray
    acceleration: FloatArray
    omega: FloatArray
    omega_dot: FloatArray
    legs: FloatArray
    sensor_gyro: FloatArray | None = None
    leg_force: FloatArray | None = None
    leg_velocity: FloatArray | None = None
    rotation: FloatArray | None = None

    @property
    def leg_power(self) -> FloatArray | None:
        """Each actuator's mechanical power [W] (force times extension rate; full model)."""
        if self.leg_force is None or self.leg_velocity is None:
            return None
        return self.leg_force * self.leg_velocity

    @property
    def rate_hz(self) -> float:
        """Sample rate [Hz]."""
        return 1.0 / float(self.t[1] - self.t[0])

    def run(self, i: int) -> PlatformResponse:
        """One run of a response stepped for several runs (arrays ``(runs, m, ...)``)."""
        out = {}
        for f in fields(self):
            v = getattr(self, f.name)
            out[f.name] = v if (v is None or f.name == "t") else v[i]
        return type(self)(**out)

    @classmethod
    def concatenate(cls, parts: Iterable[PlatformResponse]) -> PlatformResponse:
        """Join consecutive chunks of one run."""
        chunks = list(parts)
        out = {}
        for f in fields(cls):
            arrays = [getattr(c, f.name) for c in chunks]
            missing = any(a is None for a in arrays)  # e.g. a rotation some chunks dropped
            out[f.name] = None if missing else np.concatenate(arrays)
        return cls(**out)
