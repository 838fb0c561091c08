"""The closed loop of Chapter 2 (Fig 2.1), many runs at once.

    e = f_t - x,   u = H_pe e - H_px x + n,   x = H_c (u + f_d),   H_c = 4 / s^2

simulated at 100 Hz: H_c by zero-order hold, the pilot's rational parts by the bilinear
transform with their delays as whole samples, and the remnant of Eq 2.21 driven by seeded
unit white noise and scaled so that its power is a chosen fraction of the power of u (10 % in
§2.5.1). Runs are vectorised: every time step updates all runs together, and the steps go in
blocks as long as the pilot's shorter delay (the pilot acts on samples of earlier blocks), with
the bits of stepping one sample at a time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import signal

from twin.core.errors import SignalError
from twin.pilot.models.forcing import MEASUREMENT_S, RATE_HZ, RUN_IN_S, ForcingFunction
from twin.pilot.models.model import REMNANT_FILTER, RollPilot

FloatArray = NDArray[np.float64]


class _Filter:
    """A discrete transfer function stepped for many runs (transposed direct form II)."""

    def __init__(self, b: FloatArray, a: FloatArray, runs: int) -> None:
        self.b, self.a = np.asarray(b) / a[0], np.asarray(a) / a[0]
        n = max(len(self.a), len(self.b))
        self.b = np.pad(self.b, (0, n - len(self.b)))
        self.a = np.pad(self.a, (0, n - len(self.a)))
        self.z = np.zeros((n - 1, runs))

    def step(self, x: FloatArray) -> FloatArray:
        """Return the output for one input sample of every run, shape (runs,)."""
        y = self.b[0] * x + (self.z[0] if len(self.z) else 0.0)
        for i in range(len(self.z) - 1):
            self.z[i] = self.z[i + 1] + self.b[i + 1] * x - self.a[i + 1] * y
        if len(self.z):
            self.z[-1] = self.b[-1] * x - self.a[-1] * y
        return y

    def block(self, x: FloatArray) -> FloatArray:
        """Return the outputs for samples ``x``, shape (samples, runs), the state carried on.

        :func:`scipy.signal.lfilter` does the products and sums of :meth:`step` in the same
        order, so the outputs have the same bits as stepping sample by sample (tested).
        """
        if not len(self.z):  # a gain: step's "+ 0.0" turns -0.0 into 0.0, as here
            return self.b[0] * x + 0.0
        y, self.z = signal.lfilter(self.b, self.a, x, axis=0, zi=self.z)
        return y


def _bilinear(num: FloatArray, den: FloatArray, rate: float) -> tuple[FloatArray, FloatArray]:
    """Return the bilinear transform of num/den at ``rate``.

    A zero numerator (K_m = 0: no motion channel) is a zero gain, which scipy cannot transform.
    """
    if not np.any(num):
        return np.zeros(1), np.ones(1)
    b, a = signal.bilinear(num, den, fs=rate)
    return b, a


@dataclass(frozen=True, eq=False)
class LoopData:
    """Signals of the measurement window of many runs, shape (runs, samples).

    Attributes
    ----------
    t : ndarray, shape (samples,)
        Time [s] from the start of the window.
    e, u, x, n, ft, fd : ndarray, shape (runs, samples)
        Error, control, state, remnant and forcing functions.
    rate_hz : float
        Sample rate.

    """

    t: FloatArray
    e: FloatArray
    u: FloatArray
    x: FloatArray
    n: FloatArray
    ft: FloatArray
    fd: FloatArray
    rate_hz: float


#: Run-in of the simulated loop before the window [s]: the forced response is computed with a
#: whole extra period (the slow canal mode, tau_v2 = 6 s, would not settle in the 8.08 s
#: run-in of the experiment), the remnant response with 30 s (five tau_v2).
FORCED_RUN_IN_S = RUN_IN_S + MEASUREMENT_S
REMNANT_RUN_IN_S = 30.0


def simulate_loop(
    pilot: RollPilot,
    fd: ForcingFunction,
    ft: ForcingFunction,
    runs: int = 1,
    seed: int = 0,
    remnant_scale: float = 0.0,
    rate_hz: float = RATE_HZ,
) -> LoopData:
    """Simulate ``runs`` closed-loop runs and return their 81.92 s measurement windows.

    The loop is linear, so each run is the forced response (one simulation, in periodic
    steady state) plus its own remnant response (all runs at once, seeded).

    Parameters
    ----------
    pilot : RollPilot
        Pilot model.
    fd, ft : ForcingFunction
        Disturbance (added to u, before H_c) and target.
    runs : int
        Number of runs with fresh remnant.
    seed : int
        Seed of the remnant's white noise (same seed, same bits).
    remnant_scale : float
        Gain on the Eq 2.21 remnant (see :func:`remnant_scale_for`); 0 for none.
    rate_hz : float
        Simulation rate [Hz].

    """
    if runs < 1:
        raise SignalError(f"runs must be >= 1; got {runs}")
    n_keep = round(MEASUREMENT_S * rate_hz)
    start = round(FORCED_RUN_IN_S * rate_hz)
    t = np.arange(start + n_keep) / rate_hz
    forced = _simulate(pilot, ft(t), fd(t), 1, 0.0, None, rate_hz, start)
    out = {k: np.repeat(v, runs, axis=0) for k, v in forced.items()}
    if remnant_scale:
        rng = np.random.default_rng(seed)
        start_n = round(REMNANT_RUN_IN_S * rate_hz)
        zero = np.zeros(start_n + n_keep)
        noise = _simulate(pilot, zero, zero, runs, remnant_scale, rng, rate_hz, start_n)
        for k in ("e", "u", "x", "n"):
            out[k] += noise[k]
    t_run = t[start:] - RUN_IN_S - MEASUREMENT_S  # t = 0 at the window's start ...
    t_exp = t_run + RUN_IN_S  # ... which is 8.08 s into the experiment's run
    return LoopData(
        t_run - t_run[0],
        out["e"],
        out["u"],
        out["x"],
        out["n"],
        np.broadcast_to(ft(t_exp), (runs, n_keep)),
        np.broadcast_to(fd(t_exp), (runs, n_keep)),
        rate_hz,
    )


def _simulate(
    pilot: RollPilot,
    f_t: FloatArray,
    f_d: FloatArray,
    runs: int,
    remnant_scale: float,
    rng: np.random.Generator | None,
    rate_hz: float,
    start: int,
) -> dict[str, FloatArray]:
    """Step the loop over the samples of ``f_t``/``f_d``; keep the samples from ``start``.

    The pilot acts on e and x at least one delay late, so the samples of a block as long as
    the shorter delay need nothing of the block itself: its pilot outputs are filtered at
    once (:meth:`_Filter.block`) and H_c's zero-order hold is a running sum
    (:func:`_hold_blocks`), with the products and sums of stepping sample by sample in the
    same order, so the same bits (tested against :func:`_stepped`, which a pilot with a
    delay that rounds to no sample still takes).
    """
    parts = _LoopParts.of(pilot, runs, remnant_scale, rng, rate_hz)
    run = _stepped if min(parts.d_pe, parts.d_px) < 1 else _in_blocks
    return run(parts, f_t, f_d, 1.0 / rate_hz, start)


@dataclass
class _LoopParts:
    """The pilot's filters and delays [samples] and the remnant of :func:`_simulate`."""

    pe: _Filter
    px: _Filter
    d_pe: int
    d_px: int
    remnant: Remnant | None
    runs: int

    @classmethod
    def of(
        cls, pilot: RollPilot, runs: int, remnant_scale: float, rng: np.random.Generator | None,
        rate_hz: float,
    ) -> _LoopParts:  # fmt: skip
        """Return the parts of ``pilot``'s loop (no remnant without ``rng``)."""
        parts = pilot.rational_parts()
        pe = _Filter(*_bilinear(*parts["pe"][:2], rate_hz), runs)
        px = _Filter(*_bilinear(*parts["px"][:2], rate_hz), runs)
        d_pe, d_px = round(parts["pe"][2] * rate_hz), round(parts["px"][2] * rate_hz)
        remnant = Remnant(rng, remnant_scale, runs, rate_hz) if rng is not None else None
        return cls(pe, px, d_pe, d_px, remnant, runs)


