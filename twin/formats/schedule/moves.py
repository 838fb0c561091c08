"""A test schedule: timed moves of the platform, and the pose commands they make.

A schedule is what a motion lab runs on its platform: a list of moves, each starting at a
time, from a pose, along a direction in the six DOFs (``axis``: the direction and the scale,
e.g. 0.7 rad per unit for rotations), driven by one profile (:mod:`twin.chain.profiles`). Between
moves the platform holds the last pose. Readers (:mod:`twin.formats.schedule.movement_series` for
the SIMONA Research Simulator's JSON, :mod:`twin.formats.schedule.toml_schedule` for the twin's own
TOML) build a :class:`Schedule`; it checks that the moves follow each other without a jump in pose
or speed, makes the commands (:meth:`Schedule.commands`), travels in a run's ``meta.json``
(:meth:`Schedule.to_json`, :meth:`Schedule.from_json`) and says which AGARD-AR-144 test each
move serves (:func:`test_of`).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from twin.chain.profiles import (
    JerkProfile,
    constant_acceleration,
    constant_speed,
    faded_sines,
    faded_sines_rate,
    point_to_point,
)
from twin.chain.trajectory import Trajectory
from twin.core.checks import check_duration
from twin.core.errors import ScheduleError, SignalError
from twin.core.frames import DOF_NAMES

FloatArray = NDArray[np.float64]

#: Move kinds and the parameters each profile takes (SI units; rad/s for ``omega``).
KINDS: dict[str, tuple[str, ...]] = {
    "still": (),
    "sines": ("omega_rad_s", "gain", "phase_rad", "t_fade_s"),
    "constant_acceleration": ("acceleration", "v_start", "v_end", "a_start", "a_end"),
    "constant_speed": ("speed",),
    "point_to_point": ("distance", "vmax", "amax", "jmax"),
}
#: Largest mismatch between where a move starts and where the one before it left the platform,
#: in the pose's units (m, rad): 1 mm or 1 mrad (a schedule's rounding, not a jump).
POSE_TOL = 1e-3
#: Largest step in speed between one move and the next (units/s): the SRS's public bump
#: schedule steps 5 mm/s into its last move; a larger step is a schedule error.
SPEED_TOL = 0.01
#: Times closer than this are the same instant [s].
TIME_TOL = 1e-6
#: A single sine at or below this frequency is a hysteresis move (AR-144 D and E: 6 and 1.5
#: mHz; the twin's own hysteresis test: 50 mHz).
HYSTERESIS_HZ = 0.05


@dataclass(frozen=True, eq=False)
class Move:
    """One move of a schedule.

    Attributes
    ----------
    number : int
        Position in the schedule file, from 1 (messages name it).
    start_s, duration_s : float
        When it starts and how long it lasts [s].
    kind : str
        One of :data:`KINDS`.
    origin : ndarray, shape (6,)
        Pose at its start (offsets from neutral, m and rad).
    axis : ndarray, shape (6,)
        Direction and scale: the pose is ``origin + axis * s(t)``.
    parameters : dict of str to float or list of float
        The profile's parameters (:data:`KINDS`).
    label : str
        What the schedule called it (type and profile), for messages and reports.

    """

    number: int
    start_s: float
    duration_s: float
    kind: str
    origin: FloatArray
    axis: FloatArray
    parameters: Mapping[str, object] = field(default_factory=dict)
    label: str = ""
    _profile: JerkProfile | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        """Check the kind and build the profile (a bad parameter names the move)."""
        if self.kind not in KINDS:
            raise ScheduleError(
                f"move {self.number}: unknown kind {self.kind!r}; allowed: {', '.join(KINDS)}"
            )
        object.__setattr__(self, "origin", np.asarray(self.origin, dtype=float))
        object.__setattr__(self, "axis", np.asarray(self.axis, dtype=float))
        try:
            object.__setattr__(self, "_profile", self._make_profile())
        except SignalError as e:
            raise ScheduleError(f"move {self.number} ({self.label or self.kind}): {e}") from e

    def _make_profile(self) -> JerkProfile | None:
        p, t = self.parameters, self.duration_s
        if self.kind == "constant_acceleration":
            return constant_acceleration(
                float(p["acceleration"]),
                float(p["v_start"]),
                float(p["v_end"]),
                t,  # type: ignore[arg-type]
                float(p.get("a_start", 0.0)),
                float(p.get("a_end", 0.0)),  # type: ignore[arg-type]
            )
        if self.kind == "constant_speed":
            return constant_speed(float(p["speed"]), t)  # type: ignore[arg-type]
        if self.kind == "point_to_point":
            prof = point_to_point(*(float(p[k]) for k in KINDS["point_to_point"]))  # type: ignore[arg-type]
            if prof.duration > t + 0.5e-2:
                raise SignalError(
                    f"the profile takes {prof.duration:.3f} s, longer than the "
                    f"move's duration {t:g} s"
                )
            return prof
        return None

    @property
    def end_s(self) -> float:
        """When the move ends [s]."""
        return self.start_s + self.duration_s

    def path(self, t: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Return the path coordinate s and its speed at times ``t`` from the move's start."""
        if self._profile is not None:
            s, v, _, _ = self._profile.at(t)
            return s, v
        if self.kind == "sines":
            p = self.parameters
            args = (p["omega_rad_s"], p["gain"], p["phase_rad"], p["t_fade_s"], self.duration_s)
            return faded_sines(t, *args), faded_sines_rate(t, *args)  # type: ignore[arg-type]
        return np.zeros_like(t), np.zeros_like(t)

    def poses(self, t: FloatArray) -> FloatArray:
        """Return the poses (n, 6) at times ``t`` from the move's start."""
        s, _ = self.path(np.asarray(t, dtype=float))
        return self.origin + np.multiply.outer(s, self.axis)

    def end(self) -> tuple[FloatArray, FloatArray]:
        """Return the pose and the pose rate at the move's end."""
        s, v = self.path(np.array([self.duration_s]))
        return self.origin + s[0] * self.axis, v[0] * self.axis

    @property
    def dof(self) -> str | None:
        """The one DOF the move drives (None: still, or several at once)."""
        moving = np.flatnonzero(np.abs(self.axis) > 0)
        return DOF_NAMES[moving[0]] if len(moving) == 1 and self.kind != "still" else None

    @property
    def frequencies_hz(self) -> FloatArray:
        """Frequencies of a sines move [Hz] (empty for other kinds)."""
        if self.kind != "sines":
            return np.zeros(0)
        return np.asarray(self.parameters["omega_rad_s"], dtype=float) / (2 * np.pi)

    @property
    def amplitudes(self) -> FloatArray:
        """Pose amplitudes of a sines move in its DOF's units (gain times the axis' scale)."""
        if self.kind != "sines":
            return np.zeros(0)
        return np.abs(np.asarray(self.parameters["gain"], dtype=float)) * float(
            np.linalg.norm(self.axis)
        )

    def to_json(self) -> dict[str, object]:
        """Return the move as plain JSON (the schedule's entry in ``meta.json``)."""
        return {
            "number": self.number,
            "start_s": self.start_s,
            "duration_s": self.duration_s,
            "kind": self.kind,
            "origin": self.origin.tolist(),
            "axis": self.axis.tolist(),
            "parameters": {k: _plain(v) for k, v in self.parameters.items()},
            "label": self.label,
            "dof": self.dof,
            "test": test_of(self),
        }

    @classmethod
    def from_json(cls, d: Mapping[str, object]) -> Move:
        """Return the move :meth:`to_json` wrote."""
        return cls(
            int(d["number"]),
            float(d["start_s"]),
            float(d["duration_s"]),
            str(d["kind"]),  # type: ignore[arg-type]
            np.asarray(d["origin"], dtype=float),
            np.asarray(d["axis"], dtype=float),
            dict(d["parameters"]),
            str(d.get("label", "")),  # type: ignore[arg-type]
        )


