"""The recorded-run format ``twin-run/1``: one folder per run, simulated or measured.

Layout::

    RUN/meta.json        format, platform, platform_config, command_rate_hz, imu, notes
    RUN/commands.csv     t,x,y,z,roll,pitch,yaw   UGP pose set-points, offsets from neutral,
                         thesis base frame (x fwd, y right, z down), m and rad
    RUN/imu.csv          t,ax,ay,az,p,q,r         specific force [m/s^2] (at rest az = -9.81),
                         angular rate [rad/s], cabin axes
    RUN/actuators.csv    t,l1,l2,l3,l4,l5,l6     optional: leg lengths [m]
    RUN/forces.csv       t,f1,f2,f3,f4,f5,f6     optional: actuator forces along the legs [N]
                                                 (positive extends; measured, or the full model's)

``meta.json`` holds ``format`` ("twin-run/1"), ``platform`` ("mpi" or "srs"),
``platform_config`` ({"filter_break_hz": number or null, "delay_s": number, "noise": bool},
more keys allowed), ``command_rate_hz``, ``imu`` ({"position_m": [x, y, z] in the cabin frame,
"rate_hz"}) and free ``notes``; a simulator may add keys (``model``, ``seed``, ``limits``).
Times are seconds, uniformly sampled, strictly increasing. :class:`RunWriter` writes a run
into a temporary folder and renames it when complete, so a failed run leaves nothing.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

import numpy as np
from numpy.typing import NDArray

from twin.chain.config import MotionSystem
from twin.chain.signals import check_physical
from twin.chain.trajectory import Trajectory, uniform_rate
from twin.core.checks import ENCODING, not_utf8, number, numbers, read_json
from twin.core.errors import ConfigError, OutputError, RunFormatError, SignalError, UsageError
from twin.core.frames import DOF_NAMES
from twin.core.lifecycle import (
    CloseOrAbort,
    StagedFolder,
    cannot_write,
    check_output_dir,
    refuse_replacing,
    writing,
)
from twin.core.ownership import read_manifest
from twin.formats.schedule import Schedule
from twin.platform.facts import PLATFORMS

FloatArray = NDArray[np.float64]
FORMAT = "twin-run/1"
HEADERS = {
    "commands.csv": ("t", "x", "y", "z", "roll", "pitch", "yaw"),
    "imu.csv": ("t", "ax", "ay", "az", "p", "q", "r"),
    "actuators.csv": ("t", "l1", "l2", "l3", "l4", "l5", "l6"),
    "forces.csv": ("t", "f1", "f2", "f3", "f4", "f5", "f6"),
}
#: The files a run has at least (the others are optional).
REQUIRED = ("commands.csv", "imu.csv")
#: The files of a simulated run: with the full model's leg forces where it has them.
SIMULATED = (*REQUIRED, "actuators.csv")
#: Largest magnitude a recorded value may have, per column (beyond it the file is not a
#: recording of a motion system: a unit or logging error): specific force 1000 m/s^2 (100 g),
#: angular rate 100 rad/s, leg length 100 m, leg force 1e8 N. Commands:
#: :data:`twin.chain.signals.MAX_COMMAND`.
MAX_VALUE = {"ax": 1e3, "ay": 1e3, "az": 1e3, "p": 1e2, "q": 1e2, "r": 1e2,
             **{f"l{i}": 1e2 for i in range(1, 7)},
             **{f"f{i}": 1e8 for i in range(1, 7)}}  # fmt: skip
#: Highest sample rate a file may state [Hz] (a 1 MHz log is not a motion-system run).
MAX_RATE_HZ = 1e6
#: Allowed relative difference between a file's sample rate and the rate in meta.json.
RATE_TOLERANCE = 0.005


@dataclass(frozen=True, eq=False)
class RecordedRun:
    """A run read from disk.

    Attributes
    ----------
    path : Path
        The folder.
    meta : dict
        Contents of ``meta.json``.
    commands : Trajectory
        Pose commands.
    imu_t : ndarray, shape (n,)
        IMU sample times [s].
    imu : ndarray, shape (n, 6)
        ax, ay, az [m/s^2], p, q, r [rad/s].
    actuators : ndarray, shape (m, 7) or None
        t, l1..l6, if recorded.
    forces : ndarray, shape (k, 7) or None
        t, f1..f6 [N], if recorded.
    notes : tuple of str
        What the reader did to the data, one sentence each (e.g. an IMU resampled to a rate
        the analyses are made for: :func:`twin.formats.run_checks.supported_rate`).
    plausible : bool
        Whether :func:`twin.formats.run_checks.plausible_run` has passed it (it is not checked
        again).

    """

    path: Path
    meta: dict
    commands: Trajectory
    imu_t: FloatArray
    imu: FloatArray
    actuators: FloatArray | None
    forces: FloatArray | None = None
    notes: tuple[str, ...] = ()
    plausible: bool = False


def _read_csv(path: Path) -> FloatArray:
    """Read one CSV of the format, checking header, numbers, finiteness and time."""
    name = path.name
    if not path.is_file():
        raise RunFormatError(f"{path.parent}: missing {name}")
    data, _ = read_number_table(path, HEADERS[name])
    try:
        uniform_rate(data[:, 0], str(path))
    except SignalError as e:
        raise RunFormatError(str(e)) from None
    return data


def read_number_table(
    path: Path,
    header: tuple[str, ...],
    optional: tuple[str, ...] = (),
    limits: Mapping[str, float] = MAX_VALUE,
) -> tuple[FloatArray, tuple[str, ...]]:
    """Read a CSV of numbers with a header row: ``header``, then any of ``optional``.

    ``limits`` bounds the magnitude of named columns (:data:`MAX_VALUE` by default).

    UTF-8 (a byte-order mark is dropped); shared by the ``twin-run/1`` files and
    ``twin-pilot/1``.

    Raises
    ------
    RunFormatError
        Naming the file: not UTF-8 text, a header that is not ``header`` (+ ``optional``), a
        value that is not a finite number or beyond its limit, rows of different lengths,
        fewer than 2 rows.

    """
    with path.open(encoding=ENCODING) as fh:
        try:
            got = tuple(c.strip() for c in fh.readline().strip().split(","))
            extra = got[len(header) :]
            if got[: len(header)] != header or any(c not in optional for c in extra):
                want = ",".join(header) + "".join(f"[,{c}]" for c in optional)
                shown = ",".join(got)[:200] or "an empty line"
                raise RunFormatError(f"{path}: header must be {want}; got {shown}")
            with warnings.catch_warnings():  # an empty table is refused below, not warned of
                warnings.simplefilter("ignore", UserWarning)
                data = np.loadtxt(fh, delimiter=",", ndmin=2)
        except UnicodeDecodeError as e:
            raise RunFormatError(not_utf8(path, e, "a CSV of numbers")) from None
        except RunFormatError:
            raise
        except ValueError as e:
            why = _first_bad_line(path, got) or str(e)[:200]
            raise RunFormatError(f"{path}: not a table of numbers: {why}") from None
    if data.shape[0] < 2 or data.shape[1] != len(got):
        raise RunFormatError(f"{path}: needs at least 2 rows of {len(got)} numbers")
    bad = ~np.isfinite(data)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise RunFormatError(
            f"{path}: {_where(path, int(row) + 1)}: {got[col]} is {data[row, col]}; "
            "all values must be finite"
        )
    check_values(data, got, str(path), limits)
    return data, got


def _data_lines(path: Path) -> Iterator[tuple[int, int, str]]:
    """Yield (row, line, text) of each data row after the header, as numpy.loadtxt reads them.

    Comments and blank lines are no rows; row 1 is the first data row, line 1 the header.
    """
    with path.open(encoding=ENCODING) as fh:
        fh.readline()
        row = 0
        for number, line in enumerate(fh, start=2):
            text = line.split("#", 1)[0]
            if text.strip():
                row += 1
                yield row, number, text


def _where(path: Path, row: int) -> str:
    """Return 'row R (line L)' for data row ``row`` (from 1) of ``path``."""
    line = next((n for r, n, _ in _data_lines(path) if r == row), row + 1)
    return f"row {row} (line {line})"


def _first_bad_line(path: Path, header: tuple[str, ...]) -> str | None:
    """Say where a CSV of numbers first is not one after its header; None if no line is.

    Rows and lines are counted as in the other messages (:func:`_data_lines`).
    """
    for row, line, text in _data_lines(path):
        cells = [c.strip() for c in text.split(",")]
        where = f"row {row} (line {line})"
        if len(cells) != len(header):
            return f"{where} has {len(cells)} values, the header {len(header)}"
        for name, cell in zip(header, cells, strict=True):
            try:
                if "_" in cell:  # float() takes 1_0, loadtxt does not
                    raise ValueError(cell)
                float(cell)
            except ValueError:
                shown = repr(cell[:40]) if cell else "empty"
                return f"{where}: {name} is {shown}, not a number"
    return None


def check_values(
    data: FloatArray, names: Sequence[str], where: str, limits: Mapping[str, float] = MAX_VALUE
) -> None:
    """Raise :class:`RunFormatError` for a value beyond its column's limit (:data:`MAX_VALUE`).

    Parameters
    ----------
    data : ndarray, shape (n, len(names))
        The table.
    names : sequence of str
        Its column names.
    where : str
        The file (or what the values are), for the message.
    limits : mapping of str to float
        Largest magnitude per column name (others are not bounded).

    """
    top = np.array([limits.get(c, np.inf) for c in names])
    over = np.abs(data) > top
    if over.any():
        row, col = np.argwhere(over)[0]
        raise RunFormatError(
            f"{where}: data row {row + 1}: {names[col]} is {data[row, col]:g}; it must lie "
            f"within +-{top[col]:g} (a larger value is a unit or logging error)"
        )


def _check_rate(path: Path, t: FloatArray, expected: float) -> None:
    """Refuse a file (``path``, its times ``t``) not sampled at the rate meta.json states."""
    rate = uniform_rate(t, str(path))
    if abs(rate / expected - 1) > RATE_TOLERANCE:
        raise RunFormatError(f"{path}: sampled at {rate:.6g} Hz but meta.json says {expected:g} Hz")


def _check_meta(meta: object, path: Path) -> dict:
    """Check a ``meta.json``'s keys and types (the configuration as :meth:`from_meta` does)."""
    where = f"{path}/meta.json"
    if not isinstance(meta, dict):
        raise RunFormatError(f"{where}: must hold a JSON object")
    if meta.get("format") != FORMAT:
        raise RunFormatError(f"{where}: format must be {FORMAT!r}; got {meta.get('format')!r}")
    if not isinstance(meta.get("platform"), str) or meta["platform"] not in PLATFORMS:
        raise RunFormatError(
            f"{where}: platform must be one of {', '.join(PLATFORMS)}; got {meta.get('platform')!r}"
        )
    try:
        MotionSystem.from_meta(meta["platform"], meta.get("platform_config"))
    except ConfigError as e:
        raise RunFormatError(f"{where}: {e}") from None
    number(meta.get("command_rate_hz"), f"{where}: command_rate_hz", lo=0, lo_open=True,
           hi=MAX_RATE_HZ, error=RunFormatError)  # fmt: skip
    imu = meta.get("imu")
    if not isinstance(imu, dict):
        raise RunFormatError(f"{where}: imu must hold position_m [x, y, z] and rate_hz > 0")
    number(imu.get("rate_hz"), f"{where}: imu.rate_hz", lo=0, lo_open=True, hi=MAX_RATE_HZ,
           error=RunFormatError)  # fmt: skip
    numbers(imu.get("position_m"), f"{where}: imu.position_m [x, y, z]", size=3,
            error=RunFormatError)  # fmt: skip
    _check_optional(meta, where)
    if "schedule" in meta:
        Schedule.from_json(meta["schedule"], f"{where}: schedule")
    return meta


