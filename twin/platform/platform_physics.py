"""A platform's physics as a configuration carries it: actuators and payload beyond the MJCF's.

The ``physics`` entry of a ``twin-config/1`` ``platform_config`` (and so of a run's
``meta.json``) changes the full MuJoCo model when it is loaded, without editing the MJCF:

.. code-block:: json

    "physics": {
      "legs": {"coulomb_n": [0, 400, 0, 0, 0, 0], "gain": 1.0},
      "payload": {"mass_kg": 120.0, "position_m": [0.4, 0.0, -0.6], "inertia": [30, 40, 30]}
    }

``legs`` takes the fields of :class:`~twin.platform.actuators.LegPhysics` (each one number for
all legs or a list of six; a missing field is the ideal actuator's), ``payload`` those of
:class:`~twin.platform.payload.Payload`. Only the full model has legs and a cabin to load:
the reduced model (Eq 5.11) refuses a configuration with physics.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from twin.core.checks import check_keys
from twin.core.errors import ConfigError
from twin.platform.actuators import LegPhysics
from twin.platform.payload import Payload

#: The keys of the ``physics`` entry.
PHYSICS_KEYS = ("legs", "payload")
#: The keys of its ``payload``.
PAYLOAD_KEYS = ("mass_kg", "position_m", "inertia")


@dataclass(frozen=True, eq=False)
class PlatformPhysics:
    """The actuators' physics and a payload of a configuration (None: the MJCF's own).

    Attributes
    ----------
    legs : LegPhysics or None
        Each leg's friction, play, force limit, gain and lag.
    payload : Payload or None
        A body fixed to the cabin.

    """

    legs: LegPhysics | None = None
    payload: Payload | None = None

    @classmethod
    def from_dict(cls, data: object, where: str = "physics") -> PlatformPhysics:
        """Read a ``physics`` entry (strict: an unknown key is an error with a did-you-mean).

        Raises
        ------
        ConfigError
            Naming the key or value that is wrong and what is allowed.

        """
        if not isinstance(data, Mapping):
            raise ConfigError(f"{where} must be an object with {', '.join(PHYSICS_KEYS)}; got "
                              f"{data!r}")  # fmt: skip
        check_keys(data, PHYSICS_KEYS, where, ConfigError)
        legs = data.get("legs")
        if legs is not None:
            if not isinstance(legs, Mapping):
                raise ConfigError(f"{where} legs must be an object; got {legs!r}")
            legs = LegPhysics.from_table(legs, f"{where} legs")
        payload = data.get("payload")
        if payload is not None:
            if not isinstance(payload, Mapping):
                raise ConfigError(f"{where} payload must be an object; got {payload!r}")
            check_keys(payload, PAYLOAD_KEYS, f"{where} payload", ConfigError)
            if "mass_kg" not in payload:
                raise ConfigError(f"{where} payload lacks 'mass_kg'")
            zero = (0.0, 0.0, 0.0)
            payload = Payload.of(payload["mass_kg"], payload.get("position_m", zero),
                                 payload.get("inertia", zero), f"{where} payload")  # fmt: skip
        return cls(legs, payload)

    def to_dict(self) -> dict[str, object]:
        """Return the ``physics`` entry (JSON-ready; absent parts left out)."""
        out: dict[str, object] = {}
        if self.legs is not None:
            out["legs"] = self.legs.to_dict()
        if self.payload is not None:
            out["payload"] = self.payload.to_dict()
        return out

    def describe(self) -> str:
        """One line: what differs from the platform's MJCF."""
        parts = []
        if self.legs is not None:
            changed = self.legs.differs(LegPhysics.ideal())
            parts += [f"legs {k} {v}" for k, v in changed.items()] or ["legs ideal"]
        if self.payload is not None:
            at = [round(x, 3) for x in self.payload.position_m.tolist()]
            parts.append(f"payload {self.payload.mass_kg:g} kg at {at} m")
        return "; ".join(parts) or "the model's own"
