"""The six actuators' physics beyond the PD of Eq 5.9: friction, play, force limits, faults.

The thesis' platform model (Fig 5.4, Eq A.14) has ideal legs: the PD force acts along each
leg, nothing else. A real actuator also has Coulomb and viscous friction, play between the
motor and the rod, a largest force, and one leg may be weaker or slower than its neighbours
(a servo retuned or wearing). :class:`LegPhysics` holds these per leg; the nominal values of
each platform are in its ``build.toml`` ``[actuators]`` table and so in its MJCF (one truth):

=====================  ================================================  ====================
field                  in the MJCF                                       applied by
=====================  ================================================  ====================
``coulomb_n``          the leg tendon's ``frictionloss`` [N]             MuJoCo
``viscous_ns_per_m``   the leg tendon's ``damping`` [N s/m]              MuJoCo
``force_limit_n``      the leg tendon's ``actuatorfrcrange`` on the PD   MuJoCo
                       force, offset by the leg's static force at
                       neutral (0: none) [N]
``gain``               factor on the leg's K_p and K_d (Eq 5.9)          MuJoCo
``lag_s``              ``<custom><numeric name="leg_lag_s">``: a         :mod:`twin.chain.physics`
                       first-order lag of the leg's servo [s]            (on the leg reference)
``play_m``             ``<custom><numeric name="leg_play_m">``: a dead   :mod:`twin.chain.physics`
                       band between reference and rod [m]                (on the leg reference)
=====================  ================================================  ====================

The static-force feedback K_s (the cabin's ``gravcomp``) carries the cabin's weight outside
the legs' PD, so a leg's force is its PD force plus K_s times its share of the weight at the
pose (:func:`twin.platform.kinematics.static_leg_forces`); a force limit L on that total is
the PD's range [-L - f0, L - f0] with f0 the static share at neutral (the pose moves f0 by a
few per cent within the workspace: the limit is that close).

Friction acts on the leg's tendon (the line of action the PD drives), not on its slide joint:
the slide's light rod inside the closed loop gives MuJoCo's friction constraint so little
inertia that it saturates near 25 N whatever the ``frictionloss`` (measured: 100 N and 1600 N
on the MPI's leg 2 cost the same); on the tendon it acts through the cabin's inertia and a
leg's force changes by the friction, as a real actuator's would.

MuJoCo has neither a servo lag on a two-actuator PD nor play, so those two act on the leg's
reference, at the physics rate, before the PD: the rod follows a reference that lags or rests
in its dead band, as it would follow a lagging valve or a loose coupling.

:meth:`LegPhysics.of_model` reads them from a compiled model and :meth:`LegPhysics.apply`
writes them into a private copy of one (a calibrated or faulty platform, no recompilation).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace

import mujoco
import numpy as np
from numpy.typing import NDArray

from twin.core.checks import check_keys, number
from twin.core.errors import ConfigError, ModelFileError
from twin.platform.geometry import geometry_from_model
from twin.platform.kinematics import static_leg_forces
from twin.platform.payload import cabin_mass_properties

FloatArray = NDArray[np.float64]
N_LEGS = 6
#: Custom numerics of the MJCF that carry what MuJoCo does not apply itself.
LAG_NUMERIC = "leg_lag_s"
PLAY_NUMERIC = "leg_play_m"
#: Allowed range of each field (the unit is in its name; a gain is a factor).
RANGES: dict[str, tuple[float, float]] = {
    "coulomb_n": (0.0, 1e6),
    "viscous_ns_per_m": (0.0, 1e8),
    "force_limit_n": (0.0, 1e8),
    "gain": (0.01, 100.0),
    "lag_s": (0.0, 1.0),
    "play_m": (0.0, 0.1),
}
#: The ``build.toml`` ``[actuators]`` key of each field.
TOML_KEYS = {
    "coulomb_n": "coulomb_friction",
    "viscous_ns_per_m": "viscous_friction",
    "force_limit_n": "force_limit",
    "gain": "gain_factor",
    "lag_s": "lag",
    "play_m": "play",
}
#: Each field's value for an ideal actuator (the thesis' model).
IDEAL = {"coulomb_n": 0.0, "viscous_ns_per_m": 0.0, "force_limit_n": 0.0, "gain": 1.0,
         "lag_s": 0.0, "play_m": 0.0}  # fmt: skip


def _per_leg(value: object, where: str, lo: float, hi: float, error: type[Exception]) -> FloatArray:
    """Return a number for all six legs, or a list of six, checked, as an array of six."""
    values = value if isinstance(value, list | tuple | np.ndarray) else [value] * N_LEGS
    if len(values) != N_LEGS:
        raise error(f"{where} must be one number or a list of {N_LEGS} (one per leg); got "
                    f"{len(values)}")  # fmt: skip
    return np.array([number(v, f"{where}[{k}]", lo=lo, hi=hi, error=error)
                     for k, v in enumerate(values)])  # fmt: skip


@dataclass(frozen=True, eq=False)
class LegPhysics:
    """Per-leg actuator physics (arrays of six, leg 1 first; see the module docstring).

    Attributes
    ----------
    coulomb_n, viscous_ns_per_m, force_limit_n, gain, lag_s, play_m : ndarray, shape (6,)
        Coulomb friction [N], viscous friction [N s/m], force limit [N] (0: none), factor
        on K_p and K_d, servo lag [s], play [m].

    """

    coulomb_n: FloatArray
    viscous_ns_per_m: FloatArray
    force_limit_n: FloatArray
    gain: FloatArray
    lag_s: FloatArray
    play_m: FloatArray

    @classmethod
    def ideal(cls) -> LegPhysics:
        """Return ideal actuators: no friction, play, lag or force limit, gain 1."""
        return cls(**{k: np.full(N_LEGS, v) for k, v in IDEAL.items()})

    @classmethod
    def from_table(
        cls, table: Mapping[str, object], where: str, keys: Mapping[str, str] | None = None,
        error: type[Exception] = ConfigError,
    ) -> LegPhysics:  # fmt: skip
        """Read from a table (``build.toml`` ``[actuators]`` or a configuration's physics).

        Parameters
        ----------
        table : mapping
            Each key a number for all legs or a list of six; missing keys are ideal.
        where : str
            Names the table in error messages.
        keys : mapping of str to str, optional
            Field -> key in the table (default: the field names).
        error : type
            The exception raised for a bad value.

        Raises
        ------
        ConfigError (or ``error``)
            For an unknown key (with the allowed ones) or a value out of range.

        """
        keys = dict(keys or {f: f for f in IDEAL})
        check_keys(table, keys.values(), where, error)
        out = {}
        for f, key in keys.items():
            lo, hi = RANGES[f]
            value = table.get(key, IDEAL[f])
            out[f] = _per_leg(value, f"{where} {key}", lo, hi, error)
        return cls(**out)

    @classmethod
    def of_model(cls, model: mujoco.MjModel) -> LegPhysics:
        """Read the actuator physics of a compiled platform model.

        Raises
        ------
        ModelFileError
            For a model without the legs' joints, tendons and actuators of
            :mod:`twin.platform.build`.

        """
        try:
            tendons = [model.tendon(f"leg{j + 1}_axis").id for j in range(N_LEGS)]
            kp = np.array([model.actuator(f"leg{j + 1}_position").gainprm[0]
                           for j in range(N_LEGS)])  # fmt: skip
        except KeyError as e:
            raise ModelFileError(f"the model has no leg {e} of a twin platform") from None
        nominal = _numeric(model, "leg_kp", np.full(N_LEGS, np.nan))
        limited = model.tendon_actfrclimited[tendons].astype(bool)
        span = np.diff(model.tendon_actfrcrange[tendons], axis=1)[:, 0] / 2
        return cls(
            coulomb_n=model.tendon_frictionloss[tendons].copy(),
            viscous_ns_per_m=_damping(model.tendon_damping, tendons),
            force_limit_n=np.where(limited, span, 0.0),
            gain=np.where(np.isfinite(nominal), kp / nominal, 1.0),
            lag_s=_numeric(model, LAG_NUMERIC, np.zeros(N_LEGS)),
            play_m=_numeric(model, PLAY_NUMERIC, np.zeros(N_LEGS)),
        )

    def apply(self, model: mujoco.MjModel) -> None:
        """Write these physics into ``model`` (a private copy: it is changed in place).

        The gain factor is taken relative to the model's nominal K_p and K_d (the custom
        numerics ``leg_kp`` and ``leg_kd`` of the MJCF), so applying twice does not compound.
        """
        ranges = pd_force_ranges(self.force_limit_n, neutral_static_forces(model))
        for j in range(N_LEGS):
            tendon = model.tendon(f"leg{j + 1}_axis").id
            model.tendon_frictionloss[tendon] = self.coulomb_n[j]
            _set_damping(model.tendon_damping, tendon, float(self.viscous_ns_per_m[j]))
            model.tendon_actfrclimited[tendon] = self.force_limit_n[j] > 0
            model.tendon_actfrcrange[tendon] = ranges[j]
        kp = _numeric(model, "leg_kp", None)
        kd = _numeric(model, "leg_kd", None)
        for j in range(N_LEGS):
            g = float(self.gain[j])
            pos = model.actuator(f"leg{j + 1}_position")
            vel = model.actuator(f"leg{j + 1}_velocity")
            pos.gainprm[0], pos.biasprm[1] = g * kp[j], -g * kp[j]
            vel.gainprm[0], vel.biasprm[2] = g * kd[j], -g * kd[j]
        _set_numeric(model, LAG_NUMERIC, self.lag_s)
        _set_numeric(model, PLAY_NUMERIC, self.play_m)

    def replace(self, **changes: object) -> LegPhysics:
        """Return a copy with fields changed (arrays of six or one number for all legs)."""
        checked = {k: _per_leg(v, k, *RANGES[k], ConfigError) for k, v in changes.items()}
        return replace(self, **checked)

    def is_ideal(self) -> bool:
        """Return whether these are the thesis' ideal actuators."""
        return all(np.all(getattr(self, f) == v) for f, v in IDEAL.items())

    def shapes_reference(self) -> bool:
        """Return whether a lag or play acts on the leg references (not applied by MuJoCo)."""
        return bool(np.any(self.lag_s > 0) or np.any(self.play_m > 0))

    def differs(self, other: LegPhysics) -> dict[str, list[float]]:
        """Return the fields that differ from ``other``, as lists of six."""
        return {f.name: getattr(self, f.name).tolist() for f in fields(self)
                if not np.array_equal(getattr(self, f.name), getattr(other, f.name))}  # fmt: skip

    def to_dict(self) -> dict[str, list[float]]:
        """JSON-ready: each field as a list of six."""
        return {f.name: getattr(self, f.name).tolist() for f in fields(self)}


