"""The ``twin`` command line.

Errors from bad input are printed as one line on stderr (``twin: error: ...``) with exit
code 2 (:func:`error_line` is the one place that decides); output paths are checked while
the arguments are parsed, and outputs are written under a temporary name and renamed, so
nothing half-written is left.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import os
import sys
from collections.abc import Sequence
from typing import NoReturn

from twin.cli import common, terminal
from twin.cli.simulate import add_parser as add_simulate
from twin.core.errors import TwinError, UsageError
from twin.core.frames import DOF_NAMES
from twin.core.interrupts import handling_ctrl_c
from twin.core.ownership import output_policy
from twin.core.version import __version__

EXIT_USAGE = 2
#: Exit code of a bug (``EX_SOFTWARE`` of sysexits.h).
EXIT_BUG = 70
#: Exit code after Ctrl-C (128 + SIGINT).
EXIT_INTERRUPTED = 130
#: Exit code when the reader of stdout went away (128 + SIGPIPE, as a shell reports it).
EXIT_BROKEN_PIPE = 141


#: The attribute that carries the innermost command's ``prog`` while parsing.
_PROG = "_twin_prog"


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are :class:`UsageError` (one line, exit code 2).

    An unrecognised argument is reported with the help of the command it was given to
    (``see `twin pilot experiment fixed --help```), not the ``twin`` command's.
    """

    def error(self, message: str) -> NoReturn:
        raise UsageError(f"{message} (see `{self.prog} --help`)")

    def parse_known_args(
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        parsed, extra = super().parse_known_args(args, namespace)
        if not hasattr(parsed, _PROG):  # the innermost command parses first
            setattr(parsed, _PROG, self.prog)
        return parsed, extra

    def parse_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> argparse.Namespace:
        parsed, extra = self.parse_known_args(args, namespace)
        prog = vars(parsed).pop(_PROG, self.prog)
        if extra:
            raise UsageError(f"unrecognized arguments: {' '.join(extra)} (see `{prog} --help`)")
        return parsed


def _platform_of(config: str, command: str, physics: bool) -> str:
    """Return the platform of ``CONFIG`` for a command that models only the platform.

    Raises
    ------
    UsageError
        For a configuration with calibrated physics where the command models the platform's
        own (``physics``): the command would not use it.

    """
    from twin.chain.config import motion_system

    ms = motion_system(config)
    if physics and ms.physics is not None:
        raise UsageError(f"{config}: carries calibrated physics (legs, payload), which twin "
                         f"{command} does not model (it fits the {ms.platform} platform's own "
                         f"full model); give the platform, {ms.platform}")  # fmt: skip
    return ms.platform


def _cmd_workspace(args: argparse.Namespace) -> int:
    from twin.platform.geometry import load_geometry
    from twin.platform.kinematics import workspace
    from twin.platform.workspace import format_table, to_json_dict

    platform = _platform_of(args.config, "workspace", physics=False)
    ws = workspace(load_geometry(platform))
    if args.json:
        print(json.dumps(to_json_dict(ws), indent=2))
    else:
        print(format_table(ws, platform))
    return 0


def _cmd_compare(args: argparse.Namespace) -> int:
    from twin.agard.compare import compare

    cfg = common.configured(args.config, args)
    cmp = compare(cfg, dofs=args.dof or DOF_NAMES, progress=common.progress(args))
    if args.plot:
        cmp.plot(path=args.plot)
    print(json.dumps(cmp.to_dict(), indent=2) if args.json else cmp.format_table())
    return 0


def _cmd_dynamics(args: argparse.Namespace) -> int:
    from twin.agard.compare import platform_dynamics

    platform = _platform_of(args.config, "dynamics", physics=True)
    dyn = platform_dynamics(platform, dofs=args.dof or DOF_NAMES, progress=common.progress(args))
    print(json.dumps(dyn.to_dict(), indent=2) if args.json else dyn.format_table())
    return 0


def _add_analysis(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "compare",
        parents=[
            common.json_parent(),
            common.quiet_parent(),
            common.overrides_parent(imu=False),
        ],
        help="full vs reduced model: describing functions per DOF (§5.5)",
        description="Drive the full and the reduced model of a configuration with the same "
        "multi-sines (Table 5.2, plus 4.5-10 Hz) in each DOF and print gain and phase "
        "differences, the equivalent delay and the time-domain RMS difference.",
    )
    common.add_config(p)
    common.add_dof(p, "a DOF to compare (default all six)")
    p.add_argument("--plot", metavar="PNG", type=common.figure_file, help="save a Bode plot")
    p.set_defaults(func=_cmd_compare)
    d = sub.add_parser(
        "dynamics",
        parents=[common.json_parent(), common.quiet_parent()],
        help="the full model's own lag per DOF beside Table 5.5",
        description="Fit a first-order lag plus delay to the full model's describing functions "
        "(no filter, delay or noise; thesis §5.5.1) and compare with Table 5.5.",
    )
    common.add_config(
        d,
        note="; only its platform matters: the fit is of the "
        "platform's own full model, without the configuration's filter, delay "
        "and noise (a configuration with calibrated physics is refused)",
    )
    common.add_dof(d, "a DOF to fit (default all six)")
    d.set_defaults(func=_cmd_dynamics)


def build_parser() -> argparse.ArgumentParser:
    """Return the parser of the ``twin`` command."""
    parser = _Parser(prog="twin", description="Digital twin of flight-simulator motion systems.")
    parser.add_argument("--version", action="version", version=f"twin {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    ws = sub.add_parser(
        "workspace",
        parents=[common.json_parent()],
        help="workspace per DOF (App. B.3) beside Table 5.1",
        description="Workspace per degree of freedom about neutral: each DOF alone, the others "
        "at neutral, limited by the actuator stroke (thesis App. B.3).",
    )
    common.add_config(
        ws,
        note="; only its platform matters: the workspace is the platform's "
        "geometry and actuator stroke",
    )
    ws.set_defaults(func=_cmd_workspace)
    add_simulate(sub)
    _add_analysis(sub)
    from twin.cli.agard import add_parser as add_agard

    add_agard(sub, _Parser)
    from twin.cli.pilot import add_parser as add_pilot

    add_pilot(sub, _Parser)
    from twin.cli.diagnose import add_parser as add_diagnose

    add_diagnose(sub)
    from twin.cli.design import add_parser as add_design

    add_design(sub)
    from twin.cli.ingest import add_parser as add_import

    add_import(sub)
    from twin.cli.sweep import add_parser as add_sweep

    add_sweep(sub)
    common.add_overwrite(parser)
    return parser


def _os_error(e: OSError) -> str:
    """One line for an operating-system error: the path(s) and the reason."""
    paths = " -> ".join(str(p) for p in (e.filename, e.filename2) if p is not None)
    reason = e.strerror or str(e)
    return f"{paths}: {reason}" if paths else reason


def error_line(e: BaseException) -> tuple[str, int]:
    """Return the one line printed for an exception that ends a command, and the exit code.

    The one place where errors become ``twin: error: ...`` on stderr:

    - bad input of any kind (:class:`~twin.core.errors.TwinError`: usage, data, configuration,
      output path): exit code 2;
    - the operating system refusing a file or folder (missing, permission, read-only file
      system, disk full): the path and the reason, exit 2;
    - a text file that is not UTF-8, or a job larger than memory: exit 2;
    - Ctrl-C: ``interrupted``, exit 130 (outputs are written under a temporary name, so
      nothing half-written is left);
    - anything else is a bug in the twin: one line saying so, exit 70 (``TWIN_DEBUG=1``
      shows the traceback instead).
    """
    if isinstance(e, TwinError):
        return f"twin: error: {e}", EXIT_USAGE
    if isinstance(e, OSError):
        return f"twin: error: {_os_error(e)}", EXIT_USAGE
    if isinstance(e, UnicodeDecodeError):
        return f"twin: error: an input file is not UTF-8 text ({e.reason})", EXIT_USAGE
    if isinstance(e, MemoryError):
        why = f" ({e})" if str(e) else ""
        return f"twin: error: not enough memory for this job{why}; give a shorter run or fewer "\
               "runs", EXIT_USAGE  # fmt: skip
    if isinstance(e, KeyboardInterrupt):
        return "twin: interrupted", EXIT_INTERRUPTED
    return (f"twin: internal error: {type(e).__name__}: {e} (a bug in twin {__version__}; "
            "please report it with the command; TWIN_DEBUG=1 shows the traceback)",
            EXIT_BUG)  # fmt: skip


@functools.cache
def _parser() -> argparse.ArgumentParser:
    """Return the parser :func:`main` uses, built once per process.

    Building it reads nothing of the environment and parsing leaves it as it was; a build
    costs 20-40 ms, which a test suite calling :func:`main` hundreds of times notices. The
    commands' functions are bound when it is built (patch what they call, not them).
    """
    return build_parser()


def _quiet_stdout() -> None:
    """Point stdout at the null device, so Python's flush at exit does not fail again."""
    # a stdout that is no real file (a test's capture) has no descriptor to point elsewhere
    with contextlib.suppress(OSError, ValueError, AttributeError):
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``twin`` command; return its exit code (see :func:`error_line`).

    Whatever the locale: files are read and written as UTF-8, and a terminal that cannot
    encode the twin's text gets ASCII spellings (:mod:`twin.cli.terminal`). Ctrl-C ends the
    command once, cleanly (:mod:`twin.core.interrupts`). Without ``argv`` the command is this
    process's own (``sys.argv``): after a Ctrl-C, SIGINT then stays ignored while Python waits
    for the threads still running (MuJoCo's) and exits.
    """
    terminal.fit_streams(sys.stdout, sys.stderr)
    with handling_ctrl_c(process=argv is None) as ctrl_c:
        try:
            args = _parser().parse_args(argv)
            policy = output_policy(overwrite=getattr(args, "overwrite", False),
                                   inputs=common.inputs_of(args))  # fmt: skip
            with policy:  # no output replaces an input, nor a file twin did not write
                common.outputs_checked(args)
                return int(args.func(args))
        except BrokenPipeError:
            # the reader of stdout went away (``twin ... | head``): nothing to report
            _quiet_stdout()
            return EXIT_BROKEN_PIPE
        except (Exception, KeyboardInterrupt) as e:
            if os.environ.get("TWIN_DEBUG") and not isinstance(e, TwinError):
                raise
            # whatever a Ctrl-C cut short (an import raises ImportError then), it ended the command
            line, code = error_line(KeyboardInterrupt() if ctrl_c.interrupted else e)
            print(line, file=sys.stderr)
            return code


if __name__ == "__main__":
    sys.exit(main())
