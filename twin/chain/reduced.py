"""The reduced platform (Eq 5.11): a rigid cabin that follows its (filtered, delayed) input.

Together with the blocks of :mod:`twin.chain.config` in front of it this is the thesis'
reduced MPI model, H = 1 / (1 + s / (2 pi f_b))^2 e^{-tau s}, plus the Eq 5.10 noise. What it
leaves out, by construction: the platform's own first-order lag (t_m of Table 5.5, a few ms),
parasitic motion in the undriven DOFs, the static sag of K_s, leg dynamics, and actuator
saturation (limits are counted, never applied).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from twin.chain.limits import ActuatorLimits, LimitReport
from twin.chain.noise import NoiseRealisation
from twin.chain.physics import CHUNK_S, reference_chunks
from twin.chain.response import PlatformResponse, rigid_motion
from twin.geometry import load_geometry
from twin.platforms import load_facts, load_model
from twin.trajectory import Trajectory


class ReducedPlatform:
    """A rigid cabin that follows its input exactly: with the blocks in front, Eq 5.11.

    Produces the same :class:`PlatformResponse` as :class:`FullPlatform`, sampled at the same
    rate by default; leg lengths come from the inverse kinematics, and actuator limits are
    counted (never limited: the reduced model has no actuators to saturate).

    Parameters
    ----------
    platform : str
        ``"mpi"`` or ``"srs"`` (for the geometry and limits).
    rate_hz : float, optional
        Output rate [Hz]; the full model's physics rate by default.
    limit_mode : str
        ``"limit"`` (count only) or ``"strict"`` (raise on any limit).

    """

    kind = "reduced"

    def __init__(self, platform: str, rate_hz: float | None = None, limit_mode: str = "limit"):
        self.platform = platform
        self.geometry = load_geometry(platform)
        self.limits = ActuatorLimits.of(self.geometry, load_facts(platform), limit_mode)
        self.own_lag_s = np.zeros(6)
        self.rate_hz = rate_hz or 1.0 / load_model(platform).opt.timestep

    def run(
        self,
        commands: Trajectory,
        noise: NoiseRealisation | None = None,
        report: LimitReport | None = None,
        chunk_s: float = CHUNK_S * 6,
    ) -> Iterator[PlatformResponse]:
        """Evaluate the response chunk by chunk (same arguments as :meth:`FullPlatform.run`)."""
        report = report if report is not None else LimitReport(self.limits.mode, self.rate_hz)
        for ref in reference_chunks(commands, noise, self.geometry, self.rate_hz, chunk_s):
            self.limits.check(ref.t, ref.lengths, ref.velocities, ref.accelerations, report)
            motion = rigid_motion(ref.pose, ref.rate, ref.acc)
            yield PlatformResponse(ref.t, ref.pose, ref.pose.copy(), *motion, ref.lengths)
