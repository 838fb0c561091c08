"""Motion noise of the MPI platform (Eq 5.10): shaped white noise in heave acceleration.

The thesis applies H_n,z = 0.084 (1 + 0.022 s) / ((1 + 0.009 s)(1 + 0.008 s)) to zero-mean,
unit-variance Gaussian white noise; sampled at the IMU rate (819.2 Hz) that gives
sigma = 4.23e-2 m/s^2 (§5.4.4). For the SRS the noise was generated in the frequency domain
with the spectrum set to zero below 1 Hz "to prevent extreme excursions" (§5.4.4); this block
does the same, which also makes the double integral to a heave *position* offset bounded, so
the noise can be fed to a platform as a command. A platform cannot be given white
acceleration down to 0 Hz as a position, so the position needs ``highpass_hz > 0``.

Examples
--------
>>> n = MotionNoise(highpass_hz=None)
>>> a = n.generate(600.0, seed=1).acceleration
>>> bool(abs(a.std() / 0.0423 - 1) < 0.05)
True

"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.errors import SignalError
from twin.thesis import EQ_5_10

FloatArray = NDArray[np.float64]


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

    """

    rate_hz: float = 819.2
    highpass_hz: float | None = 1.0

    def __post_init__(self) -> None:
        """Check rate and high-pass."""
        if not np.isfinite(self.rate_hz) or self.rate_hz <= 0:
            raise SignalError(f"noise rate must be > 0 Hz; got {self.rate_hz}")
        if self.highpass_hz is not None and not 0 < self.highpass_hz < self.rate_hz / 2:
            raise SignalError(
                f"noise high-pass must be None or between 0 and {self.rate_hz / 2:g} Hz; "
                f"got {self.highpass_hz}"
            )

    @property
    def name(self) -> str:
        """Short description."""
        hp = "" if self.highpass_hz is None else f", none below {self.highpass_hz:g} Hz"
        return f"heave noise Eq 5.10 at {self.rate_hz:g} Hz{hp}"

    def generate(
        self, duration_s: float, seed: int | np.random.Generator | None = 0
    ) -> NoiseRealisation:
        """Generate ``duration_s`` seconds of noise.

        The white sequence is drawn in the time domain (so a seed gives the same sequence
        whatever is done with it) and shaped in the frequency domain with the exact response
        of Eq 5.10; the result is periodic over its length.

        Parameters
        ----------
        duration_s : float
            Length [s] (> 0).
        seed : int or numpy.random.Generator or None
            Seed or generator for the white noise.

        """
        if not np.isfinite(duration_s) or duration_s <= 0:
            raise SignalError(f"noise duration must be > 0 s; got {duration_s}")
        n = int(np.ceil(duration_s * self.rate_hz)) + 1
        rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        white = rng.standard_normal(n)
        f = np.fft.rfftfreq(n, 1.0 / self.rate_hz)
        spec = np.fft.rfft(white) * shaping_response(f)
        if self.highpass_hz is None:
            return NoiseRealisation(self.rate_hz, np.fft.irfft(spec, n), None, None)
        spec[f < self.highpass_hz] = 0.0
        jw = 2j * np.pi * f
        jw[0] = 1.0  # bin 0 is zero already
        return NoiseRealisation(
            self.rate_hz,
            np.fft.irfft(spec, n),
            np.fft.irfft(spec / jw, n),
            np.fft.irfft(spec / jw**2, n),
        )
