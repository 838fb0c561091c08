"""The currency between the chain's blocks: sampled jets (value, rate, acceleration).

Every block of the chain is a causal, stateful map from one sampled signal to another at the
command rate. What flows between blocks is a *jet* per sample: the value of each DOF and its
first two time derivatives, array shape ``(runs, n, 6, 3)``. Between two samples the signal is
the quintic Hermite polynomial through the two jets (value, slope and curvature match at both
ends), so it is C^2, causal at the sample level (the interval (t[k-1], t[k]] needs nothing
after sample k) and exact to O(h^6) for smooth signals. Linear blocks are discretised exactly
for that input (:mod:`twin.chain.lti`); a delay evaluates the polynomial between the samples
it falls between (:mod:`twin.chain.delay`); a platform evaluates it at its own rate.

The commands themselves enter as jets of their cubic spline (:meth:`JetSignal.from_trajectory`)
in open loop, or of the simulated aircraft in a closed loop (:mod:`twin.pilot.models.pitch`).

Examples
--------
>>> import numpy as np
>>> from twin.chain.trajectory import Trajectory, UniformGrid
>>> t = np.arange(101) / 100.0
>>> sig = JetSignal.from_trajectory(Trajectory(100.0, np.outer(t**2, np.ones(6))))
>>> sig.jets.shape, round(float(sig.jets[0, 50, 0, 2]), 6)   # d2/dt2 of t^2
((1, 101, 6, 3), 2.0)

"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.chain.kernels import hermite_basis, hermite_gather
from twin.chain.trajectory import Trajectory, UniformGrid
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES

FloatArray = NDArray[np.float64]

#: Derivatives carried per sample: value, first and second derivative.
ORDER = 3


def _hermite_inverse() -> FloatArray:
    """V^-1 mapping (p(0), p'(0), p''(0), p(1), p'(1), p''(1)) to monomial coefficients in s."""
    powers = np.arange(6)
    rows = [
        (powers == 0).astype(float),
        (powers == 1).astype(float),
        2.0 * (powers == 2),
        np.ones(6),
        powers.astype(float),
        powers * (powers - 1.0),
    ]
    return np.linalg.inv(np.array(rows))


#: Quintic Hermite: monomial coefficients (in s = tau / h) from the scaled end jets.
HERMITE = _hermite_inverse()


def scaled(jets: FloatArray, h: float) -> FloatArray:
    """Return jets with the k-th derivative times h^k (the Hermite data in s = tau / h)."""
    return jets * np.array([1.0, h, h * h])


def hermite_coefficients(j0: FloatArray, j1: FloatArray, h: float) -> FloatArray:
    """Monomial coefficients a_0..a_5 (in s = tau / h) of the quintic through two jets.

    Parameters
    ----------
    j0, j1 : ndarray, shape (..., 3)
        Jets at the start and the end of an interval of length ``h``.
    h : float
        Interval length [s].

    Returns
    -------
    ndarray, shape (..., 6)

    """
    data = np.concatenate([scaled(j0, h), scaled(j1, h)], axis=-1)
    return data @ HERMITE.T


#: Falling factorials d!/(d-k)! of the powers s^0..s^5 for derivative orders 0..3.
_FALLING = np.array([[np.prod(np.arange(p - d + 1, p + 1)) if p >= d else 0.0 for p in range(6)]
                     for d in range(4)])  # fmt: skip


def _weights_unscaled(ss: FloatArray, order: int) -> FloatArray:
    """Return the weights of :func:`hermite_weights` before the division by h^d."""
    powers = ss[..., None] ** np.arange(6)
    basis = np.empty((*ss.shape, order + 1, 6))
    hermite_basis(powers.reshape(-1, 6), _FALLING, basis.reshape(-1, order + 1, 6))
    # one (n, 6) @ (6, 6) product: the stacked (3, 6) @ (6, 6) ones give the same bits, slower
    return (basis.reshape(-1, 6) @ HERMITE).reshape(basis.shape)


def hermite_weights(s: ArrayLike, h: float, order: int = 2) -> FloatArray:
    """Weights of the scaled end jets for the quintic's derivatives 0..order at s = tau / h.

    Returns an array of shape ``s.shape + (order + 1, 6)``: derivative ``d`` at ``s`` is
    ``weights[..., d, :] @ data`` with ``data`` the scaled jets of both ends (see
    :func:`scaled`).
    """
    ss = np.asarray(s, dtype=float)
    return _weights_unscaled(ss, order) / (h ** np.arange(order + 1))[:, None]


def hermite_samples(jets: FloatArray, k: NDArray[np.intp], s: FloatArray, h: float) -> FloatArray:
    """Evaluate a sampled signal's quintics, and two derivatives, at many points at once.

    Point ``i`` lies at ``s[i]`` in the interval from sample ``k[i]`` to ``k[i] + 1``. The
    arithmetic is that of :func:`hermite_eval` (the same products and sums, in the same
    order, so the same bits), in one compiled pass over the points
    (:func:`twin.chain.kernels.hermite_gather`): several times faster for the long arrays of a
    platform's own samples.

    Parameters
    ----------
    jets : ndarray, shape (runs, n, c, 3)
        Jets of the signal's samples (interval length ``h``).
    k : ndarray of int, shape (m,)
        Interval of each point (``0 <= k < n - 1``).
    s : float or ndarray, shape (m,)
        Position of each point in its interval, in [0, 1] (one for all points, or one each).
    h : float
        Interval length [s].

    Returns
    -------
    ndarray, shape (3, runs, m, c)
        Value, first and second derivative (a transposed view of a (3, runs, c, m) array).

    """
    jets = np.ascontiguousarray(jets, dtype=float)
    kk = np.ascontiguousarray(k, dtype=np.intp)
    if kk.ndim != 1:
        raise IndexError(f"interval indices must be 1-D; got shape {kk.shape}")
    if kk.size and (kk.min() < 0 or kk.max() >= jets.shape[1] - 1):
        raise IndexError(
            f"interval indices must be in 0..{jets.shape[1] - 2} (from sample k to k + 1 of "
            f"{jets.shape[1]}); got {kk.min()}..{kk.max()}"
        )
    ss = np.asarray(s, float)
    unscaled = _weights_unscaled(ss, 2)  # (m, 3, 6), or (3, 6) for one s at every point
    if ss.ndim == 0:
        unscaled = np.broadcast_to(unscaled, (kk.size, 3, 6))
    out = np.empty((3, jets.shape[0], jets.shape[2], kk.shape[0]))
    hermite_gather(jets, kk, unscaled, h ** np.arange(3), float(h), out)
    return out.transpose(0, 1, 3, 2)  # a view: a channel over time stays contiguous


def hermite_eval(
    j0: FloatArray, j1: FloatArray, s: ArrayLike, h: float, order: int = 2
) -> FloatArray:
    """Evaluate the quintic through two jets, and its derivatives, at s = tau / h in [0, 1].

    Parameters
    ----------
    j0, j1 : ndarray, shape (..., 3)
        Jets at the interval's ends.
    s : float or ndarray
        Position in the interval: a scalar, or one value per element of ``j0.shape[:-1]``'s
        trailing axes (broadcast like ``s[..., None]`` against the jets).
    h : float
        Interval length [s].
    order : int
        Highest derivative returned (2 or 3).

    Returns
    -------
    ndarray, shape (..., order + 1)

    """
    data = np.concatenate([scaled(j0, h), scaled(j1, h)], axis=-1)
    weights = hermite_weights(s, h, order)
    # six broadcast multiply-adds beat a broadcast einsum by about 2x
    return _weighted_sum([data[..., j, None] for j in range(6)],
                         [weights[..., j] for j in range(6)])  # fmt: skip


def _weighted_sum(terms, weights) -> FloatArray:
    """``terms[0] * weights[0] + ... + terms[5] * weights[5]``, summed in that order.

    The one order both Hermite evaluations use, so that they give the same bits.
    """
    out = terms[0] * weights[0]
    for x, w in zip(terms[1:], weights[1:], strict=True):
        out = out + x * w
    return out


def held(first: FloatArray) -> FloatArray:
    """Return the jet of a signal held at ``first``'s value (derivatives zero), same shape."""
    out = np.zeros_like(first)
    out[..., 0] = first[..., 0]
    return out


