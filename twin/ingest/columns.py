"""Columns of a measured CSV: which twin signal each is, and in what unit.

A measured log names its columns as its logger does (``Time [ms]``, ``heave_mm``,
``AccZ (g)``, ``gyro_y_dps``). :func:`read_table` reads a delimited text table (comma,
semicolon, tab or whitespace; ``#`` comment lines; one header row); :func:`recognise` maps
header names to the twin's signals (:data:`TARGETS`) with their units, from the name itself
(:data:`ALIASES`, unit decorations ``[deg]``, ``(g)``, ``_deg``, ``/s``) or from an explicit
mapping ``TARGET=COLUMN[:UNIT]``. A column that is not recognised is ignored and listed;
a mapping that names a missing column or an unknown unit is an error that lists what is
allowed.
"""

from __future__ import annotations

import csv
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from twin.chain.imu import G
from twin.core.checks import ENCODING
from twin.core.errors import DataError

FloatArray = NDArray[np.float64]

#: Twin signals by kind: pose commands (offsets from neutral), IMU channels and time.
COMMAND_TARGETS = ("x", "y", "z", "roll", "pitch", "yaw")
IMU_TARGETS = ("ax", "ay", "az", "p", "q", "r")
TARGETS = ("t", *COMMAND_TARGETS, *IMU_TARGETS)
#: Physical quantity of every target.
KIND = {"t": "time"} | dict.fromkeys(("x", "y", "z"), "length") | dict.fromkeys(
    ("roll", "pitch", "yaw"), "angle") | dict.fromkeys(("ax", "ay", "az"), "acceleration") | (
    dict.fromkeys(("p", "q", "r"), "rate"))  # fmt: skip
#: Units per kind: name -> factor to the twin's SI unit (s, m, rad, m/s^2, rad/s).
UNITS: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9},
    "length": {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254, "ft": 0.3048},
    "angle": {"rad": 1.0, "deg": np.pi / 180, "mrad": 1e-3},
    "acceleration": {"m/s^2": 1.0, "g": G, "mg": 1e-3 * G, "ft/s^2": 0.3048},
    "rate": {"rad/s": 1.0, "deg/s": np.pi / 180, "mrad/s": 1e-3},
}
#: Spellings of units (after lower-casing and removing spaces) -> canonical unit.
UNIT_SPELLINGS = {
    "s": "s", "sec": "s", "secs": "s", "seconds": "s", "ms": "ms", "msec": "ms", "us": "us",
    "µs": "us", "usec": "us", "ns": "ns", "m": "m", "mm": "mm", "cm": "cm", "in": "in",
    "inch": "in", "ft": "ft", "rad": "rad", "radians": "rad", "deg": "deg", "degree": "deg",
    "degrees": "deg", "°": "deg", "mrad": "mrad", "m/s^2": "m/s^2", "m/s2": "m/s^2",
    "m/s²": "m/s^2", "ms^-2": "m/s^2", "ms-2": "m/s^2", "mps2": "m/s^2", "m_s2": "m/s^2",
    "m_s^2": "m/s^2", "g": "g", "mg": "mg", "ft/s^2": "ft/s^2", "ft/s2": "ft/s^2",
    "rad/s": "rad/s", "rad_s": "rad/s", "rps": "rad/s", "deg/s": "deg/s", "deg_s": "deg/s",
    "dps": "deg/s", "°/s": "deg/s", "degps": "deg/s", "mrad/s": "mrad/s",
}  # fmt: skip
#: Names (normalised: lower case, separators as ``_``) -> target.
ALIASES: dict[str, str] = {}
for _target, _names in {
    "t": ("t", "time", "timestamp", "time_stamp", "stamp", "clock"),
    "x": ("x", "surge", "pos_x", "position_x"),
    "y": ("y", "sway", "pos_y", "position_y"),
    "z": ("z", "heave", "pos_z", "position_z"),
    "roll": ("roll", "phi"),
    "pitch": ("pitch", "theta"),
    "yaw": ("yaw", "psi"),
    "ax": ("ax", "acc_x", "accel_x", "accx", "a_x", "f_x", "fx", "specific_force_x"),
    "ay": ("ay", "acc_y", "accel_y", "accy", "a_y", "f_y", "fy", "specific_force_y"),
    "az": ("az", "acc_z", "accel_z", "accz", "a_z", "f_z", "fz", "specific_force_z"),
    "p": ("p", "gyro_x", "gyr_x", "gx", "wx", "omega_x", "rate_x", "roll_rate"),
    "q": ("q", "gyro_y", "gyr_y", "gy", "wy", "omega_y", "rate_y", "pitch_rate"),
    "r": ("r", "gyro_z", "gyr_z", "gz", "wz", "omega_z", "rate_z", "yaw_rate"),
}.items():
    for _n in _names:
        ALIASES[_n.replace("_", "")] = _target
