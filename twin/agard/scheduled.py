"""The AGARD-AR-144 report of a recorded (or scheduled) run: the tests it holds, and not.

A lab's schedule (:mod:`twin.formats.schedule`) runs many tests in one run. :func:`analyse_schedule`
finds each test's moves (:mod:`twin.agard.segments`), runs the test's analysis on their
windows and says which tests the run does not hold, and why (what moves they need). The
tests and what they take from a schedule are :data:`ANALYSES`. A run made for one test
(its ``meta.json`` names the signal design) is reported by :func:`analyse_designed`.
:meth:`RunReport.write` writes the report folder (``report.json``, ``summary.md``, a figure
per test and DOF).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from twin.agard import bump, df, hysteresis, limits, linearity, parasitic, threshold
from twin.agard.positions import PositionRecord
from twin.agard.segments import Segment, by_dof, largest_per_frequency, segments
from twin.core.errors import SignalError
from twin.core.frames import DOF_NAMES
from twin.core.lifecycle import writing
from twin.formats.schedule.moves import HYSTERESIS_HZ, Schedule
from twin.measurement.measure import Measurement, driven_dof


@dataclass(frozen=True)
class Analysis:
    """How one test is read from a schedule.

    Attributes
    ----------
    moves : str
        The move class it uses (:func:`twin.formats.schedule.moves.test_of`).
    needs : str
        What the schedule must hold for it (the "missing" message).
    analyse : callable
        ``(measurement, segments of one DOF, positions) -> result`` (``per_dof``), or of
        every DOF; ``positions`` is the run's pose record (None: the run has none).
    per_dof : bool
        One result per driven DOF, or one for all.

    """

    moves: str
    needs: str
    analyse: Callable[[Measurement, list[Segment], PositionRecord | None], object]
    per_dof: bool = True


def _plain_figure(result: object, m: Measurement) -> object:
    return result.plot()  # type: ignore[attr-defined]


#: Tests whose figure needs more than the result (default: ``result.plot()``).
FIGURES: dict[str, Callable[[object, Measurement], object]] = {
    "df": lambda r, m: r.plot(config=m.config),  # type: ignore[attr-defined]
}


def _df(m: Measurement, segs: list[Segment], positions: object = None) -> df.DfResult:
    """Return the describing function of one DOF: its largest amplitude per frequency."""
    big = largest_per_frequency(segs)
    return df.analyse_windows(m, big[0].k, [(s.frequencies_hz, s.window) for s in big])


def _parasitic(
    m: Measurement, segs: list[Segment], positions: object = None
) -> parasitic.ParasiticResult:
    """Return the parasitic motion of every driven DOF: largest amplitude per frequency."""
    return parasitic.analyse_segments(
        {
            dof: [
                parasitic.Segment(m, s.window, tuple(s.frequencies_hz))
                for s in largest_per_frequency(group)
            ]
            for dof, group in by_dof(segs).items()
        }
    )


def _single_sines(segs: list[Segment]) -> list[Segment]:
    return [s for s in segs if len(s.frequencies_hz) == 1]


def _linearity_points(segs: list[Segment]) -> list[Segment]:
    """Single sines at frequencies the schedule runs at two amplitudes or more."""
    amplitudes: dict[float, set[float]] = {}
    for s in _single_sines(segs):
        amplitudes.setdefault(round(float(s.frequencies_hz[0]), 9), set()).add(s.amplitude)
    return [s for s in _single_sines(segs)
            if len(amplitudes[round(float(s.frequencies_hz[0]), 9)]) > 1]  # fmt: skip


def _linearity(
    m: Measurement, segs: list[Segment], positions: object = None
) -> linearity.LinearityResult:
    """Return the linearity of one DOF from its sines at two amplitudes or more."""
    points = [
        linearity.LinearitySegment(m, *s.window, float(s.frequencies_hz[0]),
                                   s.amplitude * (2 * np.pi * float(s.frequencies_hz[0])) ** 2)
        for s in _linearity_points(segs)
    ]  # fmt: skip
    if not points:
        raise NotInRun("no frequency run at two amplitudes or more")
    return linearity.analyse_linearity(points, segs[0].dof)


def _hysteresis(
    m: Measurement, segs: list[Segment], positions: PositionRecord | None
) -> hysteresis.HysteresisResult:
    """Return the hysteresis loops of one DOF's very-low-frequency sines."""
    if positions is None:
        raise NotInRun("the run has no position record (actuators.csv: leg lengths)")
    loops = [hysteresis.HysteresisSegment(positions, *s.window, float(s.frequencies_hz[0]),
                                          s.amplitude) for s in segs]  # fmt: skip
    return hysteresis.analyse_hysteresis(loops, segs[0].dof)