def cabin_static(model: mujoco.MjModel) -> tuple[float, FloatArray, float]:
    """Return the cabin's mass [kg] and centre of gravity [m] (with a payload) and K_s."""
    mass, com = cabin_mass_properties(model)
    return mass, com, float(model.body_gravcomp[model.body("cabin").id])


def neutral_static_forces(model: mujoco.MjModel) -> FloatArray:
    """Each leg's static force at neutral that the K_s feedback supplies [N] (see above)."""
    mass, com, ks = cabin_static(model)
    geo = geometry_from_model(model)
    return ks * static_leg_forces(geo, np.zeros(N_LEGS), mass, com)


def pd_force_ranges(limit: FloatArray, static: FloatArray) -> FloatArray:
    """Return the PD force range of each leg for a total force limit (0: none), (6, 2)."""
    return np.where((limit > 0)[:, None], np.column_stack([-limit - static, limit - static]),
                    0.0)  # fmt: skip


def _numeric(model: mujoco.MjModel, name: str, default: FloatArray | None) -> FloatArray:
    """Return a custom numeric of six values (``default`` where the model has none)."""
    try:
        return np.array(model.numeric(name).data[:N_LEGS], dtype=float)
    except KeyError:
        if default is None:
            raise ModelFileError(f"the model has no custom numeric {name!r} (rebuild it with "
                                 "`make models`)") from None  # fmt: skip
        return default