def _stepped(
    parts: _LoopParts, f_t: FloatArray, f_d: FloatArray, dt: float, start: int
) -> dict[str, FloatArray]:
    """:func:`_simulate` one sample at a time (the reference of :func:`_in_blocks`)."""
    pe, px, remnant, runs = parts.pe, parts.px, parts.remnant, parts.runs
    d_pe, d_px = parts.d_pe, parts.d_px
    pos, vel = np.zeros(runs), np.zeros(runs)  # H_c = 4 / s^2 by zero-order hold
    n_keep = f_t.size - start
    out = {k: np.empty((runs, n_keep)) for k in ("e", "u", "x", "n")}
    hist = max(d_pe, d_px) + 1
    e_hist, x_hist = np.zeros((hist, runs)), np.zeros((hist, runs))
    zeros = np.zeros(runs)
    for k in range(f_t.size):
        x = pos
        e = f_t[k] - x
        e_hist[k % hist], x_hist[k % hist] = e, x
        ye = pe.step(e_hist[(k - d_pe) % hist] if k >= d_pe else zeros)
        yx = px.step(x_hist[(k - d_px) % hist] if k >= d_px else zeros)
        n = remnant.sample(k) if remnant is not None else zeros
        u = ye - yx + n
        acc = 4.0 * (u + f_d[k])
        pos = pos + vel * dt + 0.5 * acc * dt**2
        vel = vel + acc * dt
        if k >= start:
            j = k - start
            out["e"][:, j], out["u"][:, j], out["x"][:, j], out["n"][:, j] = e, u, x, n
    return out


