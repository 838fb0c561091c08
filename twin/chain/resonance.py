"""The SRS's measured resonance terms H = 1 + T s (Eq 5.12 heave, Eq 5.13 pitch)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.errors import SignalError
from twin.frames import DOF_NAMES
from twin.thesis import EQ_5_12_13
from twin.trajectory import Trajectory


@dataclass(frozen=True)
class Resonance:
    """Add ``T * d/dt`` of the signal on the DOFs given (the thesis measured heave and pitch).

    Attributes
    ----------
    time_constants : mapping of str to float
        T [s] per DOF name; DOFs not named pass unchanged. Default: Eq 5.12 and 5.13.

    """

    time_constants: Mapping[str, float] = field(default_factory=lambda: dict(EQ_5_12_13))

    def __post_init__(self) -> None:
        """Check DOF names and time constants."""
        for dof, tc in self.time_constants.items():
            if dof not in DOF_NAMES:
                raise SignalError(f"resonance: unknown DOF {dof!r}; expected one of {DOF_NAMES}")
            if not np.isfinite(tc) or tc < 0:
                raise SignalError(f"resonance: time constant for {dof} must be >= 0 s; got {tc}")

    @property
    def _t(self) -> NDArray[np.float64]:
        return np.array([self.time_constants.get(d, 0.0) for d in DOF_NAMES])

    @property
    def name(self) -> str:
        """Short description."""
        return "resonance " + ", ".join(f"{d} 1+{t:g}s" for d, t in self.time_constants.items())

    def frequency_response(self, f: ArrayLike) -> NDArray[np.complex128]:
        """Response at frequencies ``f`` [Hz], shape (len(f), 6)."""
        s = 2j * np.pi * np.asarray(f, dtype=float)
        return 1.0 + np.outer(s, self._t)

    def __call__(self, tr: Trajectory) -> Trajectory:
        """Apply the resonance terms (derivative from the trajectory's cubic spline)."""
        return tr.replace(tr.values + tr.at(tr.t, 1) * self._t)
