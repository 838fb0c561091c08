"""What every ``twin`` command shares: parent parsers, overrides, progress.

Parent parsers (``parents=[...]`` of a subcommand) give the same options the same spelling,
type and help everywhere:

``--json``                    print the result as JSON
``--seed N``                  seed of the noise and the IMU (integer >= 0; default 0)
``--out DIR``                 where results go (the command says what it writes)
``--rrd FILE``                save a Rerun recording
``--quiet``                   no progress on stderr
``--scheduler WHERE``         where a batch command's tasks run (:mod:`twin.tasks.engine`)
``--model {full,reduced}``    platform model; **full by default everywhere**; a command
                              that defaults to ``reduced`` says why in its help
``--delay-ms``, ``--break-hz``, ``--no-noise``, ``--resonance``
                              configuration overrides (:meth:`MotionSystem.override`)
``--ideal-imu``               IMU without noise and bias (commands that use an IMU)

Progress goes through one helper, :func:`progress`: a :class:`twin.progress.Progress` that
library functions take as their ``progress=`` argument (a tqdm bar with ETA for counted work);
it prints on stderr only when stderr is a terminal and ``--quiet`` is not given.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import TYPE_CHECKING

from twin.errors import TwinError, UsageError
from twin.lifecycle import check_output_file, check_writable
from twin.ownership import check_replace, kind_of
from twin.progress import Progress

if TYPE_CHECKING:
    from twin.chain.config import MotionSystem

#: The default platform model of every command (unless its help says why not).
DEFAULT_MODEL = "full"
#: Figure files the twin writes (by suffix; matplotlib's common formats).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".svgz", ".jpg", ".jpeg", ".tif", ".tiff", ".webp",
                   ".eps", ".ps")  # fmt: skip
#: The platform models (as :data:`twin.chain.simulate.MODELS`; not imported: startup stays light).
MODELS = ("full", "reduced")


def _parent() -> argparse.ArgumentParser:
    return argparse.ArgumentParser(add_help=False)


def seed_type(text: str) -> int:
    """Parse a ``--seed``: an integer >= 0 (argparse ``type``)."""
    try:
        seed = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"seed must be an integer >= 0; got {text!r}") from None
    if seed < 0:
        raise argparse.ArgumentTypeError(f"seed must be an integer >= 0; got {seed}")
    return seed


def count(lo: int, hi: int) -> Callable[[str], int]:
    """Return an argparse ``type``: an integer in [lo, hi] (``--runs``, ``--subjects``)."""

    def parse(text: str) -> int:
        try:
            n = int(text)
        except ValueError:
            n = None
        if n is None or not lo <= n <= hi:
            raise argparse.ArgumentTypeError(f"must be an integer in [{lo}, {hi:,}]; got {text!r}")
        return n

    return parse


@contextmanager
def options_named(names: Mapping[str, str]) -> Iterator[None]:
    """Within the block, an error about a library parameter names the option the user typed.

    The library's messages name its parameters (``max_hz must be in ...``), right for a caller
    of the library; on the command line the user typed the option (``--max-hz``).

    Parameters
    ----------
    names : mapping of str to str
        A parameter's name as the library's message begins with it -> the option's text.

    Examples
    --------
    >>> from twin.errors import SignalError
    >>> with options_named({"max_hz": "--max-hz"}):
    ...     raise SignalError("max_hz must be in (0.5, 45] Hz; got 100")
    Traceback (most recent call last):
    ...
    twin.errors.SignalError: --max-hz must be in (0.5, 45] Hz; got 100

    """
    try:
        yield
    except TwinError as e:
        text = str(e)
        for name, option in names.items():
            if text.startswith(f"{name} "):
                raise type(e)(option + text[len(name) :]) from None
        raise


def json_parent(what: str = "the result") -> argparse.ArgumentParser:
    """Return a parent parser with ``--json``."""
    p = _parent()
    p.add_argument("--json", action="store_true", help=f"print {what} as JSON")
    return p


def seed_parent(what: str = "seed of the noise and the IMU") -> argparse.ArgumentParser:
    """Return a parent parser with ``--seed`` (an integer >= 0, default 0)."""
    p = _parent()
    p.add_argument("--seed", type=seed_type, default=0, metavar="N", help=f"{what} (default 0)")
    return p


class OutputFile(str):
    """A file the command writes, as named on the command line (see :func:`outputs_checked`)."""


class OutputFolder(str):
    """A folder the command writes, as named on the command line."""


def _path_type(
    check: Callable[[str], object], kind: type[str] = OutputFile
) -> Callable[[str], str]:
    """Return an argparse ``type`` that runs ``check`` on an output path (text kept as given)."""

    def parse(text: str) -> str:
        try:
            check(text)
        except UsageError as e:
            raise argparse.ArgumentTypeError(str(e)) from None
        return kind(text)

    return parse


def check_output_dir_path(text: str) -> None:
    """Refuse an output folder path that is a file or cannot be written (while parsing)."""
    if not text.strip():
        raise UsageError("an empty folder name; give a folder")
    if Path(text).exists() and not Path(text).is_dir():
        raise UsageError(f"{text}: is a file; give a folder")
    check_writable(text)


#: ``type=`` of an output folder: not a file, and somewhere this process may write.
output_dir = _path_type(check_output_dir_path, OutputFolder)
#: ``type=`` of an output file: not a folder, and somewhere this process may write.
output_file = _path_type(check_output_file)
#: ``type=`` of a Rerun recording: a ``.rrd`` file.
rrd_file = _path_type(lambda text: check_output_file(text, (".rrd",)))
#: ``type=`` of a CSV file written by the twin.
csv_file = _path_type(lambda text: check_output_file(text, (".csv",)))
#: ``type=`` of a figure file: also a suffix matplotlib writes (:data:`FIGURE_SUFFIXES`).
figure_file = _path_type(lambda text: check_output_file(text, FIGURE_SUFFIXES))


def out_parent(what: str, metavar: str = "DIR") -> argparse.ArgumentParser:
    """Return a parent parser with ``--out``; ``what`` says what is written there.

    A ``metavar`` of ``DIR`` is a folder, ``CSV`` a ``.csv`` file, anything else a file. The
    path is checked while parsing (:func:`output_dir`, :func:`csv_file`, :func:`output_file`),
    before any work.
    """
    p = _parent()
    kind = {"DIR": output_dir, "CSV": csv_file}.get(metavar, output_file)
    p.add_argument("--out", metavar=metavar, type=kind, help=what)
    return p


#: ``--overwrite``'s help: the same on every command that writes.
OVERWRITE_HELP = ("replace existing outputs: a file twin did not write, an earlier run "
                  "folder (never an input of the command, nor a user's files in an output "
                  "folder)")  # fmt: skip


def _writes(parser: argparse.ArgumentParser) -> bool:
    """Return whether ``parser`` has an output path option (an :func:`_path_type` type)."""
    return any(getattr(a.type, "__qualname__", "").startswith("_path_type.")
               for a in parser._actions)  # fmt: skip


def add_overwrite(parser: argparse.ArgumentParser) -> None:
    """Give ``--overwrite`` to ``parser`` and each of its subcommands that writes an output.

    Called once on the whole ``twin`` parser, so that every command with an output has the
    same ``--overwrite`` (:data:`OVERWRITE_HELP`).
    """
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in dict.fromkeys(action.choices.values()):
                add_overwrite(sub)
    if _writes(parser) and "--overwrite" not in parser._option_string_actions:
        parser.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)


def inputs_of(args: argparse.Namespace) -> list[str]:
    """Return the command's inputs: every existing path among its arguments but the outputs.

    A name that happens to be a file here too (``mpi`` beside a folder ``mpi``) is protected
    as well: an input is never replaced, so protecting one too many costs nothing.
    """
    found: list[str] = []
    for value in vars(args).values():
        for v in value if isinstance(value, list | tuple) else [value]:
            if isinstance(v, OutputFile | OutputFolder) or not isinstance(v, str | Path):
                continue
            with suppress(OSError, ValueError):
                if str(v) and os.path.lexists(v):
                    found.append(str(v))
    return found


def outputs_checked(args: argparse.Namespace) -> None:
    """Refuse, before any work, an output file that would replace what it must not.

    Run within the command's :func:`twin.ownership.output_policy`: an existing file is
    replaced only if it is an earlier output of the same kind or with ``--overwrite``, never
    an input (:func:`twin.ownership.check_replace`). Output folders are checked by the
    command, which knows their kind (:func:`twin.lifecycle.check_output_dir`).
    """
    for value in vars(args).values():
        for v in value if isinstance(value, list | tuple) else [value]:
            if isinstance(v, OutputFile):
                check_replace(v, kind_of(v))


def rrd_parent(what: str = "save a Rerun recording") -> argparse.ArgumentParser:
    """Return a parent parser with ``--rrd FILE`` (checked while parsing)."""
    p = _parent()
    p.add_argument("--rrd", metavar="FILE", type=rrd_file, help=what)
    return p


def scheduler_parent() -> argparse.ArgumentParser:
    """Return a parent parser with ``--scheduler`` (:mod:`twin.tasks.engine`)."""
    from twin.tasks.engine import SCHEDULER_HELP

    p = _parent()
    p.add_argument("--scheduler", metavar="WHERE", help=SCHEDULER_HELP)
    return p


def engine(args: argparse.Namespace):
    """Return the :class:`~twin.tasks.engine.Engine` of ``--scheduler`` (checked, not started)."""
    from twin.tasks.engine import Engine

    return Engine(args.scheduler)


def quiet_parent() -> argparse.ArgumentParser:
    """Return a parent parser with ``--quiet``."""
    p = _parent()
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    return p


def model_parent(default: str = DEFAULT_MODEL, why: str | None = None) -> argparse.ArgumentParser:
    """Return a parent parser with ``--model``.

    Parameters
    ----------
    default : str
        ``full`` everywhere; a command that defaults to ``reduced`` must say ``why``.
    why : str, optional
        Why this command departs from the ``full`` default (shown in the help).

    Raises
    ------
    ValueError
        For a non-default default without a reason (a programming error).

    """
    if default != DEFAULT_MODEL and not why:
        raise ValueError(f"--model defaults to {DEFAULT_MODEL}; say why {default} here")
    note = f"default {default}" + (f": {why}" if why else "")
    p = _parent()
    p.add_argument(
        "--model",
        choices=MODELS,
        default=default,
        help=f"platform model: full rigid-body MuJoCo or reduced Eq 5.11 ({note})",
    )
    return p


def overrides_parent(imu: bool = True) -> argparse.ArgumentParser:
    """Return a parent parser with the configuration overrides (and ``--ideal-imu``).

    Parameters
    ----------
    imu : bool
        Also offer ``--ideal-imu`` (commands that measure with an IMU).

    """
    p = _parent()
    g = p.add_argument_group("configuration overrides")
    g.add_argument(
        "--break-hz", type=float, metavar="HZ", help="platform-filter break frequency, Hz (0: none)"
    )
    g.add_argument("--delay-ms", type=float, metavar="MS", help="total motion-system delay, ms")
    g.add_argument("--no-noise", action="store_true", help="switch the Eq 5.10 noise off")
    g.add_argument(
        "--resonance", action="store_true", help="add the SRS resonance terms of Eq 5.12/5.13"
    )
    if imu:
        g.add_argument("--ideal-imu", action="store_true", help="IMU without noise and bias")
    return p


def overrides_given(args: argparse.Namespace) -> list[str]:
    """Return the configuration overrides (:func:`overrides_parent`) given, by option name.

    A value of 0 counts as given (``--break-hz 0`` removes the filter).
    """
    values = {
        "--break-hz": args.break_hz,
        "--delay-ms": args.delay_ms,
        "--no-noise": args.no_noise or None,
        "--resonance": args.resonance or None,
    }
    return [name for name, v in values.items() if v is not None]


def configured(config: str | MotionSystem, args: argparse.Namespace) -> MotionSystem:
    """Return a configuration (name, file or object) with the overrides in ``args``.

    Parameters
    ----------
    config : str or MotionSystem
        A configuration name, a ``twin-config/1`` file, or a configuration.
    args : argparse.Namespace
        Parsed options of a command with :func:`overrides_parent`.

    Returns
    -------
    MotionSystem
        ``config.override(...)`` with the options that were given.

    """
    from twin.chain.config import motion_system

    ms = motion_system(config) if isinstance(config, str) else config
    return ms.override(
        args.break_hz,
        args.delay_ms,
        False if args.no_noise else None,
        True if args.resonance else None,
    )


def imu_of(config: MotionSystem, args: argparse.Namespace):
    """Return the IMU of ``--ideal-imu`` (None: the platform's default IMU)."""
    if not getattr(args, "ideal_imu", False):
        return None
    from twin.chain.simulate import default_imu

    return default_imu(config.platform).ideal()


def progress(args: argparse.Namespace | bool = False) -> Progress:
    """Return the progress callback of a command (silent with ``--quiet``).

    Parameters
    ----------
    args : argparse.Namespace or bool
        Parsed options (``quiet`` read when present), or ``quiet`` itself.

    """
    if isinstance(args, bool):
        return Progress(args)
    return Progress(bool(getattr(args, "quiet", False)))
