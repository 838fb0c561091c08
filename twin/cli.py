"""The ``twin`` command line.

Errors from bad input are printed as one line on stderr (``twin: error: ...``) with exit
code 2; nothing is written before the input has been checked.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from typing import NoReturn

from twin import __version__
from twin.errors import TwinError

EXIT_USAGE = 2


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line and exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"twin: error: {message} (see `{self.prog} --help`)\n")


def _cmd_workspace(args: argparse.Namespace) -> int:
    from twin.geometry import load_geometry
    from twin.kinematics import workspace
    from twin.platforms import check_platform
    from twin.workspace_report import format_table, to_json_dict

    check_platform(args.platform)
    ws = workspace(load_geometry(args.platform))
    if args.json:
        print(json.dumps(to_json_dict(ws), indent=2))
    else:
        print(format_table(ws, args.platform))
    return 0


def build_parser() -> argparse.ArgumentParser:
    """Return the parser of the ``twin`` command."""
    parser = _Parser(prog="twin", description="Digital twin of flight-simulator motion systems.")
    parser.add_argument("--version", action="version", version=f"twin {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    ws = sub.add_parser(
        "workspace",
        help="workspace per DOF (App. B.3) beside Table 5.1",
        description="Workspace per degree of freedom about neutral: each DOF alone, the others "
        "at neutral, limited by the actuator stroke (thesis App. B.3).",
    )
    ws.add_argument("platform", metavar="PLATFORM", help="mpi or srs")
    ws.add_argument("--json", action="store_true", help="print JSON (m and deg) instead")
    ws.set_defaults(func=_cmd_workspace)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``twin`` command; return its exit code."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args))
    except TwinError as e:
        print(f"twin: error: {e}", file=sys.stderr)
        return EXIT_USAGE


if __name__ == "__main__":
    sys.exit(main())
