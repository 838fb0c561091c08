"""Checks of values read from files and command lines: types and ranges, named in the error.

Every reader of the twin (``twin-run/1``, ``twin-config/1``, ``twin-pilot/1``, OMCT bounds,
sweep files, ``platform.toml``) takes its numbers, flags, text, documents and keys through these
helpers, so that a string where a number belongs, a NaN, a value out of range, a binary file, a
byte-order mark, a 5000-digit integer or a misspelt key gets the same kind of message: the
file, the key and what is allowed (a misspelt key also gets a did-you-mean).

Examples
--------
>>> number(0.5, "delay_s", lo=0.0, hi=10.0)
0.5
>>> number("x", "delay_s", lo=0.0)
Traceback (most recent call last):
...
twin.core.errors.DataError: delay_s must be a number >= 0; got 'x'
>>> numbers([1, 2, 3], "position_m", size=3).tolist()
[1.0, 2.0, 3.0]
>>> check_keys({"dealy": 0.1}, ("delay",), "cfg.json")
Traceback (most recent call last):
...
twin.core.errors.DataError: cfg.json: unknown key 'dealy' (did you mean 'delay'?); allowed: delay

"""

from __future__ import annotations

import difflib
import json
import math
import os
import tomllib
from collections.abc import Callable, Iterable, Mapping
from contextlib import suppress
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from twin.core.errors import DataError

#: The encoding every text file is read in: UTF-8, with a byte-order mark allowed (and dropped).
ENCODING = "utf-8-sig"


def _shown(value: object, width: int = 60) -> str:
    """``repr(value)``, cut to ``width`` characters (a 400-digit number is not read)."""
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def _range(lo: float, hi: float, lo_open: bool, hi_open: bool) -> str:
    """Describe an interval (``>= 0``, ``in (0, 100]``)."""
    if math.isinf(hi):
        return "" if math.isinf(lo) else f" {'>' if lo_open else '>='} {lo:g}"
    if math.isinf(lo):
        return f" {'<' if hi_open else '<='} {hi:g}"
    return f" in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"


def number(
    value: object,
    where: str,
    *,
    lo: float = -math.inf,
    hi: float = math.inf,
    lo_open: bool = False,
    hi_open: bool = False,
    error: type[Exception] = DataError,
) -> float:
    """Return ``value`` as a float if it is a finite number in the range, else raise ``error``.

    Parameters
    ----------
    value : object
        What was read (JSON, TOML or command line).
    where : str
        Names it in the message (e.g. ``"run/meta.json: imu.rate_hz"``).
    lo, hi : float
        Allowed range.
    lo_open, hi_open : bool
        Exclude the bound itself.
    error : type of Exception
        Raised on a bad value (a subclass of :class:`~twin.core.errors.TwinError`).

    """
    ok = isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)
    try:
        v = float(value) if ok else math.nan  # type: ignore[arg-type]
    except OverflowError:  # an integer beyond any float
        v = math.nan
    if ok and math.isfinite(v):
        ok = (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)
    if not ok or not math.isfinite(v):
        raise error(
            f"{where} must be a number{_range(lo, hi, lo_open, hi_open)}; got {_shown(value)}"
        )
    return v


def flag(value: object, where: str, error: type[Exception] = DataError) -> bool:
    """Return ``value`` if it is a boolean (``true``/``false``), else raise ``error``."""
    if not isinstance(value, bool | np.bool_):
        raise error(f"{where} must be true or false; got {_shown(value)}")
    return bool(value)


def numbers(
    value: object,
    where: str,
    *,
    size: int | None = None,
    min_size: int = 1,
    error: type[Exception] = DataError,
) -> NDArray[np.float64]:
    """Return a list of finite numbers as an array, else raise ``error``.

    Parameters
    ----------
    value : object
        What was read: a list (or tuple) of numbers.
    where : str
        Names it in the message.
    size : int, optional
        Exact length required.
    min_size : int
        Least length (when ``size`` is not given).
    error : type of Exception
        Raised on a bad value.

    """
    want = f"{size} numbers" if size is not None else f"a list of at least {min_size} numbers"
    if not isinstance(value, list | tuple) or (
        len(value) != size if size is not None else len(value) < min_size
    ):
        raise error(f"{where} must be {want}; got {_shown(value)}")
    return np.array([number(v, f"{where}[{i}]", error=error) for i, v in enumerate(value)])


def not_utf8(path: str | Path, e: UnicodeDecodeError, what: str) -> str:
    """Return the message for a file that is not UTF-8: the path, its first bad byte, ``what``."""
    return f"{path}: not UTF-8 text (byte 0x{e.object[e.start]:02x} at offset {e.start}); " \
           f"expected {what}"  # fmt: skip


def read_text(path: str | Path, what: str, error: type[Exception] = DataError) -> str:
    """Return a text file's contents (UTF-8, a byte-order mark dropped), else raise ``error``.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What it should be (``"a twin-config/1 file"``), for the message.
    error : type of Exception
        Raised when it is missing, a folder, unreadable or not UTF-8 text.

    """
    p = Path(path)
    try:
        return p.read_text(encoding=ENCODING)
    except UnicodeDecodeError as e:
        raise error(not_utf8(p, e, what)) from None
    except IsADirectoryError:
        raise error(f"{p}: is a folder; expected {what}") from None
    except FileNotFoundError:
        raise error(f"{p}: no such file; expected {what}") from None
    except OSError as e:
        raise error(f"{p}: cannot be read ({e.strerror}); expected {what}") from None


