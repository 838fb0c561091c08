"""What every ``twin`` command shares: parent parsers, overrides, progress.

Parent parsers (``parents=[...]`` of a subcommand) give the same options the same spelling,
type and help everywhere:

==============================  ===========================================================
option                          meaning
==============================  ===========================================================
``CONFIG``                      the motion system (first positional, :func:`add_config`):
                                a configuration name, a platform name, a ``twin-config/1``
                                file, or (where the command reads one) a ``twin-run/1`` folder
``--dof DOF``                   a DOF, repeated for several (``--dof pitch --dof roll``); a
                                command that takes one refuses a second (:func:`add_dof`)
``--json``                      print the result as JSON on stdout
``--seed N``                    seed of the noise and the IMU (integer >= 0; default 0)
numbers                         every numeric option's ``type`` is :func:`number` or
                                :func:`count`: finite and in a range its help gives
``--out DIR``                   where results go (the command says what it writes); a
                                command that writes a folder by default writes
                                ``out/<command>-<name>`` (:func:`default_out`), the others
                                write nothing unless asked (``--out``, ``--plot``, ``--rrd``)
``--rrd FILE``                  save a Rerun recording
``--quiet``                     no progress on stderr (never changes stdout)
``--overwrite``                 on every command that writes: replace what twin wrote before
``--scheduler WHERE``           where a batch command's tasks run (:mod:`twin.core.tasks.engine`)
``--model {full,reduced}``      platform model; **full by default everywhere**; a command
                                that defaults to ``reduced`` says why in its help
overrides                       ``--delay-ms``, ``--break-hz``, ``--no-noise``,
                                ``--resonance``: configuration overrides
                                (:meth:`MotionSystem.override`)
``--ideal-imu``                 IMU without noise and bias (commands that use an IMU)
==============================  ===========================================================

Progress goes through one helper, :func:`progress`: a :class:`twin.core.progress.Progress` that
library functions take as their ``progress=`` argument (a tqdm bar with ETA for counted work);
it prints on stderr only when stderr is a terminal and ``--quiet`` is not given.
"""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import TYPE_CHECKING

from twin.chain.bounds import MAX_BREAK_HZ, MAX_DELAY_S, MIN_BREAK_HZ
from twin.core.errors import TwinError, UsageError
from twin.core.lifecycle import check_output_file, check_writable
from twin.core.ownership import check_replace, kind_of
from twin.core.progress import Progress

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


# --- numbers: every numeric option is a finite number in a range, given in its help --------


class Number:
    """An argparse ``type``: a finite number (or an integer) in a range.

    Made by :func:`number` (and :func:`count`, :func:`seed_type`); every numeric option of
    the twin takes one, so ``nan``, ``inf``, ``1e9`` or ``-1`` where they make no sense are
    refused while parsing, with one line naming the option and the range. :attr:`span` is the
    range as the help shows it.

    Parameters
    ----------
    lo, hi : float
        The range (``math.inf`` for none on that side).
    lo_open, hi_open : bool
        Exclude the bound itself.
    integer : bool
        Only integers (``--runs``, ``--seed``).
    name : str
        Begins the message (``seed``); argparse adds the option's name in front anyway.

    Examples
    --------
    >>> number(0, 90)("45")
    45.0
    >>> number(0, 90).span
    'in [0, 90]'
    >>> number(0, 90)("nan")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: must be a number in [0, 90]; got nan

    """

    def __init__(self, lo: float, hi: float, *, lo_open: bool = False, hi_open: bool = False,
                 integer: bool = False, name: str = "") -> None:  # fmt: skip
        self.lo, self.hi, self.lo_open, self.hi_open = lo, hi, lo_open, hi_open
        self.integer = integer
        self.name = name

    def _bound(self, x: float) -> str:
        return f"{int(x):,}" if self.integer else f"{x:g}"

    @property
    def span(self) -> str:
        """The range: ``in [0, 90]``, ``in (0, 1]``, ``>= 0``."""
        lo, hi = math.isinf(self.lo), math.isinf(self.hi)
        if hi:
            return "" if lo else f"{'>' if self.lo_open else '>='} {self._bound(self.lo)}"
        if lo:
            return f"{'<' if self.hi_open else '<='} {self._bound(self.hi)}"
        return (f"in {'(' if self.lo_open else '['}{self._bound(self.lo)}, "
                f"{self._bound(self.hi)}{')' if self.hi_open else ']'}")  # fmt: skip

    def __call__(self, text: str) -> float:
        """Return the number ``text`` gives, else raise :class:`argparse.ArgumentTypeError`."""
        value: float | None
        try:  # int(): no "1e3" or "1.5"; an integer of more than 4300 digits is a ValueError
            value = int(text) if self.integer else float(text)
        except ValueError:
            value = None
        if value is not None and (self.integer or math.isfinite(value)) and self._within(value):
            return value + 0  # -0.0 is 0.0
        if value is None:  # not a number at all: shown as typed (a 5000-digit one cut short)
            shown = repr(_cut(text))
        else:
            shown = _cut(str(value)) if self.integer else f"{value:g}"
        what = "an integer" if self.integer else "a number"
        raise argparse.ArgumentTypeError(
            f"{self.name + ' ' if self.name else ''}must be {what} {self.span}; got {shown}"
        )

    def _within(self, v: float) -> bool:
        above = v > self.lo if self.lo_open else v >= self.lo
        return above and (v < self.hi if self.hi_open else v <= self.hi)


