"""Uniformly sampled multichannel signals: the currency passed between the chain's blocks.

A :class:`Trajectory` is a uniformly sampled signal of shape ``(n, k)`` with a start time and
a rate, usually the six UGP pose offsets of Eq A.1 (surge, sway, heave [m], roll, pitch,
yaw [rad], thesis base frame). It can be evaluated between its samples with a cubic spline,
which also gives consistent first and second derivatives.

Examples
--------
>>> import numpy as np
>>> tr = Trajectory(rate_hz=100.0, values=np.zeros((201, 6)))
>>> tr.duration, float(tr.t[-1])
(2.0, 2.0)

"""

from __future__ import annotations

import threading
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import CubicSpline

from twin.chain.kernels import cubic_jets
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES

FloatArray = NDArray[np.float64]

#: Samples per spline block and extra samples on each side (see :meth:`Trajectory.at`).
SPLINE_BLOCK, SPLINE_MARGIN = 4096, 48
_SPLINE_LOCK = threading.Lock()


class UniformGrid(ABC):
    """Sample times of a uniformly sampled signal (``n``, ``rate_hz`` and ``t0`` given)."""

    rate_hz: float
    t0: float

    @property
    @abstractmethod
    def n(self) -> int:
        """Number of samples."""

    @property
    def dt(self) -> float:
        """Sample period [s]."""
        return 1.0 / self.rate_hz

    @property
    def t(self) -> FloatArray:
        """Sample times [s]."""
        return self.t0 + np.arange(self.n) / self.rate_hz

    @property
    def duration(self) -> float:
        """Time from the first to the last sample [s]."""
        return (self.n - 1) / self.rate_hz


