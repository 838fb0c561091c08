"""Linear blocks, discretised exactly for the chain's inter-sample signal.

A continuous SISO transfer function num(s)/den(s) (proper) per DOF, driven by the quintic
Hermite input between samples (:mod:`twin.chain.jets`). Over one sample step h the state
obeys, exactly,

    x[k] = Phi x[k-1] + G0 J[k-1] + G1 J[k],   Phi = e^{A h},

with G0, G1 from the integrals int_0^h e^{A (h - tau)} B (tau / h)^m dtau (m = 0..5), each one
matrix exponential of an augmented system (Van Loan). The output jet follows from the state
and the input jet: y = C x + D u, y' = C A x + C B u + D u', y'' = C A^2 x + C A B u + C B u'
+ D u''. No oversampling, no bilinear warping; the recursion runs through
:func:`scipy.signal.lfilter` along time, so a chunk of one sample and a chunk of a million
cost the same per sample, and start in steady state at the first sample.

Examples
--------
>>> import numpy as np
>>> from twin.chain.jets import JetSignal
>>> from twin.chain.trajectory import Trajectory
>>> ramp = Trajectory(100.0, np.outer(np.arange(300.0) * 0.01, np.ones(6)))
>>> lag = LtiBlock(((1.0,), (0.1, 1.0)))           # 1 / (1 + 0.1 s) on every DOF
>>> y = lag(JetSignal.from_trajectory(ramp)).jets   # a ramp lags by 0.1 s
>>> round(float(ramp.values[-1, 0] - y[0, -1, 0, 0]), 6)
0.1

"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import linalg, signal

from twin.chain.block import Block, ComplexArray
from twin.chain.jets import HERMITE, scaled
from twin.core.errors import SignalError

FloatArray = NDArray[np.float64]
#: One DOF's system: (numerator, denominator) in s, highest power first; None passes.
System = tuple[tuple[float, ...], tuple[float, ...]] | None


@dataclass(frozen=True, eq=False)
class Discrete:
    """A system discretised for the quintic-Hermite input at one step (see module docstring)."""

    phi: FloatArray  # (nx, nx)
    g0: FloatArray  # (nx, 3): from the previous sample's jet
    g1: FloatArray  # (nx, 3): from this sample's jet
    cy: FloatArray  # (3, nx): state to the output jet
    dy: FloatArray  # (3, 3): input jet to the output jet
    steady: FloatArray  # (nx,): state per unit constant input
    lfilters: tuple[tuple[FloatArray, FloatArray], ...]  # (I - Phi z^-1)^-1, row-major


@lru_cache(maxsize=256)
def discretise(num: tuple[float, ...], den: tuple[float, ...], h: float) -> Discrete:
    """Discretise num(s)/den(s) for the chain's inter-sample input at step ``h`` (cached)."""
    a, b, c, d = signal.tf2ss(num, den)
    nx = a.shape[0]
    b = b[:, 0]
    c = c[0]
    d = float(d[0, 0])
    phi = linalg.expm(a * h)
    # int_0^h e^{A(h - tau)} B tau^m / m! dtau via an augmented system with w_k = tau^k / k!
    gam = np.empty((nx, 6))
    shift = np.diag(np.ones(5), -1)  # dw_k / dtau = w_{k-1}
    for m in range(6):
        f = np.zeros((nx + 6, nx + 6))
        f[:nx, :nx] = a
        f[:nx, nx + m] = b
        f[nx:, nx:] = shift
        e = linalg.expm(f * h)
        gam[:, m] = e[:nx, nx] * float(np.prod(np.arange(1, m + 1))) / h**m  # (tau/h)^m
    g = gam @ HERMITE  # state forcing per scaled end-jet component
    g0, g1 = g[:, :3], g[:, 3:]
    cy = np.array([c, c @ a, c @ a @ a])
    cb, cab = float(c @ b), float(c @ a @ b)
    dy = np.array([[d, 0.0, 0.0], [cb, d, 0.0], [cab, cb, d]])
    steady = -np.linalg.solve(a, b)
    filters = []
    for j in range(nx):
        for i in range(nx):
            e_i = np.zeros((nx, 1))
            e_i[i] = 1.0
            nz, dz = signal.ss2tf(phi, e_i, np.eye(nx)[j : j + 1], np.zeros((1, 1)))
            filters.append((nz[0][1:], dz))  # times z: x[k] = Phi x[k-1] + f[k]
    return Discrete(phi, g0, g1, cy, dy, steady, tuple(filters))