def _cut(text: str, width: int = 40) -> str:
    return text if len(text) <= width else text[: width - 3] + "..."


def number(lo: float, hi: float, *, lo_open: bool = False, hi_open: bool = False) -> Number:
    """Return an argparse ``type``: a finite number in [lo, hi] (bounds excluded if open)."""
    return Number(lo, hi, lo_open=lo_open, hi_open=hi_open)


def count(lo: int, hi: int) -> Number:
    """Return an argparse ``type``: an integer in [lo, hi] (``--runs``, ``--subjects``)."""
    return Number(lo, hi, integer=True)


#: ``type=`` of ``--seed``: an integer >= 0.
seed_type = Number(0, math.inf, integer=True, name="seed")
#: ``--break-hz``: 0 (no filter) up to the largest break frequency (the library refuses the gap
#: between 0 and the smallest, naming both).
BREAK_HZ = number(0, MAX_BREAK_HZ)
#: ``--delay-ms`` (and delays given in ms): 0 up to the longest delay the chain holds.
DELAY_MS = number(0, MAX_DELAY_S * 1e3)


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
    >>> from twin.core.errors import SignalError
    >>> with options_named({"max_hz": "--max-hz"}):
    ...     raise SignalError("max_hz must be in (0.5, 45] Hz; got 100")
    Traceback (most recent call last):
    ...
    twin.core.errors.SignalError: --max-hz must be in (0.5, 45] Hz; got 100

    """
    try:
        yield
    except TwinError as e:
        text = str(e)
        for name, option in names.items():
            if text.startswith(f"{name} "):
                raise type(e)(option + text[len(name) :]) from None
        raise


#: The metavar of every argument that names a motion system.
CONFIG = "CONFIG"


def config_phrase(run: bool = False) -> str:
    """Return the help of a ``CONFIG`` argument: what names a motion system.

    Parameters
    ----------
    run : bool
        The command also reads a recorded ``twin-run/1`` folder in its place.

    """
    from twin.chain.config import config_names

    names = config_names()
    conditions = [n for n in names if n.startswith("condition-")]
    shown = [n for n in names if n not in conditions]
    if conditions:  # the eight Table 6.3 conditions as a range
        shown.append(f"{conditions[0]} ... {conditions[-1]}" if conditions[1:] else conditions[0])
    names = ", ".join(shown)
    text = (f"the motion system: a configuration ({names}; mpi and srs are also the "
            "platforms' names) or a twin-config/1 .json file")  # fmt: skip
    return text + (", or a recorded twin-run/1 folder" if run else "")


def add_config(parser: argparse.ArgumentParser, *, run: bool = False, note: str = "") -> None:
    """Add the positional ``CONFIG`` (``dest`` ``config``) with the one help of every command.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's parser.
    run : bool
        The command also reads a recorded ``twin-run/1`` folder (:func:`config_phrase`).
    note : str
        What this command does with it, appended to the help (``; only its platform ...``).

    """
    parser.add_argument("config", metavar=CONFIG, help=config_phrase(run) + note)


class _OneDof(argparse.Action):
    """``--dof`` of a command that takes one DOF: a second ``--dof`` is refused."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: object, option_string: str | None = None) -> None:  # fmt: skip
        given = getattr(namespace, self.dest, None)
        if given is not None:
            raise argparse.ArgumentError(
                self, f"{parser.prog} takes one DOF; got --dof {given} --dof {values}"
            )
        setattr(namespace, self.dest, values)


def add_dof(parser: argparse.ArgumentParser, what: str, *, one: bool = False,
            choices: tuple[str, ...] | None = None) -> None:  # fmt: skip
    """Add ``--dof DOF``: repeated for several DOFs, or (``one``) given at most once.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's parser.
    what : str
        The help: what the DOFs are for and the default.
    one : bool
        The command takes one DOF: ``args.dof`` is a str (or None) and a second ``--dof`` is
        refused in one line naming the command and both DOFs. Otherwise ``args.dof`` is a list
        (or None) and ``--dof`` is repeated (``--dof pitch --dof roll``).
    choices : tuple of str, optional
        The DOFs allowed (default all six).

    """
    from twin.core.frames import DOF_NAMES

    allowed = DOF_NAMES if choices is None else choices
    if one:
        parser.add_argument("--dof", action=_OneDof, choices=allowed, metavar="DOF",
                            help=f"{what} (one of {', '.join(allowed)})")  # fmt: skip
    else:
        parser.add_argument("--dof", action="append", choices=allowed, metavar="DOF",
                            help=f"{what}; repeat for several: --dof pitch --dof roll (each "
                            f"one of {', '.join(allowed)})")  # fmt: skip


