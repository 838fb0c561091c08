"""Named motion-system configurations: which blocks sit in front of which platform.

A configuration is the reduced model of Eq 5.11 made of blocks: platform filter (Eq 5.1),
pure delay, optional SRS resonance (Eq 5.12, 5.13), optional heave noise (Eq 5.10), in front
of a platform (the MPI or the SRS MJCF).

``delay_s`` is the *total* motion-system delay as measured on the real machine, from command
to measured response (35 ms on the MPI, §5.5.2; 25 ms on the SRS, §6.2.2). The measured figure
already contains the platform's own dynamic lag, so:

* the reduced platform (a rigid cabin that follows its input exactly) gets the whole
  ``delay_s`` as a delay block;
* the full MuJoCo platform lags by itself: its delay block is ``delay_s`` minus the
  platform's equivalent delay per DOF (its fitted first-order time constant t_m, Table 5.5,
  stored in ``platform.toml`` ``[full_model] equivalent_delay_s``), so that both reproduce the
  measured delay.

The eight conditions of Table 6.3 are the MPI blocks in front of the SRS platform; their
delays are the totals of Table 6.3 (25 ms is the SRS alone, condition 1).

Examples
--------
>>> ms = motion_system("condition-6")
>>> ms.platform, ms.filter_break_hz, ms.delay_s, ms.noise
('srs', 1.0, 0.025, True)

"""

from __future__ import annotations

import dataclasses
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twin.chain.block import Backlash, Block
from twin.chain.delay import MAX_DELAY_S, Delay
from twin.chain.extensions import DOF_CHANNEL, Extension, imu_rotation
from twin.chain.filter import MAX_BREAK_HZ, MIN_BREAK_HZ, PlatformFilter, check_break_hz
from twin.chain.lti import LinearModel
from twin.chain.noise import MotionNoise
from twin.chain.resonance import Resonance
from twin.core.checks import check_keys, did_you_mean, flag, number, read_json
from twin.core.errors import ConfigError, SignalError, UnknownPlatformError, UsageError
from twin.core.frames import dof_index
from twin.core.lifecycle import replacing_file
from twin.core.thesis import TABLE_6_3
from twin.platform.facts import PLATFORMS, load_facts
from twin.platform.platform_physics import PlatformPhysics

#: Format tag of a configuration file (``twin diagnose --save-config``).
CONFIG_FORMAT = "twin-config/1"
#: The keys of a ``twin-config/1`` file.
FILE_KEYS = ("format", "platform", "description", "platform_config")
#: The keys of a ``platform_config`` (of a configuration file or a run's ``meta.json``).
CONFIG_KEYS = ("name", "filter_break_hz", "delay_s", "noise", "noise_highpass_hz", "resonance",
               "extensions", "physics")  # fmt: skip


