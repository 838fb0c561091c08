"""The SIMONA Research Simulator's motion-test schedules: JSON ``MovementSeries``.

A ``MovementSeries`` is ``{"type": "MovementSeries", "moves": [...]}``; each entry has a start
``time`` [s] and a ``move`` of one of three types:

- ``Still``: hold the pose ``xyz`` [m], ``phithetapsi`` [rad] (until the next move);
- ``ProfileMotion``: from the pose ``from``, along ``axis`` (a 6-vector in surge, sway,
  heave, roll, pitch, yaw: the direction and the scale, e.g. 0.7 for a rotation), for ``dt``
  seconds, with a ``profile``:

  - ``FadedSineProfile`` {``omg`` [rad/s], ``gain``, ``phi0`` [rad] (lists, one per sine),
    ``Tfade``, ``Ttotal`` [s]}: ``sum gain sin(omg t + phi0)`` faded in and out;
  - ``ConstantAccelProfile`` {``a0``, ``a1``, ``ai``, ``v0``, ``v1``, ``Ttotal``}: from speed
    ``v0`` to ``v1`` at acceleration ``ai``;
  - ``ConstantSpeedProfile`` {``v0``, ``Ttotal``};

- ``Movement``: from ``from``, over the displacement ``move`` = ``axis`` x ``dist``, with a
  ``Profile`` {``dist``, ``vmx``, ``amx``, ``jmx``}: the jerk-limited point-to-point move.

What the reader assumes where the format does not say (checked against public example files
wherever they allow):

- ``xyz`` and ``phithetapsi`` are the thesis' frame (x forward, y right, z down) and Euler
  angles, offsets from the neutral pose: they map onto surge, sway, heave, roll, pitch, yaw;
- a pose is ``from + axis * s(t)``, ``s`` being the profile's output; for a ``Movement`` the
  ``move`` pose is the displacement (checked: it must equal ``axis * dist``), for a
  ``ProfileMotion`` it is not used (the public files put the axis' direction there);
- the fade of a ``FadedSineProfile`` is a raised cosine lasting ``Tfade`` at each end;
- a ``ConstantAccelProfile`` reaches ``ai`` from ``a0`` and leaves it for ``a1`` by linear
  jerk ramps of equal length, solved from ``v1`` (the public files' ``Ttotal`` then has
  10 ms ramps, and the pose each move ends at is the next one's ``from`` to 1e-12 m);
- a ``Profile`` move is the seven-phase jerk-limited move (its duration reproduces each
  public file's ``dt`` to 10 ms);
- the ``uvw`` and ``pqr`` of a pose (speeds, zero in every public file) are read and not
  used: the profile defines the motion;
- ``Ttotal`` and ``dt`` must agree (the move lasts ``dt``); a ``Still`` lasts until the next
  move starts (the last one, one second).

Anything else is refused in one line naming the move (its number, from 1, and its time).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from twin.core.checks import check_keys, number, numbers, read_json
from twin.core.errors import ScheduleError
from twin.formats.schedule.moves import Move, Schedule, sorted_moves

FORMAT = "MovementSeries"
#: A still move at the end of a schedule lasts this long [s].
LAST_STILL_S = 1.0
#: Keys a pose may have.
POSE_KEYS = ("type", "xyz", "phithetapsi", "uvw", "pqr")
#: Profile type -> (move kind, parameter names in the file).
PROFILES: dict[str, tuple[str, tuple[str, ...]]] = {
    "FadedSineProfile": ("sines", ("omg", "gain", "phi0", "Tfade", "Ttotal")),
    "ConstantAccelProfile": ("constant_acceleration", ("a0", "a1", "ai", "v0", "v1", "Ttotal")),
    "ConstantSpeedProfile": ("constant_speed", ("v0", "Ttotal")),
    "Profile": ("point_to_point", ("dist", "vmx", "amx", "jmx")),
}
#: Move types and the profiles each takes.
MOVE_TYPES = {
    "Still": (),
    "ProfileMotion": ("FadedSineProfile", "ConstantAccelProfile", "ConstantSpeedProfile"),
    "Movement": ("Profile",),
}
#: How far a profile's ``Ttotal`` may differ from its move's ``dt`` [s].
DURATION_TOL = 1e-6


def looks_like(doc: object) -> bool:
    """Return True for a parsed JSON document that says it is a ``MovementSeries``."""
    return isinstance(doc, dict) and doc.get("type") == FORMAT


def read_movement_series(path: str | Path) -> Schedule:
    """Read a ``MovementSeries`` JSON file.

    Raises
    ------
    ScheduleError
        For a file that is not JSON, not a ``MovementSeries``, or has a move the reader
        refuses (named by its number and time).

    """
    doc = read_json(path, "a MovementSeries JSON schedule", ScheduleError)
    return movement_series(doc, str(path), Path(path).stem)


def movement_series(doc: object, source: str, name: str) -> Schedule:
    """Return the schedule of a parsed ``MovementSeries`` document (see the module)."""
    if not looks_like(doc):
        raise ScheduleError(
            f'{source}: not a MovementSeries (a JSON object with "type": '
            f'"{FORMAT}" and a list of "moves")'
        )
    entries = doc.get("moves")  # type: ignore[union-attr]
    if not isinstance(entries, list) or not entries:
        raise ScheduleError(f'{source}: "moves" must be a non-empty list of moves')
    starts = []
    for i, e in enumerate(entries, 1):
        if not isinstance(e, dict) or "time" not in e or "move" not in e:
            raise ScheduleError(f'{source}: move {i} must be an object with "time" and "move"')
        starts.append(number(e["time"], f"{source}: move {i} time", lo=0, error=ScheduleError))
    moves = []
    for i, (e, start) in enumerate(zip(entries, starts, strict=True), 1):
        later = [s for s in starts[i:] if s > start]
        moves.append(_move(e["move"], i, start, min(later) if later else None, source))
    return Schedule(name, source, sorted_moves(moves), FORMAT)


def _move(m: object, i: int, start: float, next_start: float | None, source: str) -> Move:
    """Return move ``i`` of the file (``next_start``: when the next move starts, for Still)."""
    where = f"{source}: move {i} (t = {start:g} s)"
    if not isinstance(m, dict) or m.get("type") not in MOVE_TYPES:
        kind = m.get("type") if isinstance(m, dict) else m
        raise ScheduleError(
            f"{where}: unknown move type {kind!r}; allowed: {', '.join(MOVE_TYPES)}"
        )
    if m["type"] == "Still":
        check_keys(m, POSE_KEYS, where, ScheduleError)
        pose = _pose(m, where)
        duration = LAST_STILL_S if next_start is None else next_start - start
        return Move(i, start, duration, "still", pose, np.zeros(6), {}, "Still")
    check_keys(m, ("type", "from", "move", "axis", "profile", "dt"), where, ScheduleError)
    for key in ("from", "axis", "profile", "dt"):
        if key not in m:
            raise ScheduleError(f"{where}: a {m['type']} needs {key!r}")
    origin = _pose(m["from"], f"{where} from")
    axis = numbers(m["axis"], f"{where} axis", size=6, error=ScheduleError)
    if not np.any(axis):
        raise ScheduleError(f"{where}: axis is all zero; it gives the direction of the motion")
    dt = number(m["dt"], f"{where} dt", lo=0, lo_open=True, error=ScheduleError)
    prof = m["profile"]
    ptype = prof.get("type") if isinstance(prof, dict) else None
    if ptype not in MOVE_TYPES[m["type"]]:
        raise ScheduleError(
            f"{where}: profile {ptype!r} in a {m['type']}; allowed: "
            f"{', '.join(MOVE_TYPES[m['type']])}"
        )
    kind, keys = PROFILES[ptype]
    check_keys(prof, ("type", *keys), f"{where} profile", ScheduleError)
    missing = [k for k in keys if k not in prof]
    if missing:
        raise ScheduleError(f"{where}: {ptype} needs {', '.join(missing)}")
    if "Ttotal" in prof:
        total = number(prof["Ttotal"], f"{where} Ttotal", lo=0, lo_open=True, error=ScheduleError)
        if abs(total - dt) > DURATION_TOL:
            raise ScheduleError(
                f"{where}: Ttotal {total:g} s and dt {dt:g} s differ; the move lasts one time"
            )
    params = _parameters(ptype, prof, f"{where} {ptype}")
    if m["type"] == "Movement" and "move" in m:
        shift = _pose(m["move"], f"{where} move")
        want = axis * float(params["distance"])  # type: ignore[arg-type]
        if np.abs(shift - want).max() > 1e-6 * max(1.0, np.abs(want).max()):
            raise ScheduleError(
                f"{where}: the displacement 'move' {shift.tolist()} is not "
                f"axis x dist {want.tolist()}"
            )
    return Move(i, start, dt, kind, origin, axis, params, f"{m['type']} {ptype}")


def _parameters(ptype: str, p: Mapping[str, object], where: str) -> dict[str, object]:
    """Return a profile's parameters under :data:`twin.formats.schedule.moves.KINDS`' names."""

    def num(key: str, **kw: object) -> float:
        return number(p[key], f"{where} {key}", error=ScheduleError, **kw)  # type: ignore[arg-type]

    if ptype == "FadedSineProfile":
        omg, gain, phi = (
            numbers(p[k], f"{where} {k}", error=ScheduleError).tolist()
            for k in ("omg", "gain", "phi0")
        )
        if not len(omg) == len(gain) == len(phi):
            raise ScheduleError(
                f"{where}: omg, gain and phi0 must have one entry per sine; "
                f"got {len(omg)}, {len(gain)}, {len(phi)}"
            )
        if min(omg) <= 0:
            raise ScheduleError(f"{where}: every omg must be > 0 rad/s; got {omg}")
        return {"omega_rad_s": omg, "gain": gain, "phase_rad": phi, "t_fade_s": num("Tfade", lo=0)}
    if ptype == "ConstantAccelProfile":
        return {
            "acceleration": num("ai"),
            "v_start": num("v0"),
            "v_end": num("v1"),
            "a_start": num("a0"),
            "a_end": num("a1"),
        }
    if ptype == "ConstantSpeedProfile":
        return {"speed": num("v0")}
    return {
        "distance": num("dist", lo=0),
        "vmax": num("vmx", lo=0, lo_open=True),
        "amax": num("amx", lo=0, lo_open=True),
        "jmax": num("jmx", lo=0, lo_open=True),
    }


def _pose(p: object, where: str) -> np.ndarray:
    """Return (surge, sway, heave, roll, pitch, yaw) of a pose object."""
    if not isinstance(p, dict):
        raise ScheduleError(f"{where}: a pose must be an object with xyz and phithetapsi")
    check_keys(p, POSE_KEYS, where, ScheduleError)
    xyz = numbers(p.get("xyz", [0, 0, 0]), f"{where} xyz", size=3, error=ScheduleError)
    ang = numbers(
        p.get("phithetapsi", [0, 0, 0]), f"{where} phithetapsi", size=3, error=ScheduleError
    )
    for key in ("uvw", "pqr"):  # speeds: read (they must be numbers), not used
        if key in p:
            numbers(p[key], f"{where} {key}", size=3, error=ScheduleError)
    return np.concatenate([xyz, ang])
