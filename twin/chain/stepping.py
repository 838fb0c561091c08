"""The one platform interface (dm_control's ``Physics`` role): reset, step, limits, run.

A platform takes the chain's output, jets at the command rate (:mod:`twin.chain.jets`), and
produces cabin motion at its own rate: the full MuJoCo model at its 1 kHz physics rate
(:class:`twin.chain.physics.FullPlatform`), the reduced Eq 5.11 cabin wherever it is looked at
(:class:`twin.chain.reduced.ReducedPlatform`). Both share this base:

* :meth:`Platform.reset` from the first command sample (and the heave-noise streams, one per
  run, and the limit report);
* :meth:`Platform.step` with any number of further command samples: the reference between
  samples is the quintic through their jets, evaluated at the platform's sample times in
  (t[k-1], t[k]], plus the heave noise; the subclass turns it into motion (``_advance``);
* :meth:`Platform.run`, the stepping loop, written once: a whole signal, chunk by chunk.

Open-loop runs, the AGARD tests and the pilot in the loop all step a platform through this
interface, several runs at once where they want (``runs`` axis first).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from twin.chain.jets import JetSignal, hermite_samples
from twin.chain.limits import ActuatorLimits, LimitReport
from twin.chain.noise import NoiseStream
from twin.chain.response import PlatformResponse
from twin.core.errors import SignalError
from twin.core.threads import one_blas_thread
from twin.platform.geometry import Geometry

FloatArray = NDArray[np.float64]

#: Default chunk length [s] of :meth:`Platform.run`: memory stays bounded for any duration.
CHUNK_S = 10.0


@dataclass
class PlatformState:
    """Where a platform stands between steps.

    Attributes
    ----------
    t0 : float
        Time of the first command sample [s].
    command_rate_hz : float
        Rate of the command samples [Hz].
    last : ndarray, shape (runs, 6, 3)
        Jets of the last command sample consumed.
    consumed : int
        Command samples consumed.
    next_sample : int
        Index of the platform's next own sample (time ``t0 + next_sample / rate_hz``).
    noise : list of (NoiseStream or None)
        Heave noise per run.
    report : LimitReport
        Actuator-limit counts (all runs).
    inner : object
        The subclass's own state (MuJoCo states, limiter).

    """

    t0: float
    command_rate_hz: float
    last: FloatArray
    consumed: int
    next_sample: int
    noise: list[NoiseStream | None]
    report: LimitReport
    inner: Any = field(default=None)

    @property
    def runs(self) -> int:
        """Runs stepped together."""
        return self.last.shape[0]


@dataclass(frozen=True, eq=False)
class Reference:
    """The platform's input at its own sample times, for every run.

    Attributes
    ----------
    t : ndarray, shape (m,)
        Times [s].
    command : ndarray, shape (runs, m, 6)
        The chain's output (before the heave noise).
    pose, rate, acc : ndarray, shape (runs, m, 6)
        Pose reference and its derivatives, heave noise included.

    """

    t: FloatArray
    command: FloatArray
    pose: FloatArray
    rate: FloatArray
    acc: FloatArray


class Platform(ABC):
    """Base of the full and the reduced platform (see the module docstring).

    Subclasses set ``kind``, ``platform``, ``geometry``, ``limits``, ``own_lag_s`` and
    ``rate_hz`` and implement :meth:`_reset_inner` and :meth:`_advance`.
    """

    kind = "platform"
    platform: str
    geometry: Geometry
    limits: ActuatorLimits
    own_lag_s: FloatArray
    rate_hz: float

    def reset(
        self,
        first: FloatArray,
        t0: float,
        command_rate_hz: float,
        noise: Sequence[NoiseStream | None] | NoiseStream | None = None,
        report: LimitReport | None = None,
    ) -> PlatformState:
        """Start at rest at the neutral pose, before the first command sample.

        Parameters
        ----------
        first : ndarray, shape (runs, 6, 3)
            Jets of the first command sample (given again to the first :meth:`step`).
        t0 : float
            Its time [s].
        command_rate_hz : float
            Command rate [Hz].
        noise : sequence of (NoiseStream or None), or NoiseStream, optional
            Fresh heave-noise streams, one per run (consumed); a single stream for one run.
        report : LimitReport, optional
            Filled with the actuator-limit counts.

        """
        runs = first.shape[0]
        if isinstance(noise, NoiseStream):
            noise = [noise]
        streams = list(noise) if noise is not None else [None] * runs
        if len(streams) != runs:
            raise SignalError(f"need one noise stream per run ({runs}); got {len(streams)}")
        for s in streams:
            if s is not None and s.noise.highpass_hz is None:
                raise SignalError(
                    "heave noise without a high-pass has no bounded position and cannot be a "
                    "platform command; give the noise a highpass_hz > 0"
                )
        rep = report if report is not None else LimitReport(self.limits.mode, self.rate_hz)
        state = PlatformState(t0, float(command_rate_hz), first.copy(), 0, 0, streams, rep)
        state.inner = self._reset_inner(runs)
        return state

    def step(self, jets: FloatArray, state: PlatformState) -> PlatformResponse:
        """Advance through consecutive command samples ``(runs, n, 6, 3)``.

        Returns the motion at the platform's samples up to the last command sample's time
        (arrays ``(runs, m, ...)``, ``t`` of shape ``(m,)``; ``m`` may be 0).
        """
        ref = self._reference(jets, state)
        return self._advance(ref, state)

    def submit(self, jets: FloatArray, state: PlatformState) -> Callable[[], PlatformResponse]:
        """Start :meth:`step` through ``jets``; return a call that finishes it.

        The same arithmetic as :meth:`step`, in the same order (the same bits), but the caller
        may prepare the next step, or use the previous one, before it calls the finisher:
        the full platform rolls its physics in a background thread meanwhile (MuJoCo releases
        the GIL), so an open-loop run's Python work overlaps the physics. Steps are finished
        in the order they were submitted; submitting the next before finishing this one is
        allowed (the physics of the next waits for this one's).
        """
        ref = self._reference(jets, state)
        return self._start(ref, state)

    def run(
        self,
        signal: JetSignal,
        noise: Sequence[NoiseStream | None] | NoiseStream | None = None,
        report: LimitReport | None = None,
        chunk_s: float = CHUNK_S,
    ) -> Iterator[PlatformResponse]:
        """Step through a whole signal, yielding the motion chunk by chunk (one run: 2-D arrays).

        Parameters
        ----------
        signal : JetSignal
            The platform's input (the chain's output).
        noise : sequence of (NoiseStream or None), optional
            Heave noise, one fresh stream per run.
        report : LimitReport, optional
            Filled with the actuator-limit counts.
        chunk_s : float
            Command samples per step, in seconds.

        """
        state = self.reset(signal.jets[:, 0], signal.t0, signal.rate_hz, noise, report)
        step = max(1, round(chunk_s * signal.rate_hz))
        pieces = (signal.jets[:, k : k + step] for k in range(0, signal.n, step))
        for resp in overlapped(pieces, lambda jets: self.submit(jets, state)):
            yield resp.run(0) if signal.runs == 1 else resp

    # --- shared by both platforms -------------------------------------------------------------

    def _reference(self, jets: FloatArray, state: PlatformState) -> Reference:
        """Return the reference at the platform's sample times covered by ``jets``."""
        n = jets.shape[1]
        ratio = self.rate_hz / state.command_rate_hz
        last_cmd = state.consumed + n - 1
        stop = int(np.floor(last_cmd * ratio + 1e-9)) + 1
        idx = np.arange(state.next_sample, stop)
        x = idx / ratio - state.consumed  # position in command samples, relative to the chunk
        k = np.clip(np.ceil(x - 1e-9).astype(int), 0, n - 1)  # interval (k-1, k]
        s = x - (k - 1)
        ext = np.concatenate([state.last[:, None], jets], axis=1)  # ext[k] is sample k - 1
        pose, rate, acc = hermite_samples(ext, k, s, 1.0 / state.command_rate_hz)
        state.last = jets[:, -1].copy()
        state.consumed += n
        state.next_sample = stop
        t = state.t0 + idx / self.rate_hz
        command = pose.copy()
        for r, stream in enumerate(state.noise):
            if stream is not None and t.size:
                z = stream.at(t - state.t0)
                acc[r, :, 2] += z[:, 0]
                rate[r, :, 2] += z[:, 1]
                pose[r, :, 2] += z[:, 2]
        return Reference(t, command, pose, rate, acc)

    def _reset_inner(self, runs: int) -> Any:
        """Return the subclass's own state at rest."""
        return None

    def _start(self, ref: Reference, state: PlatformState) -> Callable[[], PlatformResponse]:
        """Begin turning the reference into motion; the finisher returns it (subclass).

        By default the motion is computed at once.
        """
        resp = self._advance(ref, state)
        return lambda: resp

    @abstractmethod
    def _advance(self, ref: Reference, state: PlatformState) -> PlatformResponse:
        """Turn the reference into motion (subclass)."""


def overlapped(
    items: Iterable[Any], submit: Callable[[Any], Callable[[], PlatformResponse]]
) -> Iterator[PlatformResponse]:
    """Submit each item, finishing the previous one only once the next is submitted.

    With the full platform the physics of step k + 1 then rolls while the caller handles the
    response of step k (the IMU, a recording): one step of look-ahead, the same results.
    Meanwhile BLAS keeps to one thread (:mod:`twin.core.threads`; restored after the last step):
    a BLAS pool of one thread per core would take the physics thread's core, and make the run
    slower than without the look-ahead (bench/twin_throughput.py, in a process that has not
    set its threads as the ``twin`` command does).
    """
    with one_blas_thread():
        pending = None
        for item in items:
            nxt = submit(item)
            if pending is not None:
                yield pending()
            pending = nxt
        if pending is not None:
            yield pending()