def _in_blocks(
    parts: _LoopParts, f_t: FloatArray, f_d: FloatArray, dt: float, start: int
) -> dict[str, FloatArray]:
    """:func:`_simulate` in blocks of the shorter pilot delay (both delays >= 1 sample)."""
    pe, px, remnant, runs = parts.pe, parts.px, parts.remnant, parts.runs
    d_pe, d_px = parts.d_pe, parts.d_px
    block = min(d_pe, d_px)
    # time-major histories, with zeros before the run for the delayed inputs
    lead = max(d_pe, d_px)
    e_all, x_all = np.zeros((lead + f_t.size, runs)), np.zeros((lead + f_t.size, runs))
    u_all, n_all = np.empty((f_t.size, runs)), np.empty((f_t.size, runs))
    pos, vel = np.zeros(runs), np.zeros(runs)
    for k in range(0, f_t.size, block):
        m = min(block, f_t.size - k)
        ye = pe.block(e_all[lead + k - d_pe : lead + k - d_pe + m])
        yx = px.block(x_all[lead + k - d_px : lead + k - d_px + m])
        n = remnant.samples(k, m) if remnant is not None else np.zeros((m, runs))
        u = ye - yx + n
        acc = 4.0 * (u + f_d[k : k + m, None])
        x, pos, vel = _hold_blocks(pos, vel, acc, dt)
        x_all[lead + k : lead + k + m] = x
        e_all[lead + k : lead + k + m] = f_t[k : k + m, None] - x
        u_all[k : k + m], n_all[k : k + m] = u, n
    kept = {"e": e_all[lead:], "u": u_all, "x": x_all[lead:], "n": n_all}
    return {k: np.ascontiguousarray(v[start:].T) for k, v in kept.items()}