@dataclass(frozen=True)
class LtiBlock(Block):
    """A continuous linear filter per DOF, streamed exactly (see module docstring).

    Attributes
    ----------
    systems : tuple
        One (num, den) pair in s for every DOF, or a single pair for all six; None: that
        DOF passes unchanged. Each must be proper (len(num) <= len(den)), stable.
    label : str
        Name in reports.

    """

    systems: tuple[System, ...] | tuple[tuple[float, ...], tuple[float, ...]]
    label: str = "linear filter"

    def __post_init__(self) -> None:
        """Normalise to six entries and check them."""
        sys = self.systems
        if len(sys) == 2 and sys[0] is not None and np.ndim(sys[0][0]) == 0:
            sys = (sys,) * 6  # one (num, den) for all DOFs
        if len(sys) != 6:
            raise SignalError(f"need one system per DOF (6); got {len(sys)}")
        norm = []
        for s in sys:
            if s is None:
                norm.append(None)
                continue
            num = tuple(float(x) for x in np.atleast_1d(s[0]))
            den = tuple(float(x) for x in np.atleast_1d(s[1]))
            if len(num) > len(den) or len(den) < 2 or den[0] == 0:
                raise SignalError(f"{self.label}: num {num} / den {den} must be proper, order >= 1")
            if not np.all(np.isfinite(num + den)):
                raise SignalError(f"{self.label}: coefficients must be finite; got {num}, {den}")
            if np.any(np.roots(den).real >= 0):
                raise SignalError(
                    f"{self.label}: den {den} must be stable (poles in the left half)"
                )
            norm.append((num, den))
        object.__setattr__(self, "systems", tuple(norm))

    @property
    def name(self) -> str:  # type: ignore[override]
        """Short description."""
        return self.label

    def groups(self) -> list[tuple[System, NDArray[np.intp]]]:
        """DOFs sharing one system (None excluded)."""
        out: dict[System, list[int]] = {}
        for k, s in enumerate(self.systems):
            if s is not None:
                out.setdefault(s, []).append(k)  # type: ignore[arg-type]
        return [(s, np.array(cols)) for s, cols in out.items()]

    def start(self, first: FloatArray, rate_hz: float) -> Any:
        """State: per group, the state vectors (steady state at the first input) and last jet."""
        h = 1.0 / rate_hz
        self._check_rate(rate_hz)
        state = []
        for sys, cols in self.groups():
            dis = discretise(*sys, h)  # type: ignore[misc]
            x = first[:, cols, 0][..., None] * dis.steady  # (runs, k, nx)
            state.append((x, None))
        return (h, state)

    def _check_rate(self, rate_hz: float) -> None:
        for sys, _ in self.groups():
            poles = np.abs(np.roots(sys[1]))  # type: ignore[index]
            if poles.max() / (2 * np.pi) >= rate_hz / 2:
                raise SignalError(
                    f"{self.label}: a pole at {poles.max() / (2 * np.pi):g} Hz must be below the "
                    f"Nyquist frequency of the commands ({rate_hz / 2:g} Hz)"
                )

    def stream(self, jets: FloatArray, state: Any) -> tuple[FloatArray, Any]:
        """Filter consecutive samples (see the module docstring for the recursion)."""
        h, groups = state
        out = jets.copy()
        new = []
        for (sys, cols), (x_prev, j_prev) in zip(self.groups(), groups, strict=True):
            dis = discretise(*sys, h)  # type: ignore[misc]
            u = scaled(jets[:, :, cols], h)  # (runs, n, k, 3)
            if j_prev is None:  # first sample: the steady state itself
                f = np.einsum("xd,rnkd->rnkx", dis.g1, u[:, 1:])
                f = f + np.einsum("xd,rnkd->rnkx", dis.g0, u[:, :-1])
                first = x_prev[:, None]
            else:
                before = np.concatenate([scaled(j_prev, h)[:, None], u[:, :-1]], axis=1)
                f = np.einsum("xd,rnkd->rnkx", dis.g1, u)
                f = f + np.einsum("xd,rnkd->rnkx", dis.g0, before)
                first = None
            if f.shape[1]:
                f[:, 0] += np.einsum("yx,rkx->rky", dis.phi, x_prev)
                nx = dis.phi.shape[0]
                x = np.zeros_like(f)
                for idx, (b, a) in enumerate(dis.lfilters):
                    j, i = divmod(idx, nx)
                    x[..., j] += signal.lfilter(b, a, f[..., i], axis=1)
                states = x if first is None else np.concatenate([first, x], axis=1)
            else:
                states = first
            y = np.einsum("dx,rnkx->rnkd", dis.cy, states)
            y += np.einsum("de,rnke->rnkd", dis.dy, jets[:, :, cols])
            out[:, :, cols] = y
            new.append((states[:, -1].copy(), jets[:, -1, cols].copy()))
        return out, (h, new)

    def response_at_hz(self, f: ArrayLike) -> ComplexArray:
        """num(s) / den(s) per DOF at ``f`` [Hz], shape (len(f), 6)."""
        s = 2j * np.pi * np.asarray(f, dtype=float)
        h = np.ones((s.size, 6), dtype=complex)
        for sys, cols in self.groups():
            h[:, cols] = (np.polyval(sys[0], s) / np.polyval(sys[1], s))[:, None]  # type: ignore[index]
        return h

    def transfer_function(self, dof: int) -> Any:
        """Return the DOF's system as a python-control transfer function (1 if it passes)."""
        import control

        sys = self.systems[dof]
        if sys is None:
            return control.tf([1.0], [1.0])
        return control.tf(list(sys[0]), list(sys[1]))  # type: ignore[index]


