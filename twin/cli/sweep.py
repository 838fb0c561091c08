"""``twin sweep GRID.toml``: a parameter grid, one task per point, one tidy table."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from twin.cli import common

#: Exit code of a sweep whose table was written but some points failed.
EXIT_PARTIAL = 1


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``twin sweep`` to the ``twin`` parser."""
    from twin.studies import sweep

    p = sub.add_parser(
        "sweep",
        parents=[
            common.out_parent(
                common.default_out_help("sweep folder", "sweep", "<grid file's name>")
            ),
            common.json_parent(),
            common.quiet_parent(),
            common.scheduler_parent(),
        ],
        help="run a parameter grid (TOML): describing functions or the pitch task per point",
        description=sweep.__doc__.split("\n\n", 1)[0]  # type: ignore[union-attr]
        + " Writes the tidy table (CSV or Parquet), each point's result (points/NNNN.json), "
        "sweep.json and sweep.png. A point that fails is listed with its inputs and the others "
        f"are written (exit code {EXIT_PARTIAL}). Tasks: "
        + "; ".join(f"{k}: {v}" for k, v in sweep.TASKS.items()),
    )
    p.add_argument("grid", metavar="GRID_TOML", help="sweep file (see twin.studies.sweep)")
    p.add_argument("--format", choices=("csv", "parquet"), default="csv",
                   help="table format (default csv)")  # fmt: skip
    p.set_defaults(func=_cmd_sweep)


def _cmd_sweep(args: argparse.Namespace) -> int:
    from twin.core.lifecycle import check_output_dir
    from twin.studies.sweep import read_grid, run_sweep
    from twin.studies.sweep_report import check_table_format, write_sweep

    check_table_format(args.format)  # before the sweep runs, not after
    grid = read_grid(args.grid)
    out = Path(args.out or common.default_out("sweep", Path(args.grid).stem))
    check_output_dir(out, "sweep.json")
    with common.engine(args) as engine:
        result = run_sweep(grid, engine, common.progress(args))
    table = write_sweep(result, out, args.format)
    if args.json:
        print((out / "sweep.json").read_text(encoding="utf-8"), end="")
    else:
        print(f"{len(result.points) - len(result.failures)} of {len(result.points)} points "
              f"({result.scheduler}); table: {table}")  # fmt: skip
    for f in result.failures:
        print(f"twin: point failed: {f.describe()}", file=sys.stderr)
    return EXIT_PARTIAL if result.failures else 0