@dataclass(frozen=True, eq=False)
class Trajectory(UniformGrid):
    """A uniformly sampled signal.

    Attributes
    ----------
    rate_hz : float
        Sample rate [Hz].
    values : ndarray, shape (n, k)
        Samples; for a pose, the offsets from neutral (m, rad).
    t0 : float
        Time of the first sample [s].
    names : tuple of str
        Channel names (``k`` of them); the six DOF names by default.

    """

    rate_hz: float
    values: FloatArray
    t0: float = 0.0
    names: tuple[str, ...] = field(default=DOF_NAMES)

    def __post_init__(self) -> None:
        """Validate rate, shape and finiteness."""
        if not np.isfinite(self.rate_hz) or self.rate_hz <= 0:
            raise SignalError(f"sample rate must be a positive number of Hz; got {self.rate_hz}")
        v = np.asarray(self.values, dtype=float)
        if v.ndim != 2 or v.shape[1] != len(self.names) or v.shape[0] < 2:
            raise SignalError(
                f"values must have shape (n >= 2, {len(self.names)}) for channels "
                f"{', '.join(self.names)}; got {v.shape}"
            )
        bad = ~np.isfinite(v)
        if bad.any():
            row, col = np.argwhere(bad)[0]
            raise SignalError(
                f"{self.names[col]} is not finite at sample {row} (t = "
                f"{self.t0 + row / self.rate_hz:.4f} s); all samples must be finite numbers"
            )
        if not np.isfinite(self.t0):
            raise SignalError(f"t0 must be finite; got {self.t0}")
        object.__setattr__(self, "values", v)

    @property
    def n(self) -> int:
        """Number of samples."""
        return self.values.shape[0]

    def replace(self, values: ArrayLike) -> Trajectory:
        """Return a trajectory on the same time grid with other values."""
        return Trajectory(self.rate_hz, np.asarray(values, dtype=float), self.t0, self.names)

    def block_spline(self, block: int) -> CubicSpline:
        """Return the cubic spline of block ``block`` of samples, with margins (see :meth:`at`)."""
        with _SPLINE_LOCK:  # a trajectory may be read from several threads
            cache = self._splines
            if block not in cache:
                lo = max(0, block * SPLINE_BLOCK - SPLINE_MARGIN)
                hi = min(self.n, (block + 1) * SPLINE_BLOCK + SPLINE_MARGIN + 1)
                t = self.t0 + np.arange(lo, hi) / self.rate_hz
                if len(cache) >= 4:
                    cache.pop(next(iter(cache)))
                cache[block] = CubicSpline(t, self.values[lo:hi], axis=0)
            return cache[block]

    @cached_property
    def _splines(self) -> dict[int, CubicSpline]:
        return {}

    def at(self, t: ArrayLike, derivative: int = 0) -> FloatArray:
        """Evaluate the signal (or a derivative) at arbitrary times.

        The interpolant is the not-a-knot cubic spline through all samples. Long signals are
        splined block by block (:data:`SPLINE_BLOCK` samples with :data:`SPLINE_MARGIN` more
        on each side; a spline's dependence on distant samples decays by 2 - sqrt(3) per
        sample, so this equals the global spline to rounding) and only a few blocks are kept,
        so memory does not grow with the signal's length beyond the samples themselves.
        Times before the first sample hold the first value, times after the last hold the
        last value (derivatives are zero there).

        Parameters
        ----------
        t : array_like, shape (m,)
            Times [s].
        derivative : int
            0, 1 or 2.

        Returns
        -------
        ndarray, shape (m, k)

        """
        if derivative not in (0, 1, 2):
            raise SignalError(f"derivative must be 0, 1 or 2; got {derivative}")
        return self.derivatives(t, derivative)[derivative]

    def derivatives(self, t: ArrayLike, order: int = 2) -> list[FloatArray]:
        """Evaluate the signal and its derivatives up to ``order`` in one pass.

        Parameters
        ----------
        t : array_like, shape (m,)
            Times [s] (held at the ends as in :meth:`at`).
        order : int
            Highest derivative (0, 1 or 2).

        Returns
        -------
        list of ndarray, shape (m, k)
            Value, first derivative, ... up to ``order``.

        """
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        t_end = self.t0 + self.duration
        inside = np.clip(tt, self.t0, t_end)
        # interval index on the uniform grid, and the block holding it
        index = np.minimum(((inside - self.t0) * self.rate_hz).astype(int), self.n - 2)
        blocks = index // SPLINE_BLOCK
        out = [np.empty((tt.size, self.values.shape[1])) for _ in range(3)]
        present = np.unique(blocks)
        for b in present:
            spline = self.block_spline(int(b))
            first = round((spline.x[0] - self.t0) * self.rate_hz)
            if present.size == 1:  # Horner in tau = t - x[i], highest power first
                cubic_jets(spline.c, spline.x, index - first, inside, order, *out)
                continue
            sel = blocks == b
            part = [np.empty((int(sel.sum()), self.values.shape[1])) for _ in range(3)]
            cubic_jets(spline.c, spline.x, index[sel] - first, inside[sel], order, *part)
            for d in range(order + 1):
                out[d][sel] = part[d]
        out = out[: order + 1]
        outside = (tt < self.t0) | (tt > t_end)
        if outside.any():
            for d in out[1:]:
                d[outside] = 0.0
        if np.ndim(t) == 0:
            return [d[0] for d in out]
        return out

    def resample(self, rate_hz: float, t0: float | None = None, n: int | None = None) -> Trajectory:
        """Evaluate on another uniform grid (cubic spline).

        Parameters
        ----------
        rate_hz : float
            New rate [Hz].
        t0 : float, optional
            First sample time; this trajectory's by default.
        n : int, optional
            Number of samples; by default as many as fit in this trajectory's span.

        """
        start = self.t0 if t0 is None else t0
        if n is None:
            n = int(np.floor((self.t0 + self.duration - start) * rate_hz + 1e-9)) + 1
        times = start + np.arange(n) / rate_hz
        return Trajectory(rate_hz, self.at(times), start, self.names)


