"""Actuator limits on leg-length references: counted, then limited or rejected.

The real machines cannot follow a reference beyond their stroke, velocity or acceleration
(Table 5.1). The twin checks the leg references at the physics rate, counts every sample that
breaks a limit, and either limits the reference (``mode="limit"``: clip to the stroke,
rate- and acceleration-limit with a braking curve, then rejoin the reference as soon as it is
feasible again) or raises :class:`twin.core.errors.ActuatorLimitError` (``mode="strict"``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from twin.chain.kernels import limit_legs
from twin.core.errors import ActuatorLimitError
from twin.platform.facts import PlatformFacts
from twin.platform.geometry import Geometry

FloatArray = NDArray[np.float64]
MODES = ("limit", "strict")
_KINDS = ("stroke", "velocity", "acceleration")


@dataclass
class LimitReport:
    """How many physics samples of the leg references broke each limit.

    Attributes
    ----------
    mode : str
        ``"limit"`` or ``"strict"``.
    samples : dict of str to int
        Samples (any leg) beyond the stroke, velocity and acceleration limits of the
        references.
    force_samples : int
        Physics samples with an actuator at its force limit (full model with a
        ``force_limit``, :mod:`twin.platform.actuators`).
    first : str or None
        Description of the first violation.
    rate_hz : float
        Rate at which samples were counted.

    """

    mode: str
    rate_hz: float
    samples: dict[str, int] = field(default_factory=lambda: dict.fromkeys(_KINDS, 0))
    first: str | None = None
    force_samples: int = 0

    @property
    def total(self) -> int:
        """Samples with any violation counted (a sample may count under several limits)."""
        return sum(self.samples.values()) + self.force_samples

    def to_dict(self) -> dict[str, object]:
        """JSON-ready summary."""
        return {"mode": self.mode, "rate_hz": self.rate_hz, "samples": dict(self.samples),
                "force_samples": self.force_samples, "first": self.first}  # fmt: skip

    def summary(self) -> str:
        """One line for a report."""
        if not self.total:
            return "actuator limits: none reached"
        counts = {**self.samples, "force": self.force_samples}
        parts = ", ".join(f"{k} {v} samples" for k, v in counts.items() if v)
        return f"actuator limits LIMITED: {parts}; first: {self.first}"


@dataclass
class LimiterState:
    """Leg reference carried between chunks.

    Last length [m], velocity [m/s], and whether the limiter is still off the reference.
    """

    length: FloatArray
    velocity: FloatArray
    active: bool = False


@dataclass(frozen=True)
class ActuatorLimits:
    """Stroke, velocity and acceleration limits of the six legs.

    Attributes
    ----------
    leg_min, leg_max : ndarray, shape (6,)
        Stroke ends [m].
    max_velocity, max_acceleration : float
        [m/s, m/s^2].
    mode : str
        ``"limit"`` or ``"strict"``.

    """

    leg_min: FloatArray
    leg_max: FloatArray
    max_velocity: float
    max_acceleration: float
    mode: str = "limit"

    def __post_init__(self) -> None:
        """Check the mode."""
        if self.mode not in MODES:
            raise ValueError(f"limit mode must be one of {MODES}; got {self.mode!r}")

    @classmethod
    def of(cls, geometry: Geometry, facts: PlatformFacts, mode: str = "limit") -> ActuatorLimits:
        """Return the limits of a platform: stroke from its geometry, the rest from its facts."""
        return cls(geometry.leg_min, geometry.leg_max, facts.max_velocity,
                   facts.max_acceleration, mode)  # fmt: skip

    def check(
        self,
        t: FloatArray,
        lengths: FloatArray,
        velocities: FloatArray,
        accelerations: FloatArray,
        report: LimitReport,
    ) -> NDArray[np.bool_]:
        """Count the samples that break a limit; raise in strict mode.

        Parameters
        ----------
        t : ndarray, shape (n,)
            Times [s].
        lengths, velocities, accelerations : ndarray, shape (n, 6)
            Reference leg lengths, velocities, accelerations.
        report : LimitReport
            Counts, updated in place.

        Returns
        -------
        ndarray of bool, shape (n,)
            Samples with any violation.

        Raises
        ------
        ActuatorLimitError
            In strict mode, if any sample breaks a limit.

        """
        eps = 1e-9
        broken = {
            "stroke": (lengths < self.leg_min - eps) | (lengths > self.leg_max + eps),
            "velocity": np.abs(velocities) > self.max_velocity * (1 + 1e-9),
            "acceleration": np.abs(accelerations) > self.max_acceleration * (1 + 1e-9),
        }
        any_row = np.zeros(len(t), dtype=bool)
        for kind, b in broken.items():
            rows = b.any(axis=1)
            report.samples[kind] += int(rows.sum())
            if rows.any() and report.first is None:
                i = int(np.argmax(rows))
                leg = int(np.argmax(b[i]))
                report.first = (
                    f"{kind} limit, leg {leg + 1}, t = {t[i]:.3f} s "
                    f"(length {lengths[i, leg]:.4f} m, velocity {velocities[i, leg]:.3f} m/s, "
                    f"acceleration {accelerations[i, leg]:.3f} m/s^2)"
                )
            any_row |= rows
        if any_row.any() and self.mode == "strict":
            raise ActuatorLimitError(
                f"commands break an actuator limit ({report.first}); limits are stroke "
                f"[{self.leg_min.min():.3f}, {self.leg_max.max():.3f}] m, velocity "
                f"{self.max_velocity} m/s, acceleration {self.max_acceleration} m/s^2 "
                "(use limit mode 'limit' to have them limited and counted)"
            )
        return any_row

    def apply(
        self,
        t: FloatArray,
        lengths: FloatArray,
        velocities: FloatArray,
        accelerations: FloatArray,
        state: LimiterState,
        report: LimitReport,
    ) -> tuple[FloatArray, FloatArray]:
        """Check and limit one chunk of references (arguments as :meth:`check`).

        Parameters
        ----------
        t, lengths, velocities, accelerations, report
            As for :meth:`check`.
        state : LimiterState
            Limited reference at the previous sample; updated in place.

        Returns
        -------
        lengths, velocities : ndarray, shape (n, 6)
            The references to send to the legs.

        """
        any_row = self.check(t, lengths, velocities, accelerations, report)
        if not any_row.any() and not state.active:
            state.length, state.velocity = lengths[-1].copy(), velocities[-1].copy()
            return lengths, velocities
        return self._limit(1.0 / report.rate_hz, lengths, velocities, any_row, state)

    def _limit(
        self,
        dt: float,
        x: FloatArray,
        xd: FloatArray,
        broken: NDArray[np.bool_],
        state: LimiterState,
    ) -> tuple[FloatArray, FloatArray]:
        """Sequential limiter, run only from a violation until the reference is rejoined.

        Compiled (:func:`twin.chain.kernels.limit_legs`, the bits of the NumPy loop it replaced):
        a large play or a jump in the references keeps it on for most of a run, where the
        loop cost some 15 µs a sample.
        """
        y, yd = x.copy(), xd.copy()
        active = limit_legs(x, xd, broken, state.length, state.velocity, state.active, dt,
                            float(self.max_acceleration), float(self.max_velocity),
                            self.leg_min, self.leg_max, y, yd)  # fmt: skip
        state.length, state.velocity, state.active = y[-1].copy(), yd[-1].copy(), bool(active)
        return y, yd
