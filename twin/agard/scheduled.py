"""The AGARD-AR-144 report of a scheduled run: each test from the moves that serve it.

A lab's schedule (:mod:`twin.schedule`) runs many tests in one run. :func:`analyse_schedule`
finds each test's moves (:mod:`twin.agard.segments`), runs the test's analysis on their
windows and says which tests the schedule does not hold, and why (what moves they need). The
tests and what they take from a schedule are :data:`ANALYSES`; :func:`write_scheduled`
writes the report folder (``report.json``, ``summary.md``, a figure per test and DOF).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib.pyplot as plt

from twin.agard import df
from twin.agard.segments import Segment, by_dof, largest_per_frequency, segments
from twin.lifecycle import writing
from twin.measurement.measure import Measurement
from twin.schedule.moves import Schedule


@dataclass(frozen=True)
class Analysis:
    """How one test is read from a schedule.

    Attributes
    ----------
    moves : str
        The move class it uses (:func:`twin.schedule.moves.test_of`).
    needs : str
        What the schedule must hold for it (the "missing" message).
    analyse : callable
        ``(measurement, segments of one DOF) -> result`` (``per_dof``), or of every DOF.
    per_dof : bool
        One result per driven DOF, or one for all.
    figure : callable
        ``(result, measurement) -> matplotlib figure``.

    """

    moves: str
    needs: str
    analyse: Callable[[Measurement, list[Segment]], object]
    per_dof: bool = True
    figure: Callable[[object, Measurement], object] = field(
        default=lambda r, m: r.plot()  # type: ignore[attr-defined]
    )


def _df(m: Measurement, segs: list[Segment]) -> df.DfResult:
    """Describing function of one DOF: its largest amplitude at each schedule frequency."""
    big = largest_per_frequency(segs)
    return df.analyse_windows(m, big[0].k, [(s.frequencies_hz, s.window) for s in big])


#: The tests a schedule can hold, in report order.
ANALYSES: dict[str, Analysis] = {
    "df": Analysis("df", "sine moves in one DOF", _df,
                   figure=lambda r, m: r.plot(config=m.config)),  # type: ignore[attr-defined]
}
#: Tests no schedule move serves (they need the twin's own signals: ``twin agard TEST``).
NOT_FROM_SCHEDULES = {
    "threshold": "acceleration steps (§3.3.4) are the twin's own signal",
    "omct": "the OMCT's twelve sines are the twin's own signal",
}


@dataclass(frozen=True)
class ScheduledReport:
    """The tests a scheduled run holds, their results, and the tests it lacks.

    Attributes
    ----------
    source : str
        What was measured.
    schedule : Schedule
        The run's schedule.
    results : dict of str to dict of str to object
        Test -> DOF (or ``"all"``) -> result (with ``to_dict``, ``format_table``, ``plot``).
    missing : dict of str to str
        Test -> why the run does not hold it.
    skipped : dict of str to list of str
        Test -> moves left out, and why.

    """

    source: str
    schedule: Schedule
    results: dict[str, dict[str, object]]
    missing: dict[str, str]
    skipped: dict[str, list[str]]

    def to_dict(self) -> dict[str, object]:
        """Return the report as JSON."""
        return {
            "source": self.source,
            "schedule": {"name": self.schedule.name, "source": self.schedule.source,
                         "format": self.schedule.format, "moves": len(self.schedule.moves)},  # fmt: skip
            "tests": {t: {d: r.to_dict() for d, r in rs.items()}  # type: ignore[attr-defined]
                      for t, rs in self.results.items()},  # fmt: skip
            "missing": self.missing,
            "skipped": self.skipped,
        }

    def format_table(self) -> str:
        """Return the report as text (what ``summary.md`` holds, without figures)."""
        return "\n".join(self._md(figures={}))

    def _md(self, figures: dict[tuple[str, str], str]) -> list[str]:
        s = self.schedule
        md = [f"# AGARD-AR-144 report: {self.source}", "",
              f"Schedule `{s.name}` ({s.format}, {len(s.moves)} moves, {s.duration_s:.0f} s) "
              f"from {s.source}.", ""]  # fmt: skip
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
                fig = ANALYSES[test].figure(r, m)
                path = folder / f"{test}-{dof}.png"
                try:
                    with writing(path):
                        fig.savefig(path, dpi=120)  # type: ignore[attr-defined]
                finally:
                    plt.close(fig)  # type: ignore[arg-type]
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
) -> ScheduledReport:
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

    """
    offset = m.commands.t0 if offset_s is None else offset_s
    results: dict[str, dict[str, object]] = {}
    missing: dict[str, str] = {}
    skipped: dict[str, list[str]] = {}
    for test in tests or ANALYSES:
        a = ANALYSES[test]
        segs, left_out = segments(schedule, a.moves, offset)
        segs = [s for s in segs if m.t[0] - 1e-6 <= s.window[0] and s.window[1] <= m.t[-1] + 1e-6]
        if left_out:
            skipped[test] = left_out
        if not segs:
            missing[test] = f"needs {a.needs}; the schedule has none" + (
                " that the run covers" if schedule.tests().get(a.moves) else "")  # fmt: skip
            continue
        groups = by_dof(segs) if a.per_dof else {"all": segs}
        results[test] = {dof: a.analyse(m, group) for dof, group in groups.items()}
    missing.update({t: why for t, why in NOT_FROM_SCHEDULES.items() if tests is None})
    return ScheduledReport(m.source, schedule, results, missing, skipped)
