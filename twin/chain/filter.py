"""Platform filter of Eq 5.1: a second-order low-pass 1 / (1 + s / (2 pi f_b))^2."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.chain.spline_filter import filter_spline
from twin.errors import SignalError
from twin.trajectory import Trajectory


@dataclass(frozen=True)
class PlatformFilter:
    """The MPI platform filter (Eq 5.1) on every DOF.

    Applied to the trajectory's cubic spline exactly (:func:`twin.chain.spline_filter.
    filter_spline`) at the command rate: no frequency warping (a bilinear filter at 100 Hz
    would cost 0.3 dB at 7 Hz with f_b = 1 Hz), started in steady state at the first sample.

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
        wb = 2 * np.pi * self.break_hz
        return tr.replace(filter_spline(tr, [1.0], [1 / wb**2, 2 / wb, 1.0]))


@dataclass(frozen=True)
class PerDofFilter:
    """The Eq 5.1 filter with its own break frequency per DOF (None: that DOF unfiltered).

    Attributes
    ----------
    breaks_hz : tuple of (float or None), length 6
        Break frequency per DOF [Hz].

    """

    breaks_hz: tuple[float | None, ...]

    def __post_init__(self) -> None:
        """Check the break frequencies."""
        if len(self.breaks_hz) != 6:
            raise SignalError(f"need six break frequencies; got {len(self.breaks_hz)}")
        for b in self.breaks_hz:
            if b is not None:
                PlatformFilter(b)

    @property
    def name(self) -> str:
        """Short description."""
        return (
            "platform filter "
            + "/".join("-" if b is None else f"{b:g}" for b in self.breaks_hz)
            + " Hz"
        )

    def frequency_response(self, f: ArrayLike) -> NDArray[np.complex128]:
        """Continuous-time response at frequencies ``f`` [Hz], shape (len(f), 6)."""
        h = np.ones((np.size(f), 6), dtype=complex)
        for k, b in enumerate(self.breaks_hz):
            if b is not None:
                h[:, k] = PlatformFilter(b).frequency_response(f)[:, k]
        return h

    def __call__(self, tr: Trajectory) -> Trajectory:
        """Filter each DOF with its own break frequency."""
        out = tr.values.copy()
        for b in {b for b in self.breaks_hz if b is not None}:
            cols = [k for k, bk in enumerate(self.breaks_hz) if bk == b]
            out[:, cols] = PlatformFilter(b)(tr).values[:, cols]
        return tr.replace(out)
