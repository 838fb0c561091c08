"""Where each AGARD-AR-144 test finds its data in a scheduled run: windows of moves.

A lab runs a whole test schedule (:mod:`twin.formats.schedule`) as one long run; each move serves
one test (:func:`twin.formats.schedule.moves.test_of`). This module turns the moves into analysis
windows on the run's clock: a sine move's window is the longest whole number of periods of
all its frequencies between its fade-in and its fade-out; other moves are used whole.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from twin.core.checks import number
from twin.core.errors import SignalError
from twin.core.frames import dof_index
from twin.formats.schedule.moves import Move, Schedule

FloatArray = NDArray[np.float64]
#: A window's frequencies must each fit a whole number of periods to this share of a period.
WHOLE_PERIODS = 1e-3
#: Least periods of the lowest frequency a sine window must hold.
MIN_PERIODS = 1
#: Largest distance of a given window's periods from a whole number (leakage otherwise).
WHOLE_PERIODS_TOLERANCE = 0.01
#: Largest relative difference between a segment's stated amplitude and the commanded one.
AMPLITUDE_TOLERANCE = 0.25


@dataclass(frozen=True)
class Segment:
    """One move of a scheduled run, as a test uses it.

    Attributes
    ----------
    move : Move
        The schedule's move.
    window : tuple of float
        Analysis window on the run's clock [s].
    frequencies_hz : ndarray
        The move's frequencies (sines; empty otherwise).
    amplitude : float
        Largest pose amplitude of a sines move in its DOF's units (0 otherwise).
    rest_until_s : float
        Until when the platform stays at rest after the move, on the run's clock: the start
        of the next move that is not still (the end of the schedule after the last). A
        platform behind its filter and delay arrives there.

    """

    move: Move
    window: tuple[float, float]
    frequencies_hz: FloatArray
    amplitude: float
    rest_until_s: float = np.nan

    @property
    def dof(self) -> str:
        """The driven DOF."""
        return self.move.dof or ""

    @property
    def k(self) -> int:
        """The driven DOF's index."""
        return dof_index(self.dof)


def window_in(
    window: Sequence[object] | None, span: tuple[float, float], test: str
) -> tuple[float, float]:
    """Return a user's analysis window (start, end) checked to lie in ``span``; None: ``span``.

    Raises
    ------
    SignalError
        Naming the ``test``: not two numbers, or not an interval inside ``span``.

    """
    if window is None:
        return span
    if len(window) != 2:
        raise SignalError(f"a {test} window is (start, end) in seconds; got {window!r}")
    lo = number(window[0], f"{test} window start [s]", lo=span[0], hi=span[1], error=SignalError)
    hi = number(window[1], f"{test} window end [s]", lo=lo, lo_open=True, hi=span[1],
                error=SignalError)  # fmt: skip
    return lo, hi


def checked_window(
    where: str,
    frequency_hz: object,
    amplitude: object,
    window: tuple[object, object],
    span: tuple[float, float],
    f_range: tuple[float, float] = (0.0, np.inf),
) -> tuple[float, float, float]:
    """Return (frequency, start, end) of a one-sine segment given by a user, checked.

    Raises
    ------
    SignalError
        Naming ``where``: a frequency outside ``f_range`` (its low end open at 0), an amplitude
        that is not positive, a window outside ``span`` (what was measured) or one that does not
        hold a whole number of periods (1 or more, within :data:`WHOLE_PERIODS_TOLERANCE`).

    """
    f = number(frequency_hz, f"{where}: frequency [Hz]", lo=f_range[0], hi=f_range[1],
               lo_open=f_range[0] == 0, error=SignalError)  # fmt: skip
    number(amplitude, f"{where}: amplitude", lo=0, lo_open=True, error=SignalError)
    start = number(window[0], f"{where}: start_s", error=SignalError)
    end = number(window[1], f"{where}: end_s", error=SignalError)
    if not (span[0] - 1e-6 <= start < end <= span[1] + 1e-6):
        raise SignalError(f"{where}: the window {start:g}-{end:g} s must be non-empty and lie "
                          f"within what was measured ({span[0]:g}-{span[1]:g} s)")  # fmt: skip
    periods = (end - start) * f
    if round(periods) < 1 or abs(periods - round(periods)) > WHOLE_PERIODS_TOLERANCE:
        raise SignalError(f"{where}: the window {start:g}-{end:g} s holds {periods:.3f} periods "
                          "of the sine; it must hold a whole number (1 or more)")  # fmt: skip
    return f, start, end


def sine_window(move: Move, offset_s: float = 0.0) -> tuple[float, float] | None:
    """Return the longest whole-periods window between a sine move's fades (None: too short).

    The window ends where the fade-out starts and holds ``n`` periods of the lowest
    frequency, ``n`` the largest for which every frequency fits whole periods (to
    :data:`WHOLE_PERIODS`).
    """
    f = move.frequencies_hz
    fade = float(move.parameters.get("t_fade_s", 0.0))  # type: ignore[arg-type]
    lo, hi = move.start_s + fade + offset_s, move.end_s - fade + offset_s
    f_min = float(f.min())
    for n in range(int(np.floor((hi - lo) * f_min + 1e-9)), MIN_PERIODS - 1, -1):
        length = n / f_min
        cycles = f * length
        if np.abs(cycles - np.round(cycles)).max() <= WHOLE_PERIODS:
            return hi - length, hi
    return None


def segments(
    schedule: Schedule, test: str, offset_s: float = 0.0
) -> tuple[list[Segment], list[str]]:
    """Return the segments of the moves serving ``test``, and why any move was left out.

    Parameters
    ----------
    schedule : Schedule
        The run's schedule.
    test : str
        ``df``, ``hysteresis``, ``bump``, ``limits`` or ``noise`` (see
        :func:`~twin.formats.schedule.moves.test_of`).
    offset_s : float
        Time of the schedule's t = 0 on the run's clock.

    """
    out, skipped = [], []
    for move in schedule.tests().get(test, []):
        if move.kind == "sines":
            window = sine_window(move, offset_s)
            if window is None:
                skipped.append(f"move {move.number}: shorter than a whole period between its fades")
                continue
            out.append(Segment(move, window, move.frequencies_hz, float(move.amplitudes.max())))
        else:
            span = (move.start_s + offset_s, move.end_s + offset_s)
            later = [m.start_s for m in schedule.moves
                     if m.start_s >= move.end_s - 1e-9 and m.kind != "still"]  # fmt: skip
            rest = min(later, default=schedule.duration_s) + offset_s
            out.append(Segment(move, span, np.zeros(0), 0.0, rest))
    return out, skipped


def by_dof(segs: Sequence[Segment]) -> dict[str, list[Segment]]:
    """Group segments by driven DOF (in the order of the DOFs' first moves)."""
    out: dict[str, list[Segment]] = {}
    for s in segs:
        out.setdefault(s.dof, []).append(s)
    return out


def largest_per_frequency(segs: Sequence[Segment]) -> list[Segment]:
    """Keep, for each set of frequencies, the move with the largest amplitude (the DF's)."""
    best: dict[tuple[float, ...], Segment] = {}
    for s in segs:
        key = tuple(np.round(s.frequencies_hz, 9))
        if key not in best or s.amplitude > best[key].amplitude:
            best[key] = s
    return sorted(best.values(), key=lambda s: float(s.frequencies_hz.min()))
