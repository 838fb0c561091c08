"""Motion profiles of test schedules: faded sines and piecewise-constant-jerk motions.

Motion computers drive their test moves from a few profile types; the SIMONA Research
Simulator's schedules (:mod:`twin.formats.schedule`) name four, and the AGARD-AR-144 turn-around
bump and system-limit tests are built from the same shapes:

- faded sines (:func:`faded_sines`): a sum of sines under a raised-cosine fade-in and
  fade-out (the fade of Eq 3.1, lasting ``t_fade`` at each end);
- constant acceleration (:func:`constant_acceleration`): from one speed to another at a
  constant acceleration, the acceleration reached and left by jerk ramps;
- constant speed (:func:`constant_speed`);
- point to point (:func:`point_to_point`): the classic seven-phase jerk-limited move of a
  given distance within a velocity, an acceleration and a jerk limit (a trapezoidal velocity
  profile with jerk-limited corners).

The last three are :class:`JerkProfile` s: motion whose jerk is constant between breakpoints,
evaluated exactly (position a cubic, acceleration piecewise linear), so that an acceleration
step or a reversal lands where the profile puts it, whatever the sample rate.

Examples
--------
>>> p = point_to_point(0.5, 0.4, 4.0, 100.0)
>>> round(p.duration, 3)
1.39
>>> s, v, a, j = p.at([p.duration])
>>> round(float(s[0]), 6), abs(float(v[0])) < 1e-12
(0.5, True)

"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from twin.core.errors import SignalError

FloatArray = NDArray[np.float64]

#: Relative tolerance within which a profile's given end speed must follow from its other
#: parameters (a constant-acceleration profile's ramps are solved from it).
END_SPEED_RTOL = 1e-3


@dataclass(frozen=True, eq=False)
class JerkProfile:
    """A motion whose jerk is constant between breakpoints (one axis, from s = 0).

    Attributes
    ----------
    durations : ndarray, shape (k,)
        Duration of each phase [s] (>= 0).
    jerks : ndarray, shape (k,)
        Jerk of each phase [units/s^3].
    v0, a0 : float
        Speed and acceleration at the start.

    """

    durations: FloatArray
    jerks: FloatArray
    v0: float = 0.0
    a0: float = 0.0

    def __post_init__(self) -> None:
        """Check the phases and precompute the state at each breakpoint."""
        d = np.asarray(self.durations, dtype=float)
        j = np.asarray(self.jerks, dtype=float)
        if d.ndim != 1 or d.shape != j.shape or (d < 0).any() or not np.isfinite([*d, *j]).all():
            raise SignalError("a jerk profile needs as many finite jerks as durations (>= 0)")
        object.__setattr__(self, "durations", d)
        object.__setattr__(self, "jerks", j)
        s, v, a = [0.0], [float(self.v0)], [float(self.a0)]
        for dt, jk in zip(d, j, strict=True):
            s.append(s[-1] + v[-1] * dt + a[-1] * dt**2 / 2 + jk * dt**3 / 6)
            v.append(v[-1] + a[-1] * dt + jk * dt**2 / 2)
            a.append(a[-1] + jk * dt)
        object.__setattr__(self, "_starts", np.concatenate([[0.0], np.cumsum(d)]))
        object.__setattr__(self, "_state", np.array([s, v, a]))

    @property
    def duration(self) -> float:
        """Length of the profile [s]."""
        return float(self._starts[-1])

    @property
    def end(self) -> tuple[float, float, float]:
        """Position, speed and acceleration at the end."""
        s, v, a = self._state[:, -1]
        return float(s), float(v), float(a)

    def at(self, t: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Return position, speed, acceleration and jerk at times ``t`` [s] from the start.

        Outside the profile the motion goes on at constant speed (the start speed before it,
        the end speed after it): a move from rest to rest holds its start and its end.
        """
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        tc = np.clip(tt, 0.0, self.duration)
        k = np.clip(np.searchsorted(self._starts, tc, side="right") - 1, 0, None)
        k = np.minimum(k, max(len(self.jerks) - 1, 0))
        jerk = self.jerks[k] if len(self.jerks) else np.zeros(tt.shape)
        dt = tc - self._starts[k]
        s0, v0, a0 = self._state[:, k]
        s = s0 + v0 * dt + a0 * dt**2 / 2 + jerk * dt**3 / 6
        v = v0 + a0 * dt + jerk * dt**2 / 2
        a = a0 + jerk * dt
        outside = tt != tc
        s = s + v * (tt - tc)
        a, jerk = np.where(outside, 0.0, a), np.where(outside, 0.0, jerk)
        return s, v, a, jerk


