"""The motion a pilot feels in a closed loop, step by step (10 ms at a time).

The chain's blocks work on whole trajectories (their splines look ahead), which a closed loop
cannot: here the configuration's platform filter (Eq 5.1, bilinear at the loop rate) and delay
(fractional, linear interpolation) are causal, and the platform is either

* reduced (Eq 5.11): the felt attitude is the filtered, delayed command; or
* full: the MJCF platform stepped by MuJoCo through each loop interval (``mujoco.rollout``
  over all runs at once, warm start carried), driven by the exact inverse kinematics of the
  commanded pose (pitch, and the pitch-heave -l theta at the UGP) interpolated linearly within
  the interval; the delay block is the configuration's total minus the platform's own pitch
  lag, as in :mod:`twin.chain.config`.

Heave noise (Eq 5.10, seeded per run) enters the heave command; the pilot feels the attitude
plus the heave offset at the pilot station read as attitude, -z_noise / l.
"""

from __future__ import annotations

import mujoco
import numpy as np
from mujoco import rollout
from numpy.typing import NDArray
from scipy import signal

from twin.chain.config import MotionSystem
from twin.chain.physics import FullPlatform
from twin.frames import euler_from_matrix, matrix_from_quat
from twin.pilot.loop import _Filter
from twin.platform.kinematics import leg_rates

FloatArray = NDArray[np.float64]
_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
PITCH = 4


class _Blocks:
    """Causal filter and fractional delay of a configuration, for many runs."""

    def __init__(self, cfg: MotionSystem, runs: int, rate_hz: float, delay_s: float) -> None:
        self.filter = None
        if cfg.filter_break_hz is not None:
            wb = 2 * np.pi * cfg.filter_break_hz
            self.filter = _Filter(*signal.bilinear([1.0], [1 / wb**2, 2 / wb, 1.0], fs=rate_hz),
                                  runs)  # fmt: skip
        delay = max(delay_s, 0.0) * rate_hz
        self.d0, self.frac = int(np.floor(delay)), delay - np.floor(delay)
        self.hist = np.zeros((self.d0 + 2, runs))
        self.k = 0

    def step(self, x: FloatArray) -> FloatArray:
        y = self.filter.step(x) if self.filter is not None else x
        n = self.hist.shape[0]
        self.hist[self.k % n] = y
        a = self.hist[(self.k - self.d0) % n] if self.k >= self.d0 else 0.0 * y
        b = self.hist[(self.k - self.d0 - 1) % n] if self.k >= self.d0 + 1 else 0.0 * y
        self.k += 1
        return (1 - self.frac) * a + self.frac * b


class ReducedMotion:
    """Felt attitude = the configuration's Eq 5.11 applied to the attitude, plus noise."""

    kind = "reduced"

    def __init__(self, cfg: MotionSystem, runs: int, rate_hz: float, station_m: float) -> None:
        self.blocks = _Blocks(cfg, runs, rate_hz, cfg.delay_s)
        self.station_m = station_m

    def step(self, theta: FloatArray, z_noise: FloatArray) -> FloatArray:
        """Advance one loop interval; return the felt attitude [rad]."""
        return self.blocks.step(theta) - z_noise / self.station_m


class FullMotion:
    """Felt attitude from the MuJoCo platform (cabin pitch and pitch-heave deviation)."""

    kind = "full"

    def __init__(self, cfg: MotionSystem, runs: int, rate_hz: float, station_m: float) -> None:
        self.plat = FullPlatform(cfg.platform)
        model = self.plat.model
        self.sub = round(self.plat.rate_hz / rate_hz)
        if abs(self.plat.rate_hz / rate_hz - self.sub) > 1e-9:
            raise ValueError("the loop rate must divide the physics rate")
        self.blocks = _Blocks(cfg, runs, rate_hz, cfg.delay_s - self.plat.own_lag_s[PITCH])
        self.station_m, self.rate_hz, self.runs = station_m, rate_hz, runs
        data = mujoco.MjData(model)
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
        state = np.empty(mujoco.mj_stateSize(model, _STATE))
        mujoco.mj_getState(model, data, state, _STATE)
        self.data = [mujoco.MjData(model) for _ in range(2)]
        self.state = np.repeat(state[None], runs, axis=0)
        self.warm = np.repeat(data.qacc_warmstart[None], runs, axis=0)
        self.prev = np.zeros((runs, 6))
        adr = {n: model.sensor(n).adr[0] for n in ("ugp_position", "ugp_orientation")}
        self._pos, self._quat = adr["ugp_position"], adr["ugp_orientation"]

    def step(self, theta: FloatArray, z_noise: FloatArray) -> FloatArray:
        """Advance one loop interval; return the felt attitude [rad]."""
        cmd_theta = self.blocks.step(theta)
        pose = np.zeros((self.runs, 6))
        pose[:, PITCH] = cmd_theta
        pose[:, 2] = -self.station_m * cmd_theta + z_noise
        frac = np.arange(1, self.sub + 1) / self.sub
        poses = self.prev[:, None, :] + (pose - self.prev)[:, None, :] * frac[None, :, None]
        rates = np.broadcast_to(((pose - self.prev) * self.rate_hz)[:, None, :], poses.shape)
        lengths, vels, _ = leg_rates(self.plat.geometry, poses, rates)
        ctrl = np.concatenate([lengths, vels], axis=-1)
        states, sens = rollout.rollout(self.plat.model, self.data, self.state, ctrl,
                                       initial_warmstart=self.warm)  # fmt: skip
        self.state = states[:, -1]
        self.prev = pose
        last = sens[:, -1]
        T = matrix_from_quat(last[:, self._quat : self._quat + 4])
        pitch = euler_from_matrix(T)[:, 1]
        z = last[:, self._pos + 2] - self.plat.geometry.neutral_ugp[2]
        # attitude, plus the heave at the station that is not the commanded pitch-heave
        return pitch - (z + self.station_m * cmd_theta) / self.station_m