def _check_optional(meta: dict, where: str) -> None:
    """Check the optional ``signal`` (the test design) and ``import`` entries of a meta.json."""

    def table(value: object, name: str) -> dict:
        if not isinstance(value, dict):
            raise RunFormatError(f"{where}: {name} must be a JSON object; got {value!r:.60}")
        return value

    sig = table(meta.get("signal", {}), "signal")
    if "dof" in sig and (not isinstance(sig["dof"], str) or sig["dof"] not in DOF_NAMES):
        raise RunFormatError(f"{where}: signal.dof must be one of {', '.join(DOF_NAMES)}; "
                             f"got {sig['dof']!r:.60}")  # fmt: skip
    for key in ("amplitude", "step_s"):
        if key in sig:
            number(sig[key], f"{where}: signal.{key}", lo=0, lo_open=True, error=RunFormatError)
    if "start_s" in sig:
        number(sig["start_s"], f"{where}: signal.start_s", lo=0, error=RunFormatError)
    if "levels" in sig:
        numbers(sig["levels"], f"{where}: signal.levels", error=RunFormatError)
    if "frequencies_hz" in sig:
        f = numbers(sig["frequencies_hz"], f"{where}: signal.frequencies_hz", error=RunFormatError)
        if np.any(f <= 0):
            raise RunFormatError(f"{where}: signal.frequencies_hz must be > 0")
    if sig.get("amplitudes") is not None:
        numbers(sig["amplitudes"], f"{where}: signal.amplitudes", error=RunFormatError)
    if "window_s" in sig:
        w = numbers(sig["window_s"], f"{where}: signal.window_s [start, end]", size=2,
                    error=RunFormatError)  # fmt: skip
        if not 0 <= w[0] < w[1]:
            raise RunFormatError(f"{where}: signal.window_s must be [start, end], 0 <= start < end")
    clock = table(table(meta.get("import", {}), "import").get("clock", {}), "import.clock")
    if not isinstance(clock.get("delay_identifiable", False), bool):
        raise RunFormatError(f"{where}: import.clock.delay_identifiable must be true or false")


