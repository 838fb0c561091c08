"""``twin simulate``: run a configuration on a signal and write a ``twin-run/1`` folder.

Argument glue only: the run's ``meta.json`` and the streaming into the folder and the
recording are :func:`twin.formats.run_folder.run_meta` and :func:`twin.formats.run_folder.execute`.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

from twin.chain.trajectory import Trajectory
from twin.cli import common
from twin.formats.schedule import SUFFIXES, Schedule, read_schedule


def signal_help() -> str:
    """Return what ``--signal`` takes (its help, and the message for a missing file)."""
    from twin.chain.signals import BUILTIN_HELP
    from twin.formats.runs import COMMANDS_FILE

    return (f"a commands.csv (twin-run/1: {COMMANDS_FILE}), a run folder holding one, a test "
            "schedule (.json MovementSeries or .toml twin-schedule/1), or a "
            f"built-in: {BUILTIN_HELP}")  # fmt: skip


def load_signal(spec: str, rate_hz: float = 100.0) -> tuple[Trajectory, Schedule | None]:
    """Return commands from a ``commands.csv`` path (or a run folder), a schedule or a name.

    A schedule (:func:`twin.formats.schedule.read_schedule`) is returned with its commands, for the
    run's ``meta.json``; the other sources return None there.

    Raises
    ------
    UsageError
        For a path (a ``.csv``, a name with a folder in it, or a run folder without a
        ``commands.csv``) that does not exist, saying what ``--signal`` takes.

    """
    from twin.chain.signals import builtin_signal
    from twin.core.errors import UsageError
    from twin.formats.runs import read_commands

    path = Path(spec)
    if path.is_dir():
        path = path / "commands.csv"
    elif not path.exists() and path.suffix != ".csv" and "/" not in spec and os.sep not in spec:
        return builtin_signal(spec, rate_hz), None  # a name, not a path
    if not path.exists():
        raise UsageError(f"{path}: no such file or folder; --signal takes {signal_help()}")
    if path.suffix.lower() in SUFFIXES:
        schedule = read_schedule(path)
        return schedule.commands(rate_hz), schedule
    return read_commands(path), None


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``twin simulate`` to the ``twin`` parser."""
    p = sub.add_parser(
        "simulate",
        parents=[
            common.model_parent(),
            common.seed_parent(),
            common.out_parent(
                common.default_out_help("run folder", "simulate", "CONFIG-MODEL-SIGNAL-seedN")
            ),
            common.quiet_parent(),
            common.overrides_parent(imu=False),
        ],
        help="run a configuration on a signal; write a twin-run/1 folder",
        description="Drive a motion-system configuration (filter, delay, noise in front of the "
        "full MuJoCo or the reduced platform) with pose commands and write the run in the "
        "twin-run/1 format (meta.json, commands.csv, imu.csv, actuators.csv; forces.csv with "
        "the full model).",
    )
    common.add_config(p)
    p.add_argument(
        "--signal",
        required=True,
        metavar="FILE_OR_NAME",
        help=signal_help(),
    )
    view = p.add_mutually_exclusive_group()
    view.add_argument(
        "--rrd", metavar="FILE", type=common.rrd_file, help="also save a Rerun recording"
    )
    view.add_argument(
        "--connect",
        nargs="?",
        const="",
        metavar="URL",
        help="stream live to a running Rerun viewer (default URL if omitted)",
    )
    p.add_argument(
        "--raw-imu",
        action="store_true",
        help="record every IMU sample (819.2 Hz) instead of ~100 Hz block means for display",
    )
    p.add_argument(
        "--strict",
        action="store_true",
        help="reject commands beyond an actuator limit instead of limiting them",
    )
    p.set_defaults(func=_cmd_simulate)


def _cmd_simulate(args: argparse.Namespace) -> int:
    from twin.chain.simulate import prepare
    from twin.formats.run_folder import execute, run_meta

    commands, schedule = load_signal(args.signal)
    ms = common.configured(args.config, args)
    limit_mode = "strict" if args.strict else "limit"
    run = prepare(ms, commands, args.model, args.seed, limit_mode=limit_mode)
    name = Path(args.signal).stem if Path(args.signal).exists() else args.signal
    folder = Path(args.out or common.default_out(
        "simulate", f"{run.config.name}-{args.model}-{name}-seed{args.seed}"))  # fmt: skip
    meta = run_meta(run, f"simulated by twin ({args.model} model) from signal {args.signal!r}",
                    schedule=schedule)  # fmt: skip
    if args.rrd:
        common.refuse_file_in_folder(args.rrd, folder)
    recorder = None
    if args.rrd is not None or args.connect is not None:
        from twin.viz.record import Recorder

        recorder = Recorder(
            run.platform.geometry,
            folder.name,
            rrd=args.rrd,
            connect=args.connect,
            imu_position_m=run.imu_spec.position_m,
            imu_rate_hz=None if args.raw_imu else 100.0,
        )
    start = time.perf_counter()
    try:
        execute(run, meta, folder, args.overwrite, recorder, common.progress(args))
    except BaseException:
        if recorder is not None:
            recorder.abort()
        raise
    if recorder is not None:
        recorder.close()
    wall = time.perf_counter() - start
    print(f"wrote {folder} ({commands.duration:.1f} s simulated in {wall:.1f} s, "
          f"{commands.duration / wall:.0f}x real time)")  # fmt: skip
    if args.rrd is not None:
        print(f"wrote {args.rrd} (a Rerun recording; view it with python -m rerun "
              f"{args.rrd})")  # fmt: skip
    print(run.limits.summary())
    for note in run.notes:
        print(f"note: {note}")
    return 0