def constant_speed(v0: float, duration_s: float) -> JerkProfile:
    """Return a motion at constant speed ``v0`` for ``duration_s`` seconds."""
    _check_positive(duration_s, "duration")
    return JerkProfile(np.array([duration_s]), np.array([0.0]), v0=float(v0))


def constant_acceleration(
    ai: float, v0: float, v1: float, duration_s: float, a0: float = 0.0, a1: float = 0.0
) -> JerkProfile:
    """Return a move from speed ``v0`` to ``v1`` at constant acceleration ``ai``.

    The acceleration goes from ``a0`` to ``ai`` and, at the end, from ``ai`` to ``a1`` by
    linear ramps of equal length tau, solved so that the speed changes by ``v1 - v0`` in
    ``duration_s``: ``v1 - v0 = ai (T - tau) + (a0 + a1) tau / 2``.

    Raises
    ------
    SignalError
        If no ramp length in [0, T/2] gives ``v1`` (the parameters disagree).

    """
    _check_positive(duration_s, "the duration")
    dv, t_total = v1 - v0, float(duration_s)
    den = ai - (a0 + a1) / 2
    tau = 0.0 if abs(den) < 1e-12 else (ai * t_total - dv) / den
    tol = END_SPEED_RTOL * max(abs(v0), abs(v1), abs(ai) * t_total, 1e-9)
    if abs(den) < 1e-12 and abs(ai * t_total - dv) > tol:
        raise SignalError(_end_speed_message(ai, v0, v1, t_total))
    if not -tol / max(abs(den), 1e-12) <= tau <= t_total / 2 + tol / max(abs(den), 1e-12):
        raise SignalError(_end_speed_message(ai, v0, v1, t_total))
    tau = float(np.clip(tau, 0.0, t_total / 2))
    if tau < 1e-12:
        return JerkProfile(np.array([t_total]), np.array([0.0]), v0=float(v0), a0=float(ai))
    durations = np.array([tau, t_total - 2 * tau, tau])
    jerks = np.array([(ai - a0) / tau, 0.0, (a1 - ai) / tau])
    return JerkProfile(durations, jerks, v0=float(v0), a0=float(a0))


def _end_speed_message(ai: float, v0: float, v1: float, t_total: float) -> str:
    return (
        f"constant acceleration {ai:g} for {t_total:g} s cannot take speed {v0:g} to {v1:g} "
        "(the change of speed must be about the acceleration times the duration, less the "
        "jerk ramps at both ends)"
    )