#: Words a command column may carry besides its name (``cmd_z``, ``pitch_setpoint``).
COMMAND_WORDS = ("cmd", "command", "commanded", "setpoint", "set_point", "sp", "ref", "demand")


@dataclass(frozen=True)
class Column:
    """One recognised column.

    Attributes
    ----------
    target : str
        Twin signal (:data:`TARGETS`).
    header : str
        The column's name in the file.
    index : int
        Column number in the file (0-based).
    unit : str or None
        Canonical unit (:data:`UNITS`), or None when neither header nor mapping gives it.

    """

    target: str
    header: str
    index: int
    unit: str | None

    @property
    def kind(self) -> str:
        """Physical quantity (``time``, ``length``, ...)."""
        return KIND[self.target]

    def factor(self, unit: str | None = None) -> float:
        """Factor from ``unit`` (default: the column's, else SI) to the twin's SI unit."""
        return UNITS[self.kind][unit or self.unit or next(iter(UNITS[self.kind]))]


@dataclass(frozen=True, eq=False)
class Table:
    """A delimited text table.

    Attributes
    ----------
    path : Path
        File.
    header : tuple of str
        Column names.
    data : ndarray, shape (n, k)
        Numbers (NaN where a cell was empty).

    """

    path: Path
    header: tuple[str, ...]
    data: FloatArray


def read_table(path: str | Path) -> Table:
    """Read a delimited table with one header row (``#`` lines are comments).

    Raises
    ------
    DataError
        Missing or empty file, no header, a row with another number of cells, a cell that is
        not a number (naming row and column).

    """
    p = Path(path)
    if not p.is_file():
        raise DataError(f"{p}: no such file")
    data = p.read_bytes()
    utf16 = data.startswith((b"\xff\xfe", b"\xfe\xff"))  # spreadsheets' "Unicode text"
    try:
        raw = data.decode("utf-16" if utf16 else ENCODING)
    except UnicodeDecodeError:  # a log from an older Windows tool: "pitch [\xb0]" in Latin-1
        raw = data.decode("utf-16" if utf16 else "latin-1", errors="replace")
    if "\x00" in raw:
        raise DataError(f"{p}: a binary file (it holds NUL bytes), not a CSV log")
    text = [ln for ln in raw.splitlines() if ln.strip()]
    text = [ln for ln in text if not ln.lstrip().startswith("#")]
    if len(text) < 3:
        raise DataError(f"{p}: needs a header row and at least 2 rows of numbers")
    try:
        dialect = csv.Sniffer().sniff(text[0] + "\n" + text[1], delimiters=",;\t ")
        delim = dialect.delimiter
    except csv.Error:
        delim = ","
    rows = [[c.strip() for c in row] for row in csv.reader(text, delimiter=delim)]
    if delim == " ":
        rows = [[c for c in row if c] for row in rows]
    header = tuple(rows[0])
    if any(_is_number(c) for c in header if c):
        raise DataError(f"{p}: the first row must name the columns; got {', '.join(header)}")
    data = np.full((len(rows) - 1, len(header)), np.nan)
    for i, row in enumerate(rows[1:]):
        if len(row) != len(header):
            raise DataError(f"{p}: line {i + 2} has {len(row)} cells; the header has {len(header)}")
        for j, cell in enumerate(row):
            if cell == "" or cell.lower() in ("nan", "na", "null"):
                continue
            try:
                data[i, j] = float(cell)
            except ValueError:
                raise DataError(
                    f"{p}: line {i + 2}, column {header[j]!r}: {cell!r} is not a number"
                ) from None
            if not abs(data[i, j]) <= MAX_CELL:
                raise DataError(f"{p}: line {i + 2}, column {header[j]!r}: {cell[:40]!r} is not "
                                f"a measurement (finite, within +-{MAX_CELL:g})")  # fmt: skip
    return Table(p, header, data)


#: Largest magnitude of a logged number: room for time stamps in ns since 1970 (1.8e18),
#: far below where arithmetic on it overflows.
MAX_CELL = 1e20


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _normalise(name: str) -> str:
    """Lower case without separators: ``Acc_X``, ``acc-x`` and ``AccX`` are one name."""
    return re.sub(r"[\s\-._]+", "", name.strip().lower())


