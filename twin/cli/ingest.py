"""``twin import CSV [CSV ...]``: measured logs into a ``twin-run/1`` folder."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from twin.cli import common

#: ``--clock-offset``: any offset of two clocks, one of them counting from 1970 included.
CLOCK_OFFSET_S = common.number(-1e10, 1e10)
#: ``--imu-position``, each coordinate: within 5 m of the UGP (as the importer allows).
IMU_POSITION_M = common.number(-5, 5)


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``twin import`` to the ``twin`` parser."""
    p = sub.add_parser(
        "import",
        parents=[
            common.out_parent(
                common.default_out_help("run folder to write", "import", "<first file's name>")
            ),
            common.json_parent(),
            common.quiet_parent(),
        ],
        help="turn measured CSV logs into a twin-run/1 folder (units, time bases, clocks, "
        "IMU mount)",
        description="Read CSV logs as a lab writes them (any column names and units, jittery "
        "or irregular time stamps, an IMU on its own clock or logging z up, mounted off the "
        "UGP) and write a twin-run/1 folder for twin diagnose and twin agard. Names and units "
        "come from the headers (e.g. 'pitch [deg]', 'AccZ (g)', 'heave_mm') or --map; the "
        "clock offset and the IMU mount are estimated when not given, and the import says "
        "what it assumed, and whether a clock offset can be told from a motion delay.",
    )
    p.add_argument(
        "files", nargs="+", metavar="CSV",
        help="one file with commands and IMU, or a command file and an IMU file",
    )  # fmt: skip
    p.add_argument("--platform", choices=("mpi", "srs"), help="the platform (or give --config)")
    p.add_argument("--config", metavar=common.CONFIG,
                   help="the configuration the run was made on (name or twin-config/1 file; "
                   "default: the platform's)")  # fmt: skip
    p.add_argument("--map", action="append", default=[], metavar="TARGET=COLUMN[:UNIT]",
                   help="a column the names do not give, e.g. z=heave_cmd:mm or q=gy:deg/s "
                   "(targets t x y z roll pitch yaw ax ay az p q r); repeat")  # fmt: skip
    p.add_argument("--clock-offset", type=CLOCK_OFFSET_S, metavar="S",
                   help=f"IMU clock minus command clock [s] ({CLOCK_OFFSET_S.span}: clocks in "
                   "seconds since 1970 too), when known")  # fmt: skip
    p.add_argument("--imu-position", type=IMU_POSITION_M, nargs=3, metavar=("X", "Y", "Z"),
                   help="IMU mount relative to the UGP, cabin axes (x fwd, y right, z down) "
                   f"[m], each {IMU_POSITION_M.span}; estimated from the rotation when not "
                   "given")  # fmt: skip
    p.add_argument(
        "--imu-axes", choices=("auto", "frd", "flu"), default="auto",
        help="IMU axes: frd (z down), flu (z up), or auto from gravity (default)",
    )  # fmt: skip
    p.set_defaults(func=_cmd_import)


def _cmd_import(args: argparse.Namespace) -> int:
    from twin.ingest import import_run

    out = Path(args.out or common.default_out("import", Path(args.files[0]).stem))
    report = import_run(
        args.files, out, args.platform, args.config, args.map, args.clock_offset,
        args.imu_position, args.imu_axes, args.overwrite, common.progress(args),
    )  # fmt: skip
    print(json.dumps(report.to_dict(), indent=2) if args.json else report.format_text())
    return 0