def point_to_point(distance: float, vmax: float, amax: float, jmax: float) -> JerkProfile:
    """Return the jerk-limited move over ``distance`` (>= 0) from rest to rest.

    Seven phases: jerk up, constant acceleration, jerk down, cruise, and the mirror image.
    The speed reaches ``vmax`` when the distance allows; otherwise the highest speed that
    covers the distance exactly (accelerating all the way, then braking).

    Raises
    ------
    SignalError
        For a limit that is not positive and finite, or a negative distance.

    """
    for value, name in (
        (vmax, "the speed limit"),
        (amax, "the acceleration limit"),
        (jmax, "the jerk limit"),
    ):
        _check_positive(value, name)
    if not np.isfinite(distance) or distance < 0:
        raise SignalError(f"the distance must be finite and >= 0; got {distance}")
    if distance == 0:
        return JerkProfile(np.zeros(0), np.zeros(0))

    def ramp_up(v: float) -> tuple[float, float, float]:
        """Jerk time, constant-acceleration time and distance to reach speed ``v``."""
        tj = min(amax / jmax, np.sqrt(v / jmax))
        ta = max(0.0, v / amax - tj) if tj > 0 else 0.0
        return tj, ta, v * (2 * tj + ta) / 2

    v = vmax
    if 2 * ramp_up(v)[2] > distance:
        v = brentq(lambda x: 2 * ramp_up(x)[2] - distance, 0.0, vmax, xtol=1e-15, rtol=1e-14)
    tj, ta, d_ramp = ramp_up(v)
    a = jmax * tj
    cruise = max(0.0, (distance - 2 * d_ramp) / v)
    durations = np.array([tj, ta, tj, cruise, tj, ta, tj])
    jerks = np.array([jmax, 0.0, -jmax, 0.0, -jmax, 0.0, jmax]) * (a / (jmax * tj))
    return JerkProfile(durations, jerks)


def faded_sines(
    t: ArrayLike,
    omega: ArrayLike,
    gain: ArrayLike,
    phase: ArrayLike,
    t_fade: float,
    t_total: float,
) -> FloatArray:
    """Return ``sum gain sin(omega t + phase)`` under a raised-cosine fade at both ends.

    Parameters
    ----------
    t : array_like
        Times from the start of the move [s]; zero outside [0, ``t_total``].
    omega, gain, phase : array_like
        Angular frequencies [rad/s], amplitudes and phases [rad], one per sine.
    t_fade : float
        Length of the fade-in and of the fade-out [s] (0: none).
    t_total : float
        Length of the move [s].

    """
    tt, y, _ = _sines(t, omega, gain, phase)
    window, _ = _fade(tt, t_fade, t_total)
    return window * y


def faded_sines_rate(
    t: ArrayLike,
    omega: ArrayLike,
    gain: ArrayLike,
    phase: ArrayLike,
    t_fade: float,
    t_total: float,
) -> FloatArray:
    """Return the time derivative of :func:`faded_sines` (same arguments), exactly."""
    tt, y, dy = _sines(t, omega, gain, phase)
    window, rate = _fade(tt, t_fade, t_total)
    return window * dy + rate * y


def _sines(
    t: ArrayLike, omega: ArrayLike, gain: ArrayLike, phase: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Return the times, the sum of sines and its derivative."""
    tt = np.asarray(t, dtype=float)
    w, g, p = (np.atleast_1d(np.asarray(x, dtype=float)) for x in (omega, gain, phase))
    if not (w.shape == g.shape == p.shape) or w.ndim != 1:
        raise SignalError("omg, gain and phi0 must be lists of equal length")
    arg = np.multiply.outer(tt, w) + p
    return tt, np.sin(arg) @ g, np.cos(arg) @ (g * w)


def _fade(tt: FloatArray, t_fade: float, t_total: float) -> tuple[FloatArray, FloatArray]:
    """Return the raised-cosine window (0 outside [0, ``t_total``]) and its derivative."""
    inside = (tt >= 0) & (tt <= t_total)
    if t_fade <= 0:
        return inside.astype(float), np.zeros_like(tt)
    edge = np.minimum(tt, t_total - tt)
    ramp = np.clip(edge / t_fade, 0.0, 1.0)
    slope = np.where((edge >= 0) & (edge < t_fade),
                     np.where(tt < t_total - tt, 1.0, -1.0) / t_fade, 0.0)  # fmt: skip
    window = np.where(inside, 0.5 - 0.5 * np.cos(np.pi * ramp), 0.0)
    rate = np.where(inside, 0.5 * np.pi * np.sin(np.pi * ramp) * slope, 0.0)
    return window, rate


def _check_positive(value: float, name: str) -> None:
    if not np.isfinite(value) or value <= 0:
        raise SignalError(f"{name} must be a positive finite number; got {value}")
