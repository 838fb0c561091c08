"""``twin simulate``: run a configuration on a signal and write a ``twin-run/1`` folder."""

from __future__ import annotations

import sys
import time
from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from twin.chain.config import motion_system
from twin.chain.simulate import Run, Simulation, prepare
from twin.runs import RunWriter, read_commands
from twin.signals import builtin_signal
from twin.trajectory import Trajectory

if TYPE_CHECKING:
    from twin.record import Recorder


def load_signal(spec: str, rate_hz: float = 100.0) -> Trajectory:
    """Return commands from a ``commands.csv`` path (or a run folder) or a built-in name."""
    path = Path(spec)
    if path.is_dir():
        path = path / "commands.csv"
    if path.suffix == ".csv" or path.exists():
        return read_commands(path)
    return builtin_signal(spec, rate_hz)


def _legs_at(t_cmd: np.ndarray, t: np.ndarray, legs: np.ndarray) -> np.ndarray:
    return np.column_stack([np.interp(t_cmd, t, legs[:, j]) for j in range(6)])


def run_to_folder(
    config: str,
    signal: str,
    model: str = "full",
    seed: int = 0,
    out: str | Path | None = None,
    rrd: str | None = None,
    connect: str | None = None,
    limit_mode: str = "limit",
    resonance: bool = False,
    overwrite: bool = False,
    quiet: bool = False,
) -> Path:
    """Simulate and write the run folder (see ``twin simulate --help``); return its path."""
    commands = load_signal(signal)
    ms = motion_system(config)
    if resonance:
        ms = ms.replace(name=f"{ms.name}+resonance", resonance=True)
    run = prepare(ms, commands, model, seed, limit_mode=limit_mode)
    name = Path(signal).stem if Path(signal).exists() else signal
    folder = Path(out) if out else Path("out") / f"{run.config.name}-{model}-{name}-seed{seed}"
    meta = {
        "platform": run.config.platform,
        "platform_config": run.config.to_meta(),
        "command_rate_hz": commands.rate_hz,
        "imu": {"position_m": list(run.imu_spec.position_m), "rate_hz": run.imu_spec.rate_hz},
        "notes": f"simulated by twin ({model} model) from signal {signal!r}",
        "model": model,
        "seed": seed,
    }
    recorder = None
    if rrd is not None or connect is not None:
        from twin.record import Recorder

        recorder = Recorder(run.platform.geometry, folder.name, rrd=rrd, connect=connect)
    start = time.perf_counter()
    try:
        execute(run, meta, folder, overwrite, recorder, quiet)
    except BaseException:
        if recorder is not None:
            recorder.abort()
        raise
    if recorder is not None:
        recorder.close()
    wall = time.perf_counter() - start
    if not quiet:
        print(file=sys.stderr)
        print(f"wrote {folder} ({commands.duration:.1f} s simulated in {wall:.1f} s, "
              f"{commands.duration / wall:.0f}x real time)")  # fmt: skip
        print(run.limits.summary())
        for note in run.notes:
            print(f"note: {note}")
    return folder


def execute(
    run: Run,
    meta: dict | None = None,
    folder: Path | None = None,
    overwrite: bool = False,
    recorder: Recorder | None = None,
    quiet: bool = True,
    offset_s: float = 0.0,
) -> Simulation:
    """Run all chunks, streaming them into a run folder and a recorder if given.

    Parameters
    ----------
    run : Run
        A prepared run.
    meta : dict, optional
        ``meta.json`` contents (needed with ``folder``).
    folder : Path, optional
        Destination ``twin-run/1`` folder.
    overwrite : bool
        Replace an existing folder.
    recorder : Recorder, optional
        Rerun sink.
    quiet : bool
        No progress on stderr.
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
    writer = RunWriter(folder, meta or {}, overwrite=overwrite) if folder else nullcontext()
    with writer as w:
        if w is not None:
            w.write("commands.csv", t_cmd, commands.values)
        written = 0  # command samples whose leg lengths are written
        carry: tuple[np.ndarray, np.ndarray] | None = None  # the previous chunk's last row
        for response, imu in run.chunks():
            responses.append(response)
            records.append(imu)
            if w is not None:
                t, legs = response.t, response.legs
                if carry is not None:
                    t, legs = np.concatenate([carry[0], t]), np.vstack([carry[1], legs])
                upto = int(np.searchsorted(t_cmd, t[-1] + 1e-9))
                w.write("actuators.csv", t_cmd[written:upto], _legs_at(t_cmd[written:upto], t, legs))
                written, carry = upto, (t[-1:], legs[-1:])
                w.write("imu.csv", imu.t, np.hstack([imu.accel, imu.gyro]))
            if recorder is not None:
                recorder.log(response, imu, offset_s)
            if not quiet:
                print(f"\r  simulated {response.t[-1] - commands.t0:7.1f} / "
                      f"{commands.duration:.1f} s", end="", file=sys.stderr)  # fmt: skip
        if w is not None:
            w.meta["limits"] = run.limits.to_dict()
            w.meta["run_notes"] = run.notes
    return run.simulation(responses, records)