def _hold_blocks(
    pos: FloatArray, vel: FloatArray, acc: FloatArray, dt: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Run H_c's zero-order hold over accelerations ``acc`` (samples, runs).

    Returns the positions at the samples (before each update) and the position and velocity
    after the last. The recursion ``pos + vel * dt + 0.5 * acc * dt**2``, ``vel + acc * dt``
    is summed left to right, so running sums (:func:`numpy.cumsum`, which adds in order) over
    the interleaved terms give its bits.
    """
    m = acc.shape[0]
    v = np.cumsum(np.concatenate([vel[None], acc * dt]), axis=0)
    terms = np.empty((2 * m + 1, acc.shape[1]))
    terms[0], terms[1::2], terms[2::2] = pos, v[:-1] * dt, 0.5 * acc * dt**2
    p = np.cumsum(terms, axis=0)
    return p[0 : 2 * m : 2], p[2 * m], v[m]


#: Samples of remnant drawn and filtered at once (memory: 8 bytes x runs x this, twice).
REMNANT_BLOCK = 1000


class Remnant:
    """The Eq 2.21 remnant of many runs, sample by sample, filtered ahead in blocks.

    The remnant is open loop, so it need not be stepped with the loop:
    :func:`scipy.signal.lfilter` does the transposed direct form II with the same products and
    sums in the same order as :class:`_Filter` stepped sample by sample, and the white noise
    is drawn in the same order, so the samples have the same bits (tested), at a fraction of
    the cost. The filter's state carries from block to block.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the unit white noise (``runs`` values per sample, in order).
    scale : float
        Gain on the filtered noise.
    runs : int
        Runs.
    rate_hz : float
        Sample rate [Hz].

    """

    def __init__(self, rng: np.random.Generator, scale: float, runs: int, rate_hz: float):
        self._rng, self._scale, self._runs = rng, scale, runs
        f = _Filter(*_bilinear(*REMNANT_FILTER, rate_hz), runs)
        self._b, self._a, self._z = f.b, f.a, f.z
        self._block = np.empty((0, runs))
        self._next = 0

    def sample(self, k: int) -> FloatArray:
        """Return sample ``k`` of every run, shape (runs,); samples are asked for in order."""
        if k != self._next:
            raise SignalError(f"remnant samples are drawn in order: asked {k}, next {self._next}")
        self._next += 1
        if k % REMNANT_BLOCK == 0:
            white = self._rng.standard_normal((REMNANT_BLOCK, self._runs))
            y, self._z = signal.lfilter(self._b, self._a, white, axis=0, zi=self._z)
            self._block = self._scale * y
        return self._block[k % REMNANT_BLOCK]

    def samples(self, k: int, m: int) -> FloatArray:
        """Return samples ``k`` to ``k + m - 1`` of every run, shape (m, runs), in order."""
        parts, end = [], k + m
        while k < end:
            self.sample(k)  # checks the order; draws the next block where one begins
            i, stop = k % REMNANT_BLOCK, min(end, (k // REMNANT_BLOCK + 1) * REMNANT_BLOCK)
            parts.append(self._block[i : i + stop - k])
            self._next = k = stop
        return parts[0] if len(parts) == 1 else np.concatenate(parts)


def remnant_scale_for(
    pilot: RollPilot,
    fd: ForcingFunction,
    ft: ForcingFunction,
    ratio: float = 0.1,
    rate_hz: float = RATE_HZ,
    runs: int = 64,
    seed: int = 12345,
) -> float:
    """Gain on the Eq 2.21 remnant that makes its power ``ratio`` times the power of u.

    The loop is linear: u = u_f + g u_n and n = g n_1, so g^2 P(n_1) = ratio (P(u_f) +
    g^2 P(u_n)) gives g; the powers of the remnant parts are averaged over ``runs`` runs.
    """
    if not 0 < ratio < 1:
        raise SignalError(f"remnant power ratio must be between 0 and 1; got {ratio}")
    forced = simulate_loop(pilot, fd, ft, 1, seed, 0.0, rate_hz)
    zero = ForcingFunction(fd.omega_rad_s[:1], np.zeros(1), np.zeros(1))
    noise = simulate_loop(pilot, zero, zero, runs, seed, 1.0, rate_hz)
    p_uf = float(np.mean(forced.u**2))
    p_n1 = float(np.mean(noise.n**2))
    p_un = float(np.mean(noise.u**2))
    if p_n1 <= ratio * p_un:
        raise SignalError(f"a remnant power ratio of {ratio} cannot be reached in this loop")
    return float(np.sqrt(ratio * p_uf / (p_n1 - ratio * p_un)))