def read_run(folder: str | Path | RecordedRun) -> RecordedRun:
    """Read and validate a ``twin-run/1`` folder (a run already read is returned as it is).

    This is the format only; the analyses read runs through
    :func:`twin.formats.run_checks.read_plausible_run`, which also checks that the data are
    plausible for a motion system (gravity, units, axes, clock and IMU rate) and resamples an IMU
    faster than the analyses are made for, with a note in :attr:`RecordedRun.notes`.

    Raises
    ------
    RunFormatError
        Naming the file (and row) that is wrong: missing file, wrong header, a value that is
        not a finite number, time not uniform and strictly increasing, or a rate that does not
        match ``meta.json``.

    """
    if isinstance(folder, RecordedRun):
        return folder
    path = Path(folder)
    if not path.is_dir():
        raise RunFormatError(f"{path}: not a run folder (expected a directory)")
    meta_path = path / "meta.json"
    if not meta_path.is_file():
        raise RunFormatError(f"{path}: missing meta.json")
    meta = _check_meta(read_json(meta_path, "a twin-run/1 meta.json", RunFormatError), path)
    cmd = _read_csv(path / "commands.csv")
    _check_rate(path / "commands.csv", cmd[:, 0], float(meta["command_rate_hz"]))
    imu = _read_csv(path / "imu.csv")
    _check_rate(path / "imu.csv", imu[:, 0], float(meta["imu"]["rate_hz"]))
    act = None
    if (path / "actuators.csv").exists():
        act = _read_csv(path / "actuators.csv")
    forces = _read_csv(path / "forces.csv") if (path / "forces.csv").exists() else None
    commands = _trajectory(cmd, path / "commands.csv")
    return RecordedRun(path, meta, commands, imu[:, 0], imu[:, 1:], act, forces)