@dataclass(frozen=True)
class MotionSystem:
    """A motion-system configuration.

    Attributes
    ----------
    name : str
        Configuration name.
    platform : str
        Platform model it drives, ``"mpi"`` or ``"srs"``.
    filter_break_hz : float or None
        Platform-filter break frequency (Eq 5.1), None for no filter.
    delay_s : float
        Total motion-system delay [s] (see module docstring).
    noise : bool
        Whether the Eq 5.10 heave noise is added.
    noise_highpass_hz : float
        Noise spectrum removed below this frequency [Hz] (§5.4.4).
    resonance : bool
        Whether the SRS resonance terms (Eq 5.12, 5.13) are applied.
    description : str
        Where the configuration comes from.
    extensions : tuple of Extension
        Model extensions (:mod:`twin.chain.extensions`), e.g. found by ``twin diagnose``.
    physics : PlatformPhysics or None
        The full model's actuators and payload where they differ from its MJCF
        (:mod:`twin.platform.platform_physics`); None: the MJCF's own.

    """

    name: str
    platform: str
    filter_break_hz: float | None
    delay_s: float
    noise: bool
    noise_highpass_hz: float = 1.0
    resonance: bool = False
    description: str = ""
    extensions: tuple[Extension, ...] = ()
    physics: PlatformPhysics | None = None

    def __post_init__(self) -> None:
        """Check the values."""
        if self.platform not in PLATFORMS:
            raise UnknownPlatformError(
                f"unknown platform {self.platform!r}; expected one of {', '.join(PLATFORMS)}"
            )
        if self.filter_break_hz is not None:
            PlatformFilter(self.filter_break_hz)
        Delay(self.delay_s)
        if self.noise:
            MotionNoise(highpass_hz=self.noise_highpass_hz)
        for ext in self.extensions:
            if not isinstance(ext, Extension):
                raise SignalError(f"extensions must be Extension objects; got {ext!r}")
        if self.physics is not None and self.physics.payload is not None:
            self.physics.payload.check_for(self.platform)

    def of(self, effect: str) -> list[Extension]:
        """Return the extensions of one effect type."""
        return [e for e in self.extensions if e.effect == effect]

    @property
    def imu_rotation(self) -> NDArray[np.float64] | None:
        """Rotation of the IMU's axes on the cabin (``imu_alignment``; None: well mounted).

        See :func:`twin.chain.extensions.imu_rotation`.
        """
        return imu_rotation(self.extensions)

    @property
    def noise_scale(self) -> float:
        """Factor on the motion noise (product of the ``noise`` extensions; not the IMU's)."""
        return float(np.prod([e.value("scale") for e in self.of("noise")]))

    @property
    def delays_s(self) -> NDArray[np.float64]:
        """Total delay per DOF [s]: ``delay_s`` plus the ``delay`` extensions (at least 0)."""
        extra = sum((e.value("extra_delay_s") * e.dof_mask for e in self.of("delay")), np.zeros(6))
        return np.maximum(self.delay_s + extra, 0.0)

    def without_delay(self) -> MotionSystem:
        """Return this configuration without any delay (``delay_s`` 0, no ``delay`` extension)."""
        keep = tuple(e for e in self.extensions if e.effect != "delay")
        return self.replace(name=self.name, delay_s=0.0, extensions=keep)

    @property
    def breaks_hz(self) -> tuple[float | None, ...]:
        """Platform-filter break frequency per DOF, ``platform_filter`` extensions applied."""
        out = [self.filter_break_hz] * 6
        for e in self.of("platform_filter"):
            for k in np.flatnonzero(e.dof_mask):
                out[k] = e.value("break_hz")
        return tuple(out)

    def replace(self, **changes: object) -> MotionSystem:
        """Return a copy with some fields changed (and the name marked as modified)."""
        changes.setdefault("name", f"{self.name}+custom")
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]

    def filter_scaled(self, factor: float) -> MotionSystem:
        """Return this configuration with its platform filter set ``factor`` times higher.

        A run recorded at another setting of the platform filter (the thesis' Ch. 4 measured
        the MPI at 1, 5 and 10 Hz) is this configuration with the filter's break and every
        ``platform_filter`` extension's break times ``factor``: a filter that runs off its
        setting (a break x1.05, or one at 0.54 Hz where 1 Hz is set) runs off by the same
        factor at another setting. The name is kept (the configuration's, at another
        setting); without a filter, or at a factor of 1, the configuration itself.

        Raises
        ------
        ConfigError
            For a factor that is not a positive finite number.

        Examples
        --------
        >>> motion_system("mpi").filter_scaled(10.0).filter_break_hz
        10.0
        >>> motion_system("srs").filter_scaled(10.0).filter_break_hz is None
        True

        """
        number(factor, "filter scale factor", lo=1e-6, hi=1e6, error=ConfigError)
        if factor == 1.0 or self.filter_break_hz is None:
            return self
        exts = tuple(
            Extension(e.effect, {**e.parameters, "break_hz": e.value("break_hz") * factor}, e.dofs)
            if e.effect == "platform_filter" else e for e in self.extensions
        )  # fmt: skip
        return dataclasses.replace(
            self, filter_break_hz=self.filter_break_hz * factor, extensions=exts
        )

    def override(
        self,
        break_hz: float | None = None,
        delay_ms: float | None = None,
        noise: bool | None = None,
        resonance: bool | None = None,
    ) -> MotionSystem:
        """Return this configuration with the command-line overrides applied (None: keep).

        The one place where ``--break-hz``, ``--delay-ms``, ``--no-noise`` and
        ``--resonance`` change a configuration; the name gets a tag per change
        (e.g. ``srs-fb1-60ms``).

        Parameters
        ----------
        break_hz : float, optional
            Platform-filter break frequency [Hz]; 0 removes the filter.
        delay_ms : float, optional
            Total motion-system delay [ms] (command to measured response, as §5.6.2.2
            measures it: on the SRS, 25 ms is the SRS alone and 60 ms adds the MPI's 35 ms).
        noise : bool, optional
            Heave noise of Eq 5.10 on or off.
        resonance : bool, optional
            SRS resonance terms of Eq 5.12/5.13 on or off.

        Raises
        ------
        ConfigError
            For a negative or non-finite break frequency or delay.

        Examples
        --------
        >>> motion_system("srs").override(break_hz=1.0, delay_ms=60).name
        'srs-fb1-60ms'

        """
        changes: dict[str, object] = {}
        tags = []
        if break_hz is not None:
            check_break_hz(break_hz, "--break-hz", ConfigError)
            changes["filter_break_hz"] = float(break_hz) or None
            tags.append(f"fb{break_hz:g}")
        if delay_ms is not None:
            number(delay_ms, "--delay-ms", lo=0, hi=MAX_DELAY_S * 1e3, error=ConfigError)
            changes["delay_s"] = float(delay_ms) / 1e3
            tags.append(f"{delay_ms:g}ms")
        if noise is not None and noise != self.noise:
            changes["noise"] = bool(noise)
            tags.append("noise" if noise else "quiet")
        if resonance is not None and resonance != self.resonance:
            changes["resonance"] = bool(resonance)
            tags.append("resonance" if resonance else "no-resonance")
        if not changes:
            return self
        return self.replace(name="-".join([self.name, *tags]), **changes)

    def blocks(self, platform_lag_s: ArrayLike = 0.0) -> list[Block]:
        """Return the command blocks, in order, for a platform with the given own lag.

        Parameters
        ----------
        platform_lag_s : float or array_like of 6
            The platform's own equivalent delay per DOF [s]; subtracted from ``delay_s``
            (never below zero).

        """
        out: list[Block] = []
        breaks = self.breaks_hz
        if any(b is not None for b in breaks):
            out.append(PlatformFilter(breaks))
        lag = np.broadcast_to(np.asarray(platform_lag_s, dtype=float), (6,))
        delay = np.maximum(self.delays_s - lag, 0.0)
        if np.any(delay > 0):
            out.append(Delay(tuple(float(d) for d in delay)))
        if self.resonance:
            out.append(Resonance())
        for effect in ("gain", "resonance", "lead", "backlash", "platform_lag"):
            out.extend(e.block() for e in self.of(effect))
        return out

    def noise_block(self, imu_rate_hz: float = 819.2) -> MotionNoise | None:
        """Return the heave-noise generator, or None if this configuration has no noise."""
        if not self.noise:
            return None
        return MotionNoise(imu_rate_hz, self.noise_highpass_hz, self.noise_scale)

    def response_at_hz(self, f: ArrayLike) -> NDArray[np.complex128]:
        """Return the reduced model (Eq 5.11 and the optional resonance) at ``f`` [Hz].

        An ``imu_alignment`` is left out (here and in :meth:`transfer_function`): it mixes the
        IMU's channels rather than filtering one (on a DOF's own channel it is a constant
        factor, a diagonal element of the rotation, 1 - O(angle^2); the leakage goes to the
        others).

        Returns
        -------
        ndarray, shape (len(f), 6)

        """
        h = np.ones((np.size(f), 6), dtype=complex)
        for block in self.blocks():
            if not isinstance(block, Backlash):
                h = h * block.response_at_hz(f)
        for ext in self.of("sensor_filter"):
            mask = _sensed(ext)
            h[:, mask] = h[:, mask] * ext.response(f)[:, None]
        return h

    def transfer_function(self, dof: int | str) -> LinearModel:
        """Return one DOF's reduced model as a python-control transfer function and a delay.

        The same model as :meth:`response_at_hz` (the blocks' own transfer functions
        multiplied, a ``sensor_filter`` on the DOF's IMU channel included; backlash has none).
        """
        import control

        k = dof_index(dof) if isinstance(dof, str) else int(dof)
        tf, delay = control.tf([1.0], [1.0]), 0.0
        for block in self.blocks():
            if isinstance(block, Delay):
                delay += float(block.per_dof[k])
            elif not isinstance(block, Backlash):
                tf = tf * block.transfer_function(k)
        for ext in self.of("sensor_filter"):
            if _sensed(ext)[k]:
                tf = tf * control.tf([1.0], [1.0 / (2 * np.pi * ext.value("cutoff_hz")), 1.0])
        return LinearModel(tf, delay)

    def to_meta(self) -> dict[str, object]:
        """Return the ``platform_config`` entry of a run's ``meta.json``."""
        return {
            "name": self.name,
            "filter_break_hz": self.filter_break_hz,
            "delay_s": self.delay_s,
            "noise": self.noise,
            "noise_highpass_hz": self.noise_highpass_hz,
            "resonance": self.resonance,
            "extensions": [e.to_json() for e in self.extensions],
        } | ({"physics": self.physics.to_dict()} if self.physics is not None else {})

    @classmethod
    def from_meta(cls, platform: str, cfg: object, description: str = "") -> MotionSystem:
        """Build a configuration from a ``platform_config`` entry (of ``meta.json`` or a file).

        Raises
        ------
        ConfigError
            For a missing, unknown or malformed key (the message names it; an unknown one
            with the allowed keys and a did-you-mean).

        """
        if not isinstance(cfg, dict):
            raise ConfigError(f"platform_config must be an object; got {cfg!r}")
        check_keys(cfg, CONFIG_KEYS, "platform_config", ConfigError)
        for key in ("filter_break_hz", "delay_s", "noise"):
            if key not in cfg:
                raise ConfigError(f"platform_config lacks {key!r}")
        fb = cfg["filter_break_hz"]
        if fb is not None:
            fb = number(fb, "platform_config filter_break_hz (or null)", lo=MIN_BREAK_HZ,
                        hi=MAX_BREAK_HZ, error=ConfigError)  # fmt: skip
        exts = cfg.get("extensions", [])
        if not isinstance(exts, list):
            raise ConfigError(f"platform_config extensions must be a list; got {exts!r}")
        name = cfg.get("name", "recorded")
        if not isinstance(name, str):
            raise ConfigError(f"platform_config name must be a string; got {name!r}")
        return cls(
            name=name,
            platform=platform,
            filter_break_hz=fb,
            delay_s=number(
                cfg["delay_s"], "platform_config delay_s", lo=0, hi=MAX_DELAY_S, error=ConfigError
            ),
            noise=flag(cfg["noise"], "platform_config noise", ConfigError),
            noise_highpass_hz=number(
                cfg.get("noise_highpass_hz", 1.0),
                "platform_config noise_highpass_hz",
                lo=MIN_BREAK_HZ,
                hi=MAX_BREAK_HZ,
                error=ConfigError,
            ),
            resonance=flag(cfg.get("resonance", False), "platform_config resonance", ConfigError),
            description=description,
            extensions=tuple(_extension(e, k) for k, e in enumerate(exts)),
            physics=_physics(cfg.get("physics")),
        )

    def save(self, path: str | Path) -> Path:
        """Write this configuration as a ``twin-config/1`` JSON file (atomically)."""
        path = Path(path)
        data = {
            "format": CONFIG_FORMAT,
            "platform": self.platform,
            "description": self.description,
            "platform_config": self.to_meta(),
        }
        with replacing_file(path) as tmp:
            tmp.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
        return path


