"""The SRS's measured resonance terms H = 1 + T s (Eq 5.12 heave, Eq 5.13 pitch)."""

from __future__ import annotations

from collections.abc import Mapping

from twin.chain.block import Lead
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES
from twin.core.thesis import EQ_5_12_13


class Resonance(Lead):
    """Add ``T * d/dt`` of the signal on the DOFs given (the thesis measured heave and pitch).

    Parameters
    ----------
    time_constants : mapping of str to float, optional
        T [s] per DOF name; DOFs not named pass unchanged. Default: Eq 5.12 and 5.13.

    """

    def __init__(self, time_constants: Mapping[str, float] | None = None) -> None:
        tc = dict(EQ_5_12_13) if time_constants is None else dict(time_constants)
        for dof in tc:
            if dof not in DOF_NAMES:
                raise SignalError(f"resonance: unknown DOF {dof!r}; expected one of {DOF_NAMES}")
        super().__init__(tuple(float(tc.get(d, 0.0)) for d in DOF_NAMES))
        object.__setattr__(self, "named", tc)

    @property
    def name(self) -> str:  # type: ignore[override]
        """Short description."""
        return "resonance " + ", ".join(f"{d} 1+{t:g}s" for d, t in self.named.items())  # type: ignore[attr-defined]
