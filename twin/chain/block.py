"""The shape every block of the chain has: a causal stream with its state, and its whole form.

A block maps jets to jets at the command rate (:mod:`twin.chain.jets`). Its one
implementation is the stream: ``state = block.start(first, rate_hz)`` from the first sample's
jets, then ``out, state = block.stream(jets, state)`` for any number of consecutive samples
(one at a time in a closed loop, thousands at a time in open loop: the same arithmetic). The
whole-trajectory form, ``block(signal)``, is that stream run over the whole array. Linear
blocks also give their continuous frequency response (the reduced model, Eq 5.11).

Besides the base class this module holds the small blocks: :class:`Gain`, :class:`Lead`
(1 + T s: the SRS terms of Eq 5.12/5.13 and the ``lead`` extension) and :class:`Backlash`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.chain.jets import JetSignal, hermite_eval
from twin.chain.trajectory import Trajectory
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES, dof_index

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


class Block(ABC):
    """Base of the chain's blocks (see the module docstring)."""

    name = "block"

    def start(self, first: FloatArray, rate_hz: float) -> Any:
        """Return the state before the first sample, from its jets ``(runs, 6, 3)``."""
        return None

    @abstractmethod
    def stream(self, jets: FloatArray, state: Any) -> tuple[FloatArray, Any]:
        """Map consecutive samples' jets ``(runs, n, 6, 3)``; return the output and the state."""

    @overload
    def __call__(self, sig: JetSignal) -> JetSignal: ...
    @overload
    def __call__(self, sig: Trajectory) -> Trajectory: ...

    def __call__(self, sig: JetSignal | Trajectory) -> JetSignal | Trajectory:
        """Run the stream over every sample of ``sig`` (the whole-trajectory form).

        A :class:`~twin.chain.trajectory.Trajectory` goes in as the jets of its cubic spline and
        comes out as the output's values.
        """
        if isinstance(sig, Trajectory):
            return self(JetSignal.from_trajectory(sig)).trajectory()
        out, _ = self.stream(sig.jets, self.start(sig.jets[:, 0], sig.rate_hz))
        return sig.replace(out)

    def response_at_hz(self, f: ArrayLike) -> ComplexArray:
        """Continuous response at ``f`` [Hz], shape (len(f), 6) (linear blocks only).

        In Hz, as the name says: python-control's ``frequency_response`` takes rad/s (the
        block's :meth:`transfer_function` is the python-control system).
        """
        raise SignalError(f"{self.name} is not linear; it has no frequency response")

    def transfer_function(self, dof: int) -> Any:
        """Return the DOF's response as a python-control transfer function (rational blocks)."""
        raise SignalError(
            f"{self.name} is not a rational linear block; it has no transfer function"
        )


def dof_mask(dofs: tuple[str, ...] | None) -> NDArray[np.bool_]:
    """Mask over the six DOFs for a tuple of names (all six for None or empty)."""
    mask = np.zeros(len(DOF_NAMES), dtype=bool)
    if not dofs:
        mask[:] = True
    for d in dofs or ():
        mask[dof_index(d)] = True
    return mask


@dataclass(frozen=True)
class Gain(Block):
    """Multiply some DOFs by ``gain`` (stateless)."""

    gain: float
    mask: tuple[bool, ...] = (True,) * 6

    @property
    def name(self) -> str:  # type: ignore[override]
        """Short description."""
        return f"gain {self.gain:g}"

    def stream(self, jets: FloatArray, state: Any) -> tuple[FloatArray, Any]:
        """Scale the masked DOFs."""
        out = jets.copy()
        out[:, :, np.array(self.mask)] *= self.gain
        return out, state

    def response_at_hz(self, f: ArrayLike) -> ComplexArray:
        """``gain`` on the masked DOFs."""
        h = np.ones((np.size(f), 6), dtype=complex)
        h[:, np.array(self.mask)] = self.gain
        return h

    def transfer_function(self, dof: int) -> Any:
        """``gain`` (or 1) as a python-control transfer function."""
        import control

        return control.tf([self.gain if self.mask[dof] else 1.0], [1.0])


