"""Test schedules as motion labs write them: read, turned into commands, split by test.

:func:`read_schedule` reads a SIMONA Research Simulator ``MovementSeries`` (``.json``,
:mod:`twin.formats.schedule.movement_series`) or the twin's own ``twin-schedule/1`` (``.toml``,
:mod:`twin.formats.schedule.toml_schedule`) into a :class:`~twin.formats.schedule.moves.Schedule`.
"""

from __future__ import annotations

from pathlib import Path

from twin.core.errors import ScheduleError
from twin.formats.schedule.movement_series import read_movement_series
from twin.formats.schedule.moves import Move, Schedule
from twin.formats.schedule.toml_schedule import read_toml_schedule

__all__ = ["SUFFIXES", "Move", "Schedule", "read_schedule"]

#: File suffixes of schedules and their readers.
SUFFIXES = {".json": read_movement_series, ".toml": read_toml_schedule}


def read_schedule(path: str | Path) -> Schedule:
    """Read a schedule file: ``.json`` (``MovementSeries``) or ``.toml`` (``twin-schedule/1``).

    Raises
    ------
    ScheduleError
        For another suffix, or a file its reader refuses (one line naming the move).

    """
    reader = SUFFIXES.get(Path(path).suffix.lower())
    if reader is None:
        raise ScheduleError(
            f"{path}: a schedule is a .json MovementSeries or a .toml twin-schedule/1 file"
        )
    return reader(path)
