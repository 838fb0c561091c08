"""A sweep's folder: the tidy table, each point's result, the failures and a figure.

``write_sweep`` writes, into a staging folder renamed into place when complete:

* ``sweep.csv`` (or ``sweep.parquet``): the tidy table (:mod:`twin.studies.sweep`);
* ``points/NNNN.json``: each point's inputs, configuration and whole result;
* ``sweep.json``: the grid, where it ran, the point count and the failures (inputs, error,
  traceback);
* ``sweep.png``: the describing functions of every point (df), or each measure against the
  first axis with a line per combination of the others (pilot).
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from typing import Any

import numpy as np

from twin.core.lifecycle import replacing_dir
from twin.core.plotting import finish, subplots
from twin.studies.sweep import SweepError, SweepResult

#: Table formats, by file suffix.
FORMATS = ("csv", "parquet")
#: Most lines a figure labels in its legend.
LEGEND_MAX = 12


def _plain(v: object) -> object:
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    raise TypeError(f"not JSON: {type(v).__name__}")


def check_table_format(table_format: str) -> None:
    """Refuse a table format that is unknown or, for Parquet, has no writer installed.

    Raises
    ------
    SweepError
        Naming the formats, or what installs pyarrow (the ``cluster`` extra).

    """
    if table_format not in FORMATS:
        raise SweepError(f"table format must be one of {', '.join(FORMATS)}; got {table_format!r}")
    if table_format == "parquet" and importlib.util.find_spec("pyarrow") is None:
        raise SweepError(
            "a Parquet table needs pyarrow, which is not installed (pip install "
            "'twin[cluster]'); CSV needs nothing more"
        )


def write_sweep(result: SweepResult, out: str | Path, table_format: str = "csv") -> Path:
    """Write a sweep's folder (see the module docstring); return the table's path."""
    check_table_format(table_format)
    out = Path(out)
    g = result.grid
    with replacing_dir(out, "sweep.json") as tmp:
        table = result.table()
        name = f"sweep.{table_format}"
        if table_format == "csv":
            table.to_csv(tmp / name, index=False)
        else:
            table.to_parquet(tmp / name, index=False)
        (tmp / "points").mkdir()
        for i, (p, c, r) in enumerate(zip(result.points, result.configs, result.results,
                                          strict=True)):  # fmt: skip
            if r is not None:
                doc = {"point": p, "config": c.to_meta(), **r["result"]}
                (tmp / "points" / f"{i:04d}.json").write_text(
                    json.dumps(doc, indent=1, default=_plain) + "\n", encoding="utf-8"
                )
        manifest = {
            "format": "twin-sweep/1",
            "source": g.source,
            "task": g.task,
            "settings": g.settings,
            "fixed": g.fixed,
            "grid": g.axes,
            "points": len(result.points),
            "failed": len(result.failures),
            "scheduler": result.scheduler,
            "table": name,
            "failures": [f.to_dict() for f in result.failures],
        }
        (tmp / "sweep.json").write_text(
            json.dumps(manifest, indent=2, default=_plain) + "\n", encoding="utf-8"
        )
        if len(table):
            plot_sweep(result, tmp / "sweep.png")
    return out / name


def _label(point: dict[str, Any], axes: list[str]) -> str:
    return ", ".join(f"{a} {point[a]:g}" if isinstance(point[a], float) else f"{a} {point[a]}"
                     for a in axes)  # fmt: skip


def plot_sweep(result: SweepResult, path: str | Path | None = None):
    """Draw a sweep (see the module docstring); return the figure."""
    return (_plot_df if result.grid.task == "df" else _plot_pilot)(result, path)


def _plot_df(result: SweepResult, path):
    dofs = list(dict.fromkeys(p["dof"] for p in result.points))
    fig, axes = subplots(None, 2, len(dofs), figsize=(4.5 * len(dofs) + 1, 6.5), sharex=True,
                         squeeze=False)  # fmt: skip
    others = [a for a in result.grid.axes if a != "dof"]
    from matplotlib import colormaps

    colours = colormaps["viridis"]
    for j, dof in enumerate(dofs):
        mine = [(p, r) for p, r in zip(result.points, result.results, strict=True)
                if p["dof"] == dof and r is not None]  # fmt: skip
        for k, (p, r) in enumerate(mine):
            c = colours(k / max(1, len(mine) - 1))
            rows = r["rows"]
            f = [q["frequency_hz"] for q in rows]
            label = _label(p, others) or p["config"]
            axes[0, j].semilogx(f, [q["gain_db"] for q in rows], "o-", ms=3, lw=0.8, color=c,
                                label=label)  # fmt: skip
            axes[0, j].semilogx(f, [q["model_gain_db"] for q in rows], ":", lw=0.8, color=c)
            axes[1, j].semilogx(f, [q["phase_deg"] for q in rows], "o-", ms=3, lw=0.8, color=c)
            axes[1, j].semilogx(f, [q["model_phase_deg"] for q in rows], ":", lw=0.8, color=c)
        axes[0, j].set_title(f"{dof}: measured (dots), Eq 5.11 (dotted)")
        axes[0, j].set_ylabel("gain [dB]")
        axes[1, j].set_ylabel("phase [deg]")
        axes[1, j].set_xlabel("frequency [Hz]")
        for ax in axes[:, j]:
            ax.grid(True, which="both", alpha=0.3)
        if 1 < len(mine) <= LEGEND_MAX:
            axes[0, j].legend(fontsize=7)
    fig.suptitle(f"Describing-function sweep ({result.grid.source}), {len(result.points)} points")
    return finish(fig, path)


#: Pilot measures drawn, with axis labels.
PILOT_PANELS = (
    ("var_e_deg2", "var(e) [deg^2]"),
    ("var_u_deg2", "var(u) [deg^2]"),
    ("crossover_d_rad_s", "disturbance crossover [rad/s]"),
    ("phase_margin_d_deg", "disturbance phase margin [deg]"),
    ("crossover_t_rad_s", "target crossover [rad/s]"),
    ("phase_margin_t_deg", "target phase margin [deg]"),
)


def _plot_pilot(result: SweepResult, path):
    fig, axes = subplots(None, 2, 3, figsize=(12, 6.5))
    names = list(result.grid.axes) or ["config"]
    x_axis, others = names[0], names[1:]
    xs = list(dict.fromkeys(p[x_axis] for p in result.points))
    numeric = all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in xs)
    groups: dict[str, list[tuple[Any, dict]]] = {}
    for p, r in zip(result.points, result.results, strict=True):
        if r is not None:
            groups.setdefault(_label(p, others), []).append((p[x_axis], r["rows"][0]))
    for ax, (col, label) in zip(axes.flat, PILOT_PANELS, strict=True):
        for k, (name, pts) in enumerate(groups.items()):
            x = [v if numeric else xs.index(v) for v, _ in pts]
            ax.plot(x, [row[col] for _, row in pts], "o-", color=f"C{k % 10}",
                    label=name or None)  # fmt: skip
        ax.set_ylabel(label)
        ax.set_xlabel(x_axis)
        if not numeric:
            ax.set_xticks(range(len(xs)), [str(x) for x in xs])
        ax.grid(True, alpha=0.3)
    if 1 < len(groups) <= LEGEND_MAX:
        axes[0, 0].legend(fontsize=7)
    fig.suptitle(f"Pitch-task sweep ({result.grid.source}), {len(result.points)} points")
    return finish(fig, path)
