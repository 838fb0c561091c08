"""The whole chain as one stream: a configuration's blocks in front of a platform.

:class:`ChainStream` is the only place where a chain is put together: the blocks of
:meth:`twin.chain.config.MotionSystem.blocks` (for the platform's own lag), then the platform
with the configuration's heave noise, for one or several runs. Open-loop runs
(:mod:`twin.chain.simulate`) feed it their commands a chunk at a time; the pilot in the loop
(:mod:`twin.pilot.models.pitch`) feeds it one sample per loop step. Same blocks, same arithmetic.

Examples
--------
>>> import numpy as np
>>> from twin.chain.reduced import ReducedPlatform
>>> chain = ChainStream("mpi", ReducedPlatform("mpi", rate_hz=100.0), 100.0, seed=1)
>>> jets = np.zeros((1, 1, 6, 3)); jets[0, 0, 4, 0] = 0.01   # pitch 0.01 rad from t = 0
>>> resp = chain.step(jets)
>>> resp.pose.shape, round(float(resp.pose[0, 0, 4]), 3)
((1, 1, 6), 0.01)

"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from twin.chain.block import Block
from twin.chain.config import MotionSystem, resolve
from twin.chain.limits import LimitReport
from twin.chain.noise import NoiseStream
from twin.chain.response import PlatformResponse
from twin.chain.stepping import Platform, PlatformState
from twin.core.errors import SignalError

FloatArray = NDArray[np.float64]


def noise_streams(config: MotionSystem, seeds: Sequence[int], rate_hz: float = 819.2) -> list:
    """Fresh heave-noise streams of a configuration, one per run seed (None without noise)."""
    gen = config.noise_block(rate_hz)
    if gen is None:
        return [None] * len(seeds)
    return [gen.stream(np.random.SeedSequence([int(s), 0])) for s in seeds]


class ChainStream:
    """A configuration's blocks and platform, stepped together (see the module docstring).

    Parameters
    ----------
    config : MotionSystem or str
        The configuration.
    platform : Platform
        The full or the reduced platform (its ``own_lag_s`` shortens the delay block).
    command_rate_hz : float
        Rate of the samples given to :meth:`step` [Hz].
    t0 : float
        Time of the first sample [s].
    seed : int or sequence of int
        Run seeds: the heave noise of run ``i`` draws from ``SeedSequence([seed_i, 0])``
        (as an open-loop run with that seed does). One seed per run.
    noise_rate_hz : float
        Rate of the heave-noise generator (the IMU rate).
    report : LimitReport, optional
        Filled with the actuator-limit counts.

    """

    def __init__(
        self,
        config: MotionSystem | str,
        platform: Platform,
        command_rate_hz: float,
        t0: float = 0.0,
        seed: int | Sequence[int] = 0,
        noise_rate_hz: float = 819.2,
        report: LimitReport | None = None,
    ) -> None:
        self.config = resolve(config)
        if self.config.platform != platform.platform:
            raise SignalError(
                f"configuration {self.config.name!r} drives the {self.config.platform} platform, "
                f"not {platform.platform!r}"
            )
        self.platform = platform
        self.blocks: list[Block] = self.config.blocks(platform.own_lag_s)
        self.rate_hz = float(command_rate_hz)
        self.t0 = float(t0)
        self.seeds = [int(seed)] if np.ndim(seed) == 0 else [int(s) for s in seed]  # type: ignore[arg-type]
        self.noise_rate_hz = noise_rate_hz
        self.report = (
            report if report is not None else LimitReport(platform.limits.mode, platform.rate_hz)
        )
        self._states: list[Any] | None = None
        self._platform: PlatformState | None = None

    @property
    def runs(self) -> int:
        """Runs stepped together."""
        return len(self.seeds)

    def step(self, jets: FloatArray) -> PlatformResponse:
        """Feed consecutive command samples ``(runs, n, 6, 3)``; return the platform's motion.

        The response covers the platform's samples up to the last command sample (arrays
        ``(runs, m, ...)``); its ``command`` is the platform's input before the heave noise.
        """
        x = self._through_blocks(jets)
        return self.platform.step(x, self._platform)  # type: ignore[arg-type]

    def submit(self, jets: FloatArray) -> Callable[[], PlatformResponse]:
        """Start :meth:`step`; the returned call finishes it and returns the motion.

        The full platform's physics then rolls in a thread while the caller goes on
        (:meth:`twin.chain.stepping.Platform.submit`).
        """
        x = self._through_blocks(jets)
        return self.platform.submit(x, self._platform)  # type: ignore[arg-type]

    def _through_blocks(self, jets: FloatArray) -> FloatArray:
        """Check the samples, stream them through the blocks; reset the platform at the first."""
        if jets.ndim != 4 or jets.shape[0] != self.runs or jets.shape[2:] != (6, 3):
            raise SignalError(
                f"commands must be jets of shape ({self.runs}, n, 6, 3); got {jets.shape}"
            )
        if not np.all(np.isfinite(jets)):
            raise SignalError("commands must be finite numbers")
        if self._states is None:
            self._states = [b.start(jets[:, 0], self.rate_hz) for b in self.blocks]
        x = jets
        for i, block in enumerate(self.blocks):
            x, self._states[i] = block.stream(x, self._states[i])
        if self._platform is None:
            noise: list[NoiseStream | None] = noise_streams(
                self.config, self.seeds, self.noise_rate_hz
            )
            self._platform = self.platform.reset(x[:, 0], self.t0, self.rate_hz, noise, self.report)
        return x
