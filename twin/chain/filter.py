"""Platform filter of Eq 5.1: a second-order low-pass 1 / (1 + s / (2 pi f_b))^2."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal

from twin.errors import SignalError
from twin.trajectory import Trajectory

#: Internal rate of the filter [Hz].
OVERSAMPLED_HZ = 1000.0


@dataclass(frozen=True)
class PlatformFilter:
    """The MPI platform filter (Eq 5.1) on every DOF.

    Runs at >= 1 kHz (the trajectory's cubic spline is sampled ten times or more per
    command sample), where the bilinear transform's frequency warping is negligible (at
    100 Hz it would cost 0.3 dB at 7 Hz with f_b = 1 Hz); started in steady state at the first
    sample and sampled back at the trajectory's own times.

    Attributes
    ----------
    break_hz : float
        Break frequency f_b [Hz] (> 0; the MPI default is 1 Hz, §5.5.2).

    Examples
    --------
    >>> f = PlatformFilter(1.0)
    >>> round(20 * float(np.log10(abs(f.frequency_response([1.0])[0, 0]))), 2)  # -6 dB at f_b
    -6.02

    """

    break_hz: float

    def __post_init__(self) -> None:
        """Check the break frequency."""
        if not np.isfinite(self.break_hz) or self.break_hz <= 0:
            raise SignalError(f"filter break frequency must be > 0 Hz; got {self.break_hz}")

    @property
    def name(self) -> str:
        """Short description."""
        return f"platform filter {self.break_hz:g} Hz (Eq 5.1)"

    def frequency_response(self, f: ArrayLike) -> NDArray[np.complex128]:
        """Continuous-time response at frequencies ``f`` [Hz], shape (len(f), 6)."""
        s = 2j * np.pi * np.asarray(f, dtype=float)
        h = 1.0 / (1.0 + s / (2 * np.pi * self.break_hz)) ** 2
        return np.repeat(h[:, None], 6, axis=1)

    def __call__(self, tr: Trajectory) -> Trajectory:
        """Filter every channel of ``tr``."""
        if self.break_hz >= tr.rate_hz / 2:
            raise SignalError(
                f"filter break frequency {self.break_hz:g} Hz must be below the Nyquist "
                f"frequency of the commands ({tr.rate_hz / 2:g} Hz)"
            )
        factor = max(1, int(np.ceil(OVERSAMPLED_HZ / tr.rate_hz)))
        fine = tr.at(tr.t0 + np.arange((tr.n - 1) * factor + 1) / (tr.rate_hz * factor))
        wb = 2 * np.pi * self.break_hz
        b, a = signal.bilinear([1.0], [1 / wb**2, 2 / wb, 1.0], fs=tr.rate_hz * factor)
        zi = signal.lfilter_zi(b, a)[:, None] * tr.values[0]
        y, _ = signal.lfilter(b, a, fine, axis=0, zi=zi)
        return tr.replace(y[::factor])