def uniform_rate(t: ArrayLike, what: str = "time column", tol: float = 0.01) -> float:
    """Return the sample rate of a uniform time grid, or raise naming the first bad row.

    Two checks: every step must be within ``2 tol`` of the typical (median) step (two times
    each ``tol`` off), which names a glitch (a dropped sample, a clock jump) at its row; and
    every time within ``tol`` of a step of the uniform grid through the first and last time,
    which names a clock that drifts by steps each small enough to pass.

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times [s].
    what : str
        Name used in error messages (e.g. a file's path).
    tol : float
        Allowed deviation of any time from the uniform grid, as a fraction of the step (so
        times written with limited decimals still pass); a step may deviate twice as much.

    Raises
    ------
    SignalError
        If fewer than 2 samples, a non-finite or non-increasing time, or non-uniform steps.

    Examples
    --------
    >>> uniform_rate([0.0, 0.01, 0.02, 0.03])
    100.0
    >>> uniform_rate([0.0, 0.01, 0.02, 0.033, 0.043], "t.csv")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    twin.core.errors.SignalError: t.csv: time steps must be uniform: row 4 is at 0.033 s, ...

    """
    tt = np.asarray(t, dtype=float)
    if tt.ndim != 1 or tt.size < 2:
        raise SignalError(f"{what}: needs at least 2 samples")
    # rows are counted from 1, the first sample (in a CSV with a header: line row + 1)
    if not np.all(np.isfinite(tt)):
        row = int(np.argmin(np.isfinite(tt))) + 1
        raise SignalError(f"{what}: time is not finite at row {row}")
    d = np.diff(tt)
    if np.any(d <= 0):
        row = int(np.argmax(d <= 0)) + 2
        raise SignalError(
            f"{what}: time must increase strictly; row {row} ({tt[row - 1]:.6g} s) is not "
            f"after row {row - 1} ({tt[row - 2]:.6g} s)"
        )
    typical = float(np.median(d))
    odd = np.abs(d - typical) > 2 * tol * typical
    if odd.any():
        row = int(np.argmax(odd)) + 2
        raise SignalError(
            f"{what}: time steps must be uniform: row {row} is at {tt[row - 1]:.6g} s, "
            f"{d[row - 2]:.3g} s after row {row - 1} ({tt[row - 2]:.6g} s); the typical step "
            f"is {typical:.6g} s and each must be within {200 * tol:g} % of it"
        )
    step = (tt[-1] - tt[0]) / (tt.size - 1)
    off = np.abs(tt - (tt[0] + np.arange(tt.size) * step)) > tol * step
    if off.any():
        k = int(np.argmax(off))
        raise SignalError(
            f"{what}: time steps must be uniform (mean {step:.6g} s); row {k + 1} is at "
            f"{tt[k]:.6g} s, {tt[k] - tt[0] - k * step:+.3g} s off the grid, more than "
            f"{100 * tol:g} % of a step: the clock drifts"
        )
    return float(1.0 / step)


def interp_columns(x: ArrayLike, xp: ArrayLike, fp: ArrayLike) -> FloatArray:
    """``numpy.interp`` of every column of ``fp`` (shape (len(xp), k)) at ``x``.

    Where every ``x`` is one of the sample times ``xp`` (a platform sampled at the IMU rate, a
    noise generated at it) the samples are taken as they are: ``numpy.interp`` returns the
    sample itself at a sample time, so the result is the same, bit for bit, only faster.

    Examples
    --------
    >>> xp = np.arange(4) / 4.0
    >>> fp = np.column_stack([xp, 2 * xp])
    >>> interp_columns([0.25, 0.5], xp, fp).tolist(), interp_columns([0.125], xp, fp).tolist()
    ([[0.25, 0.5], [0.5, 1.0]], [[0.125, 0.25]])

    """
    xx, grid, values = np.asarray(x, float), np.asarray(xp, float), np.asarray(fp, float)
    if xx.ndim == 1 and grid.ndim == 1 and xx.size and grid.size:
        # a run of consecutive sample times (the IMU reading a platform at its own rate),
        # strictly increasing one past its end: each is the last of its equals, so the same
        # samples as below, without the search per point
        first = max(int(np.searchsorted(grid, xx[0], "right")) - 1, 0)
        window = grid[first : first + xx.size + 1]
        if (window.size >= xx.size and np.array_equal(window[: xx.size], xx)
                and bool(np.all(window[1:] > window[:-1]))):  # fmt: skip
            return values[first : first + xx.size].copy()
        # the last of equal sample times, as numpy.interp takes it
        pos = np.clip(np.searchsorted(grid, xx, "right") - 1, 0, grid.size - 1)
        if np.array_equal(grid[pos], xx):
            return values[pos]
    return np.column_stack([np.interp(xx, grid, values[:, k]) for k in range(values.shape[1])])
