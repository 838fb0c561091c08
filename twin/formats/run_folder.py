"""Stream a prepared run into a ``twin-run/1`` folder (and a Rerun recording).

The format itself (reading, checking, :class:`~twin.formats.runs.RunWriter`) is in
:mod:`twin.formats.runs`; this module is the one place where a simulated run's ``meta.json`` is
built (:func:`run_meta`, with the signal design of :func:`signal_meta`) and where a run's chunks are
written as they are simulated (:func:`execute`). Every command and library function that
writes a simulated run goes through here; none of it depends on the command line.
"""

from __future__ import annotations

from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np

from twin.chain.signals import DescribingSignal, StepSignal
from twin.chain.trajectory import interp_columns
from twin.core.progress import ProgressFn
from twin.formats.runs import SIMULATED, RunWriter
from twin.formats.schedule import Schedule

if TYPE_CHECKING:
    from twin.chain.config import MotionSystem
    from twin.chain.imu import ImuRecord
    from twin.chain.response import PlatformResponse
    from twin.chain.simulate import Run, Simulation

#: Progress messages of :func:`execute` per run (at most).
PROGRESS_STEPS = 10


class RunRecorder(Protocol):
    """Where a run's chunks go as they are simulated, besides its folder.

    A Rerun recording (:class:`twin.viz.record.Recorder`) is one; the caller builds it and
    hands it to :func:`execute` or to an AGARD session (:class:`twin.agard.session.Session`).
    """

    def log(
        self, response: PlatformResponse, imu: ImuRecord | None = None, offset_s: float = 0.0
    ) -> None:
        """Take one chunk of a run, its times shifted by ``offset_s`` [s]."""

    def close(self) -> None:
        """Finish the recording."""

    def abort(self) -> None:
        """Delete a partial recording."""


def signal_meta(sig: DescribingSignal | StepSignal) -> dict[str, object]:
    """Return the ``signal`` entry of a run's ``meta.json``: how to analyse the run.

    Parameters
    ----------
    sig : DescribingSignal or StepSignal
        The designed test signal the run was driven with (or any signal with a ``meta()``
        method returning this entry: :mod:`twin.agard.bump`, :mod:`twin.agard.limits`).

    Returns
    -------
    dict
        ``kind`` ("periodic", "steps", or the signal's own), ``dof`` and the design's
        parameters.

    """
    own = getattr(sig, "meta", None)
    if callable(own):  # a test signal that describes itself (bump, system limits)
        return own()
    if isinstance(sig, StepSignal):
        return {
            "kind": "steps",
            "dof": sig.dof,
            "amplitude": sig.amplitude,
            "step_s": sig.step_s,
            "start_s": sig.start_s,
            "levels": list(sig.levels),
        }
    return {
        "kind": "periodic",
        "dof": sig.dof,
        "label": sig.label,
        "frequencies_hz": [float(f) for f in sig.frequencies_hz],
        "amplitudes": None if sig.amplitudes is None else [float(a) for a in sig.amplitudes],
        "window_s": [float(sig.window[0]), float(sig.window[1])],
    }


def run_meta(
    run: Run,
    notes: str,
    config: MotionSystem | None = None,
    signal: DescribingSignal | StepSignal | None = None,
    schedule: Schedule | None = None,
) -> dict[str, object]:
    """Return the ``meta.json`` of a simulated run (the one place it is built).

    Parameters
    ----------
    run : Run
        The prepared run (platform, model, seed, IMU and command rate come from it).
    notes : str
        Free text: what the run is.
    config : MotionSystem, optional
        The configuration ``meta.json`` names (default: the run's own; a hidden-effect run
        names the nominal configuration instead of the one it was simulated with).
    signal : DescribingSignal or StepSignal, optional
        The signal design, written as the ``signal`` entry (see :func:`signal_meta`).
    schedule : Schedule, optional
        The test schedule the commands were made from, written as the ``schedule`` entry
        (:meth:`twin.formats.schedule.moves.Schedule.to_json`: each move with its time, kind, DOF
        and the AGARD test it serves).

    Returns
    -------
    dict
        ``platform``, ``platform_config``, ``command_rate_hz``, ``imu``, ``notes``, ``model``,
        ``seed`` and, with ``signal``, ``signal``.

    """
    cfg = run.config if config is None else config
    meta: dict[str, object] = {
        "platform": cfg.platform,
        "platform_config": cfg.to_meta(),
        "command_rate_hz": run.commands.rate_hz,
        "imu": {"position_m": list(run.imu_spec.position_m), "rate_hz": run.imu_spec.rate_hz},
        "notes": notes,
        "model": run.model,
        "seed": run.seed,
    }
    if signal is not None:
        meta["signal"] = signal_meta(signal)
    if schedule is not None:
        meta["schedule"] = schedule.to_json()
    return meta


