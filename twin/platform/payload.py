"""A payload on the cabin: a new cockpit, a heavier cabin, another centre of gravity.

A :class:`Payload` is a rigid body attached to the cabin of a platform's MJCF with MuJoCo's
own ``MjSpec`` (the model is recompiled, so its centre of gravity, inertia and every derived
constant follow). The static-force feedback K_s (the cabin's ``gravcomp``) carries the
payload's weight as it carries the cabin's: it feeds back the measured static load, so a
heavier cabin sags no more than the nominal one; what changes is the dynamics (a heavier
cabin lags more behind the PD, Table 5.5's t_m grows with mass and inertia).

:meth:`Payload.scaling` is the payload that makes a cabin ``factor`` times heavier in mass
and inertia without moving its centre of gravity.

Examples
--------
>>> from twin.platform.facts import load_model
>>> p = Payload.scaling("mpi", 1.5)
>>> heavier = p.model("mpi")
>>> cabin = load_model("mpi").body("cabin").id
>>> round(float(heavier.body_subtreemass[cabin] / load_model("mpi").body_subtreemass[cabin]), 6)
1.5

"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.core.checks import number, numbers
from twin.core.errors import ConfigError
from twin.platform.facts import load_model, model_path

FloatArray = NDArray[np.float64]
#: Largest payload relative to the cabin's own mass (beyond it the PD of Eq 5.9 and the
#: actuators are not the machine's any more).
MAX_MASS_RATIO = 10.0


@dataclass(frozen=True, eq=False)
class Payload:
    """A rigid body fixed to the cabin (thesis cabin frame: x forward, y right, z down).

    Attributes
    ----------
    mass_kg : float
        Its mass [kg] (> 0).
    position_m : ndarray, shape (3,)
        Its centre of gravity in the cabin frame [m].
    inertia : ndarray, shape (3,)
        Its principal moments about its centre of gravity, along the cabin axes [kg m^2].

    """

    mass_kg: float
    position_m: FloatArray
    inertia: FloatArray

    @classmethod
    def of(cls, mass_kg: float, position_m: ArrayLike = (0.0, 0.0, 0.0),
           inertia: ArrayLike = (0.0, 0.0, 0.0), where: str = "payload") -> Payload:  # fmt: skip
        """Return a checked payload (ConfigError naming ``where`` and the field otherwise)."""
        m = number(mass_kg, f"{where} mass_kg", lo=0.0, lo_open=True, error=ConfigError)
        pos = numbers(position_m, f"{where} position_m", size=3, error=ConfigError)
        if np.abs(pos).max() > 5.0:
            raise ConfigError(f"{where} position_m must lie within 5 m of the UGP; got "
                              f"{pos.tolist()}")  # fmt: skip
        inertia_ = numbers(inertia, f"{where} inertia", size=3, error=ConfigError)
        if (inertia_ < 0).any():
            raise ConfigError(f"{where} inertia must be >= 0; got {inertia_.tolist()}")
        return cls(m, pos, inertia_)

    @classmethod
    def scaling(cls, platform: str, factor: float) -> Payload:
        """Return the payload that makes the cabin ``factor`` times heavier (mass and inertia).

        It sits at the cabin's centre of gravity with (factor - 1) times its inertia.

        Raises
        ------
        ConfigError
            For a factor not in (1, 1 + MAX_MASS_RATIO].

        """
        f = number(factor, "payload factor", lo=1.0, hi=1.0 + MAX_MASS_RATIO, lo_open=True,
                   error=ConfigError)  # fmt: skip
        cabin = load_model(platform).body("cabin")
        return cls((f - 1) * float(cabin.mass[0]), np.array(cabin.ipos, dtype=float),
                   (f - 1) * np.array(cabin.inertia, dtype=float))  # fmt: skip

    def check_for(self, platform: str) -> None:
        """Refuse a payload heavier than :data:`MAX_MASS_RATIO` times the platform's cabin."""
        cabin_mass = float(load_model(platform).body("cabin").mass[0])
        if self.mass_kg > MAX_MASS_RATIO * cabin_mass:
            raise ConfigError(f"payload mass_kg {self.mass_kg:g} is more than "
                              f"{MAX_MASS_RATIO:g} times the {platform} cabin's "
                              f"{cabin_mass:g} kg")  # fmt: skip

    def model(self, platform: str) -> mujoco.MjModel:
        """Return the platform's model with this payload attached to the cabin (compiled).

        Raises
        ------
        ConfigError
            For a payload too heavy for the platform (:meth:`check_for`).

        """
        self.check_for(platform)
        spec = mujoco.MjSpec.from_file(str(model_path(platform)))
        cabin = spec.body("cabin")
        body = cabin.add_body(name="payload", pos=[float(x) for x in self.position_m],
                              gravcomp=cabin.gravcomp)  # fmt: skip
        body.explicitinertial = True
        body.mass = self.mass_kg
        body.ipos = [0.0, 0.0, 0.0]
        body.inertia = [float(max(x, 1e-9)) for x in self.inertia]
        return spec.compile()

    def to_dict(self) -> dict[str, object]:
        """JSON-ready."""
        return {"mass_kg": self.mass_kg, "position_m": self.position_m.tolist(),
                "inertia": self.inertia.tolist()}  # fmt: skip


def cabin_mass_properties(model: mujoco.MjModel) -> tuple[float, FloatArray]:
    """Return the mass [kg] and centre of gravity [m, cabin frame] of the cabin and its payload.

    Sums the cabin body and the bodies fixed directly to it (a :class:`Payload`).
    """
    cabin = model.body("cabin").id
    mass = float(model.body_mass[cabin])
    moment = mass * np.asarray(model.body_ipos[cabin], dtype=float)
    for b in range(model.nbody):
        if b != cabin and model.body_parentid[b] == cabin and model.body_jntnum[b] == 0:
            rot = np.empty(9)
            mujoco.mju_quat2Mat(rot, model.body_quat[b])
            com = model.body_pos[b] + rot.reshape(3, 3) @ model.body_ipos[b]
            mass += float(model.body_mass[b])
            moment += float(model.body_mass[b]) * com
    return mass, moment / mass
