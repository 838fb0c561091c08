"""The stepping of the pitch loop of :func:`~twin.pilot.models.pitch.simulate_pitch`, many runs.

Per loop sample: the aircraft's attitude (and its first two derivatives, the jets the motion
chain takes) from its zero-order-hold state, the error, the pilot's visual and motion channels
on the error and the felt attitude their delays late, the remnant, the control and the next
aircraft state. The motion chain is stepped a block of samples at a time (the pilot feels
the motion ``d_m`` samples late, so the block's felt attitude is needed only after it).

:func:`fly` takes the same route in blocks as long as the shorter pilot delay: within such a
block the pilot's channels act on samples of earlier blocks, so they are filtered at once
(:meth:`twin.pilot.models.loop._Filter.block`) and only the aircraft is stepped sample by sample.
The products and sums are those of :func:`fly_stepped`, in the same order: the same bits
(tested). A pilot whose delay rounds to no sample is stepped one sample at a time. A
loop is flown once: flying moves its filters, remnant and chain on.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from twin.chain.response import PlatformResponse
from twin.chain.stream import ChainStream
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES
from twin.core.progress import ProgressFn
from twin.pilot.models.loop import Remnant, _Filter

FloatArray = NDArray[np.float64]
PITCH, HEAVE = DOF_NAMES.index("pitch"), DOF_NAMES.index("heave")


class WithPassive:
    """A pilot's motion channel ``d_active`` samples late beside a passive path one sample late.

    Stepped by the loop as a motion channel with a delay of one sample (so the loop steps
    one sample at a time): the active channel's extra ``d_active - 1`` samples are kept here
    (an active channel of no delay, ``d_active`` 0, acts one sample late).
    ``active`` None: the passive path alone (a pilot who does not use the motion).
    """

    def __init__(self, active: _Filter | None, d_active: int, passive: _Filter, runs: int):
        self.active, self.passive = active, passive
        self.late = np.zeros((max(d_active - 1, 0), runs))  # the active channel's input queue
        self.z = passive.z

    def step(self, x: FloatArray) -> FloatArray:
        """Return the output for one felt sample of every run (one sample late), (runs,)."""
        y = self.passive.step(x)
        if self.active is None:
            return y
        if len(self.late):
            x, self.late = self.late[0], np.vstack([self.late[1:], x[None, :]])
        return y + self.active.step(x)

    def block(self, x: FloatArray) -> FloatArray:
        """Return the outputs for samples ``x``, shape (samples, runs)."""
        return np.stack([self.step(row) for row in x])


@dataclass
class PitchLoop:
    """What one flight of the pitch loop steps (built by ``simulate_pitch``).

    Attributes
    ----------
    pe, pm : _Filter, _Filter, WithPassive or None
        The pilot's visual channel on the displayed error and motion channel on the felt
        attitude (None: the pilot does not use the motion; :class:`WithPassive` with a
        passive path beside it).
    d_v, d_m : int
        Their delays [samples] (the visual one with the display's).
    remnant : Remnant or None
        The remnant (None: none).
    chain : ChainStream
        The motion chain, taking (runs, samples, 6, 3) attitude jets.
    feel : callable
        ``feel(response, station_m, times)``: the attitude felt at the station (runs,
        len(times)) in a chain response.
    ad, bd, jet_x, jet_u : ndarray
        The aircraft's zero-order-hold state update (``ad @ x + bd @ u``) and the attitude
        jets of its state and of its held input.
    station_m : float
        Pilot station ahead of the c.g. [m] (heave jets: -station_m x the attitude jets).
    t, f_t, f_d : ndarray
        Times [s], target and disturbance of every sample of the flight.
    dt : float
        Sample interval [s].
    start : int
        First sample kept.
    progress : callable or None
        Progress callback (flown time [s]).

    """

    pe: _Filter
    pm: _Filter | WithPassive | None
    d_v: int
    d_m: int
    remnant: Remnant | None
    chain: ChainStream
    feel: Callable[[PlatformResponse, float, FloatArray], FloatArray]
    ad: FloatArray
    bd: FloatArray
    jet_x: FloatArray
    jet_u: FloatArray
    station_m: float
    t: FloatArray
    f_t: FloatArray
    f_d: FloatArray
    dt: float
    start: int
    progress: ProgressFn | None
    flown: bool = False

    @property
    def runs(self) -> int:
        """Runs flown at once."""
        return self.pe.z.shape[1]

    @property
    def chain_block(self) -> int:
        """Samples per motion-chain step: the motion delay (at least one)."""
        return max(1, self.d_m)

    @property
    def report_every(self) -> int:
        """Samples between progress reports (about 2 % of the flight)."""
        return max(1, self.f_t.size // 50)

    def _felt(self, motion: PlatformResponse, begin: int, end: int) -> FloatArray:
        """Return the attitude felt at samples ``begin`` to ``end - 1``, (samples, runs)."""
        return self.feel(motion, self.station_m, self.t[begin:end]).T

    def _report(self, done: int, every: int) -> None:
        """Report progress after sample ``done - 1`` where a ``every``-th sample ends there."""
        n = self.f_t.size
        if self.progress and (done % every == 0 or done == n):
            self.progress("pilot in the loop [s]", round(done * self.dt, 2), round(n * self.dt, 2))

    def _outputs(self, e, u, theta, n, felt) -> dict[str, FloatArray]:
        """Return the kept samples, each (runs, samples), of time-major (samples, runs) ones."""
        kept = {"e": e, "u": u, "theta": theta, "n": n, "theta_felt": felt}
        return {k: np.ascontiguousarray(v[self.start :].T) for k, v in kept.items()}


def fly(loop: PitchLoop) -> dict[str, FloatArray]:
    """Fly ``loop``: e, u, theta, n and theta_felt of the kept samples, each (runs, samples)."""
    if loop.d_v < 1 or (loop.pm is not None and loop.d_m < 1):
        return fly_stepped(loop)
    return _fly_in_blocks(loop)


def _take_off(loop: PitchLoop) -> None:
    """Mark ``loop`` flown; refuse a second flight (its filters and chain have moved on)."""
    if loop.flown:
        raise SignalError("a pitch loop is flown once; build another with pitch_loop()")
    loop.flown = True


def fly_stepped(loop: PitchLoop) -> dict[str, FloatArray]:
    """Fly ``loop`` one sample at a time (the reference of :func:`fly`'s blocks)."""
    _take_off(loop)
    size, runs, block = loop.f_t.size, loop.runs, loop.chain_block
    state, held_u = np.zeros((loop.ad.shape[0], runs)), np.zeros(runs)
    jets = np.zeros((runs, block, 6, 3))
    series = {k: np.empty((size, runs)) for k in ("e", "u", "theta", "n", "felt")}
    zeros = np.zeros(runs)
    every = loop.report_every
    for k in range(size):
        theta_jet = (loop.jet_x @ state).T + held_u[:, None] * loop.jet_u  # (runs, 3)
        theta = theta_jet[:, 0]
        e = loop.f_t[k] - theta
        jets[:, k % block, PITCH] = theta_jet
        jets[:, k % block, HEAVE] = -loop.station_m * theta_jet
        if k % block == block - 1 or k == size - 1:
            first = k - k % block
            motion = loop.chain.step(jets[:, : k - first + 1])
            series["felt"][first : k + 1] = loop._felt(motion, first, k + 1)
        series["e"][k], series["theta"][k] = e, theta
        ye = loop.pe.step(series["e"][k - loop.d_v] if k >= loop.d_v else zeros)
        felt = series["felt"][k - loop.d_m] if k >= loop.d_m else zeros
        ym = loop.pm.step(felt) if loop.pm is not None else zeros
        n = loop.remnant.sample(k) if loop.remnant is not None else zeros
        u = ye - ym + n
        series["u"][k], series["n"][k] = u, n
        held_u = u + loop.f_d[k]
        state = loop.ad @ state + loop.bd @ held_u[None, :]
        loop._report(k + 1, every)
    return loop._outputs(**series)


def _fly_in_blocks(loop: PitchLoop) -> dict[str, FloatArray]:
    """:func:`fly` in blocks of at most the shorter delay, none across a chain step."""
    _take_off(loop)
    size, runs, block = loop.f_t.size, loop.runs, loop.chain_block
    state, held_u = np.zeros((loop.ad.shape[0], runs)), np.zeros(runs)
    jets = np.zeros((runs, block, 6, 3))
    # time-major series, with zeros before the flight for the delayed channels
    lead = max(loop.d_v, loop.d_m)
    e_all, felt_all = np.zeros((lead + size, runs)), np.zeros((lead + size, runs))
    series = {k: np.empty((size, runs)) for k in ("u", "theta", "n")}
    every = loop.report_every
    k = 0
    while k < size:
        m = min(loop.d_v, block - k % block, size - k)
        ye = loop.pe.block(e_all[lead + k - loop.d_v : lead + k - loop.d_v + m])
        if loop.pm is not None:
            ym = loop.pm.block(felt_all[lead + k - loop.d_m : lead + k - loop.d_m + m])
        else:
            ym = np.zeros((m, runs))
        n = loop.remnant.samples(k, m) if loop.remnant is not None else np.zeros((m, runs))
        u = ye - ym + n
        theta_jets = np.empty((m, runs, 3))
        for j in range(m):
            theta_jets[j] = (loop.jet_x @ state).T + held_u[:, None] * loop.jet_u
            held_u = u[j] + loop.f_d[k + j]
            state = loop.ad @ state + loop.bd @ held_u[None, :]
        first = k % block
        jets[:, first : first + m, PITCH] = theta_jets.transpose(1, 0, 2)
        jets[:, first : first + m, HEAVE] = -loop.station_m * theta_jets.transpose(1, 0, 2)
        theta = theta_jets[:, :, 0]
        e_all[lead + k : lead + k + m] = loop.f_t[k : k + m, None] - theta
        series["theta"][k : k + m], series["u"][k : k + m], series["n"][k : k + m] = theta, u, n
        k += m
        if k % block == 0 or k == size:
            begin = k - first - m
            motion = loop.chain.step(jets[:, : k - begin])
            felt_all[lead + begin : lead + k] = loop._felt(motion, begin, k)
        for done in range((k - m) // every * every + every, k + 1, every):
            loop._report(done, every)  # the reports stepping makes, at the block's end
        if k == size and k % every:
            loop._report(k, every)  # the last sample
    return loop._outputs(e_all[lead:], series["u"], series["theta"], series["n"], felt_all[lead:])
