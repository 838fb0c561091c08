"""The platforms the twin knows: where their models live and their non-physical facts.

Physical facts (geometry, inertia, gains, stroke) live in each model's MJCF and are read from
the compiled model (:mod:`twin.platform.geometry`). Non-physical facts (actuator velocity and
acceleration limits, platform filter, delay, IMU rates) live in ``platform.toml`` beside it.

The models folder is the repository's ``models/``; set ``TWIN_MODELS_DIR`` to use another.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import mujoco

from twin.core import checks
from twin.core.checks import check_keys, number
from twin.core.errors import ModelFileError, UnknownPlatformError

#: Platform name -> model folder name.
PLATFORMS: dict[str, str] = {"mpi": "mpi_stewart", "srs": "simona_srs"}
#: The tables of ``platform.toml`` and their keys.
FACT_KEYS: Mapping[str, Sequence[str]] = {
    "platform": ("name", "model", "command_rate_hz"),
    "actuator_limits": ("max_velocity", "max_acceleration"),
    "motion_system": ("filter_break_hz", "delay_s", "noise"),
    "imu": ("model", "rate_hz", "accel_range", "gyro_range_deg_s"),
    "full_model": ("equivalent_delay_s",),
}


def models_root() -> Path:
    """Return the folder holding one sub-folder per platform model."""
    env = os.environ.get("TWIN_MODELS_DIR")
    root = Path(env) if env else Path(__file__).resolve().parents[2] / "models"
    if not root.is_dir():
        raise ModelFileError(
            f"models folder not found at {root}: install the twin from its repository "
            "(pip install -e .) or set TWIN_MODELS_DIR"
        )
    return root


def read_toml(path: Path, tables: Mapping[str, Sequence[str]]) -> dict:
    """Read a model folder's TOML file (UTF-8, whatever the locale) and check its keys.

    Parameters
    ----------
    path : Path
        The file (``platform.toml``, ``build.toml``).
    tables : mapping of str to sequence of str
        Its tables and each one's keys.

    Raises
    ------
    ModelFileError
        Naming the file: missing, not UTF-8 TOML, or a table or key not in ``tables`` (with a
        did-you-mean).

    """
    doc = checks.read_toml(path, f"TOML with the tables {', '.join(tables)}", ModelFileError)
    check_keys(doc, tables, str(path), ModelFileError, "table")
    for name, table in doc.items():
        if not isinstance(table, dict):
            raise ModelFileError(f"{path}: {name} must be a table ([{name}])")
        check_keys(table, tables[name], f"{path}: [{name}]", ModelFileError)
    return doc


def check_platform(name: str) -> str:
    """Return ``name`` if it is a known platform, else raise :class:`UnknownPlatformError`."""
    if name not in PLATFORMS:
        known = ", ".join(PLATFORMS)
        raise UnknownPlatformError(f"unknown platform '{name}' (known platforms: {known})")
    return name


def model_dir(name: str) -> Path:
    """Return the model folder of platform ``name``."""
    return models_root() / PLATFORMS[check_platform(name)]


def model_path(name: str, scene: bool = False) -> Path:
    """Return the path of the platform's model XML (or of its ``scene.xml``)."""
    folder = model_dir(name)
    return folder / ("scene.xml" if scene else f"{PLATFORMS[name]}.xml")


@cache
def _load_model_cached(path: str) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(path)


def load_model(name: str, scene: bool = False) -> mujoco.MjModel:
    """Compile the platform's MJCF (cached; treat the returned model as read-only).

    Parameters
    ----------
    name : str
        Platform name, ``"mpi"`` or ``"srs"``.
    scene : bool
        Compile ``scene.xml`` (model plus floor and light) instead of the bare model.

    Returns
    -------
    mujoco.MjModel

    """
    path = model_path(name, scene)
    if not path.is_file():
        raise ModelFileError(f"model file missing: {path} (regenerate with `make models`)")
    try:
        return _load_model_cached(str(path))
    except ValueError as e:
        raise ModelFileError(f"{path}: MuJoCo could not compile it: {e}") from None


@dataclass(frozen=True)
class PlatformFacts:
    """Non-physical facts of a platform (from ``platform.toml``).

    Attributes
    ----------
    name : str
        Platform name.
    command_rate_hz : float
        Rate of the pose commands.
    max_velocity, max_acceleration : float
        Actuator velocity [m/s] and acceleration [m/s^2] limits (Table 5.1).
    filter_break_hz : float
        Platform-filter break frequency (Eq 5.1); 0 means no filter.
    delay_s : float
        Motion-system time delay [s].
    noise : bool
        Whether the Eq 5.10 motion-noise model applies.
    imu_rate_hz, imu_accel_range, imu_gyro_range_deg_s : float
        IMU sample rate and saturation limits.
    equivalent_delay_s : tuple of float
        The full MuJoCo model's own lag per DOF [s] (its fitted first-order time constant,
        Table 5.5), which the full model's delay block leaves out (``twin.chain.config``).

    """

    name: str
    command_rate_hz: float
    max_velocity: float
    max_acceleration: float
    filter_break_hz: float
    delay_s: float
    noise: bool
    imu_rate_hz: float
    imu_accel_range: float
    imu_gyro_range_deg_s: float
    equivalent_delay_s: tuple[float, ...]


@cache
def load_facts(name: str) -> PlatformFacts:
    """Read the platform's ``platform.toml`` (once per process, as the geometry).

    Raises
    ------
    UnknownPlatformError
        For an unknown platform name.
    ModelFileError
        If the file is missing or a value is missing or malformed.

    """
    path = model_dir(name) / "platform.toml"
    doc = read_toml(path, FACT_KEYS)

    def get(section: str, key: str) -> float:
        try:
            value = doc[section][key]
        except KeyError:
            raise ModelFileError(f"{path}: missing [{section}] {key}") from None
        if isinstance(value, bool):
            return value
        return number(value, f"{path}: [{section}] {key}", lo=0, error=ModelFileError)

    return PlatformFacts(
        name=name,
        command_rate_hz=get("platform", "command_rate_hz"),
        max_velocity=get("actuator_limits", "max_velocity"),
        max_acceleration=get("actuator_limits", "max_acceleration"),
        filter_break_hz=get("motion_system", "filter_break_hz"),
        delay_s=get("motion_system", "delay_s"),
        noise=bool(get("motion_system", "noise")),
        imu_rate_hz=get("imu", "rate_hz"),
        imu_accel_range=get("imu", "accel_range"),
        imu_gyro_range_deg_s=get("imu", "gyro_range_deg_s"),
        equivalent_delay_s=_six(doc, path, "full_model", "equivalent_delay_s"),
    )


def _six(doc: dict, path: Path, section: str, key: str) -> tuple[float, ...]:
    """Read a list of six numbers >= 0 from a TOML document."""
    value = doc.get(section, {}).get(key)
    if (
        not isinstance(value, list)
        or len(value) != 6
        or not all(isinstance(v, int | float) and not isinstance(v, bool) and v >= 0
                   for v in value)
    ):  # fmt: skip
        raise ModelFileError(f"{path}: [{section}] {key} must be a list of six numbers >= 0")
    return tuple(float(v) for v in value)