def _span(segs: list[Segment]) -> tuple[float, float]:
    return min(s.window[0] for s in segs), max(s.window[1] for s in segs)


def _bump(m: Measurement, segs: list[Segment], positions: object = None) -> bump.BumpResult:
    """Return the turn-around bumps of one DOF: every reversal from its first to its last."""
    lo, hi = _span(segs)  # widened: the platform turns round after its filter and delay
    window = (max(lo, float(m.t[0])), _settled(m, segs[-1], hi, BUMP_MARGIN_S))
    return bump.analyse_bump(m, segs[0].dof, window=window)


def _settled(m: Measurement, seg: Segment, end: float, most_s: float) -> float:
    """Return ``end`` widened by up to ``most_s`` while the platform rests after ``seg``."""
    if seg.move.kind == "constant_acceleration" or not np.isfinite(seg.rest_until_s):
        return min(end + most_s, float(m.t[-1]))
    return min(max(end, min(end + most_s, seg.rest_until_s)), float(m.t[-1]))


def _limits(
    m: Measurement, segs: list[Segment], positions: PositionRecord | None
) -> limits.LimitsResult:
    """Return the limits one DOF's point-to-point moves reached, and what stopped each.

    Without the limiter's counts per move (a recorded run has none), what stopped a move is
    found from its shortfall against the commands (:data:`twin.agard.limits.SHORTFALL`).
    """
    if positions is None:
        raise NotInRun("the run has no position record (actuators.csv: leg lengths)")
    pose = positions.on(m.t)
    levels = tuple(
        limits.analyse_limits(m, pose, segs[0].dof,
                              window=(s.window[0], _settled(m, s, s.window[1], LIMITS_SETTLE_S)))
        for s in segs
    )  # fmt: skip
    computed = limits.dof_limits(m.config.platform, segs[0].dof)
    return limits.LimitsResult(segs[0].dof, levels, computed, m.source)


class NotInRun(Exception):
    """The run holds a test's moves, but not what the test needs from them (the reason)."""


#: Time a bump series' window reaches beyond its last reversal move [s]: the turn-around
#: comes after the platform filter's lag and the delay, and is measured up to 0.75 s after it
#: (the window starts with the first reversal move: no other move's speed change is in it).
BUMP_MARGIN_S = 1.5
#: Most a limits move's window reaches into the rest after it: the platform arrives late [s].
LIMITS_SETTLE_S = 2.0
#: Most a non-sine move may be cut at the ends of the run [s].
CLIP_S = 0.1

