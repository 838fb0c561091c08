"""The physical vocabulary of a diagnosis: a payload on the cabin, one leg's actuator, the IMU.

The chain's extensions (:mod:`twin.chain.extensions`) change the signals around the platform;
these change the platform's physics, which only the full MuJoCo model has:

=================  ==========================================  ==============================
effect             parameters                                  applied as
=================  ==========================================  ==============================
``payload``        ``factor``: the cabin's mass and inertia    a body at the cabin's centre
                   times it (>= 1)                             of gravity
                                                               (:meth:`~twin.platform.payload.
                                                               Payload.scaling`)
``leg``            ``leg`` (1-6) and one of ``gain`` (factor   that leg's entry of
                   on K_p and K_d), ``lag_s`` (servo lag),     :class:`~twin.platform.
                   ``coulomb_n`` (friction), ``play_m``        actuators.LegPhysics`
``imu_alignment``  ``roll_rad``, ``pitch_rad``, ``yaw_rad``    the chain's ``imu_alignment``
                                                               extension (the IMU's axes
                                                               rotated)
=================  ==========================================  ==============================

What the runs can identify of a payload: from the IMU alone its effect is a slower cabin
behind the same PD, so mass and inertia (and the PD's damping) trade off: the factor is one
number on both. Its centre of gravity is held at the cabin's. Leg forces (``forces.csv``) see
the mass directly (the legs carry it), which is why they are used where a run has them.

A :class:`PhysicalCause` has the attributes of a :class:`~twin.chain.extensions.Extension`
that a finding's readers use (``effect``, ``parameters``, ``dofs``, :meth:`describe`,
:meth:`to_json`, :meth:`value`), so a physical finding is reported, merged and written like a
chain one.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np

from twin.chain.config import MotionSystem
from twin.chain.extensions import Extension
from twin.platform.actuators import LegPhysics
from twin.platform.facts import load_model
from twin.platform.payload import Payload
from twin.platform.platform_physics import PlatformPhysics

#: The physical effects and their parameter names.
PHYSICAL = {
    "payload": ("factor",),
    "leg": ("leg", "gain", "lag_s", "coulomb_n", "play_m"),
    "imu_alignment": ("roll_rad", "pitch_rad", "yaw_rad"),
}
#: A leg's faults: each fitted alone (one leg, one kind).
LEG_KINDS = ("gain", "lag_s", "coulomb_n", "play_m")
#: Per parameter: (probe, low, high, unit text). The probe is the screening simulation's value
#: (a fault a run of ordinary amplitude shows, well inside the search range); the range is
#: what a motion platform can have (beyond it a fit is "at the bound").
SEARCH = {
    "factor": (1.5, 1.0, 3.0, "x"),
    "gain": (0.7, 0.1, 2.0, "x"),
    "lag_s": (0.02, 0.0, 0.25, "s"),
    "coulomb_n": (300.0, 0.0, 5000.0, "N"),
    "play_m": (5e-4, 0.0, 0.01, "m"),
    "angle_rad": (0.01, -0.2, 0.2, "rad"),
}
ALIGNMENT = ("roll_rad", "pitch_rad", "yaw_rad")


@dataclass(frozen=True)
class PhysicalCause:
    """One physical effect with its parameters (the physical counterpart of an Extension).

    Attributes
    ----------
    effect : str
        ``payload``, ``leg`` or ``imu_alignment``.
    parameters : dict
        As in :data:`PHYSICAL` (a leg: ``leg`` and the one fault fitted).
    dofs : tuple of str
        The driven DOFs whose runs showed it.

    """

    effect: str
    parameters: Mapping[str, float]
    dofs: tuple[str, ...] = ()

    def value(self, name: str) -> float:
        """Return a parameter's value."""
        return float(self.parameters[name])

    @property
    def kind(self) -> str:
        """The fitted parameter of a leg (``gain``, ``lag_s``, ...); the effect otherwise."""
        if self.effect == "leg":
            return next(k for k in self.parameters if k != "leg")
        return self.effect

    def describe(self) -> str:
        """One line, e.g. ``leg 3: coulomb_n 412 (pitch)``."""
        on = f" ({', '.join(self.dofs)})" if self.dofs else ""
        if self.effect == "leg":
            k = self.kind
            return f"leg {int(self.value('leg'))}: {k} {self.value(k):.4g}{on}"
        if self.effect == "payload":
            return f"payload: cabin mass and inertia x{self.value('factor'):.3g}{on}"
        angles = ", ".join(f"{n.removesuffix('_rad')} {np.degrees(self.value(n)):.2f} deg"
                           for n in ALIGNMENT)  # fmt: skip
        return f"imu_alignment: {angles}{on}"

    def to_json(self) -> dict[str, object]:
        """Return the JSON form (``effect``, ``parameters``, ``dofs``)."""
        return {"effect": self.effect, "parameters": dict(self.parameters),
                "dofs": list(self.dofs)}  # fmt: skip


def base_legs(config: MotionSystem) -> LegPhysics:
    """Return the legs of the nominal configuration (its physics, or the MJCF's own)."""
    if config.physics is not None and config.physics.legs is not None:
        return config.physics.legs
    return LegPhysics.of_model(load_model(config.platform))


def nominal_value(config: MotionSystem, name: str, leg: int | None = None) -> float:
    """Return a parameter's value in the nominal configuration (a leg's, or the factor 1)."""
    if name == "factor":
        return 1.0
    if name in ALIGNMENT:
        return 0.0
    return float(getattr(base_legs(config), name)[int(leg) - 1])  # type: ignore[arg-type]


def configured(config: MotionSystem, cause: PhysicalCause) -> MotionSystem:
    """Return the nominal configuration with a physical cause applied.

    Raises
    ------
    ConfigError
        For a value outside what the physics accepts (e.g. a payload factor <= 1).

    """
    physics = config.physics or PlatformPhysics()
    if cause.effect == "payload":
        f = cause.value("factor")
        payload = Payload.scaling(config.platform, f) if f > 1.0 + 1e-9 else None
        return config.replace(physics=replace(physics, payload=payload))
    if cause.effect == "leg":
        legs = base_legs(config)
        k, j = cause.kind, int(cause.value("leg")) - 1
        values = np.array(getattr(legs, k), dtype=float)
        values[j] = cause.value(k)
        return config.replace(physics=replace(physics, legs=replace(legs, **{k: values})))
    angles = {n: cause.value(n) for n in ALIGNMENT}
    return config.replace(extensions=(*config.extensions, Extension("imu_alignment", angles)))


def merged_config(config: MotionSystem, causes: list[PhysicalCause]) -> MotionSystem:
    """Return ``config`` with every cause applied (the extended configuration's physics)."""
    for cause in causes:
        config = configured(config, cause)
    return config
