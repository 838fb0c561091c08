"""The recorded pilot-run format ``twin-pilot/1``: one CSV of a tracking run.

Header ``t,ft,fd,e,u,theta`` and optionally ``theta_felt`` (rad; time in s, uniform, strictly
increasing): target and disturbance forcing functions, tracking error, control signal, pitch
attitude, and the attitude the motion system gave the pilot (if known). The analysis uses the
last 81.92 s (whole periods of the Table 6.2 forcing functions at 100 Hz). Written to a
temporary name and renamed, so a failed write leaves nothing. Repetitions of one condition
(the thesis flew five, §6.3.4) are one file each, sharing t, ft and fd.
"""

from __future__ import annotations

import re
from contextlib import ExitStack
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from twin.chain.trajectory import uniform_rate
from twin.core.errors import RunFormatError
from twin.core.lifecycle import replacing_file
from twin.formats.runs import read_number_table

FloatArray = NDArray[np.float64]
FORMAT = "twin-pilot/1"
COLUMNS = ("t", "ft", "fd", "e", "u", "theta")
OPTIONAL = ("theta_felt",)
#: Largest magnitude of each signal [rad]: a pitch-tracking run stays within 10 rad (573 deg).
MAX_VALUE = {c: 10.0 for c in (*COLUMNS[1:], *OPTIONAL)}


def write_pilot_csv(path: str | Path, columns: dict[str, FloatArray]) -> Path:
    """Write a ``twin-pilot/1`` CSV (``columns`` holds COLUMNS and maybe theta_felt)."""
    return write_pilot_runs(path, columns)[0]


def repetition_paths(path: str | Path, runs: int) -> list[Path]:
    """Return the files of ``runs`` repetitions: ``path`` itself for one, else ``stem-1``..."""
    p = Path(path)
    if runs == 1:
        return [p]
    return [p.with_name(f"{p.stem}-{k}{p.suffix}") for k in range(1, runs + 1)]


def stale_repetitions(path: str | Path, written: list[Path]) -> list[Path]:
    """Return the files beside ``path`` named as its repetitions but not in ``written``.

    Such a ``stem-K`` file was left by an earlier run, and a glob such as ``stem-*.csv``
    would take it.
    """
    p = Path(path)
    pattern = re.compile(rf"{re.escape(p.stem)}-[0-9]+")
    return sorted(q for q in p.parent.glob(f"{p.stem}-*{p.suffix}")
                  if pattern.fullmatch(q.stem) and q not in written)  # fmt: skip


def write_pilot_runs(path: str | Path, columns: dict[str, FloatArray]) -> list[Path]:
    """Write each run of ``columns`` as a ``twin-pilot/1`` CSV; all of them or none.

    Every file is written under a hidden name first and renamed only once all are complete, so
    an error while writing leaves none; an error in the renaming itself (a full disk cannot
    cause one) could leave the later files renamed.

    Parameters
    ----------
    path : str or Path
        The file of a single run; repetitions go beside it as ``stem-1.csv``, ``stem-2.csv``...
    columns : dict of str to ndarray
        COLUMNS and maybe theta_felt; t, ft and fd of shape (n,), the others (n,) for one run
        or (runs, n).

    Returns
    -------
    list of Path
        The files written.

    """
    shared = ("t", "ft", "fd")
    runs = max(np.atleast_2d(v).shape[0] for k, v in columns.items() if k not in shared)
    names = [*COLUMNS, *(c for c in OPTIONAL if c in columns)]
    paths = repetition_paths(path, runs)
    with ExitStack() as stack:  # every file appears only once all are complete
        for k, final in enumerate(paths):
            tmp = stack.enter_context(replacing_file(final))
            data = np.column_stack([np.asarray(columns[n], dtype=float) if n in shared
                                    else np.atleast_2d(columns[n])[k] for n in names])  # fmt: skip
            np.savetxt(tmp, data, delimiter=",", header=",".join(names), comments="", fmt="%.10g",
                       encoding="utf-8")  # fmt: skip
    return paths


def read_pilot_csv(path: str | Path) -> dict[str, FloatArray]:
    """Read and check a ``twin-pilot/1`` CSV; returns the columns and ``rate_hz``."""
    p = Path(path)
    if p.is_dir():
        raise RunFormatError(f"{p}: is a folder; give a {FORMAT} CSV file")
    if not p.is_file():
        raise RunFormatError(f"{p}: no such pilot-run file")
    data, header = read_number_table(p, COLUMNS, OPTIONAL, MAX_VALUE)
    out = {h: data[:, i] for i, h in enumerate(header)}
    out["rate_hz"] = np.array(uniform_rate(out["t"], f"{p}"))
    return out