#: The tests a schedule can hold, in report order.
ANALYSES: dict[str, Analysis] = {
    "df": Analysis("df", "sine moves in one DOF", _df),
    "linearity": Analysis(
        "df", "single sines of one DOF at one frequency in two amplitudes or more", _linearity
    ),
    "parasitic": Analysis("df", "sine moves in one DOF at a time", _parasitic, per_dof=False),
    "hysteresis": Analysis(
        "hysteresis",
        f"a single sine at or below {HYSTERESIS_HZ:g} Hz in one DOF, and a position record",
        _hysteresis,
    ),
    "bump": Analysis("bump", "a constant acceleration through a speed reversal in one DOF", _bump),
    "limits": Analysis("limits", "point-to-point moves in one DOF, and a position record", _limits),
}
#: Tests no schedule move serves (they need the twin's own signals: ``twin agard TEST``).
NOT_FROM_SCHEDULES = {
    "noise": "needs the half-Hertz sines of §3.3.1 at six amplitudes (twin agard noise); "
    "still moves are not analysed",
    "snr": "needs the noise test's sines (twin agard snr)",
    "threshold": "needs the acceleration steps of §3.3.4 (twin agard threshold)",
    "omct": "needs the OMCT's twelve sines (twin agard omct)",
}


@dataclass(frozen=True)
class RunReport:
    """The tests a run holds, their results, and the tests it lacks.

    Attributes
    ----------
    source : str
        What was measured.
    schedule : Schedule or None
        The run's schedule (None: a run of one designed test signal).
    results : dict of str to dict of str to object
        Test -> DOF (or ``"all"``) -> result (with ``to_dict``, ``format_table``, ``plot``).
    missing : dict of str to str
        Test -> why the run does not hold it.
    skipped : dict of str to list of str
        Test -> moves left out, and why.

    """

    source: str
    schedule: Schedule | None
    results: dict[str, dict[str, object]]
    missing: dict[str, str]
    skipped: dict[str, list[str]]

    def to_dict(self) -> dict[str, object]:
        """Return the report as JSON."""
        s = self.schedule
        return {
            "source": self.source,
            "schedule": None
            if s is None
            else {"name": s.name, "source": s.source, "format": s.format, "moves": len(s.moves)},
            "tests": {
                t: {d: r.to_dict() for d, r in rs.items()}  # type: ignore[attr-defined]
                for t, rs in self.results.items()
            },
            "missing": self.missing,
            "skipped": self.skipped,
        }

    def format_table(self) -> str:
        """Return the report as text (what ``summary.md`` holds, without figures)."""
        return "\n".join(self._md(figures={}))

    def _md(self, figures: dict[tuple[str, str], str]) -> list[str]:
        s = self.schedule
        md = [
            f"# AGARD-AR-144 report: {self.source}",
            "",
            "One designed test signal (meta.json's signal)."
            if s is None
            else f"Schedule `{s.name}` ({s.format}, {len(s.moves)} moves, {s.duration_s:.0f} s) "
            f"from {s.source}.",
            "",
        ]
        for test, rs in self.results.items():
            md += [f"## {test}", ""]
            for dof, r in rs.items():
                md += ["```", r.format_table(), "```"]  # type: ignore[attr-defined]
                if (test, dof) in figures:
                    md.append(f"![]({figures[test, dof]})")
                md.append("")
            md += [f"- {why}" for why in self.skipped.get(test, [])]
        if self.missing:
            md += ["## Not in this run", ""]
            md += [f"- **{t}**: {why}" for t, why in self.missing.items()]
            md.append("")
        return md

    def write(self, folder: Path, m: Measurement) -> None:
        """Write ``report.json``, ``summary.md`` and a figure per test and DOF into ``folder``."""
        figures = {}
        for test, rs in self.results.items():
            for dof, r in rs.items():
                fig = FIGURES.get(test, _plain_figure)(r, m)
                path = folder / f"{test}-{dof}.png"
                with writing(path):
                    fig.savefig(path, dpi=120)  # type: ignore[attr-defined]
                figures[test, dof] = path.name
        with writing(folder / "report.json") as path:
            path.write_text(json.dumps(self.to_dict(), indent=2) + "\n", encoding="utf-8")
        with writing(folder / "summary.md") as path:
            path.write_text("\n".join(self._md(figures)) + "\n", encoding="utf-8")


