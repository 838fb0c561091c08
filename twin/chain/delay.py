"""Pure time delay e^{-tau s} (Eq 5.11), one delay per DOF or one for all, streamed.

A delay of m + f samples (m whole, 0 <= f < 1) takes each output jet from the quintic between
the input jets m + 1 and m samples back (:mod:`twin.chain.jets`), at 1 - f of that interval:
causal for any delay >= 0, exact for whole samples, and for a trajectory's jets the same as
evaluating its cubic spline at t - tau. Before the first sample the first value is held.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.chain.block import Block, ComplexArray
from twin.chain.bounds import MAX_DELAY_S
from twin.chain.jets import held, hermite_samples
from twin.core.errors import SignalError

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Delay(Block):
    """Delay every DOF by ``seconds`` (scalar or six values, each >= 0).

    Examples
    --------
    >>> from twin.chain.jets import JetSignal
    >>> from twin.chain.trajectory import Trajectory
    >>> tr = Trajectory(100.0, np.outer(np.arange(10.0), np.ones(6)))
    >>> Delay(0.02)(JetSignal.from_trajectory(tr)).jets[0, :4, 0, 0].tolist()
    [0.0, 0.0, 0.0, 1.0]

    """

    seconds: float | tuple[float, ...]

    def __post_init__(self) -> None:
        """Check the delays."""
        d = np.broadcast_to(np.asarray(self.seconds, dtype=float), (6,))
        if not np.all(np.isfinite(d)) or np.any(d < 0) or np.any(d > MAX_DELAY_S):
            raise SignalError(f"delay must be in [0, {MAX_DELAY_S:g}] s; got {self.seconds}")

    @property
    def per_dof(self) -> NDArray[np.float64]:
        """The six delays [s]."""
        return np.broadcast_to(np.asarray(self.seconds, dtype=float), (6,)).copy()

    @property
    def name(self) -> str:  # type: ignore[override]
        """Short description."""
        d = self.per_dof
        if np.all(d == d[0]):
            return f"delay {d[0] * 1e3:.1f} ms"
        return "delay " + "/".join(f"{x * 1e3:.1f}" for x in d) + " ms"

    def response_at_hz(self, f: ArrayLike) -> ComplexArray:
        """Response at frequencies ``f`` [Hz], shape (len(f), 6)."""
        w = 2 * np.pi * np.asarray(f, dtype=float)
        return np.exp(-1j * np.outer(w, self.per_dof))

    def start(self, first: FloatArray, rate_hz: float) -> Any:
        """State: the last ``m + 1`` input jets (the first one held before the start)."""
        shift = self.per_dof * rate_hz
        whole = np.floor(shift + 1e-9)
        frac = np.where(shift - whole < 1e-9, 0.0, shift - whole)
        depth = int(whole.max()) + 1
        history = np.repeat(held(first)[:, None], depth, axis=1)
        return (whole.astype(int), frac, 1.0 / rate_hz, history)

    def stream(self, jets: FloatArray, state: Any) -> tuple[FloatArray, Any]:
        """Delay consecutive samples."""
        whole, frac, h, history = state
        depth = history.shape[1]
        ext = np.concatenate([history, jets], axis=1)
        n = jets.shape[1]
        out = np.empty_like(jets)
        idx = depth + np.arange(n)
        for (m, f), cols in _groups(whole, frac).items():
            if f == 0.0:
                out[:, :, cols] = ext[:, idx - m][:, :, cols]
            else:  # the quintic from m + 1 to m samples back (hermite_eval's arithmetic)
                at = hermite_samples(ext[:, :, cols], idx - m - 1, 1.0 - f, h)
                out[:, :, cols] = np.moveaxis(at, 0, -1)
        return out, (whole, frac, h, ext[:, -depth:].copy())


def _groups(whole: NDArray[np.intp], frac: FloatArray) -> dict[tuple[int, float], list[int]]:
    """DOFs sharing one delay, keyed by (whole samples, fraction)."""
    out: dict[tuple[int, float], list[int]] = {}
    for k, (m, f) in enumerate(zip(whole, frac, strict=True)):
        out.setdefault((int(m), float(f)), []).append(k)
    return out
