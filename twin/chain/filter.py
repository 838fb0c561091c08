"""Platform filter of Eq 5.1: a second-order low-pass 1 / (1 + s / (2 pi f_b))^2 per DOF."""

from __future__ import annotations

import numpy as np

from twin.chain.bounds import MAX_BREAK_HZ, MIN_BREAK_HZ
from twin.chain.lti import LtiBlock, System
from twin.core.errors import SignalError


def check_break_hz(value: float, where: str, error: type[Exception] = SignalError) -> float:
    """Return ``value`` if it is 0 (no filter) or a break frequency in the allowed range."""
    if not (value == 0 or MIN_BREAK_HZ <= value <= MAX_BREAK_HZ):
        raise error(f"{where} must be 0 (no filter) or in [{MIN_BREAK_HZ:g}, {MAX_BREAK_HZ:g}] "
                    f"Hz; got {value!r}")  # fmt: skip
    return value


def eq_5_1(break_hz: float) -> System:
    """Return the Eq 5.1 filter with break frequency ``break_hz`` as (num, den) in s."""
    if not np.isfinite(break_hz) or not MIN_BREAK_HZ <= break_hz <= MAX_BREAK_HZ:
        raise SignalError(
            f"filter break frequency must be in [{MIN_BREAK_HZ:g}, {MAX_BREAK_HZ:g}] Hz; "
            f"got {break_hz}"
        )
    wb = 2 * np.pi * break_hz
    return ((1.0,), (1 / wb**2, 2 / wb, 1.0))


class PlatformFilter(LtiBlock):
    """The MPI platform filter (Eq 5.1), one break frequency per DOF (None: unfiltered).

    Streamed exactly for the chain's inter-sample signal (:mod:`twin.chain.lti`): no
    frequency warping (a bilinear filter at 100 Hz would cost 0.3 dB at 7 Hz with f_b = 1 Hz),
    started in steady state at the first sample.

    Parameters
    ----------
    break_hz : float or sequence of (float or None)
        Break frequency f_b [Hz] (> 0; the MPI default is 1 Hz, §5.5.2), or six of them.

    Examples
    --------
    >>> f = PlatformFilter(1.0)
    >>> round(20 * float(np.log10(abs(f.response_at_hz([1.0])[0, 0]))), 2)  # -6 dB at f_b
    -6.02

    """

    def __init__(self, break_hz: float | tuple[float | None, ...]) -> None:
        breaks = tuple(break_hz) if np.ndim(break_hz) else (break_hz,) * 6  # type: ignore[arg-type]
        if len(breaks) != 6:
            raise SignalError(f"need one or six break frequencies; got {len(breaks)}")
        systems = tuple(None if b is None else eq_5_1(float(b)) for b in breaks)
        label = "platform filter " + (
            f"{breaks[0]:g} Hz" if len(set(breaks)) == 1 and breaks[0] is not None
            else "/".join("-" if b is None else f"{b:g}" for b in breaks) + " Hz"
        )  # fmt: skip
        object.__setattr__(self, "breaks_hz", breaks)
        super().__init__(systems, f"{label} (Eq 5.1)")

    @property
    def break_hz(self) -> float | None:
        """The break frequency when every DOF has the same one (else None)."""
        b = set(self.breaks_hz)  # type: ignore[attr-defined]
        return b.pop() if len(b) == 1 else None