def _physics(data: object) -> PlatformPhysics | None:
    """Parse the ``physics`` entry of a ``platform_config`` (None where it has none)."""
    return None if data is None else PlatformPhysics.from_dict(data, "platform_config physics")


def _extension(data: object, k: int) -> Extension:
    """Parse the ``k``-th extension of a ``platform_config``; an error names which one."""
    try:
        return Extension.from_json(data)
    except ConfigError as e:
        raise ConfigError(f"platform_config extensions[{k}]: {e}") from None


def _sensed(ext: Extension) -> NDArray[np.bool_]:
    """DOFs whose measured acceleration comes from a sensor_filter's channels."""
    channels = ext.parameters["channels"]
    return np.array([DOF_CHANNEL[d] in channels for d in DOF_CHANNEL])  # type: ignore[operator]


def load_config(path: str | Path) -> MotionSystem:
    """Read a ``twin-config/1`` file (written by :meth:`MotionSystem.save`).

    Raises
    ------
    ConfigError
        Naming the file: not UTF-8 JSON, not ``twin-config/1``, an unknown key (with the
        allowed ones and a did-you-mean) or a value that is missing or out of range.
    UnknownPlatformError
        For a platform the twin does not know.

    """
    path = Path(path)
    data = read_json(path, f"a {CONFIG_FORMAT} configuration file", ConfigError)
    if isinstance(data, dict) and "format" not in data:  # a misspelt "format" is named as such
        check_keys(data, FILE_KEYS, str(path), ConfigError)
    if not isinstance(data, dict) or data.get("format") != CONFIG_FORMAT:
        raise ConfigError(
            f"{path}: not a {CONFIG_FORMAT} file (its 'format' must be {CONFIG_FORMAT!r})"
        )
    check_keys(data, FILE_KEYS, str(path), ConfigError)
    if not isinstance(data.get("platform"), str) or data["platform"] not in PLATFORMS:
        raise UnknownPlatformError(
            f"{path}: unknown platform {data.get('platform')!r}; "
            f"expected one of {', '.join(PLATFORMS)}"
        )
    try:
        return MotionSystem.from_meta(
            data["platform"], data.get("platform_config"), str(data.get("description", path))
        )
    except ConfigError as e:
        raise ConfigError(f"{path}: {e}") from None