@dataclass(frozen=True, eq=False)
class JetSignal(UniformGrid):
    """A uniformly sampled signal with its first two derivatives, for one or several runs.

    Attributes
    ----------
    rate_hz : float
        Sample rate [Hz].
    jets : ndarray, shape (runs, n, k, 3)
        Value, first and second derivative of each of the ``k`` channels.
    t0 : float
        Time of the first sample [s].
    names : tuple of str
        Channel names (the six DOFs by default).

    """

    rate_hz: float
    jets: FloatArray
    t0: float = 0.0
    names: tuple[str, ...] = DOF_NAMES

    def __post_init__(self) -> None:
        """Check rate and shape."""
        if not np.isfinite(self.rate_hz) or self.rate_hz <= 0:
            raise SignalError(f"sample rate must be a positive number of Hz; got {self.rate_hz}")
        j = np.asarray(self.jets, dtype=float)
        if j.ndim != 4 or j.shape[2] != len(self.names) or j.shape[3] != ORDER:
            raise SignalError(
                f"jets must have shape (runs, n, {len(self.names)}, {ORDER}); got {j.shape}"
            )
        object.__setattr__(self, "jets", j)

    @classmethod
    def from_trajectory(cls, tr: Trajectory) -> JetSignal:
        """Jets of a trajectory's cubic spline at its samples (one run)."""
        _, rate, acc = tr.derivatives(tr.t, 2)
        return cls(tr.rate_hz, np.stack([tr.values, rate, acc], axis=-1)[None], tr.t0, tr.names)

    @property
    def n(self) -> int:
        """Samples per run."""
        return self.jets.shape[1]

    @property
    def runs(self) -> int:
        """Number of runs."""
        return self.jets.shape[0]

    def replace(self, jets: FloatArray) -> JetSignal:
        """Return the same time grid with other jets."""
        return JetSignal(self.rate_hz, jets, self.t0, self.names)

    def trajectory(self, run: int = 0) -> Trajectory:
        """Return the values of one run as a :class:`~twin.chain.trajectory.Trajectory`."""
        return Trajectory(self.rate_hz, self.jets[run, :, :, 0], self.t0, self.names)

    def at(self, t: ArrayLike, run: int = 0) -> FloatArray:
        """Value, rate and acceleration at times ``t`` (held outside), shape (len(t), k, 3)."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        x = np.clip((tt - self.t0) * self.rate_hz, 0.0, self.n - 1.0)
        i = np.minimum(np.floor(x).astype(int), self.n - 2)
        j = self.jets[run]
        out = hermite_eval(j[i], j[i + 1], (x - i)[:, None], 1.0 / self.rate_hz)
        outside = (tt < self.t0) | (tt > self.t0 + self.duration)
        out[outside, :, 1:] = 0.0
        return out