def split_unit(header: str) -> tuple[str, str | None]:
    """Split a header into name and unit: ``pitch [deg]``, ``az (g)``, ``q_deg/s``, ``z_mm``.

    Returns the header unchanged and None when it carries no known unit.
    """
    h = header.strip()
    m = re.fullmatch(r"(.+?)\s*[\[(](.+?)[\])]", h)
    if m:
        unit = UNIT_SPELLINGS.get(m.group(2).replace(" ", "").lower())
        if unit:
            return m.group(1), unit
    low = h.lower()
    for spelling in sorted(UNIT_SPELLINGS, key=len, reverse=True):
        for sep in ("_", " ", "/"):
            if low.endswith(sep + spelling) and len(low) > len(spelling) + 1:
                return h[: -len(spelling) - 1], UNIT_SPELLINGS[spelling]
    return h, None


def target_of(name: str) -> tuple[str | None, bool]:
    """Return the target a column name means (or None) and whether it says "command"."""
    n = _normalise(name)
    if n in ALIASES:
        return ALIASES[n], False
    for word in COMMAND_WORDS:
        word = word.replace("_", "")
        for stripped in (n.removeprefix(word), n.removesuffix(word)):
            if stripped != n and stripped in ALIASES and ALIASES[stripped] in COMMAND_TARGETS:
                return ALIASES[stripped], True
    return None, False


def parse_mapping(items: Sequence[str]) -> dict[str, tuple[str, str | None]]:
    """Parse ``TARGET=COLUMN[:UNIT]`` items (``--map``) into {target: (column, unit)}.

    Raises
    ------
    DataError
        An item without ``=``, an unknown target or an unknown unit for the target's kind.

    """
    out = {}
    for item in items:
        if "=" not in item:
            raise DataError(f"--map {item!r}: expected TARGET=COLUMN[:UNIT], e.g. z=heave:mm")
        target, _, rest = item.partition("=")
        target = target.strip()
        if target not in TARGETS:
            raise DataError(f"--map {item!r}: unknown target {target!r}; expected one of "
                            f"{', '.join(TARGETS)}")  # fmt: skip
        column, unit = rest, None
        if ":" in rest:
            column, _, given = rest.rpartition(":")
            unit = canonical_unit(given, KIND[target], f"--map {item!r}")
        out[target] = (column.strip(), unit)
    return out


def canonical_unit(text: str, kind: str, where: str) -> str:
    """Return the canonical spelling of a unit of ``kind`` or raise naming the allowed ones."""
    unit = UNIT_SPELLINGS.get(text.replace(" ", "").lower())
    if unit not in UNITS[kind]:
        raise DataError(f"{where}: unknown {kind} unit {text!r}; allowed: "
                        f"{', '.join(UNITS[kind])}")  # fmt: skip
    return unit


def recognise(
    table: Table, mapping: Mapping[str, tuple[str, str | None]] | None = None
) -> tuple[dict[str, Column], list[str]]:
    """Map a table's columns to targets.

    Parameters
    ----------
    table : Table
        The file.
    mapping : mapping, optional
        Explicit ``{target: (column header, unit or None)}``; a mapped column wins over the
        names. Mapped columns missing from this file are skipped (they may be in another).

    Returns
    -------
    columns : dict
        Target -> :class:`Column`.
    ignored : list of str
        Headers that are not any target.

    Raises
    ------
    DataError
        Two columns of one file that mean the same target (naming both).

    """
    mapping = dict(mapping or {})
    columns: dict[str, Column] = {}
    ignored = []
    by_header = {h.strip(): j for j, h in enumerate(table.header)}
    mapped_headers = set()
    for target, (header, unit) in mapping.items():
        if header in by_header:
            j = by_header[header]
            columns[target] = Column(target, header, j, unit or split_unit(header)[1])
            mapped_headers.add(header)
    for j, header in enumerate(table.header):
        if header.strip() in mapped_headers:
            continue
        name, unit = split_unit(header)
        target, _ = target_of(name)
        if target is None or target in mapping:
            ignored.append(header)
            continue
        if unit is not None and unit not in UNITS[KIND[target]]:
            raise DataError(f"{table.path}: column {header!r} is {target} ({KIND[target]}) but "
                            f"its unit {unit!r} is not one; allowed: "
                            f"{', '.join(UNITS[KIND[target]])}")  # fmt: skip
        if target in columns:
            raise DataError(
                f"{table.path}: columns {columns[target].header!r} and {header!r} both mean "
                f"{target}; map one with --map {target}=COLUMN"
            )
        columns[target] = Column(target, header, j, unit)
    return columns, ignored