def _set_numeric(model: mujoco.MjModel, name: str, values: FloatArray) -> None:
    """Write a custom numeric of six values (the model must have it)."""
    try:
        model.numeric(name).data[:N_LEGS] = values
    except KeyError:
        if np.any(values):
            raise ModelFileError(f"the model has no custom numeric {name!r} (rebuild it with "
                                 "`make models`)") from None  # fmt: skip


def _damping(damping: FloatArray, ids: list[int]) -> FloatArray:
    """Linear damping coefficient of each element (a polynomial's first, where one is held)."""
    d = np.asarray(damping)
    return np.array([float(d[i]) if d.ndim == 1 else float(d[i, 0]) for i in ids])


def _set_damping(damping: FloatArray, i: int, value: float) -> None:
    """Set the linear damping coefficient of element ``i``."""
    if np.ndim(damping) == 1:
        damping[i] = value
    else:
        damping[i, 0] = value


@dataclass
class ReferenceState:
    """A run's leg references after the servo lag and after the play, carried between steps."""

    lagged: FloatArray
    rested: FloatArray
    lagged_rate: FloatArray = field(default_factory=lambda: np.zeros(N_LEGS))


def shape_reference(
    physics: LegPhysics, timestep: float, legs: FloatArray, legs_dot: FloatArray,
    state: ReferenceState,
) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """Pass one run's leg references through each leg's servo lag and play (in place of state).

    The lag is first order, exact for a reference held over each physics step
    (y += (1 - exp(-h / tau)) (u - y)), and its rate reference is the reference's rate through
    the same lag (the rate of a lagged signal is the lagged rate; (u - y) / tau instead would
    lose a third of the rate where tau is near the step h); the play is a dead band of
    width ``play_m`` (the rod rests while the lagged reference moves inside it, and follows at
    its edge, at the reference's rate).

    Parameters
    ----------
    physics : LegPhysics
        The actuators (``lag_s``, ``play_m``).
    timestep : float
        The physics step [s].
    legs, legs_dot : ndarray, shape (m, 6)
        Leg length [m] and rate [m/s] references at the physics steps.
    state : ReferenceState
        The run's references after the last step (updated).

    Returns
    -------
    tuple of ndarray, shape (m, 6)
        The shaped length and rate references.

    """
    tau, half = physics.lag_s, 0.5 * physics.play_m
    lagged_leg = tau > 0
    a = np.where(lagged_leg, -np.expm1(-timestep / np.where(lagged_leg, tau, 1.0)), 1.0)
    out, rate = np.empty_like(legs), np.empty_like(legs_dot)
    lag, rest, v = state.lagged.copy(), state.rested.copy(), state.lagged_rate.copy()
    for k in range(legs.shape[0]):
        lag += a * (legs[k] - lag)
        v += a * (legs_dot[k] - v)  # a = 1 where there is no lag: the rate itself
        lo, hi = lag - half, lag + half
        moving = (rest <= lo) | (rest >= hi)
        rest = np.clip(rest, lo, hi)
        out[k], rate[k] = rest, np.where(moving, v, 0.0)
    state.lagged, state.rested, state.lagged_rate = lag, rest, v
    return out, rate
