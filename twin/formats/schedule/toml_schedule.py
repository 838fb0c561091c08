"""The twin's own test-schedule format, ``twin-schedule/1`` (TOML), for labs without one.

Moves follow each other: each starts where and when the one before it ended (give
``start_s`` to leave a pause, at rest). Amplitudes and distances are in the DOF's units (m or
rad); a move drives one ``dof`` or, with ``axis``, a direction in all six.

.. code-block:: toml

    schedule = "twin-schedule/1"
    name = "heave bump, 0.1 m/s"            # optional (default: the file's name)

    [[move]]                                # one second at rest
    kind = "still"
    duration_s = 1.0

    [[move]]                                # a faded single sine (several: lists)
    kind = "sines"
    dof = "heave"
    frequencies_hz = [0.5]
    amplitudes = [0.05]
    phases_deg = [0.0]                      # optional, default 0
    fade_s = 2.0                            # raised-cosine fade at each end
    duration_s = 20.0

    [[move]]
    kind = "constant_speed"
    dof = "heave"
    speed = 0.1
    duration_s = 1.0

    [[move]]                                # through a reversal at constant acceleration
    kind = "constant_acceleration"
    dof = "heave"
    acceleration = -0.1
    v_start = 0.1
    v_end = -0.1
    ramp_s = 0.01                           # optional: jerk ramps at each end (default)
    # duration_s: optional, (v_end - v_start) / acceleration + ramp_s

    [[move]]                                # jerk-limited, rest to rest (signed distance)
    kind = "point_to_point"
    dof = "heave"
    distance = -0.2
    vmax = 0.4
    amax = 4.0
    jmax = 100.0
    # duration_s: optional, the profile's own
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from twin.chain.profiles import point_to_point
from twin.core.checks import check_keys, number, numbers, read_toml
from twin.core.errors import ScheduleError
from twin.core.frames import DOF_NAMES
from twin.formats.schedule.moves import KINDS, Move, Schedule

FORMAT = "twin-schedule/1"
#: Default jerk ramp of a constant-acceleration move [s] (as the SRS schedules have).
RAMP_S = 0.01
#: Keys every move may have, and the keys of each kind.
COMMON = ("kind", "dof", "axis", "start_s", "duration_s")
KEYS: dict[str, tuple[str, ...]] = {
    "still": ("kind", "start_s", "duration_s"),
    "sines": (*COMMON, "frequencies_hz", "amplitudes", "phases_deg", "fade_s"),
    "constant_speed": (*COMMON, "speed"),
    "constant_acceleration": (*COMMON, "acceleration", "v_start", "v_end", "ramp_s"),
    "point_to_point": (*COMMON, "distance", "vmax", "amax", "jmax"),
}


def read_toml_schedule(path: str | Path) -> Schedule:
    """Read a ``twin-schedule/1`` TOML file (see the module docstring).

    Raises
    ------
    ScheduleError
        For a file that is not TOML, does not say ``schedule = "twin-schedule/1"``, or has a
        move that cannot be run (named by its number).

    """
    doc = read_toml(path, f'a {FORMAT} TOML schedule (schedule = "{FORMAT}")', ScheduleError)
    return toml_schedule(doc, str(path), Path(path).stem)


def toml_schedule(doc: Mapping[str, object], source: str, name: str) -> Schedule:
    """Return the schedule of a parsed ``twin-schedule/1`` document."""
    if doc.get("schedule") != FORMAT:
        raise ScheduleError(
            f'{source}: the first line must say schedule = "{FORMAT}"; got {doc.get("schedule")!r}'
        )
    check_keys(doc, ("schedule", "name", "move"), source, ScheduleError)
    entries = doc.get("move")
    if not isinstance(entries, list) or not entries:
        raise ScheduleError(f"{source}: no moves; add [[move]] tables")
    moves: list[Move] = []
    pose, t = np.zeros(6), 0.0
    for i, entry in enumerate(entries, 1):
        move = _move(entry, i, pose, t, source)
        moves.append(move)
        pose, t = move.end()[0], move.end_s
    return Schedule(str(doc.get("name", name)), source, tuple(moves), FORMAT)


def _move(e: object, i: int, origin: np.ndarray, t: float, source: str) -> Move:
    """Return move ``i``, starting from ``origin`` at ``t`` unless it gives ``start_s``."""
    where = f"{source}: move {i}"
    if not isinstance(e, dict) or e.get("kind") not in KINDS:
        kind = e.get("kind") if isinstance(e, dict) else e
        raise ScheduleError(f"{where}: unknown kind {kind!r}; allowed: {', '.join(KINDS)}")
    kind = e["kind"]
    check_keys(e, KEYS[kind], where, ScheduleError)

    def num(key: str, default: float | None = None, **kw: object) -> float:
        if key not in e:
            if default is None:
                raise ScheduleError(f"{where}: a {kind} move needs {key}")
            return default
        return number(e[key], f"{where} {key}", error=ScheduleError, **kw)  # type: ignore[arg-type]

    start = num("start_s", t, lo=t - 1e-9)
    if kind == "still":
        return Move(
            i, start, num("duration_s", lo=0, lo_open=True), kind, origin, np.zeros(6), {}, "still"
        )
    axis = _axis(e, where)
    if kind == "sines":
        f = numbers(e.get("frequencies_hz"), f"{where} frequencies_hz", error=ScheduleError)
        amp = numbers(e.get("amplitudes"), f"{where} amplitudes", size=len(f), error=ScheduleError)
        ph = numbers(
            e.get("phases_deg", [0.0] * len(f)),
            f"{where} phases_deg",
            size=len(f),
            error=ScheduleError,
        )
        if (f <= 0).any():
            raise ScheduleError(f"{where}: frequencies_hz must be > 0; got {f.tolist()}")
        params = {
            "omega_rad_s": (2 * np.pi * f).tolist(),
            "gain": amp.tolist(),
            "phase_rad": np.radians(ph).tolist(),
            "t_fade_s": num("fade_s", lo=0),
        }
        duration = num("duration_s", lo=0, lo_open=True)
    elif kind == "constant_speed":
        params = {"speed": num("speed")}
        duration = num("duration_s", lo=0, lo_open=True)
    elif kind == "constant_acceleration":
        acc = num("acceleration")
        if acc == 0:
            raise ScheduleError(
                f"{where}: acceleration must not be 0 (a constant speed move "
                'is kind = "constant_speed")'
            )
        v0, v1, ramp = num("v_start"), num("v_end"), num("ramp_s", RAMP_S, lo=0)
        params = {"acceleration": acc, "v_start": v0, "v_end": v1}
        duration = num("duration_s", (v1 - v0) / acc + ramp, lo=0, lo_open=True)
    else:
        d = num("distance")
        limits = {k: num(k, lo=0, lo_open=True) for k in ("vmax", "amax", "jmax")}
        params = {"distance": abs(d), **limits}
        axis = axis * np.sign(d) if d != 0 else axis
        duration = num(
            "duration_s", point_to_point(abs(d), *limits.values()).duration, lo=0, lo_open=True
        )
    return Move(i, start, duration, kind, origin, axis, params, kind)


def _axis(e: Mapping[str, object], where: str) -> np.ndarray:
    """Return the move's axis: the unit vector of ``dof``, or the ``axis`` it gives."""
    if ("dof" in e) == ("axis" in e):
        raise ScheduleError(
            f"{where}: give either dof (one of {', '.join(DOF_NAMES)}) or axis (six numbers)"
        )
    if "axis" in e:
        axis = numbers(e["axis"], f"{where} axis", size=6, error=ScheduleError)
        if not axis.any():
            raise ScheduleError(f"{where}: axis is all zero")
        return axis
    if e["dof"] not in DOF_NAMES:
        raise ScheduleError(f"{where}: unknown dof {e['dof']!r}; allowed: {', '.join(DOF_NAMES)}")
    return np.eye(6)[DOF_NAMES.index(str(e["dof"]))]