#: What a commands file is, as a run folder holds it (messages and help).
COMMANDS_FILE = f"{','.join(HEADERS['commands.csv'])}; uniform time at any rate"


def read_commands(path: str | Path) -> Trajectory:
    """Read a ``commands.csv`` on its own (any rate, taken from its time column).

    Raises
    ------
    RunFormatError
        For a file that is missing, not a ``.csv`` or not a valid ``twin-run/1`` commands file
        (its header says the format; a lab's log in other columns or units goes through
        ``twin import``). Any name will do (a designed run's ``commands.csv``, a lab's copy).

    """
    p = Path(path)
    if not p.is_file():
        raise RunFormatError(f"{p}: no such file; a commands file is a twin-run/1 commands.csv "
                             f"({COMMANDS_FILE})")  # fmt: skip
    if p.suffix.lower() != ".csv":
        raise RunFormatError(f"{p}: a commands file is a .csv as in a twin-run/1 folder "
                             f"({COMMANDS_FILE}); got {p.name!r}")  # fmt: skip
    try:
        data, _ = read_number_table(p, HEADERS["commands.csv"])
        uniform_rate(data[:, 0], str(p))
    except RunFormatError as e:
        raise RunFormatError(f"{e}; a lab's log in other columns or units: twin import "
                             "reads it") from None  # fmt: skip
    except SignalError as e:
        raise RunFormatError(str(e)) from None
    return _trajectory(data, p)


def _trajectory(cmd: FloatArray, path: Path) -> Trajectory:
    """Return the commands of a ``commands.csv`` (refused beyond :data:`MAX_COMMAND`)."""
    tr = Trajectory(uniform_rate(cmd[:, 0], str(path)), cmd[:, 1:], float(cmd[0, 0]))
    try:
        check_physical(tr, str(path))
    except SignalError as e:
        raise RunFormatError(str(e)) from None
    return tr


def write_commands(path: str | Path, commands: Trajectory) -> Path:
    """Write a ``commands.csv`` on its own (e.g. a designed run for a platform to play).

    The file :func:`read_commands` reads (and ``twin simulate --signal`` takes).
    """
    p = Path(path)
    with open(p, "w", encoding="utf-8", newline="") as fh:
        fh.write(",".join(HEADERS["commands.csv"]) + "\n")
        _write_rows(fh, commands.t0 + np.arange(commands.n) / commands.rate_hz, commands.values)
    return p