def _legs_at(t_cmd: np.ndarray, t: np.ndarray, legs: np.ndarray) -> np.ndarray:
    return interp_columns(t_cmd, t, legs)


def execute(
    run: Run,
    meta: dict | None = None,
    folder: Path | None = None,
    overwrite: bool = False,
    recorder: RunRecorder | None = None,
    progress: ProgressFn | None = None,
    offset_s: float = 0.0,
) -> Simulation:
    """Run all chunks, streaming them into a run folder and a recorder if given.

    Parameters
    ----------
    run : Run
        A prepared run.
    meta : dict, optional
        ``meta.json`` contents (see :func:`run_meta`; needed with ``folder``).
    folder : Path, optional
        Destination ``twin-run/1`` folder (written atomically by
        :class:`~twin.formats.runs.RunWriter`).
    overwrite : bool
        Replace an existing folder.
    recorder : RunRecorder, optional
        Where each chunk goes as well (a Rerun recording); the caller closes it.
    progress : callable, optional
        Called with a message about every tenth of the run.
    offset_s : float
        Added to the recorded times (runs of a test follow each other in one recording).

    Returns
    -------
    Simulation
        The whole run.

    """
    commands = run.commands
    t_cmd = commands.t
    responses, records = [], []
    step = commands.duration / PROGRESS_STEPS
    reported = 0.0
    files = (*SIMULATED, "forces.csv") if run.model == "full" else SIMULATED  # legs' forces
    writer = RunWriter(folder, meta or {}, overwrite, files) if folder else nullcontext()
    with writer as w:
        if w is not None:
            w.write("commands.csv", t_cmd, commands.values)
        written = 0  # command samples whose leg lengths are written
        carry: tuple[np.ndarray, np.ndarray] | None = None  # the previous chunk's last row
        for response, imu in run.chunks():
            responses.append(response)
            records.append(imu)
            if w is not None:
                # leg lengths at every command time, also between two chunks' samples
                t, legs = response.t, response.legs
                if response.leg_force is not None:  # the forces beside the lengths
                    legs = np.hstack([legs, response.leg_force])
                if carry is not None:
                    t, legs = np.concatenate([carry[0], t]), np.vstack([carry[1], legs])
                upto = int(np.searchsorted(t_cmd, t[-1] + 1e-9))
                sel = slice(written, upto)
                at = _legs_at(t_cmd[sel], t, legs)
                w.write("actuators.csv", t_cmd[sel], at[:, :6])
                if "forces.csv" in files:
                    w.write("forces.csv", t_cmd[sel], at[:, 6:])
                written, carry = upto, (t[-1:], legs[-1:])
                w.write("imu.csv", imu.t, np.hstack([imu.accel, imu.gyro]))
            if recorder is not None:
                recorder.log(response, imu, offset_s)
            done = response.t[-1] - commands.t0
            if progress is not None and reported + step <= done < commands.duration - 1e-6:
                reported = done
                progress("simulated [s]", round(done, 3), round(commands.duration, 3))
        if progress is not None:  # the last samples may end a step short of the duration
            progress("simulated [s]", round(commands.duration, 3), round(commands.duration, 3))
        if w is not None:
            w.meta["limits"] = run.limits.to_dict()
            w.meta["run_notes"] = run.notes
    return run.simulation(responses, records)