def _plain(v: object) -> object:
    return v.tolist() if isinstance(v, np.ndarray) else v


def test_of(move: Move) -> str | None:
    """Return the AGARD-AR-144 test a move serves, or None.

    ``noise`` (a still move: the platform at rest), ``hysteresis`` (a single sine at or below
    :data:`HYSTERESIS_HZ`), ``df`` (sines in one DOF: a describing-function point; several
    amplitudes of one frequency make ``linearity``, every DOF driven makes ``parasitic``),
    ``bump`` (a constant acceleration through a speed reversal), ``limits`` (a
    point-to-point move), None for anything else (e.g. a move in several DOFs at once).
    """
    if move.kind == "still":
        return "noise"
    if move.dof is None:
        return None
    if move.kind == "sines":
        f = move.frequencies_hz
        return "hysteresis" if len(f) == 1 and f[0] <= HYSTERESIS_HZ + 1e-12 else "df"
    if move.kind == "constant_acceleration":
        p = move.parameters
        return "bump" if float(p["v_start"]) * float(p["v_end"]) < 0 else None  # type: ignore[arg-type]
    if move.kind == "point_to_point":
        return "limits"
    return None


@dataclass(frozen=True, eq=False)
class Schedule:
    """A test schedule (see the module docstring).

    Attributes
    ----------
    name : str
        Its name (the file's stem, or the name it gives itself).
    source : str
        Where it was read from.
    moves : tuple of Move
        The moves, in time order, checked to follow each other.
    format : str
        The file format it was read from (``"MovementSeries"``, ``"twin-schedule/1"``).

    """

    name: str
    source: str
    moves: tuple[Move, ...]
    format: str = "twin-schedule/1"

    def __post_init__(self) -> None:
        """Check that there are moves and that each follows the one before it."""
        if not self.moves:
            raise ScheduleError(f"{self.source}: the schedule has no moves")
        first = self.moves[0]
        _check_at_rest(first.path(np.array([0.0]))[1][0] * first.axis,
                       f"{self.source}: move {first.number} ({first.label or first.kind}) starts",
                       "the start")  # fmt: skip
        for before, move in zip(self.moves, self.moves[1:], strict=False):
            _check_follows(before, move, self.source)

    @property
    def slug(self) -> str:
        """The name as a file name: letters, digits, ``.``, ``_`` and ``-`` only."""
        return re.sub(r"[^A-Za-z0-9._-]+", "-", self.name).strip("-.") or "schedule"

    @property
    def duration_s(self) -> float:
        """End of the last move [s] (a still move lasts at least one second)."""
        return max(m.end_s for m in self.moves)

    def commands(self, rate_hz: float = 100.0) -> Trajectory:
        """Return the pose commands from t = 0 to the end of the last move at ``rate_hz``."""
        check_duration(self.duration_s, f"schedule {self.name}", ScheduleError)
        n = round(self.duration_s * rate_hz) + 1
        t = np.arange(n) / rate_hz
        poses = np.tile(self.moves[0].origin, (n, 1))
        starts = np.array([m.start_s for m in self.moves])
        which = np.searchsorted(starts, t + TIME_TOL, side="right") - 1
        for k, move in enumerate(self.moves):
            rows = which == k
            if rows.any():
                rel = np.minimum(t[rows] - move.start_s, move.duration_s)
                poses[rows] = move.poses(rel)
        return Trajectory(rate_hz, poses)

    def tests(self) -> dict[str, list[Move]]:
        """Return the moves each AGARD-AR-144 test can use (:func:`test_of`)."""
        out: dict[str, list[Move]] = {}
        for m in self.moves:
            test = test_of(m)
            if test is not None:
                out.setdefault(test, []).append(m)
        return out

    def to_json(self) -> dict[str, object]:
        """Return the schedule as plain JSON (``meta.json``'s ``schedule``)."""
        return {
            "name": self.name,
            "source": self.source,
            "format": self.format,
            "moves": [m.to_json() for m in self.moves],
        }

    @classmethod
    def from_json(cls, d: object, where: str = "schedule") -> Schedule:
        """Return the schedule :meth:`to_json` wrote (``where`` names it in errors).

        Raises
        ------
        ScheduleError
            For anything :meth:`to_json` does not write, or moves that do not follow.

        """
        try:
            moves = tuple(Move.from_json(m) for m in d["moves"])  # type: ignore[index]
            return cls(str(d["name"]), str(d["source"]), moves, str(d.get("format", "")))  # type: ignore[index,union-attr]
        except (KeyError, TypeError, ValueError, AttributeError, IndexError) as e:
            if isinstance(e, ScheduleError):
                raise
            raise ScheduleError(f"{where}: not a schedule as the twin writes it ({e!r:.80})") from e