def _write_rows(fh: TextIO, t: FloatArray, values: FloatArray, block: int = 8192) -> None:
    """Write rows of ``%.10g`` numbers, as ``np.savetxt`` would, one block at a time.

    Each block is formatted by one ``%`` of the repeated row format (C, not a Python loop per
    row as ``savetxt``): the same text, about twice as fast.
    """
    for k in range(0, len(t), block):  # in blocks: no whole-run copy
        rows = np.column_stack([t[k : k + block], values[k : k + block]])
        row = ",".join(["%.10g"] * rows.shape[1]) + "\n"
        fh.write((row * len(rows)) % tuple(rows.ravel().tolist()))


#: The kind of output a run folder is (its marker file, :class:`~twin.core.lifecycle.StagedFolder`).
RUN_KIND = "meta.json"
#: The files of a run: in an existing folder, each must be an earlier run's that the twin wrote
#: (a user's ``actuators.csv`` beside new commands would be read as the new run's).
RUN_FILES = (*HEADERS, "meta.json")


def check_run_output(folder: str | Path, overwrite: bool = False) -> None:
    """Refuse a run folder to write, before any work (also done by :class:`RunWriter`).

    A new folder is written; an existing one only with ``overwrite`` and only if it is an
    earlier run the twin wrote (its own files are replaced, a user's others stay), never an
    input of the command.

    Raises
    ------
    UsageError
        Naming the folder and what to do instead.

    """
    folder = Path(folder)
    if folder.exists() and not overwrite:
        raise UsageError(f"{folder}: already exists (choose another --out, or --overwrite to "
                         "replace a run the twin wrote)")  # fmt: skip
    check_output_dir(folder, RUN_KIND)
    if folder.is_dir():
        refuse_replacing(folder, list(RUN_FILES), read_manifest(folder)["files"], RUN_KIND)


class RunWriter(CloseOrAbort):
    """Write a run folder incrementally; it appears under its name only when complete.

    Use as a context manager: on an exception (also one of finishing the folder) the
    temporary folder is removed (:class:`~twin.core.lifecycle.StagedFolder`).

    Parameters
    ----------
    folder : str or Path
        Destination; must not exist yet (or ``overwrite=True``: an earlier run the twin wrote
        there is replaced, a user's other files in the folder stay).
    meta : dict
        ``meta.json`` contents (checked against the format).
    overwrite : bool
        Replace an existing folder.
    files : sequence of str
        The CSV files the run has (``actuators.csv`` and ``forces.csv`` are optional in the
        format).

    Raises
    ------
    OutputError
        A file that cannot be written (a full disk, ...), named by its path in ``folder``.

    """

    def __init__(
        self,
        folder: str | Path,
        meta: dict,
        overwrite: bool = False,
        files: Sequence[str] = SIMULATED,
    ) -> None:
        self.folder = Path(folder)
        check_run_output(self.folder, overwrite)
        self.meta = dict(meta, format=FORMAT)
        _check_meta(self.meta, self.folder)
        self._staged = StagedFolder(self.folder, RUN_KIND, reserved=RUN_FILES)
        self.tmp = self._staged.tmp
        self._files: dict[str, TextIO] = {}
        with self._removed_on_error():
            for name in files:
                with writing(self.folder / name):
                    self._files[name] = (self.tmp / name).open("w", encoding="utf-8")
                    self._files[name].write(",".join(HEADERS[name]) + "\n")

    def write(self, name: str, t: FloatArray, values: FloatArray) -> None:
        """Append rows to one of the run's CSV files (``commands.csv``, ``imu.csv``, ...)."""
        with writing(self.folder / name):
            _write_rows(self._files[name], t, values)

    def close(self) -> None:
        """Finish: close the files, write ``meta.json`` and rename the folder into place."""
        with self._removed_on_error():
            self._close_files()
            with writing(self.folder / "meta.json"):
                (self.tmp / "meta.json").write_text(json.dumps(self.meta, indent=2) + "\n")
            self._staged.finish()

    def abort(self) -> None:
        """Remove everything written."""
        with suppress(OutputError):
            self._close_files()
        self._staged.discard()

    @contextmanager
    def _removed_on_error(self) -> Iterator[None]:
        """Within the block, an error aborts (a failed write named by its final path)."""
        with self._staged.removed_on_error():
            try:
                yield
            except BaseException:
                self.abort()
                raise

    def _close_files(self) -> None:
        """Close every file, even after one failed; raise the first failure, named."""
        failed = None
        for name, fh in self._files.items():
            try:
                fh.close()
            except OSError as e:
                failed = failed or cannot_write(self.folder / name, e)
        if failed is not None:
            raise failed