@dataclass(frozen=True)
class Lead(Block):
    """H = 1 + T s per DOF (T = 0: unchanged): Eq 5.12/5.13's form.

    The derivative of the input's acceleration, needed for the output's acceleration, is the
    third derivative of the interval's quintic (:func:`twin.chain.jets.hermite_eval`) at its
    end: causal, from the current and the previous sample.

    Attributes
    ----------
    time_constants : tuple of float, length 6
        T per DOF [s] (>= 0).

    """

    time_constants: tuple[float, ...]

    def __post_init__(self) -> None:
        """Check the time constants."""
        t = np.asarray(self.time_constants, dtype=float)
        if t.shape != (6,) or not np.all(np.isfinite(t)) or np.any(t < 0):
            raise SignalError(f"lead time constants must be six numbers >= 0 s; got {t}")

    @property
    def name(self) -> str:  # type: ignore[override]
        """Short description."""
        return "lead 1+Ts, T = " + "/".join(f"{x:g}" for x in self.time_constants) + " s"

    def start(self, first: FloatArray, rate_hz: float) -> Any:
        """State: the previous sample's jets (none yet) and the step."""
        return (None, 1.0 / rate_hz)

    def stream(self, jets: FloatArray, state: Any) -> tuple[FloatArray, Any]:
        """Y = u + T u', y' = u' + T u'', y'' = u'' + T u'''."""
        prev, h = state
        T = np.asarray(self.time_constants)
        before = np.concatenate([jets[:, :1] if prev is None else prev[:, None], jets[:, :-1]], 1)
        jerk = hermite_eval(before, jets, 1.0, h, order=3)[..., 3]
        if prev is None:
            jerk[:, 0] = 0.0
        out = jets.copy()
        out[..., 0] += T * jets[..., 1]
        out[..., 1] += T * jets[..., 2]
        out[..., 2] += T * jerk
        return out, (jets[:, -1].copy(), h)

    def response_at_hz(self, f: ArrayLike) -> ComplexArray:
        """1 + T s per DOF."""
        s = 2j * np.pi * np.asarray(f, dtype=float)
        return 1.0 + np.outer(s, self.time_constants)

    def transfer_function(self, dof: int) -> Any:
        """1 + T s as a python-control transfer function."""
        import control

        t = float(self.time_constants[dof])
        return control.tf([t, 1.0], [1.0]) if t else control.tf([1.0], [1.0])


def backlash(x: ArrayLike, play: float) -> FloatArray:
    """Dead-band (play) operator on samples: the output moves only when the input pushes it.

    The output stays put while the input travels inside a band of width ``play`` around it
    and follows the input at the band's edge otherwise; it starts centred on the input.

    Examples
    --------
    >>> backlash([0.0, 1.0, 2.0, 1.5, 0.0], 1.0).tolist()
    [0.0, 0.5, 1.5, 1.5, 0.5]

    """
    xx = np.asarray(x, dtype=float)
    jets = np.zeros((1, xx.size, 6, 3))
    jets[0, :, 0, 0] = xx
    out, _ = Backlash(float(play), (True,) + (False,) * 5).stream(jets, None)
    return out[0, :, 0, 0]


@dataclass(frozen=True)
class Backlash(Block):
    """Play of width ``play`` [m or rad] on some DOFs, sample by sample.

    While the input pushes the output at an edge of the band the output follows it (value
    and derivatives); inside the band the output rests (derivatives zero).
    """

    play: float
    mask: tuple[bool, ...] = (True,) * 6

    @property
    def name(self) -> str:  # type: ignore[override]
        """Short description."""
        return f"backlash {self.play:g}"

    def stream(self, jets: FloatArray, state: Any) -> tuple[FloatArray, Any]:
        """Run the dead band over the samples (the state is the output position)."""
        cols = np.flatnonzero(self.mask)
        out = jets.copy()
        x = jets[:, :, cols, 0]
        y = x[:, 0].copy() if state is None else state.copy()
        half = 0.5 * self.play
        moving = np.zeros(x.shape, dtype=bool)
        ys = np.empty(x.shape)
        for r in range(x.shape[0]):  # y = clamp(y, x - half, x + half), on Python floats
            for c in range(x.shape[2]):
                v, col = float(y[r, c]), ys[r, :, c]
                for i, xi in enumerate(x[r, :, c].tolist()):
                    if xi - v > half:
                        v = xi - half
                        moving[r, i, c] = True
                    elif v - xi > half:
                        v = xi + half
                        moving[r, i, c] = True
                    col[i] = v
                y[r, c] = v
        out[:, :, cols, 0] = ys
        rest = out[:, :, cols, 1:]
        rest[~moving] = 0.0
        out[:, :, cols, 1:] = rest
        return out, y
