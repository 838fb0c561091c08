"""The full rigid-body platform: the MJCF model stepped by MuJoCo (Fig 5.4).

The chain's output (jets at the command rate) is evaluated at the physics rate (1 kHz, the
model's timestep, as the thesis simulated its model, §5.5.1) between its samples, turned into
leg length and leg velocity references by the exact inverse kinematics (App. A), checked against the
actuator limits (counted; limited or rejected), and fed to the PD of Eq 5.9 on each leg
(position and velocity actuators in the MJCF) with the K_s static-force feedback (cabin
gravity compensation in the MJCF). Physics runs step by step of the platform interface
(:mod:`twin.chain.stepping`) through :func:`mujoco.rollout` (the C side does every physics
step; Python only prepares each step's references); the warm start is carried between steps,
so results do not depend on how the run is cut into steps.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout
from numpy.typing import NDArray

from twin.chain.limits import ActuatorLimits, LimiterState
from twin.chain.response import PlatformResponse
from twin.chain.stepping import Platform, PlatformState, Reference
from twin.core.errors import PhysicsDivergedError, SignalError
from twin.core.frames import euler_from_matrix, matrix_from_quat
from twin.platform.actuators import LegPhysics, ReferenceState, cabin_static, shape_reference
from twin.platform.facts import load_facts, load_model
from twin.platform.geometry import load_geometry
from twin.platform.kinematics import leg_rates, static_leg_forces
from twin.platform.payload import Payload

FloatArray = NDArray[np.float64]
_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS


class FullPlatform(Platform):
    """The MuJoCo model of a platform behind the platform interface.

    Parameters
    ----------
    platform : str
        ``"mpi"`` or ``"srs"``.
    limit_mode : str
        ``"limit"`` (limit and count) or ``"strict"`` (raise on any limit).
    timestep_s : float, optional
        Integration step instead of the model's 1 ms (for convergence studies); the
        loop-closure constraints' time constant follows it (two steps, as the builder sets it).
    physics : LegPhysics, optional
        The actuators' physics instead of the model's own (friction, play, force limits,
        a weak or slow leg: :mod:`twin.platform.actuators`), written into the private copy.
    payload : Payload, optional
        A rigid body fixed to the cabin (:mod:`twin.platform.payload`): the model is
        recompiled with it.
    leg_forces : bool
        Return the actuators' forces (``leg_force``: the PD's plus the static share K_s
        carries, solved per sample); False: None, for a caller that reads the motion only
        (a diagnosis' predictions: the static share was most of the Python time of a run).

    Attributes
    ----------
    model : mujoco.MjModel
        A private copy of the compiled model (edit it, e.g. the ``imu`` site, freely).
    rate_hz : float
        Physics rate [Hz].
    own_lag_s : ndarray, shape (6,)
        The model's equivalent delay per DOF (``platform.toml`` ``[full_model]``).
    physics : LegPhysics
        The actuators' physics in effect.

    """

    kind = "full"

    def __init__(
        self,
        platform: str,
        limit_mode: str = "limit",
        timestep_s: float | None = None,
        physics: LegPhysics | None = None,
        payload: Payload | None = None,
        leg_forces: bool = True,
    ) -> None:
        self.platform = platform
        self.leg_forces = leg_forces
        self.payload = payload
        self.model = payload.model(platform) if payload else load_model(platform).__copy__()
        if physics is not None or payload is not None:  # a payload moves the static share
            (physics or LegPhysics.of_model(self.model)).apply(self.model)
        self.physics = LegPhysics.of_model(self.model)
        self._shaped = self.physics.shapes_reference()  # a lag or play on the references
        self._cabin = cabin_static(self.model)  # mass, centre of gravity, K_s
        tendons = [self.model.tendon(f"leg{j + 1}_axis").id for j in range(6)]
        self._pd_range = self.model.tendon_actfrcrange[tendons].copy()
        if timestep_s is not None:
            if not np.isfinite(timestep_s) or not 1e-5 <= timestep_s <= 2e-3:
                raise SignalError(f"timestep must be between 1e-5 and 2e-3 s; got {timestep_s}")
            self.model.opt.timestep = timestep_s
            self.model.eq_solref[:, 0] = 2 * timestep_s
        self.geometry = load_geometry(platform)
        facts = load_facts(platform)
        self.limits = ActuatorLimits.of(self.geometry, facts, limit_mode)
        self.own_lag_s = np.array(facts.equivalent_delay_s)
        self.rate_hz = 1.0 / self.model.opt.timestep
        self._adr = {
            name: slice(self.model.sensor(name).adr[0],
                        self.model.sensor(name).adr[0] + self.model.sensor(name).dim[0])
            for name in ("ugp_position", "ugp_orientation", "ugp_velocity",
                         "ugp_angular_velocity", "imu_gyro")
        }  # fmt: skip
        self._legs, self._forces, self._leg_rates = (
            [self.model.sensor(f"leg{j + 1}_{kind}").adr[0] for j in range(6)]
            for kind in ("length", "force", "velocity")
        )

    def _reset_inner(self, runs: int) -> _Physics:
        """Every run at rest at the neutral pose (keyframe ``home``)."""
        model = self.model
        data = mujoco.MjData(model)
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
        state = np.empty(mujoco.mj_stateSize(model, _STATE))
        mujoco.mj_getState(model, data, state, _STATE)
        return _Physics(
            data=data,
            scratch=mujoco.MjData(model),
            states=np.repeat(state[None], runs, axis=0),
            warm=np.repeat(data.qacc_warmstart[None], runs, axis=0),
            limiters=[
                LimiterState(self.geometry.neutral_lengths.copy(), np.zeros(6)) for _ in range(runs)
            ],
            references=[
                ReferenceState(
                    self.geometry.neutral_lengths.copy(), self.geometry.neutral_lengths.copy()
                )
                for _ in range(runs)
            ],
        )

    def _advance(self, ref: Reference, state: PlatformState) -> PlatformResponse:
        """Roll each run's physics through the reference's steps (warm start carried).

        Each row of the response is the state at the start of a physics step, whose control
        is the reference at that time; the step's end state starts the next row.
        """
        if state.inner.rolled is not None:  # a submitted step's physics comes first
            state.inner.rolled.wait()
        rows = self._roll(self._controls(ref, state), state.inner)
        return self._counted(self._response(ref, rows), rows, state)

    def _start(self, ref: Reference, state: PlatformState) -> Callable[[], PlatformResponse]:
        """Limit the legs now; roll the physics in a thread after the previous step's.

        Steps wait for each other by events, never by ``Thread.join``: under Python 3.11 a
        join that Ctrl-C interrupts marks the thread ended while it still runs (bpo-45274),
        so the next step would roll on the same ``MjData`` at the same time (a crash). The
        thread is no daemon: at exit Python waits for its physics (at most this step and the
        next) instead of tearing down while MuJoCo runs in C (a segmentation fault).
        """
        phys: _Physics = state.inner
        controls = self._controls(ref, state)
        before, done, box = phys.rolled, threading.Event(), {}

        def roll() -> None:
            try:
                if before is not None:
                    before.wait()
                box["rows"] = self._roll(controls, phys)
            except BaseException as exc:  # handed to the finisher, raised in the caller
                box["error"] = exc
            finally:
                done.set()

        phys.rolled = done
        threading.Thread(target=roll, name="mujoco-rollout").start()

        def finish() -> PlatformResponse:
            done.wait()
            if "error" in box:
                raise box["error"]
            return self._counted(self._response(ref, box["rows"]), box["rows"], state)

        return finish

    def _controls(self, ref: Reference, state: PlatformState) -> list[FloatArray | None]:
        """Each run's leg-length and leg-velocity references, limited (None: no samples)."""
        phys: _Physics = state.inner
        m = ref.pose.shape[1]
        if m == 0:
            return [None] * ref.pose.shape[0]
        lengths, velocities, accelerations = leg_rates(self.geometry, ref.pose, ref.rate, ref.acc)
        out: list[FloatArray | None] = []
        for r, limiter in enumerate(phys.limiters):
            legs, legs_dot = self.limits.apply(
                ref.t, lengths[r], velocities[r], accelerations[r], limiter, state.report
            )
            if self._shaped:  # each leg's servo lag and play (twin.platform.actuators)
                legs, legs_dot = shape_reference(self.physics, 1.0 / self.rate_hz, legs,
                                                 legs_dot, phys.references[r])  # fmt: skip
            out.append(np.hstack([legs, legs_dot])[None])
        return out

    def _counted(
        self, response: PlatformResponse, rows: FloatArray, state: PlatformState
    ) -> PlatformResponse:
        """Count the physics samples at an actuator's force limit (legs with one).

        A leg is at its limit where MuJoCo clamped its PD force (the sensor rows ``rows``) to
        the tendon's range (:func:`twin.platform.actuators.pd_force_ranges`).
        """
        limit = self.physics.force_limit_n
        if np.any(limit > 0):
            lo, hi = self._pd_range[:, 0], self._pd_range[:, 1]
            pd = rows[:, :-1][..., self._forces]
            span = np.maximum(hi - lo, 1.0) * 1e-9
            at = (limit > 0) & ((pd <= lo + span) | (pd >= hi - span))
            hits = at.any(axis=-1)
            if hits.any() and state.report.first is None:
                k = np.argwhere(hits)[0]
                leg = int(np.flatnonzero(at[tuple(k)])[0]) + 1
                state.report.first = (f"leg {leg} at its force limit of {limit[leg - 1]:g} N at "
                                      f"t = {response.t[k[-1]]:.3f} s")  # fmt: skip
            state.report.force_samples += int(hits.sum())
        return response

    def _roll(self, controls: list[FloatArray | None], phys: _Physics) -> FloatArray:
        """Sensor rows ``(runs, m + 1, ns)`` of each run's rollout; the states move on."""
        rows = []
        for r, ctrl in enumerate(controls):
            if ctrl is None:
                rows.append(np.empty((0, self.model.nsensordata)))
                continue
            states, sens = rollout.rollout(
                self.model, phys.data, phys.states[r], ctrl, initial_warmstart=phys.warm[r][None]
            )
            self._check_finite(states, sens, phys.data)
            phys.states[r], phys.warm[r] = states[0, -1], phys.data.qacc_warmstart
            rows.append(np.vstack([sens[0], self._sensors_at(phys.states[r], phys.scratch)]))
        return np.stack(rows)

    def _check_finite(self, states: FloatArray, sens: FloatArray, data: mujoco.MjData) -> None:
        """Stop a diverging run with one clear error (non-finite state or MuJoCo's warnings).

        Raises
        ------
        PhysicsDivergedError
            Naming the time, what MuJoCo warned of and what usually causes it.

        """
        warned = [mujoco.mjtWarning(i).name.removeprefix("mjWARN_").lower()
                  for i, w in enumerate(data.warning) if w.number > 0]  # fmt: skip
        finite = np.isfinite(states).all(axis=-1)[0]
        if finite.all() and not warned:
            return
        bad = int(np.argmin(finite)) if not finite.all() else states.shape[1] - 1
        t = float(states[0, bad, 0])  # the state's first element is its time
        for w in data.warning:
            w.number = 0
        why = f"MuJoCo warned: {', '.join(warned)}" if warned else "its state is not finite"
        raise PhysicsDivergedError(
            f"the full {self.platform} model diverged at t = {t:.3f} s ({why}); the commands or "
            "the actuator physics drive it beyond what it can integrate (a force limit far "
            "below the cabin's weight, a huge friction, or a much smaller gain; try the "
            "reduced model, or milder settings)"
        )

    def _sensors_at(self, state: FloatArray, data: mujoco.MjData) -> FloatArray:
        """Sensor values of a state (the successor row of a step: its velocities)."""
        mujoco.mj_setState(self.model, data, state, _STATE)
        mujoco.mj_forward(self.model, data)
        return data.sensordata.copy()

    def _static_forces(self, pose: FloatArray) -> FloatArray:
        """Return the legs' share of the cabin's weight that K_s supplies at ``pose`` [N]."""
        mass, com, ks = self._cabin
        return ks * static_leg_forces(self.geometry, pose, mass, com)

    def _response(self, ref: Reference, s: FloatArray) -> PlatformResponse:
        """Turn sensor rows ``(runs, m + 1, ns)`` (the last: the successor state) into motion.

        Linear and angular accelerations are the differences of the UGP velocities over each
        step, a_k = (v_{k+1} - v_k) / h: exactly the second difference of the integrated
        positions. MuJoCo's acceleration sensors are not used: under ``implicitfast`` they
        report the acceleration before the implicit damping correction, which with the legs'
        velocity feedback (K_d, Eq 5.9) is about 2.4 times too large in heave.
        """
        a = self._adr
        h = 1.0 / self.rate_hz
        v = s[..., a["ugp_velocity"]]
        w = s[..., a["ugp_angular_velocity"]]
        dv, dw = np.diff(v, axis=1) / h, np.diff(w, axis=1) / h
        s = s[:, :-1]
        T = matrix_from_quat(s[..., a["ugp_orientation"]])
        position = s[..., a["ugp_position"]] - self.geometry.neutral_ugp
        pose = np.concatenate([position, euler_from_matrix(T)], axis=-1)
        return PlatformResponse(
            t=ref.t,
            command=ref.command,
            pose=pose,
            velocity=s[..., a["ugp_velocity"]].copy(),
            acceleration=dv,  # the velocity sensors are in base-frame axes
            omega=np.einsum("...ji,...j->...i", T, s[..., a["ugp_angular_velocity"]]),
            omega_dot=np.einsum("...ji,...j->...i", T, dw),
            legs=s[..., self._legs].copy(),
            sensor_gyro=s[..., a["imu_gyro"]].copy(),
            leg_force=s[..., self._forces] + self._static_forces(pose) if self.leg_forces else None,
            leg_velocity=s[..., self._leg_rates].copy(),
        )


@dataclass
class _Physics:
    """MuJoCo state of the runs between steps."""

    data: mujoco.MjData
    scratch: mujoco.MjData
    states: FloatArray
    warm: FloatArray
    limiters: list[LimiterState]
    references: list[ReferenceState]
    rolled: threading.Event | None = None  # set when the last submitted step's physics is done