def did_you_mean(word: str, allowed: Iterable[str]) -> str:
    """Return `` (did you mean 'x'?)`` for the allowed word closest to ``word``, else ``""``."""
    near = difflib.get_close_matches(word, list(allowed), n=1, cutoff=0.6)
    return f" (did you mean {near[0]!r}?)" if near else ""


def check_keys(
    mapping: Mapping[str, object],
    allowed: Iterable[str],
    where: str,
    error: type[Exception] = DataError,
    kind: str = "key",
) -> None:
    """Refuse a key of ``mapping`` that is not ``allowed``, with a did-you-mean.

    The one check of every reader of a JSON or TOML file: a misspelt key (``dealy_s``,
    ``dof`` for ``dofs``) would otherwise be ignored and the file's intent silently lost.

    Parameters
    ----------
    mapping : mapping
        A table or object as read.
    allowed : iterable of str
        Its allowed keys (in the order the message lists them).
    where : str
        Names the file and the table (``"cfg.json: platform_config"``).
    error : type of Exception
        Raised for the first unknown key.
    kind : str
        What a key is called in the message (``"key"``, ``"axis"``, ``"table"``).

    """
    names = list(allowed)
    for key in mapping:
        if key not in names:
            word = key if isinstance(key, str) else str(key)
            raise error(f"{where}: unknown {kind} {_shown(key)}{did_you_mean(word, names)}; "
                        f"allowed: {', '.join(names)}")  # fmt: skip


def _parse(parse: Callable[[str], object], text: str, path: str | Path, kind: str,
           what: str, error: type[Exception]) -> object:  # fmt: skip
    """Parse ``text`` with ``parse``; every way it can fail is ``error`` naming the file."""
    try:
        return parse(text)
    except json.JSONDecodeError as e:
        why = f"{e.msg}, line {e.lineno}"
    except tomllib.TOMLDecodeError as e:
        why = str(e)
    except RecursionError:
        why = "nested too deeply"
    except ValueError as e:  # an integer beyond Python's int-from-string limit (4300 digits)
        why = "an integer with too many digits" if "digits" in str(e) else str(e)[:200]
    raise error(f"{path}: not valid {kind} ({why}); expected {what}")


def read_json(path: str | Path, what: str, error: type[Exception] = DataError) -> object:
    """Read a JSON file (UTF-8, see :func:`read_text`); any failure is ``error`` naming it.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What it should be (``"a twin-config/1 file"``), for the message.
    error : type of Exception
        Raised when it cannot be read or is not JSON: bad syntax, nesting too deep for the
        parser, an integer of more than 4300 digits.

    """
    return _parse(json.loads, read_text(path, what, error), path, "JSON", what, error)


def read_toml(path: str | Path, what: str, error: type[Exception] = DataError) -> dict:
    """Read a TOML file (UTF-8, see :func:`read_text`); any failure is ``error`` naming it.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What it should be (``"a TOML sweep file"``), for the message.
    error : type of Exception
        Raised when it cannot be read or is not TOML (as :func:`read_json`).

    """
    doc = _parse(tomllib.loads, read_text(path, what, error), path, "TOML", what, error)
    return doc  # type: ignore[return-value]


#: Memory a simulated run holds per second of motion [bytes]: commands, the IMU at 819.2 Hz,
#: actuators and the chain's buffers (measured: 0.5 MB/s reduced, 0.7 MB/s full; rounded up).
BYTES_PER_RUN_S = 1_000_000


def available_memory() -> int | None:
    """Return the memory this machine has available [bytes] (None where it cannot be read)."""
    with suppress(OSError, ValueError, IndexError):  # not Linux: ask sysconf
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def _size(n: float) -> str:
    """``1.5 GiB``-style size."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.3g} {unit}"
        n /= 1024
    return f"{n:.3g} TiB"  # pragma: no cover


def check_duration(duration_s: float, what: str, error: type[Exception] = DataError) -> float:
    """Refuse a run longer than this machine's memory can hold, before anything is allocated.

    Parameters
    ----------
    duration_s : float
        Run length [s] (must be finite and > 0).
    what : str
        Names the run in the message (``"rest-100000000"``).
    error : type of Exception
        Raised when it cannot fit (with the size it would need and what is available).

    """
    duration_s = number(duration_s, f"{what}: duration [s]", lo=0, lo_open=True, error=error)
    need = duration_s * BYTES_PER_RUN_S
    have = available_memory()
    if have is not None and need > have:
        raise error(
            f"{what}: a run of {duration_s:g} s needs about {_size(need)} of memory (about 1 MB "
            f"per simulated second) and {_size(have)} are available (at most about "
            f"{have / BYTES_PER_RUN_S:,.0f} s fit here); simulate it in shorter pieces"
        )
    return duration_s