@dataclass(frozen=True)
class LinearModel:
    """One DOF of a configuration's linear chain: a rational part and a pure delay.

    ``rational`` is a python-control transfer function (the product of the blocks' own,
    :meth:`twin.chain.block.Block.transfer_function`), so everything python-control does with
    an LTI system (Bode, margins, poles, step response, ``c2d``) applies; the delay
    e^{-s T} is kept exact beside it (python-control has none; a Pade approximation is one
    call away: ``control.pade(delay_s, n)``).

    Examples
    --------
    >>> from twin.chain.config import motion_system
    >>> m = motion_system("mpi").transfer_function(4)      # pitch: 1 Hz filter, 35 ms
    >>> m.rational.poles().real.round(3).tolist(), round(m.delay_s, 3)
    ([-6.283, -6.283], 0.035)
    >>> round(abs(complex(m.response_at_hz([1.0])[0])), 3)   # -6 dB at the break
    0.5

    """

    rational: Any
    delay_s: float

    def response_at_hz(self, f: ArrayLike) -> NDArray[np.complex128]:
        """Return the response at ``f`` [Hz] (python-control's evaluation times the delay).

        ``rational(2j * pi * f) * exp(-2j * pi * f * delay_s)``: python-control evaluates
        :attr:`rational` at rad/s (``frequency_response(omega)``, ``rational(1j * omega)``).
        """
        s = 2j * np.pi * np.asarray(f, dtype=float)
        return np.asarray(self.rational(s), dtype=complex).reshape(s.shape) * np.exp(
            -s * self.delay_s
        )
