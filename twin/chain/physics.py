"""The full rigid-body platform: the MJCF model stepped by MuJoCo (Fig 5.4).

Pose commands (any rate) are evaluated at the physics rate (1 kHz, the model's timestep, as
the thesis simulated its model, §5.5.1) from their cubic spline, turned into leg length and
leg velocity references by the exact inverse kinematics (App. A), checked against the
actuator limits (counted; limited or rejected), and fed to the PD of Eq 5.9 on each leg
(position and velocity actuators in the MJCF) with the K_s static-force feedback (cabin
gravity compensation in the MJCF). Physics runs in chunks through :func:`mujoco.rollout`
(the C side does every step; Python only prepares each chunk's references); the warm start
is carried between chunks, so results do not depend on the chunk size.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout
from numpy.typing import NDArray

from twin.background import prefetch
from twin.chain.limits import ActuatorLimits, LimiterState, LimitReport
from twin.chain.noise import NoiseStream
from twin.chain.response import PlatformResponse
from twin.errors import SignalError
from twin.frames import euler_from_matrix, matrix_from_quat, rotation_matrix
from twin.platform.facts import load_facts, load_model
from twin.platform.geometry import Geometry, load_geometry
from twin.platform.kinematics import leg_rates
from twin.trajectory import Trajectory

FloatArray = NDArray[np.float64]
_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS

#: Default chunk length [s]: memory stays bounded for runs of any length.
CHUNK_S = 10.0


def reference_motion(
    commands: Trajectory, t: FloatArray, noise: NoiseStream | None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Pose, pose rate and pose acceleration references at times ``t`` (noise added in heave).

    Parameters
    ----------
    commands : Trajectory
        Pose commands after the motion-system blocks.
    t : ndarray
        Times [s].
    noise : NoiseStream or None
        Heave noise (position, velocity, acceleration) from the commands' start, interpolated
        linearly; successive calls must move forward in time.

    """
    pose, rate, acc = commands.derivatives(t)
    if noise is not None:
        if noise.noise.highpass_hz is None:
            raise SignalError(
                "heave noise without a high-pass has no bounded position and cannot be a "
                "platform command; give the noise a highpass_hz > 0"
            )
        n = noise.at(t - commands.t0)
        acc[:, 2] += n[:, 0]
        rate[:, 2] += n[:, 1]
        pose[:, 2] += n[:, 2]
    return pose, rate, acc


@dataclass(frozen=True, eq=False)
class ReferenceChunk:
    """Pose and leg references for one chunk of a run, at the platform rate.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Times [s].
    pose, rate, acc : ndarray, shape (n, 6)
        Pose reference and its first and second derivatives (noise included).
    lengths, velocities, accelerations : ndarray, shape (n, 6)
        Leg references from the exact inverse kinematics (velocities and accelerations None
        when not asked for).
    rotation : ndarray, shape (n, 3, 3)
        T_c^b of the reference poses.

    """

    t: FloatArray
    pose: FloatArray
    rate: FloatArray
    acc: FloatArray
    lengths: FloatArray
    velocities: FloatArray | None
    accelerations: FloatArray | None
    rotation: FloatArray


def reference_chunks(
    commands: Trajectory,
    noise: NoiseStream | None,
    geometry: Geometry,
    rate_hz: float,
    chunk_s: float,
    leg_derivatives: bool = True,
) -> Iterator[ReferenceChunk]:
    """Yield the references of a run chunk by chunk (shared by full and reduced platforms).

    With ``leg_derivatives=False`` only leg lengths are computed (the reduced platform
    computes leg velocities and accelerations itself, where they may break a limit).

    The chunks are computed one ahead in a background thread (:func:`twin.background.prefetch`),
    overlapping with the consumer's physics or post-processing.
    """
    t_all = physics_grid(commands, rate_hz)
    step = max(1, round(chunk_s * rate_hz))

    def chunks() -> Iterator[ReferenceChunk]:
        for k0 in range(0, t_all.size, step):
            t = t_all[k0 : k0 + step]
            pose, rate, acc = reference_motion(commands, t, noise)
            T = rotation_matrix(pose[:, 3:])
            derivatives = (rate, acc) if leg_derivatives else (None, None)
            legs = leg_rates(geometry, pose, *derivatives, rotation=T)
            yield ReferenceChunk(t, pose, rate, acc, *legs, T)

    return prefetch(chunks())


def physics_grid(commands: Trajectory, rate_hz: float) -> FloatArray:
    """Return the times at which a platform running at ``rate_hz`` samples the commands' span."""
    n = int(np.floor(commands.duration * rate_hz + 1e-9)) + 1
    return commands.t0 + np.arange(n) / rate_hz