def _check_follows(before: Move, move: Move, source: str) -> None:
    """Refuse a move that overlaps the one before it, or leaves its pose or speed.

    After a pause between them both must be at rest.
    """
    where = f"{source}: move {move.number} ({move.label or move.kind})"
    if move.start_s < before.end_s - TIME_TOL:
        raise ScheduleError(f"{where} starts at {move.start_s:g} s, before move {before.number} "
                            f"ends ({before.end_s:g} s); moves must not overlap")  # fmt: skip
    pose, rate = before.end()
    start = move.poses(np.array([0.0]))[0]
    jump = np.abs(start - pose)
    if (jump > POSE_TOL).any():
        k = int(np.argmax(jump))
        raise ScheduleError(
            f"{where} starts at {DOF_NAMES[k]} {start[k]:.6g} but move {before.number} "
            f"leaves it at {pose[k]:.6g}: a jump of {jump[k]:.3g} cannot be commanded (allowed: "
            f"{POSE_TOL:g} m or rad)"
        )
    speed_in = move.path(np.array([0.0]))[1][0] * move.axis
    if move.start_s - before.end_s > TIME_TOL:  # a pause between them: at rest on both sides
        _check_at_rest(rate, f"{where}: move {before.number} ends", "the pause after it")
        _check_at_rest(speed_in, where, "the pause before it")
        return
    jump_v = np.abs(speed_in - rate)
    if (jump_v > SPEED_TOL).any():
        k = int(np.argmax(jump_v))
        raise ScheduleError(
            f"{where}: the {DOF_NAMES[k]} speed jumps from {rate[k]:.4g} to {speed_in[k]:.4g} "
            f"(move {before.number} ends at {before.end_s:g} s, this one starts at "
            f"{move.start_s:g} s); a move must start at the speed the one before ended with"
        )


def _check_at_rest(speed: FloatArray, where: str, what: str) -> None:
    """Refuse a speed above :data:`SPEED_TOL` where the platform must be at rest."""
    if (np.abs(speed) > SPEED_TOL).any():
        k = int(np.argmax(np.abs(speed)))
        raise ScheduleError(f"{where} at {DOF_NAMES[k]} speed {speed[k]:.4g}, but the platform "
                            f"rests in {what} (allowed: {SPEED_TOL:g} per s)")  # fmt: skip


def sorted_moves(moves: Sequence[Move]) -> tuple[Move, ...]:
    """Return the moves in order of start time (a stable sort: file order breaks ties)."""
    return tuple(sorted(moves, key=lambda m: m.start_s))