def analyse_schedule(
    m: Measurement,
    schedule: Schedule,
    tests: Sequence[str] | None = None,
    offset_s: float | None = None,
    positions: PositionRecord | None = None,
) -> RunReport:
    """Run every test the scheduled run holds; say which it does not.

    Parameters
    ----------
    m : Measurement
        The run.
    schedule : Schedule
        Its schedule.
    tests : sequence of str, optional
        Only these (default: all of :data:`ANALYSES`).
    offset_s : float, optional
        Time of the schedule's t = 0 on the run's clock (default: the commands' first sample).
    positions : PositionRecord, optional
        The run's poses (a simulation's, or from a recorded run's leg lengths): the
        hysteresis test needs them.

    """
    offset = m.commands.t0 if offset_s is None else offset_s
    results: dict[str, dict[str, object]] = {}
    missing: dict[str, str] = {}
    skipped: dict[str, list[str]] = {}
    for test in tests or ANALYSES:
        a = ANALYSES[test]
        segs, left_out = segments(schedule, a.moves, offset)
        segs = covered(segs, (float(m.t[0]), float(m.t[-1])))
        if left_out:
            skipped[test] = left_out
        if not segs:
            missing[test] = f"needs {a.needs}; the schedule has none" + (
                " that the run covers" if schedule.tests().get(a.moves) else ""
            )
            continue
        groups = by_dof(segs) if a.per_dof else {"all": segs}
        found, why = {}, []
        for dof, group in groups.items():
            try:
                found[dof] = a.analyse(m, group, positions)
            except (NotInRun, SignalError) as e:  # the report goes on: the reason is shown
                why.append(f"{dof}: {e}" if a.per_dof else str(e))
        if found:
            results[test] = found
            skipped.setdefault(test, []).extend(why)
        elif why:
            missing[test] = "; ".join(why)
    missing.update({t: why for t, why in NOT_FROM_SCHEDULES.items() if tests is None})
    skipped = {t: why for t, why in skipped.items() if why}
    return RunReport(m.source, schedule, results, missing, skipped)


def covered(segs: list[Segment], span: tuple[float, float]) -> list[Segment]:
    """Return the segments the run covers: a sine's window whole, another move's mostly.

    A move that is not a sine loses at most :data:`CLIP_S` at either end of the run (the
    IMU's last sample falls short of the commands' end by less than a sample).
    """
    out = []
    for s in segs:
        lo, hi = max(s.window[0], span[0]), min(s.window[1], span[1])
        inside = lo - s.window[0] <= 1e-6 and s.window[1] - hi <= 1e-6
        if inside or (not s.frequencies_hz.size and max(lo - s.window[0], s.window[1] - hi)
                      <= CLIP_S and hi > lo):  # fmt: skip
            out.append(dataclasses.replace(s, window=(lo, hi)))
    return out


def analyse_designed(m: Measurement) -> RunReport:
    """Report a run made for one test: its ``meta.json`` names the signal design.

    A periodic design (``twin agard df`` and ``parasitic`` runs, a multisine of ``twin
    simulate``) gives the describing function and the parasitic motion of its DOF; a step
    design (``twin agard threshold``) the dynamic threshold. Every other test is missing.

    Raises
    ------
    SignalError
        A run whose design cannot be found (see :func:`twin.measurement.periodic.periodic_design`).

    """
    kind = m.meta.get("signal", {}).get("kind", "periodic")
    k = driven_dof(m)
    missing: dict[str, str] = {}
    if kind == "steps":
        results = {"threshold": {DOF_NAMES[k]: threshold.analyse_threshold(m)}}
    else:
        results = {"df": {DOF_NAMES[k]: df.analyse_df(m)}}
        try:
            results["parasitic"] = {"all": parasitic.analyse_parasitic(m)}
        except SignalError as e:
            missing["parasitic"] = str(e)
    for t, a in ANALYSES.items():
        if t not in results and t not in missing:
            missing[t] = f"needs {a.needs}; this run is one {kind} test signal"
    missing.update({t: why for t, why in NOT_FROM_SCHEDULES.items() if t not in results})
    return RunReport(m.source, None, results, missing, {})
