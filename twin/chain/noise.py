"""Motion noise of the MPI platform (Eq 5.10): shaped white noise in heave acceleration.

The thesis applies H_n,z = 0.084 (1 + 0.022 s) / ((1 + 0.009 s)(1 + 0.008 s)) to zero-mean,
unit-variance Gaussian white noise; sampled at the IMU rate (819.2 Hz) that gives
sigma = 4.23e-2 m/s^2 (§5.4.4). For the SRS the noise had no content below 1 Hz "to prevent
extreme excursions" (§5.4.4, done there in the frequency domain); here a 4th-order
Butterworth high-pass at ``highpass_hz`` does the same in the time domain, which also makes
the double integral to a heave *position* offset bounded, so the noise can be fed to a
platform as a command. A platform cannot be given white acceleration down to 0 Hz as a
position, so the position needs ``highpass_hz > 0``.

The noise is generated as a stream (:class:`NoiseStream`): seeded white noise filtered by the
bilinear transforms of the acceleration, velocity and position transfer functions, with the
filter state carried, so a run of any length holds only its current chunk. The stream starts
in steady state (the filters run over a discarded lead-in first), and the same seed gives the
same samples however the stream is cut into chunks.

Examples
--------
>>> n = MotionNoise(highpass_hz=None)
>>> a = n.generate(600.0, seed=1).acceleration
>>> bool(abs(a.std() / 0.0423 - 1) < 0.05)
True

"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal

from twin.chain.trajectory import interp_columns
from twin.core.errors import SignalError
from twin.core.thesis import EQ_5_10

FloatArray = NDArray[np.float64]

#: Order of the high-pass that removes the noise below ``highpass_hz``.
HIGHPASS_ORDER = 4
#: Samples generated at a time by :meth:`NoiseStream.at` (the same samples however they are cut).
GENERATE_BLOCK = 4096
#: Noise generated and discarded before the first sample, so the stream starts stationary [s].
LEAD_IN_S = 1.0


def shaping_response(f: ArrayLike) -> NDArray[np.complex128]:
    """Return Eq 5.10 at frequencies ``f`` [Hz]."""
    s = 2j * np.pi * np.asarray(f, dtype=float)
    p1, p2 = EQ_5_10["poles_s"]
    return EQ_5_10["gain"] * (1 + EQ_5_10["zero_s"] * s) / ((1 + p1 * s) * (1 + p2 * s))


@dataclass(frozen=True)
class NoiseRealisation:
    """One realisation of the heave noise, uniformly sampled.

    Attributes
    ----------
    rate_hz : float
        Sample rate [Hz].
    acceleration, velocity, position : ndarray, shape (n,)
        Heave noise [m/s^2, m/s, m] (thesis z down). ``velocity`` and ``position`` are None
        without a high-pass (they would not be bounded).

    """

    rate_hz: float
    acceleration: FloatArray
    velocity: FloatArray | None
    position: FloatArray | None

    @property
    def t(self) -> FloatArray:
        """Sample times [s] from 0."""
        return np.arange(self.acceleration.size) / self.rate_hz


@dataclass(frozen=True)
class MotionNoise:
    """The Eq 5.10 heave-noise generator.

    Attributes
    ----------
    rate_hz : float
        Rate of the unit-variance white noise (the IMU rate, 819.2 Hz, by default).
    highpass_hz : float or None
        Spectrum set to zero below this frequency (1 Hz as on the SRS); None keeps it all
        (acceleration only).
    scale : float
        Factor on the noise amplitude (1: Eq 5.10 as identified).

    """

    rate_hz: float = 819.2
    highpass_hz: float | None = 1.0
    scale: float = 1.0

    def __post_init__(self) -> None:
        """Check rate and high-pass."""
        if not np.isfinite(self.rate_hz) or self.rate_hz <= 0:
            raise SignalError(f"noise rate must be > 0 Hz; got {self.rate_hz}")
        if self.highpass_hz is not None and not 0 < self.highpass_hz < self.rate_hz / 2:
            raise SignalError(
                f"noise high-pass must be None or between 0 and {self.rate_hz / 2:g} Hz; "
                f"got {self.highpass_hz}"
            )
        if not np.isfinite(self.scale) or self.scale < 0:
            raise SignalError(f"noise scale must be >= 0; got {self.scale}")

    @property
    def name(self) -> str:
        """Short description."""
        hp = "" if self.highpass_hz is None else f", none below {self.highpass_hz:g} Hz"
        return f"heave noise Eq 5.10 at {self.rate_hz:g} Hz{hp}"

    def sections(self) -> list[FloatArray]:
        """Second-order sections of the acceleration, velocity and position filters.

        Velocity and position are returned only with a high-pass (otherwise unbounded).
        Designed once per noise (the same sections for every run of a study).
        """
        return [sos.copy() for sos in _sections(self)]

    def stream(self, seed: int | np.random.SeedSequence | np.random.Generator = 0) -> NoiseStream:
        """Return a fresh stream of this noise (see :class:`NoiseStream`)."""
        return NoiseStream(self, seed)

    def generate(
        self, duration_s: float, seed: int | np.random.SeedSequence | np.random.Generator = 0
    ) -> NoiseRealisation:
        """Generate ``duration_s`` seconds of noise at once (the first samples of :meth:`stream`).

        Parameters
        ----------
        duration_s : float
            Length [s] (> 0).
        seed : int, SeedSequence or Generator
            Seed or generator for the white noise.

        """
        if not np.isfinite(duration_s) or duration_s <= 0:
            raise SignalError(f"noise duration must be > 0 s; got {duration_s}")
        n = int(np.ceil(duration_s * self.rate_hz)) + 1
        return self.stream(seed).take(n)


@cache
def _sections(noise: MotionNoise) -> tuple[FloatArray, ...]:
    """Return the sections of :meth:`MotionNoise.sections`, designed once per noise."""
    p1, p2 = EQ_5_10["poles_s"]
    zeros = [-1.0 / EQ_5_10["zero_s"]]
    poles = [-1.0 / p1, -1.0 / p2]
    gain = noise.scale * EQ_5_10["gain"] * EQ_5_10["zero_s"] / (p1 * p2)
    if noise.highpass_hz is None:
        outputs = [(np.array(zeros), 0)]
    else:
        hz, hp, hk = signal.butter(HIGHPASS_ORDER, 2 * np.pi * noise.highpass_hz, "highpass",
                                   analog=True, output="zpk")  # fmt: skip
        poles += list(hp)
        gain *= hk
        # acceleration, velocity (1/s cancels one zero at 0), position (two zeros)
        outputs = [(np.concatenate([zeros, hz[: len(hz) - k]]), k) for k in range(3)]
    out = []
    for z, _ in outputs:
        zd, pd, kd = signal.bilinear_zpk(z, np.array(poles), gain, noise.rate_hz)
        out.append(signal.zpk2sos(zd, pd, kd))
    return tuple(out)


class NoiseStream:
    """Consecutive samples of one noise realisation, generated on demand.

    Parameters
    ----------
    noise : MotionNoise
        The generator.
    seed : int, SeedSequence or Generator
        Seed of the white noise.

    """

    def __init__(
        self, noise: MotionNoise, seed: int | np.random.SeedSequence | np.random.Generator = 0
    ) -> None:
        self.noise = noise
        self._rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        self._sos = noise.sections()
        self._state = [np.zeros((sos.shape[0], 2)) for sos in self._sos]
        lead_in = LEAD_IN_S if noise.highpass_hz is None else LEAD_IN_S + 5.0 / noise.highpass_hz
        self._filter(int(np.ceil(lead_in * noise.rate_hz)))  # start in steady state
        self._offset = 0  # index of the next sample
        self._buffer = np.empty((0, len(self._sos)))  # samples from _buffer_start on
        self._buffer_start = 0

    def _filter(self, n: int) -> FloatArray:
        white = self._rng.standard_normal(n)
        columns = []
        for k, sos in enumerate(self._sos):
            y, self._state[k] = signal.sosfilt(sos, white, zi=self._state[k])
            columns.append(y)
        return np.column_stack(columns)

    def take(self, n: int) -> NoiseRealisation:
        """Return the next ``n`` samples as a realisation (its ``t`` starts at 0)."""
        values = self._filter(n)
        self._offset += n
        cols = [values[:, k] for k in range(values.shape[1])] + [None, None]
        return NoiseRealisation(self.noise.rate_hz, cols[0], cols[1], cols[2])

    def at(self, t: FloatArray) -> FloatArray:
        """Acceleration, velocity and position at times ``t`` [s from the stream's start].

        Samples are generated as far as needed and linearly interpolated; times must not go
        back before the previous call's last time. Returns shape ``(len(t), 3)`` (velocity and
        position columns are zero without a high-pass).
        """
        fs = self.noise.rate_hz
        need = int(np.ceil(float(t[-1]) * fs - 1e-9)) + 1
        have = self._buffer_start + self._buffer.shape[0]
        if need > have:  # whole blocks ahead: a stream stepped 10 ms at a time stays cheap
            more = max(need - have, GENERATE_BLOCK)
            self._buffer = np.vstack([self._buffer, self._filter(more)])
        ts = (self._buffer_start + np.arange(self._buffer.shape[0])) / fs
        out = np.zeros((t.size, 3))
        out[:, : self._buffer.shape[1]] = interp_columns(t, ts, self._buffer)
        drop = max(0, int(np.floor(float(t[-1]) * fs)) - self._buffer_start)
        self._buffer = self._buffer[drop:]
        self._buffer_start += drop
        return out
