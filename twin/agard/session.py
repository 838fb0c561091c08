"""A test session: the runs of one AGARD test on a bench, with their sinks.

Each run of a test is checked against the platform limits, simulated with its own seed
(``bench.seed + k``), optionally written as a ``twin-run/1`` folder (``OUT/runs/NN-name``, with
the signal's design in ``meta.json`` so that the same analysis can be run on it later) and
logged to one Rerun recording, the runs following each other on the timeline as in a
measurement session.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from twin.chain.signals import DescribingSignal, StepSignal, single_sine
from twin.chain.simulate import Simulation
from twin.chain.trajectory import Trajectory
from twin.core.errors import SignalLimitError
from twin.core.lifecycle import CloseOrAbort
from twin.core.progress import ProgressFn
from twin.formats.run_folder import RunRecorder, execute, run_meta
from twin.formats.schedule import Schedule
from twin.measurement.measure import Bench, Measurement

if TYPE_CHECKING:
    from twin.chain.config import MotionSystem


class SessionRecorder(RunRecorder, Protocol):
    """A session's recording: every run's chunks, and the describing functions found.

    :class:`twin.viz.record.Recorder` is one (:func:`twin.viz.record.bench_recorder` builds it for a
    bench).
    """

    def log_describing_function(self, result, config: MotionSystem | None = None) -> None:
        """Add a describing function (a :class:`twin.agard.df.DfResult`) to the recording."""


class Session(CloseOrAbort):
    """Runs test signals on a bench.

    Parameters
    ----------
    bench : Bench
        What is measured.
    out : str or Path, optional
        Folder for the run folders (``OUT/runs/NN-name``).
    recorder : SessionRecorder, optional
        Where every run goes as well, one after the other (a Rerun recording,
        :func:`twin.viz.record.bench_recorder`); the session closes it, or aborts it when a run
        fails.
    progress : callable, optional
        Called with a message before each run, and with the count of a test's runs when the
        test announced them (:meth:`expect`).

    """

    def __init__(
        self,
        bench: Bench,
        out: str | Path | None = None,
        recorder: SessionRecorder | None = None,
        progress: ProgressFn | None = None,
    ) -> None:
        self.bench = bench
        self.out = Path(out) if out is not None else None
        self.progress = progress
        self.count = 0
        self._job: tuple[str, int, int] | None = None  # what, first run, runs
        self._offset = 0.0
        self.recorder = recorder
        #: The last run's simulation (poses, leg lengths and forces beside the measurement).
        self.simulation: Simulation | None = None

    def expect(self, runs: int, what: str) -> None:
        """Announce the next ``runs`` runs as one job (progress counts them, with an ETA)."""
        self._job = (f"{what} on {self.bench.name} [runs]", self.count, runs)
        if self.progress:
            self.progress(self._job[0], 0, runs)

    def _counted(self) -> None:
        """Report the end of a run of the announced job."""
        if self._job is None:
            return
        what, first, runs = self._job
        if self.progress:
            self.progress(what, min(self.count - first, runs), runs)
        if self.count - first >= runs:
            self._job = None

    def measure(
        self, sig: DescribingSignal | StepSignal, name: str, check_limits: bool = True
    ) -> Measurement:
        """Run one signal and return its measurement.

        ``check_limits=False`` runs commands beyond the platform limits through the actuator
        limiter (limited and counted in :attr:`simulation`) instead of refusing them: the
        system-limits test (:mod:`twin.agard.limits`) drives into them.
        """
        return self._measure(sig.commands, name, {"signal": sig}, check_limits=check_limits)

    def measure_schedule(self, schedule: Schedule) -> Measurement:
        """Run a whole test schedule as one run; return its measurement (with the schedule).

        A schedule with system-limits moves runs through the actuator limiter (limited and
        counted, as ``twin agard limits`` runs); any other is checked against the platform's
        limits first and refused if it would break one.
        """
        limits = "limits" in schedule.tests()
        return self._measure(schedule.commands(), schedule.slug, {"schedule": schedule},
                             progress=True, check_limits=not limits)  # fmt: skip

    def _measure(
        self,
        commands: Trajectory,
        name: str,
        design: dict[str, object],
        progress: bool = False,
        check_limits: bool = True,
    ) -> Measurement:
        """Run ``commands``; ``design``: the ``signal`` or ``schedule`` for ``meta.json``."""
        k = self.count
        self.count += 1
        if self.progress:
            self.progress(f"run {k + 1}: {name} on {self.bench.name}")
        try:
            run = self.bench.prepare(commands, k, name, check_limits)
        except SignalLimitError:
            self._counted()  # a refused run still counts in the job
            raise
        meta = run_meta(run, f"AGARD-AR-144 test run {name}, simulated by twin", **design)  # type: ignore[arg-type]
        folder = None if self.out is None else self.out / "runs" / f"{k:02d}-{name}"
        try:
            sim = execute(run, meta, folder, overwrite=True, recorder=self.recorder,
                          progress=self.progress if progress else None,
                          offset_s=self._offset)  # fmt: skip
        except BaseException:
            self.abort()
            raise
        self._offset += commands.duration + 1.0
        self.simulation = sim
        self._counted()
        return self.bench.measure(sim, {key: meta[key] for key in design})

    def measure_sine(
        self, dof: str, frequency_hz: float, amplitude: float, window_s: float, name: str
    ) -> Measurement | str:
        """Run a single sine (Eq 3.4); return its measurement, or the limit it would break."""
        sig = single_sine(dof, frequency_hz, amplitude, window_s=window_s)
        try:
            return self.measure(sig, name)
        except SignalLimitError as e:
            return str(e)

    def close(self) -> None:
        """Finish the recording (if any)."""
        if self.recorder is not None:
            self.recorder.close()
            self.recorder = None

    def abort(self) -> None:
        """Delete a partial recording."""
        if self.recorder is not None:
            self.recorder.abort()
            self.recorder = None
