"""Pure time delay e^{-tau s} (Eq 5.11), one delay per DOF or one for all."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.errors import SignalError
from twin.trajectory import Trajectory


@dataclass(frozen=True)
class Delay:
    """Delay every DOF by ``seconds`` (scalar or six values, each >= 0).

    Samples between the command samples are taken from the trajectory's cubic spline, so any
    delay is exact for signals well below the command Nyquist frequency; before the first
    sample the first value is held.

    Examples
    --------
    >>> from twin.trajectory import Trajectory
    >>> tr = Trajectory(100.0, np.outer(np.arange(10.0), np.ones(6)))
    >>> Delay(0.02)(tr).values[:4, 0].tolist()
    [0.0, 0.0, 0.0, 1.0]

    """

    seconds: float | tuple[float, ...]

    def __post_init__(self) -> None:
        """Check the delays."""
        d = np.broadcast_to(np.asarray(self.seconds, dtype=float), (6,))
        if not np.all(np.isfinite(d)) or np.any(d < 0):
            raise SignalError(f"delay must be finite and >= 0 s; got {self.seconds}")

    @property
    def per_dof(self) -> NDArray[np.float64]:
        """The six delays [s]."""
        return np.broadcast_to(np.asarray(self.seconds, dtype=float), (6,)).copy()

    @property
    def name(self) -> str:
        """Short description."""
        d = self.per_dof
        if np.all(d == d[0]):
            return f"delay {d[0] * 1e3:.1f} ms"
        return "delay " + "/".join(f"{x * 1e3:.1f}" for x in d) + " ms"

    def frequency_response(self, f: ArrayLike) -> NDArray[np.complex128]:
        """Response at frequencies ``f`` [Hz], shape (len(f), 6)."""
        w = 2 * np.pi * np.asarray(f, dtype=float)
        return np.exp(-1j * np.outer(w, self.per_dof))

    def __call__(self, tr: Trajectory) -> Trajectory:
        """Delay ``tr``."""
        d = self.per_dof
        out = np.empty_like(tr.values)
        t = tr.t
        for k in range(tr.values.shape[1]):
            shift = d[k] * tr.rate_hz
            if shift == round(shift):  # whole samples: an exact shift
                s = round(shift)
                out[:s, k] = tr.values[0, k]
                out[s:, k] = tr.values[: tr.n - s, k]
            else:
                out[:, k] = tr.at(t - d[k])[:, k]
        return tr.replace(out)
