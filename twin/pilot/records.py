"""The recorded pilot-run format ``twin-pilot/1``: one CSV of a tracking run.

Header ``t,ft,fd,e,u,theta`` and optionally ``theta_felt`` (rad; time in s, uniform, strictly
increasing): target and disturbance forcing functions, tracking error, control signal, pitch
attitude, and the attitude the motion system gave the pilot (if known). The analysis uses the
last 81.92 s (whole periods of the Table 6.2 forcing functions at 100 Hz). Written to a
temporary name and renamed, so a failed write leaves nothing.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from twin.errors import RunFormatError
from twin.trajectory import uniform_rate

FloatArray = NDArray[np.float64]
COLUMNS = ("t", "ft", "fd", "e", "u", "theta")
OPTIONAL = ("theta_felt",)


def write_pilot_csv(path: str | Path, columns: dict[str, FloatArray]) -> Path:
    """Write a ``twin-pilot/1`` CSV (``columns`` holds COLUMNS and maybe theta_felt)."""
    names = [*COLUMNS, *(c for c in OPTIONAL if c in columns)]
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    tmp = p.with_name(f".{p.name}.partial")
    data = np.column_stack([np.asarray(columns[n], dtype=float) for n in names])
    np.savetxt(tmp, data, delimiter=",", header=",".join(names), comments="", fmt="%.10g")
    tmp.replace(p)
    return p


def read_pilot_csv(path: str | Path) -> dict[str, FloatArray]:
    """Read and check a ``twin-pilot/1`` CSV; returns the columns and ``rate_hz``."""
    p = Path(path)
    if not p.is_file():
        raise RunFormatError(f"{p}: no such pilot-run file")
    with p.open() as fh:
        header = fh.readline().strip().split(",")
    if header[: len(COLUMNS)] != list(COLUMNS) or any(h not in OPTIONAL for h in header[6:]):
        raise RunFormatError(
            f"{p}: header must be {','.join(COLUMNS)}[,theta_felt]; got {','.join(header)}"
        )
    try:
        data = np.loadtxt(p, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as e:
        raise RunFormatError(f"{p}: not a table of numbers ({e})") from None
    if data.shape[1] != len(header):
        raise RunFormatError(f"{p}: rows must have {len(header)} values")
    bad = ~np.isfinite(data)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise RunFormatError(f"{p}: {header[col]} is not a finite number at row {row + 2}")
    out = {h: data[:, i] for i, h in enumerate(header)}
    out["rate_hz"] = np.array(uniform_rate(out["t"], f"{p}"))
    return out
