"""Compiled loops for the chain's per-sample arithmetic: the same bits as the NumPy they replace.

A reduced run spends its time in short NumPy expressions over long arrays (a quintic's six
products per point, the IMU's lever arm, the legs' lengths): each expression a pass through
memory, the arithmetic itself a few nanoseconds per sample. The kernels here do the same
products and sums in one pass per sample, with numba.

**Same bits.** Each kernel evaluates its NumPy original's expression element by element, with
the same operands, in the same order, and numba compiles without ``fastmath``: LLVM then
neither reassociates nor fuses a multiply and an add (an FMA rounds once where NumPy rounds
twice), so every result is the IEEE double NumPy gives (``tests/test_kernels.py`` compares
them on random data, ``tests/test_stored_figures.py`` whole seeded runs; only a NaN's sign
bit, which IEEE leaves open, may differ). What is *not* moved here: transcendental functions
(NumPy's SIMD ``sin``, ``cos`` and ``pow`` need not match the C library's in the last bit),
matrix products (BLAS), NumPy's pairwise sums and an ``einsum`` over a contiguous axis (its
order follows the CPU's SIMD lanes; one over a strided axis, as ``"nji,nj->ni"``, sums in
order from zero and is replaced).

Compiled on first use, a few seconds once per machine, and cached beside this file
(``__pycache__``; numba falls back to its user-wide cache where that is not writable, and to
compiling in each process where no cache can be kept). ``nogil``: the full platform's physics
thread runs meanwhile.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


class _Kernel:
    """A numba kernel compiled on its first call.

    numba (and LLVM: about 0.2 s and 100 MB, more with the kernels loaded) loads then, not with
    ``twin``: a command that runs no chain does not pay for it. Pickled by name (a Dask task
    may hold one), as a function is.
    """

    def __init__(self, func: Callable[..., Any]) -> None:
        functools.update_wrapper(self, func)
        self._compiled: Callable[..., Any] | None = None
        self._lock = threading.Lock()

    def __reduce__(self) -> str:
        """Pickle as the module-level name it is bound to."""
        return self.__qualname__

    def __call__(self, *args: Any) -> Any:
        """Run the compiled kernel (compiling, or loading it from the cache, the first time)."""
        compiled = self._compiled
        if compiled is None:
            with self._lock:
                if self._compiled is None:
                    self._compiled = _compile(self.__wrapped__)  # type: ignore[attr-defined]
                compiled = self._compiled
        return compiled(*args)


def _compile(func: Callable[..., Any]) -> Callable[..., Any]:
    """Compile ``func`` with numba, cached on disk where a cache can be kept."""
    import numba

    try:
        return numba.njit(cache=True, nogil=True, error_model="numpy")(func)
    except RuntimeError:  # numba finds no writable cache directory: compile in each process
        return numba.njit(nogil=True, error_model="numpy")(func)


_jit = _Kernel


@_jit
def hermite_gather(
    jets: FloatArray, k: NDArray[np.intp], unscaled: FloatArray, divisor: FloatArray,
    h: float, out: FloatArray,
) -> None:  # fmt: skip
    """Quintic values and two derivatives at many points of a sampled signal, into ``out``.

    The arithmetic of :func:`twin.chain.jets.hermite_samples`: the end jets scaled by
    ``(1, h, h * h)``, the weights divided by ``divisor[d]``, and the six products summed
    in the order start value, rate, acceleration, end value, rate, acceleration.

    Parameters
    ----------
    jets : ndarray, shape (runs, n, c, 3)
        Jets of the samples (unscaled).
    k : ndarray of int, shape (m,)
        Interval of each point: from sample ``k[i]`` to ``k[i] + 1``.
    unscaled : ndarray, shape (m, 3, 6)
        :func:`twin.chain.jets._weights_unscaled` of the points' positions.
    divisor : ndarray, shape (3,)
        ``h ** arange(3)``.
    h : float
        Interval length [s].
    out : ndarray, shape (3, runs, c, m)
        Value, first and second derivative.

    """
    hh = h * h
    m = k.shape[0]
    w = np.empty((m, 3, 6))
    for i in range(m):
        for d in range(3):
            for j in range(6):
                w[i, d, j] = unscaled[i, d, j] / divisor[d]
    for r in range(jets.shape[0]):
        for ch in range(jets.shape[2]):
            for i in range(m):
                a, b = k[i], k[i] + 1
                x0, x1, x2 = jets[r, a, ch, 0], jets[r, a, ch, 1] * h, jets[r, a, ch, 2] * hh
                x3, x4, x5 = jets[r, b, ch, 0], jets[r, b, ch, 1] * h, jets[r, b, ch, 2] * hh
                for d in range(3):
                    acc = x0 * w[i, d, 0]
                    acc = acc + x1 * w[i, d, 1]
                    acc = acc + x2 * w[i, d, 2]
                    acc = acc + x3 * w[i, d, 3]
                    acc = acc + x4 * w[i, d, 4]
                    acc = acc + x5 * w[i, d, 5]
                    out[d, r, ch, i] = acc


@_jit
def hermite_basis(powers: FloatArray, falling: FloatArray, out: FloatArray) -> None:
    """Monomial derivatives ``out[i, d, p] = falling[d, p] * powers[i, p - d]`` (0 for p < d).

    The basis of :func:`twin.chain.jets._weights_unscaled` before its product with the
    Hermite matrix; ``out`` has shape (m, order + 1, 6).
    """
    for i in range(out.shape[0]):
        for d in range(out.shape[1]):
            for p in range(6):
                out[i, d, p] = falling[d, p] * powers[i, p - d] if p >= d else 0.0


@_jit
def rigid_cabin(
    pose: FloatArray, rate: FloatArray, acc: FloatArray, trig: FloatArray,
    cabin: FloatArray, base: FloatArray, neutral: FloatArray,
    rotation: FloatArray, omega: FloatArray, omega_dot: FloatArray, lengths: FloatArray,
) -> None:  # fmt: skip
    """Compute a rigid cabin's attitude, angular motion and leg lengths along a pose path.

    The arithmetic of :func:`twin.core.frames.rotation_matrix` (T, Eq A.2),
    :func:`twin.core.frames.angular_motion` turned into cabin axes as
    ``einsum("nji,nj->ni", T, omega_b)`` (omega and omega_dot, Eq A.4),
    and the lengths of :func:`twin.platform.kinematics.leg_rates`, per sample.

    Parameters
    ----------
    pose, rate, acc : ndarray, shape (n, 6)
        Pose offsets and their first and second derivatives.
    trig : ndarray, shape (6, n)
        cos and sin of roll, pitch and yaw: ``cf, sf, ct, st, cp, sp`` (NumPy's).
    cabin, base : ndarray, shape (6, 3)
        Gimbal positions in the cabin and the base frame.
    neutral : ndarray, shape (3,)
        The UGP at neutral.
    rotation : ndarray, shape (n, 3, 3)
        Out: T_c^b.
    omega, omega_dot : ndarray, shape (n, 3)
        Out: angular velocity and acceleration, cabin axes.
    lengths : ndarray, shape (n, 6)
        Out: leg lengths.

    """
    tb = np.empty(3)
    tdb = np.empty(3)
    for q in range(pose.shape[0]):
        cf, sf, ct, st, cp, sp = (trig[0, q], trig[1, q], trig[2, q],
                                  trig[3, q], trig[4, q], trig[5, q])  # fmt: skip
        T = rotation[q]
        T[0, 0] = ct * cp
        T[0, 1] = sf * st * cp - cf * sp
        T[0, 2] = cf * st * cp + sf * sp
        T[1, 0] = ct * sp
        T[1, 1] = sf * st * sp + cf * cp
        T[1, 2] = cf * st * sp - sf * cp
        T[2, 0] = -st
        T[2, 1] = sf * ct
        T[2, 2] = cf * ct
        fd, td, pd = rate[q, 3], rate[q, 4], rate[q, 5]
        fdd, tdd, pdd = acc[q, 3], acc[q, 4], acc[q, 5]
        ctcp, ctsp = ct * cp, ct * sp
        tb[0] = ctcp * fd - sp * td
        tb[1] = ctsp * fd + cp * td
        tb[2] = pd - st * fd
        tdb[0] = ctcp * fdd - sp * tdd - (st * cp * td + ctsp * pd) * fd - cp * pd * td
        tdb[1] = ctsp * fdd + cp * tdd + (ctcp * pd - st * sp * td) * fd - sp * pd * td
        tdb[2] = pdd - st * fdd - ct * td * fd
        for i in range(3):  # einsum("nji,nj->ni"): 0 + T0i w0 + T1i w1 + T2i w2
            w = 0.0
            wd = 0.0
            for j in range(3):
                w = w + T[j, i] * tb[j]
                wd = wd + T[j, i] * tdb[j]
            omega[q, i] = w
            omega_dot[q, i] = wd
        for leg in range(6):
            s = 0.0
            for i in range(3):
                ab = 0.0
                for j in range(3):
                    ab = ab + T[i, j] * cabin[leg, j]
                L = ((neutral[i] + pose[q, i]) + ab) - base[leg, i]
                s = s + L * L if i else L * L
            lengths[q, leg] = np.sqrt(s)


@_jit
def limit_suspects(
    velocity: FloatArray, acceleration: FloatArray, omega: FloatArray, omega_dot: FloatArray,
    lengths: FloatArray, radius: float, max_velocity: float, max_acceleration: float,
    leg_min: FloatArray, leg_max: FloatArray, out: NDArray[np.bool_],
) -> None:  # fmt: skip
    """Flag the samples whose bounds on the legs' rates may break a limit, or out of stroke.

    The bounds of :meth:`twin.chain.reduced.ReducedPlatform._check_limits`, per sample:
    |l_dot| <= |c_dot| + |omega| r, |l_ddot| <= |c_ddot| + (|omega_dot| + |omega|^2) r +
    (|c_dot| + |omega| r)^2 / l_min; ``max_velocity`` and ``max_acceleration`` are the
    thresholds the bounds are compared with.
    """

    def norm(v: FloatArray) -> float:  # sqrt(v0^2 + v1^2 + v2^2), summed in that order
        return np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])

    for q in range(lengths.shape[0]):
        w = norm(omega[q])
        v_bound = norm(velocity[q]) + w * radius
        lmin = lengths[q, 0]
        stroke = False
        for leg in range(6):
            x = lengths[q, leg]
            lmin = min(lmin, x)
            stroke = stroke or x < leg_min[leg] or x > leg_max[leg]
        a_bound = (norm(acceleration[q]) + (norm(omega_dot[q]) + w * w) * radius
                   + v_bound * v_bound / lmin)  # fmt: skip
        out[q] = v_bound > max_velocity or a_bound > max_acceleration or stroke


@_jit
def specific_force(
    rotation: FloatArray, acceleration: FloatArray, omega: FloatArray, omega_dot: FloatArray,
    mount: FloatArray, gravity: FloatArray, out: FloatArray,
) -> None:  # fmt: skip
    """Specific force at a cabin point and the angular rate: ``out[:, :3]`` and ``out[:, 3:]``.

    The arithmetic of :func:`twin.chain.imu.specific_force` written with NumPy: the ``einsum``
    T^T (a - g) (summed from zero in the order of the axes), then ``+ omega_dot x r`` and
    ``+ omega x (omega x r)``.
    """
    r0, r1, r2 = mount[0], mount[1], mount[2]
    for q in range(out.shape[0]):
        a0 = acceleration[q, 0] - gravity[0]
        a1 = acceleration[q, 1] - gravity[1]
        a2 = acceleration[q, 2] - gravity[2]
        w0, w1, w2 = omega[q, 0], omega[q, 1], omega[q, 2]
        d0, d1, d2 = omega_dot[q, 0], omega_dot[q, 1], omega_dot[q, 2]
        c0, c1, c2 = w1 * r2 - w2 * r1, w2 * r0 - w0 * r2, w0 * r1 - w1 * r0  # omega x r
        e0, e1, e2 = d1 * r2 - d2 * r1, d2 * r0 - d0 * r2, d0 * r1 - d1 * r0  # omega_dot x r
        g0, g1, g2 = w1 * c2 - w2 * c1, w2 * c0 - w0 * c2, w0 * c1 - w1 * c0  # omega x (..)
        T = rotation[q]
        out[q, 0] = ((((0.0 + T[0, 0] * a0) + T[1, 0] * a1) + T[2, 0] * a2) + e0) + g0
        out[q, 1] = ((((0.0 + T[0, 1] * a0) + T[1, 1] * a1) + T[2, 1] * a2) + e1) + g1
        out[q, 2] = ((((0.0 + T[0, 2] * a0) + T[1, 2] * a1) + T[2, 2] * a2) + e2) + g2
        out[q, 3], out[q, 4], out[q, 5] = w0, w1, w2


@_jit
def sensor_errors(
    values: FloatArray, bias: FloatArray, noise: FloatArray, sd: FloatArray, limit: FloatArray
) -> int:
    """Add bias and scaled white noise, saturate at +-limit; return the samples that hit it.

    In place, per channel ``c``: ``(v + bias[c]) + noise * sd[c]``, then clipped like
    ``numpy.clip`` (a NaN stays NaN); a sample counts once however many channels hit.
    """
    hits = 0
    for q in range(values.shape[0]):
        hit = False
        for c in range(values.shape[1]):
            v = (values[q, c] + bias[c]) + noise[q, c] * sd[c]
            if abs(v) > limit[c]:
                hit = True
            if v < -limit[c]:
                v = -limit[c]
            elif v > limit[c]:
                v = limit[c]
            values[q, c] = v
        hits += hit
    return hits


@_jit
def cubic_jets(
    c: FloatArray, x: FloatArray, index: NDArray[np.intp], t: FloatArray, order: int,
    out0: FloatArray, out1: FloatArray, out2: FloatArray,
) -> None:  # fmt: skip
    """Evaluate a piecewise cubic and its derivatives up to ``order`` at times ``t``.

    The arithmetic of :meth:`twin.chain.trajectory.Trajectory.derivatives` (Horner in
    ``tau = t - x[index]``): ``((c3 tau + c2) tau + c1) tau + c0``,
    ``(3 c3 tau + 2 c2) tau + c1`` and ``6 c3 tau + 2 c2``.

    Parameters
    ----------
    c : ndarray, shape (4, segments, k)
        Coefficients, highest power first (:class:`scipy.interpolate.CubicSpline`'s ``c``).
    x : ndarray, shape (segments + 1,)
        Breakpoints.
    index : ndarray of int, shape (m,)
        Segment of each time.
    t : ndarray, shape (m,)
        Times.
    order : int
        Highest derivative written (0, 1 or 2); the other outputs are left as they are.
    out0, out1, out2 : ndarray, shape (m, k)
        Value, first and second derivative.

    """
    for q in range(t.shape[0]):
        i = index[q]
        tau = t[q] - x[i]
        for col in range(c.shape[2]):
            c3, c2, c1, c0 = c[0, i, col], c[1, i, col], c[2, i, col], c[3, i, col]
            out0[q, col] = ((c3 * tau + c2) * tau + c1) * tau + c0
            if order >= 1:
                out1[q, col] = (3 * c3 * tau + 2 * c2) * tau + c1
            if order >= 2:
                out2[q, col] = 6 * c3 * tau + 2 * c2


@_jit
def limit_legs(
    x: FloatArray, xd: FloatArray, broken: NDArray[np.bool_], length: FloatArray,
    velocity: FloatArray, active: bool, dt: float, max_acceleration: float,
    max_velocity: float, leg_min: FloatArray, leg_max: FloatArray, y: FloatArray,
    yd: FloatArray,
) -> bool:  # fmt: skip
    """Limit leg references sample by sample (:meth:`twin.chain.limits.ActuatorLimits._limit`).

    Per sample, from a violation until the reference is rejoined (all legs within 1e-7 m and
    a * dt in velocity), the NumPy of the loop it replaces, leg by leg:
    ``e = x - pos``, ``v = xd + sign(e) * minimum(|e| / dt, sqrt(2 a |e|))``, clipped to the
    previous velocity +- a dt (array bounds) and to +- v_max (scalar bounds), the new length
    ``clip(pos + v dt)`` to the stroke and ``v = (new - pos) / dt``. The clips keep NumPy's
    two conventions for a tie of signed zeros (bounds given as arrays: the bound; as scalars:
    the value) and its NaN propagation, so the bits are NumPy's.

    Parameters
    ----------
    x, xd : ndarray, shape (n, legs)
        Reference lengths [m] and velocities [m/s].
    broken : ndarray of bool, shape (n,)
        Samples with a violation (where an inactive limiter starts).
    length, velocity : ndarray, shape (legs,)
        The limited reference at the sample before the chunk.
    active : bool
        Whether the limiter is off the reference at the chunk's start.
    dt : float
        Sample interval [s].
    max_acceleration, max_velocity : float
        The legs' limits [m/s^2, m/s].
    leg_min, leg_max : ndarray, shape (legs,)
        Stroke ends [m].
    y, yd : ndarray, shape (n, legs)
        Copies of ``x`` and ``xd``: the limited references are written into them.

    Returns
    -------
    bool
        Whether the limiter is still off the reference after the chunk.

    """

    def bound_max(v: float, b: float) -> float:  # numpy.clip's lower bound given as an array
        return v if v != v else (v if v > b else b)

    def bound_min(v: float, b: float) -> float:  # ... its upper bound given as an array
        return v if v != v else (v if v < b else b)

    def scalar_clip(v: float, lo: float, hi: float) -> float:  # numpy.clip, scalar bounds
        if v != v or lo != lo or hi != hi:
            return v + lo + hi  # NaN
        w = lo if v < lo else v
        return hi if w > hi else w

    legs = x.shape[1]
    pos, vel = length.copy(), velocity.copy()
    step = max_acceleration * dt
    for k in range(x.shape[0]):
        if not active:
            if not broken[k]:
                continue
            if k > 0:
                for j in range(legs):
                    pos[j], vel[j] = y[k - 1, j], yd[k - 1, j]
            active = True
        rejoined = True
        for j in range(legs):
            e = x[k, j] - pos[j]
            ae = abs(e)
            by_rate, by_braking = ae / dt, np.sqrt(2 * max_acceleration * ae)
            if by_rate != by_rate:
                smaller = by_rate
            elif by_braking != by_braking:
                smaller = by_braking
            else:
                smaller = by_rate if by_rate < by_braking else by_braking
            sign = 1.0 if e > 0 else (-1.0 if e < 0 else (0.0 if e == 0 else e))
            v = xd[k, j] + sign * smaller
            v = bound_min(bound_max(v, vel[j] - step), vel[j] + step)
            v = scalar_clip(v, -max_velocity, max_velocity)
            new = bound_min(bound_max(pos[j] + v * dt, leg_min[j]), leg_max[j])
            v = (new - pos[j]) / dt
            y[k, j], yd[k, j] = new, v
            pos[j], vel[j] = new, v
            if not (abs(x[k, j] - new) < 1e-7 and abs(xd[k, j] - v) <= step):
                rejoined = False
        if rejoined:
            active = False
    return active
