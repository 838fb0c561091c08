"""Model extensions: blocks a diagnosis can add to a motion-system configuration.

Each extension has a fixed name and fixed parameter names (the JSON vocabulary of ``twin
diagnose``) and acts on some DOFs:

===================  ==============================  =============================================
effect               parameters                      block
===================  ==============================  =============================================
``delay``            ``extra_delay_s``               e^{-d s} on top of the configuration's delay
                                                     (negative: less delay, never below zero)
``gain``             ``gain``                        g
``platform_filter``  ``break_hz``                    replaces the Eq 5.1 filter (or adds one)
``resonance``        ``frequency_hz``, ``damping``   w^2 / (s^2 + 2 z w s + w^2), a structural mode
``lead``             ``time_constant_s``             1 + T s (the form of Eq 5.12 / 5.13)
``sensor_filter``    ``cutoff_hz``, ``channels``     1 / (1 + s / w_c) inside the IMU, on the
                                                     named channels (ax ay az p q r), noise included
``backlash``         ``play``                        dead band of width ``play`` [m or rad] on the
                                                     platform input (after filter and delay)
``platform_lag``     ``lag_s``                       1 / (1 + t_m s): the platform's own first-order
                                                     lag (Eq 5.11, Table 5.5's t_m), e.g. a heavier
                                                     cabin behind the same PD
``noise``            ``scale``                       the motion noise (Eq 5.10) times ``scale``
                                                     (the IMU's own noise belongs to the IMU:
                                                     :class:`~twin.chain.imu.ImuSpec`)
``imu_alignment``    ``roll_rad``, ``pitch_rad``,    the IMU mounted with its axes rotated by
                     ``yaw_rad``                     R = Rz(yaw) Ry(pitch) Rx(roll) (IMU axes to
                                                     cabin axes, Eq A.2's form): it reads R^T f and
                                                     R^T omega, so one DOF leaks into the other
                                                     channels (each angle within +-0.2 rad)
===================  ==============================  =============================================

Command-side blocks act on the platform input in the order of the table (after the
configuration's own filter and delay); ``sensor_filter`` and ``imu_alignment`` act on the IMU
samples and ``noise`` on the noise generators, so all of them run on the full and the reduced
platform alike.

``imu_alignment`` takes the angles in the convention of the cabin's own attitude (Eq A.2): an
IMU pitched nose-up by d on a cabin at rest reads what a well-mounted one reads on a cabin
pitched nose-up by d, ax = +g sin d. The sensing elements are rotated, so the IMU's bias, noise
and saturation act in its own axes, after the rotation, and a ``sensor_filter`` after them
(:class:`~twin.chain.imu.VirtualImu`). It acts on the whole IMU (its ``dofs`` are ignored) and
has no response of one DOF's own channel (:meth:`Extension.response` refuses it): it is not
fitted DOF by DOF.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal

from twin.chain.block import Backlash, Block, Gain, Lead, backlash  # noqa: F401 (re-exported)
from twin.chain.lti import LtiBlock
from twin.core.checks import check_keys, did_you_mean, number
from twin.core.errors import ConfigError, SignalError
from twin.core.frames import DOF_NAMES, rotation_matrix

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: The fixed vocabulary: effect -> parameter names.
EFFECTS: Mapping[str, tuple[str, ...]] = {
    "delay": ("extra_delay_s",),
    "gain": ("gain",),
    "platform_filter": ("break_hz",),
    "resonance": ("frequency_hz", "damping"),
    "lead": ("time_constant_s",),
    "sensor_filter": ("cutoff_hz", "channels"),
    "backlash": ("play",),
    "platform_lag": ("lag_s",),
    "noise": ("scale",),
    "imu_alignment": ("roll_rad", "pitch_rad", "yaw_rad"),
}
#: Largest rotation of an ``imu_alignment`` about each axis [rad] (11.5 deg: a misalignment,
#: not a sensor mounted on another face).
MAX_ALIGNMENT_RAD = 0.2
#: Allowed range of each numeric parameter: (low, high, low excluded). The bounds keep a
#: configuration file physical (a 1e300 Hz filter or a 1e9 s delay is refused, not run).
RANGES: Mapping[str, tuple[float, float, bool]] = {
    "extra_delay_s": (-10.0, 10.0, False),
    "gain": (1e-3, 1e3, False),
    "break_hz": (0.01, 1e3, False),
    "frequency_hz": (0.01, 1e3, False),
    "damping": (1e-3, 100.0, False),
    "time_constant_s": (0.0, 10.0, False),
    "cutoff_hz": (0.01, 1e3, False),
    "play": (0.0, 10.0, False),
    "scale": (0.0, 1e3, False),
    "lag_s": (0.0, 1.0, False),
    "roll_rad": (-MAX_ALIGNMENT_RAD, MAX_ALIGNMENT_RAD, False),
    "pitch_rad": (-MAX_ALIGNMENT_RAD, MAX_ALIGNMENT_RAD, False),
    "yaw_rad": (-MAX_ALIGNMENT_RAD, MAX_ALIGNMENT_RAD, False),
}
#: The keys of an extension's JSON form.
JSON_KEYS = ("effect", "parameters", "dofs")
IMU_CHANNELS = ("ax", "ay", "az", "p", "q", "r")
#: The IMU channel that measures each DOF's acceleration (after App. C.2.3 processing).
DOF_CHANNEL = dict(zip(DOF_NAMES, IMU_CHANNELS, strict=True))
#: Effects that are linear, time-invariant responses of the commanded DOF.
LINEAR = ("delay", "gain", "platform_filter", "resonance", "lead", "sensor_filter",
          "platform_lag")  # fmt: skip


@dataclass(frozen=True)
class Extension:
    """One model extension.

    Attributes
    ----------
    effect : str
        A key of :data:`EFFECTS`.
    parameters : mapping
        Its parameters (numbers; ``channels`` a list of IMU channel names).
    dofs : tuple of str
        DOFs it acts on (all six if empty). ``sensor_filter``, ``noise`` and
        ``imu_alignment`` ignore it.

    Examples
    --------
    >>> Extension("delay", {"extra_delay_s": 0.065}, ("heave",)).describe()
    'delay: extra_delay_s 0.065 (heave)'

    """

    effect: str
    parameters: Mapping[str, object]
    dofs: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        """Check the effect, its parameters and the DOFs."""
        if self.effect not in EFFECTS:
            raise ConfigError(
                f"unknown effect {self.effect!r}{did_you_mean(self.effect, EFFECTS)}; expected "
                f"one of {', '.join(EFFECTS)}"
            )
        names = EFFECTS[self.effect]
        check_keys(self.parameters, names, f"effect {self.effect!r}", ConfigError, "parameter")
        if set(self.parameters) != set(names):
            raise ConfigError(
                f"effect {self.effect!r} takes parameters {', '.join(names)}; "
                f"got {', '.join(sorted(self.parameters)) or 'none'}"
            )
        for dof in self.dofs:
            if dof not in DOF_NAMES:
                raise ConfigError(f"unknown DOF {dof!r}{did_you_mean(str(dof), DOF_NAMES)}; "
                                  f"expected one of {', '.join(DOF_NAMES)}")  # fmt: skip
        for name in names:
            if name != "channels":
                lo, hi, lo_open = RANGES[name]
                number(self.parameters[name], f"{self.effect} parameter {name}", lo=lo, hi=hi,
                       lo_open=lo_open, error=ConfigError)  # fmt: skip
        if self.effect == "sensor_filter":
            ch = self.parameters["channels"]
            if (
                isinstance(ch, str)
                or not isinstance(ch, Sequence)
                or not ch
                or any(c not in IMU_CHANNELS for c in ch)
            ):
                raise ConfigError(
                    f"sensor_filter channels must be a non-empty list of {', '.join(IMU_CHANNELS)};"
                    f" got {ch!r}"
                )

    def value(self, name: str, default: float = 0.0) -> float:
        """Return a numeric parameter."""
        return float(self.parameters[name]) if name in self.parameters else default  # type: ignore[arg-type]

    @property
    def dof_mask(self) -> NDArray[np.bool_]:
        """Boolean mask over the six DOFs it acts on."""
        if not self.dofs:
            return np.ones(6, dtype=bool)
        return np.array([d in self.dofs for d in DOF_NAMES])

    def describe(self) -> str:
        """One line, e.g. ``delay: extra_delay_s 0.065 (heave)``.

        An ``imu_alignment`` in degrees, without DOFs (it acts on the whole IMU):
        ``imu_alignment: IMU rotated by roll 0.50°, pitch -0.20°, yaw 1.00°``.
        """
        if self.effect == "imu_alignment":
            angles = ", ".join(
                f"{axis} {np.degrees(self.value(f'{axis}_rad')):.2f}°"
                for axis in ("roll", "pitch", "yaw")
            )
            return f"{self.effect}: IMU rotated by {angles}"
        pars = ", ".join(
            f"{k} {v:.4g}" if isinstance(v, float | int) else f"{k} {v}"
            for k, v in self.parameters.items()
        )
        where = f" ({', '.join(self.dofs)})" if self.dofs else ""
        return f"{self.effect}: {pars}{where}"

    def to_json(self) -> dict[str, object]:
        """Return the JSON form ``{"effect", "parameters", "dofs"}``."""
        pars = {k: (list(v) if k == "channels" else float(v)) for k, v in self.parameters.items()}  # type: ignore[arg-type]
        return {"effect": self.effect, "parameters": pars, "dofs": list(self.dofs)}

    @classmethod
    def from_json(cls, data: object) -> Extension:
        """Parse the JSON form (:class:`~twin.core.errors.ConfigError` on anything malformed).

        An unknown key (``dof`` for ``dofs``) is refused with a did-you-mean, not ignored.
        """
        if isinstance(data, Mapping):
            check_keys(data, JSON_KEYS, "extension", ConfigError)
        if not isinstance(data, Mapping) or "effect" not in data or "parameters" not in data:
            raise ConfigError(f"an extension needs 'effect' and 'parameters'; got {data!r}")
        pars = data["parameters"]
        if not isinstance(pars, Mapping):
            raise ConfigError(f"extension parameters must be an object; got {pars!r}")
        dofs = data.get("dofs", [])
        if not isinstance(dofs, list | tuple):
            raise ConfigError(f"extension dofs must be a list; got {dofs!r}")
        pars = {k: (tuple(v) if isinstance(v, list) else v) for k, v in pars.items()}
        return cls(str(data["effect"]), pars, tuple(dofs))

    # --- frequency responses of the linear effects ------------------------------------------

    def response(
        self, f: ArrayLike, nominal_break_hz: float | None = None, filter_scale: float = 1.0
    ) -> ComplexArray:
        """Return the factor the extension multiplies a DOF's response by, at ``f`` [Hz].

        ``platform_filter`` is relative to the configuration's own filter (``nominal_break_hz``;
        None: no filter); in a run recorded with the filter set ``filter_scale`` times higher
        both breaks are that many times higher (:meth:`MotionSystem.filter_scaled
        <twin.chain.config.MotionSystem.filter_scaled>`). Non-linear effects (``backlash``,
        ``noise``) have none, nor has ``imu_alignment``, which mixes the IMU's channels
        (:func:`imu_rotation`).

        Raises
        ------
        SignalError
            For an effect without a response of one DOF (the message says why).

        """
        s = 2j * np.pi * np.asarray(f, dtype=float)
        p = self.value
        if self.effect == "delay":
            return np.exp(-s * p("extra_delay_s"))
        if self.effect == "gain":
            return np.full(s.shape, p("gain"), dtype=complex)
        if self.effect == "platform_filter":
            k = filter_scale if nominal_break_hz is not None else 1.0
            new = 1.0 / (1.0 + s / (2 * np.pi * k * p("break_hz"))) ** 2
            old = (
                1.0
                if nominal_break_hz is None
                else 1.0 / (1.0 + s / (2 * np.pi * k * nominal_break_hz)) ** 2
            )
            return new / old
        if self.effect == "resonance":
            w = 2 * np.pi * p("frequency_hz")
            return w**2 / (s**2 + 2 * p("damping") * w * s + w**2)
        if self.effect == "lead":
            return 1.0 + s * p("time_constant_s")
        if self.effect == "sensor_filter":
            return 1.0 / (1.0 + s / (2 * np.pi * p("cutoff_hz")))
        if self.effect == "platform_lag":
            return 1.0 / (1.0 + s * p("lag_s"))
        if self.effect == "imu_alignment":
            raise SignalError(
                "imu_alignment has no response of one DOF: it rotates the IMU's axes, so each "
                "DOF leaks into the other channels (apply it with imu_rotation to all six)"
            )
        raise SignalError(f"{self.effect} is not a linear effect; it has no frequency response")

    # --- blocks --------------------------------------------------------------------------------

    def block(self) -> Block:
        """Return the command-side stream block of this extension (:mod:`twin.chain.block`).

        ``sensor_filter`` and ``imu_alignment`` act inside the IMU (:class:`SensorFilterStream`,
        :func:`imu_rotation`) and ``noise`` on the noise generators; none has a command-side
        block.
        """
        mask = tuple(bool(m) for m in self.dof_mask)
        p = self.value
        if self.effect == "gain":
            return Gain(p("gain"), mask)
        if self.effect == "resonance":
            w = 2 * np.pi * p("frequency_hz")
            sys = ((1.0,), (1 / w**2, 2 * p("damping") / w, 1.0))
            return LtiBlock(tuple(sys if m else None for m in mask), f"resonance {self.describe()}")
        if self.effect == "lead":
            return Lead(tuple(p("time_constant_s") if m else 0.0 for m in mask))
        if self.effect == "backlash":
            return Backlash(p("play"), mask)
        if self.effect == "platform_lag":
            lag = p("lag_s")
            sys = ((1.0,), (lag, 1.0)) if lag > 0 else None
            return LtiBlock(tuple(sys if m else None for m in mask), f"platform lag {lag:g} s")
        raise SignalError(f"{self.effect} is not applied to the commands")


def imu_rotation(extensions: Iterable[Extension]) -> FloatArray | None:
    """Return the rotation of the IMU's axes that the ``imu_alignment`` extensions make.

    Several compose in their order, each the IMU's rotation relative to the axes the ones
    before it left (R = R_1 R_2 ...), so an alignment found on top of a configuration's adds
    to it.

    Parameters
    ----------
    extensions : iterable of Extension
        A configuration's extensions (the other effects are skipped).

    Returns
    -------
    ndarray, shape (3, 3), or None
        R, taking IMU axes to cabin axes (the IMU reads R^T times a cabin-axes vector);
        None where there is no ``imu_alignment`` or all its angles are zero, so that a zero
        rotation leaves the readings' bits as they are.

    Examples
    --------
    >>> R = imu_rotation([Extension("imu_alignment",
    ...                             {"roll_rad": 0.0, "pitch_rad": 0.1, "yaw_rad": 0.0})])
    >>> round(float((R.T @ [0.0, 0.0, -9.81])[0]), 4)  # nose up: gravity shows in +x
    0.9794

    """
    out = None
    for e in extensions:
        if e.effect != "imu_alignment":
            continue
        angles = [e.value("roll_rad"), e.value("pitch_rad"), e.value("yaw_rad")]
        if any(angles):
            R = rotation_matrix(angles)
            out = R if out is None else out @ R
    return out


class SensorFilterStream:
    """First-order low-pass on some IMU channels, sample by sample across chunks.

    Discretised at the IMU rate (bilinear); starts in steady state at the first sample, so
    the static 1 g does not ring.
    """

    def __init__(self, extension: Extension, rate_hz: float) -> None:
        wc = 2 * np.pi * extension.value("cutoff_hz")
        if extension.value("cutoff_hz") >= rate_hz / 2:
            raise SignalError(
                f"sensor_filter cutoff {extension.value('cutoff_hz'):g} Hz must be below the "
                f"IMU's Nyquist frequency ({rate_hz / 2:g} Hz)"
            )
        self.b, self.a = signal.bilinear([wc], [1.0, wc], rate_hz)
        channels = extension.parameters["channels"]
        self.columns = [IMU_CHANNELS.index(c) for c in channels]  # type: ignore[union-attr]
        self._state: FloatArray | None = None

    def __call__(self, values: FloatArray) -> FloatArray:
        """Filter the chosen columns of an (n, 6) chunk (in place) and return it."""
        if values.shape[0] == 0:
            return values
        cols = values[:, self.columns]
        if self._state is None:
            self._state = signal.lfilter_zi(self.b, self.a)[:, None] * cols[0]
        out, self._state = signal.lfilter(self.b, self.a, cols, axis=0, zi=self._state)
        values[:, self.columns] = out
        return values