class FullPlatform:
    """The MuJoCo model of a platform behind the platform interface.

    Parameters
    ----------
    platform : str
        ``"mpi"`` or ``"srs"``.
    limit_mode : str
        ``"limit"`` (limit and count) or ``"strict"`` (raise on any limit).

    Attributes
    ----------
    model : mujoco.MjModel
        A private copy of the compiled model (edit it, e.g. the ``imu`` site, freely).
    rate_hz : float
        Physics rate [Hz].
    own_lag_s : ndarray, shape (6,)
        The model's equivalent delay per DOF (``platform.toml`` ``[full_model]``).

    """

    kind = "full"

    def __init__(self, platform: str, limit_mode: str = "limit") -> None:
        self.platform = platform
        self.model = load_model(platform).__copy__()
        self.geometry = load_geometry(platform)
        facts = load_facts(platform)
        self.limits = ActuatorLimits.of(self.geometry, facts, limit_mode)
        self.own_lag_s = np.array(facts.equivalent_delay_s)
        self.rate_hz = 1.0 / self.model.opt.timestep
        self._adr = {
            name: slice(self.model.sensor(name).adr[0],
                        self.model.sensor(name).adr[0] + self.model.sensor(name).dim[0])
            for name in ("ugp_position", "ugp_orientation", "ugp_velocity",
                         "ugp_angular_velocity", "ugp_linear_acceleration",
                         "ugp_angular_acceleration", "imu_accelerometer", "imu_gyro")
        }  # fmt: skip
        self._legs = [self.model.sensor(f"leg{j + 1}_length").adr[0] for j in range(6)]

    def run(
        self,
        commands: Trajectory,
        noise: NoiseStream | None = None,
        report: LimitReport | None = None,
        chunk_s: float = CHUNK_S,
    ) -> Iterator[PlatformResponse]:
        """Simulate, yielding the response chunk by chunk.

        The platform starts at rest at the neutral pose (keyframe ``home``).

        Parameters
        ----------
        commands : Trajectory
            Pose commands (after the motion-system blocks).
        noise : NoiseStream, optional
            Heave noise added to the reference (a fresh stream: it is consumed).
        report : LimitReport, optional
            Filled with the actuator-limit counts.
        chunk_s : float
            Chunk length [s].

        """
        model = self.model
        data = mujoco.MjData(model)
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
        state = np.empty(mujoco.mj_stateSize(model, _STATE))
        mujoco.mj_getState(model, data, state, _STATE)
        warm = data.qacc_warmstart.copy()
        report = report if report is not None else LimitReport(self.limits.mode, self.rate_hz)
        limiter = LimiterState(self.geometry.neutral_lengths.copy(), np.zeros(6))
        held: tuple[FloatArray, FloatArray, FloatArray] | None = None  # awaiting its successor
        chunks = iter(reference_chunks(commands, noise, self.geometry, self.rate_hz, chunk_s))
        ref = next(chunks, None)
        while ref is not None:
            following = next(chunks, None)
            lengths, velocities = self.limits.apply(
                ref.t, ref.lengths, ref.velocities, ref.accelerations, limiter, report
            )
            ctrl = np.hstack([lengths, velocities])[None]
            states, sens = rollout.rollout(model, data, state, ctrl, initial_warmstart=warm[None])
            state, warm = states[0, -1], data.qacc_warmstart.copy()
            t, cmd, s = ref.t, ref.pose, sens[0]
            if held is not None:
                t, cmd, s = (np.concatenate([h, x]) for h, x in zip(held, (t, cmd, s), strict=True))
            if following is None:  # the run's last sample repeats the acceleration before it
                yield self._response(t, cmd, s)
                return
            # a sample's acceleration needs the next sample's velocity: the last one waits
            yield self._response(t[:-1], cmd[:-1], s)
            held = (t[-1:], cmd[-1:], s[-1:])
            ref = following

    def _response(self, t: FloatArray, command: FloatArray, s: FloatArray) -> PlatformResponse:
        """Turn sensor rows (sensors at the start of each step, i.e. at ``t``) into a response.

        ``s`` may hold one row more than ``t``: the successor of the last sample. Linear and
        angular accelerations are the differences of the UGP velocities over each step,
        a_k = (v_{k+1} - v_k) / h: exactly the second difference of the integrated positions.
        MuJoCo's acceleration sensors are not used: under ``implicitfast`` they report the
        acceleration before the implicit damping correction, which with the legs' velocity
        feedback (K_d, Eq 5.9) is about 2.4 times too large in heave. The last sample of a run
        repeats the acceleration before it.
        """
        a = self._adr
        n = t.size
        h = 1.0 / self.rate_hz
        v = s[:, a["ugp_velocity"]]
        w = s[:, a["ugp_angular_velocity"]]
        dv, dw = np.diff(v, axis=0) / h, np.diff(w, axis=0) / h
        if dv.shape[0] < n:
            dv, dw = np.vstack([dv, dv[-1:]]), np.vstack([dw, dw[-1:]])
        s = s[:n]
        T = matrix_from_quat(s[:, a["ugp_orientation"]])
        acc_base, alpha_base = dv[:n], dw[:n]  # the velocity sensors are in base-frame axes
        position = s[:, a["ugp_position"]] - self.geometry.neutral_ugp
        pose = np.hstack([position, euler_from_matrix(T)])
        response = PlatformResponse(
            t=t,
            command=command,
            pose=pose,
            velocity=s[:, a["ugp_velocity"]].copy(),
            acceleration=acc_base,
            omega=np.einsum("nji,nj->ni", T, s[:, a["ugp_angular_velocity"]]),
            omega_dot=np.einsum("nji,nj->ni", T, alpha_base),
            legs=s[:, self._legs].copy(),
            sensor_accelerometer=s[:, a["imu_accelerometer"]].copy(),
            sensor_gyro=s[:, a["imu_gyro"]].copy(),
        )
        return response