def _from_facts(platform: str, name: str, description: str) -> MotionSystem:
    facts = load_facts(platform)
    return MotionSystem(
        name=name,
        platform=platform,
        filter_break_hz=facts.filter_break_hz or None,
        delay_s=facts.delay_s,
        noise=facts.noise,
        description=description,
    )


def _condition(n: int) -> MotionSystem:
    fb, delay, noise = TABLE_6_3[n]
    return MotionSystem(
        name=f"condition-{n}",
        platform="srs",
        filter_break_hz=fb,
        delay_s=delay,
        noise=noise,
        description=f"Table 6.3 condition {n}: the MPI blocks simulated on the SRS",
    )


def config_names() -> list[str]:
    """Return every configuration name :func:`motion_system` accepts."""
    return ["mpi", "mpi-2008", "srs", *(f"condition-{n}" for n in TABLE_6_3)]


def config_help() -> str:
    """Return the command-line help for a CONFIG argument."""
    return f"one of {', '.join(config_names())}, or a twin-config/1 .json file"


def motion_system(name: str) -> MotionSystem:
    """Return a named configuration.

    ``mpi`` (1 Hz filter, 35 ms, noise; §5.5), ``mpi-2008`` (1 Hz, 100 ms, no noise: the MPI
    before its software update, Ch 3), ``srs`` (no filter, 25 ms; §6.2.2) and
    ``condition-1`` ... ``condition-8`` (Table 6.3); a path to a ``twin-config/1`` JSON file
    (:meth:`MotionSystem.save`, ``twin diagnose --save-config``) loads that file.

    Raises
    ------
    UnknownPlatformError
        For an unknown name (the message lists the known ones).

    """
    if name.endswith(".json") or Path(name).is_file():
        return load_config(name)
    if name == "mpi":
        return _from_facts("mpi", "mpi", "MPI Stewart platform, reduced model Eq 5.11 (§5.5)")
    if name == "srs":
        return _from_facts("srs", "srs", "SIMONA Research Simulator baseline (§5.6.1, §6.2.2)")
    if name == "mpi-2008":
        base = _from_facts("mpi", "mpi-2008", "MPI platform before the 2009 software update (Ch 3)")
        return dataclasses.replace(base, delay_s=0.100, noise=False)
    if name.startswith("condition-") and name[10:].isdigit() and int(name[10:]) in TABLE_6_3:
        return _condition(int(name[10:]))
    raise UnknownPlatformError(
        f"unknown configuration {name!r}{did_you_mean(name, config_names())}; expected one of "
        f"{', '.join(config_names())} or a twin-config/1 .json file"
    )


def resolve(config: MotionSystem | str | os.PathLike[str]) -> MotionSystem:
    """Return the configuration ``config`` names: the one resolver every entry point uses.

    Parameters
    ----------
    config : MotionSystem, str or path
        A :class:`MotionSystem` (returned as it is), a configuration name (``mpi``, ``srs``,
        ``condition-1`` ...: :func:`motion_system`) or the path of a ``twin-config/1`` file
        (as ``str`` or :class:`pathlib.Path`: :func:`load_config`).

    Raises
    ------
    UnknownPlatformError
        For an unknown name (the message lists the known ones).
    ConfigError
        For a file that is not a valid ``twin-config/1`` file.
    UsageError
        For anything else (an ``int``, None, ...).

    Examples
    --------
    >>> resolve("srs").delay_s
    0.025
    >>> resolve(resolve("mpi")).name
    'mpi'

    """
    if isinstance(config, MotionSystem):
        return config
    if isinstance(config, str):
        return motion_system(config)
    if isinstance(config, os.PathLike):
        return load_config(config)
    raise UsageError(
        f"config: expected a configuration name ({', '.join(config_names())}), the path of a "
        f"twin-config/1 file or a MotionSystem; got {type(config).__name__} {config!r}"
    )