#: ``--json``'s help: the same on every command that has it.
JSON_HELP = "print the result as JSON on stdout (instead of the text)"


def json_parent() -> argparse.ArgumentParser:
    """Return a parent parser with ``--json`` (:data:`JSON_HELP`)."""
    p = _parent()
    p.add_argument("--json", action="store_true", help=JSON_HELP)
    return p


def default_out(command: str, name: str = "") -> Path:
    """Return the folder a command writes when no ``--out`` is given: ``out/<command>-<name>``.

    The one rule of every command that writes a folder by default (``simulate``, ``agard
    report``, ``agard demo``, a scheduled ``agard`` test, ``design``, ``diagnose``,
    ``import``, ``sweep``); the other commands write nothing unless asked (``--out``,
    ``--plot``, ``--rrd``).

    Parameters
    ----------
    command : str
        The command's words joined by ``-`` (``agard-report``).
    name : str
        What the output is of: the first input's name, or the configuration and model.

    Examples
    --------
    >>> str(default_out("agard-report", "srs-full"))
    'out/agard-report-srs-full'
    >>> str(default_out("agard-demo"))
    'out/agard-demo'

    """
    return Path("out") / (f"{command}-{name}" if name else command)


def default_out_help(what: str, command: str, name: str = "") -> str:
    """Return ``--out``'s help of a command with a default folder: ``what (default ...)``."""
    shown = f"out/{command}-{name}" if name else f"out/{command}"
    return f"{what} (default {shown})"


def seed_parent(what: str = "seed of the noise and the IMU") -> argparse.ArgumentParser:
    """Return a parent parser with ``--seed`` (an integer >= 0, default 0)."""
    p = _parent()
    p.add_argument("--seed", type=seed_type, default=0, metavar="N",
                   help=f"{what} (an integer {seed_type.span}; default 0)")  # fmt: skip
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

    Run within the command's :func:`twin.core.ownership.output_policy`: an existing file is
    replaced only if it is an earlier output of the same kind or with ``--overwrite``, never
    an input (:func:`twin.core.ownership.check_replace`). Output folders are checked by the
    command, which knows their kind (:func:`twin.core.lifecycle.check_output_dir`).
    """
    values = [v for value in vars(args).values()
              for v in (value if isinstance(value, list | tuple) else [value])]  # fmt: skip
    for v in values:
        if isinstance(v, OutputFile):
            check_replace(v, kind_of(v))
            for folder in values:
                if isinstance(folder, OutputFolder):
                    refuse_file_in_folder(v, folder)


def refuse_file_in_folder(path: str | Path, folder: str | Path) -> None:
    """Refuse an output file inside the command's output folder (staged, then put in place).

    The folder appears only when complete; a file written into it before would make it a
    folder of another kind, and the folder's own output would be refused after the work.

    Raises
    ------
    UsageError
        Naming both.

    """
    here, there = Path(os.path.abspath(path)), Path(os.path.abspath(folder))
    if there == here or there in here.parents:
        raise UsageError(f"{path}: must not lie inside the output folder {folder} (it appears "
                         "only when complete); give a file outside it")  # fmt: skip


def rrd_parent(what: str = "save a Rerun recording") -> argparse.ArgumentParser:
    """Return a parent parser with ``--rrd FILE`` (checked while parsing)."""
    p = _parent()
    p.add_argument("--rrd", metavar="FILE", type=rrd_file, help=what)
    return p


def scheduler_parent() -> argparse.ArgumentParser:
    """Return a parent parser with ``--scheduler`` (:mod:`twin.core.tasks.engine`)."""
    from twin.core.tasks.engine import SCHEDULER_HELP

    p = _parent()
    p.add_argument("--scheduler", metavar="WHERE", help=SCHEDULER_HELP)
    return p


def engine(args: argparse.Namespace):
    """Return ``--scheduler``'s :class:`~twin.core.tasks.engine.Engine` (checked, not started)."""
    from twin.core.tasks.engine import Engine

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
    g.add_argument("--break-hz", type=BREAK_HZ, metavar="HZ",
                   help=f"platform-filter break frequency, Hz ({BREAK_HZ.span}; 0: none, else at "
                   f"least {MIN_BREAK_HZ:g})")  # fmt: skip
    g.add_argument("--delay-ms", type=DELAY_MS, metavar="MS",
                   help=f"total motion-system delay, ms ({DELAY_MS.span})")  # fmt: skip
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
