"""Parameter sweeps: a grid given as TOML, one task per point, one tidy table.

A sweep file names a task, the settings every point shares, and the axes of the grid; the
points are the product of the axes (the last axis varies fastest)::

    task = "df"            # "df": describing function (Table 5.2 multi-sines, §3.3.3)
                           # "pilot": the §6.3 pitch task flown through the configuration
    config = "mpi"         # base configuration: a name or a twin-config/1 file
    model = "reduced"      # platform model (df; the pilot task always flies the reduced one)
    seed = 0               # every point uses this seed unless seed is an axis

    [grid]
    break_hz = [0.5, 1.0, 2.0]   # platform-filter break frequency [Hz] (0: no filter)
    delay_ms = [35, 100]         # total motion-system delay [ms]
    dof = ["pitch", "heave"]     # driven DOF (df)

An axis may also be given once at the top level (a fixed value). Axes: ``config``,
``break_hz``, ``delay_ms``, ``noise``, ``resonance``, ``seed``; ``dof`` (df); ``pilot``
(``"fixed"`` or ``"adaptive"``: the Table 6.2 pilot, or one adapted to the point's
configuration, :mod:`twin.pilot.models.adapt`). Settings: ``model`` (df), ``runs`` and ``remnant``
(pilot).

All points share one seed unless ``seed`` is an axis: common random numbers, so differences
between points are the parameters' and not the noise's. Each point is a task of
:mod:`twin.core.tasks.engine`, a pure function of (configuration, signal, seed): the table is
bit-identical on one process or a cluster. Every point's configuration is built before any
runs, so a bad value is refused up front naming the point.

The tidy table has one row per point (pilot) or per point and frequency line (df), the axes as
columns (``point`` numbers the point), then the measures:

* df: ``frequency_hz``, ``gain_db``, ``phase_deg``, ``model_gain_db``, ``model_phase_deg``
  (Eq 5.11 of the point's configuration), ``snr_db``, ``fitted_delay_ms`` (the delay fitted
  to the point's describing function);
* pilot: ``var_e_deg2``, ``var_u_deg2``, ``var_theta_deg2``, ``crossover_d_rad_s``,
  ``phase_margin_d_deg``, ``crossover_t_rad_s``, ``phase_margin_t_deg``, and the pilot's
  ``k_v``, ``t_lead``, ``t_lag``, ``k_m``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from twin.chain.config import MotionSystem, load_config, motion_system
from twin.chain.delay import MAX_DELAY_S
from twin.chain.filter import MAX_BREAK_HZ, check_break_hz
from twin.core.checks import check_keys, number, read_toml
from twin.core.errors import ConfigError, TwinError
from twin.core.frames import DOF_NAMES
from twin.core.progress import ProgressFn
from twin.core.tasks.engine import Engine, using
from twin.core.tasks.outcome import Failure
from twin.pilot.models.pitch import MAX_RUNS

#: Tasks a sweep runs, and what each computes.
TASKS = {
    "df": "describing function (Table 5.2 multi-sines, §3.3.3) per point and DOF",
    "pilot": "the §6.3 pitch task flown through each point's configuration",
}
#: Axes (grid or fixed) of every task: name -> type.
AXES: dict[str, type] = {
    "config": str,
    "break_hz": float,
    "delay_ms": float,
    "noise": bool,
    "resonance": bool,
    "seed": int,
}
#: Axes of one task only.
TASK_AXES: dict[str, dict[str, type]] = {"df": {"dof": str}, "pilot": {"pilot": str}}
#: Settings (top level only) and their defaults, per task.
SETTINGS: dict[str, dict[str, Any]] = {
    "df": {"model": "reduced"},
    "pilot": {"runs": 2, "remnant": 0.15},
}
#: Largest value of each number axis: a platform filter up to 1000 Hz, a delay up to 10 s.
FLOAT_MAX = {"break_hz": MAX_BREAK_HZ, "delay_ms": MAX_DELAY_S * 1e3}
#: Most points a sweep may have (a bigger study: several sweep files, or the library).
MAX_POINTS = 1_000_000
#: Table columns per point of each task, after the axes.
DF_COLUMNS = ("frequency_hz", "gain_db", "phase_deg", "model_gain_db", "model_phase_deg",
              "snr_db", "fitted_delay_ms")  # fmt: skip
PILOT_COLUMNS = ("var_e_deg2", "var_u_deg2", "var_theta_deg2", "crossover_d_rad_s",
                 "phase_margin_d_deg", "crossover_t_rad_s", "phase_margin_t_deg", "k_v",
                 "t_lead", "t_lag", "k_m")  # fmt: skip


class SweepError(ConfigError):
    """A sweep file that is malformed: unknown task, key or value, empty or too large grid."""


@dataclass(frozen=True)
class Grid:
    """A parsed sweep file.

    Attributes
    ----------
    task : str
        ``"df"`` or ``"pilot"``.
    fixed : dict
        Axis values given once (with the defaults of ``config``, ``seed``, ...).
    axes : dict of str to list
        The grid's axes, in file order.
    settings : dict
        The task's settings (``model``; ``runs``, ``remnant``).
    source : str
        Where it came from (the file).
    base : Path
        Folder that relative configuration files are read from.

    """

    task: str
    fixed: dict[str, Any]
    axes: dict[str, list[Any]]
    settings: dict[str, Any]
    source: str = "<grid>"
    base: Path = field(default_factory=Path)

    def points(self) -> list[dict[str, Any]]:
        """Return every point: fixed values and one value per axis (last axis fastest)."""
        names = list(self.axes)
        return [
            {**self.fixed, **dict(zip(names, values, strict=True))}
            for values in itertools.product(*self.axes.values())
        ]

    def config(self, point: dict[str, Any]) -> MotionSystem:
        """Return a point's configuration (base configuration with its overrides)."""
        name = str(point["config"])
        path = self.base / name
        try:
            ms = load_config(path) if path.suffix == ".json" else motion_system(name)
            return ms.override(
                point.get("break_hz"), point.get("delay_ms"), point.get("noise"),
                point.get("resonance"),
            )  # fmt: skip
        except (TwinError, ArithmeticError, ValueError) as e:
            raise SweepError(f"{self.source}: point {_describe(point)}: {e}") from None


def _describe(point: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v}" for k, v in point.items())


def read_grid(path: str | Path) -> Grid:
    """Read and check a sweep file (see the module docstring).

    Raises
    ------
    SweepError
        Naming the file and the key for anything not allowed.

    """
    path = Path(path)
    doc = read_toml(path, "a TOML sweep file", SweepError)
    return parse_grid(doc, str(path), path.parent)


def parse_grid(doc: dict[str, Any], source: str = "<grid>", base: Path | None = None) -> Grid:
    """Check a sweep document (the parsed TOML) and return its :class:`Grid`."""
    task = doc.get("task")
    if task is None:  # a misspelt ``task`` is named as such
        keys = {k: None for t in TASKS for k in [*SETTINGS[t], *AXES, *TASK_AXES[t]]}
        check_keys(doc, ["task", *keys, "grid"], source, SweepError)
    if not isinstance(task, str) or task not in TASKS:
        raise SweepError(f"{source}: task must be one of {', '.join(map(repr, TASKS))}; "
                         f"got {task!r}")  # fmt: skip
    axes_types = AXES | TASK_AXES[task]
    settings = dict(SETTINGS[task])
    fixed: dict[str, Any] = {"config": "mpi" if task == "df" else "srs", "seed": 0}
    if task == "df":
        fixed["dof"] = "pitch"
    else:
        fixed["pilot"] = "fixed"
    grid = doc.get("grid", {})
    if not isinstance(grid, dict):
        raise SweepError(f"{source}: [grid] must be a table of axes; got {grid!r}")
    check_keys(doc, ["task", *settings, *axes_types, "grid"], f"{source} (task {task!r})",
               SweepError)  # fmt: skip
    for key, value in doc.items():
        if key in settings:
            settings[key] = _setting(source, task, key, value)
        elif key in axes_types:
            fixed[key] = _value(source, key, value, axes_types[key])
    check_keys(grid, axes_types, f"{source}: [grid] (task {task!r})", SweepError, "axis")
    axes: dict[str, list[Any]] = {}
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise SweepError(f"{source}: [grid].{key} must be a non-empty list; got {values!r}")
        axes[key] = [_value(source, f"[grid].{key}", v, axes_types[key]) for v in values]
        if len(set(map(repr, axes[key]))) < len(axes[key]):
            raise SweepError(f"{source}: [grid].{key} repeats a value: {values!r}")
        fixed.pop(key, None)
    n = int(np.prod([len(v) for v in axes.values()])) if axes else 1
    if n > MAX_POINTS:
        raise SweepError(f"{source}: the grid has {n} points; at most {MAX_POINTS} allowed")
    return Grid(task, fixed, axes, settings, source, base or Path())


def _value(source: str, key: str, value: object, kind: type) -> Any:
    name = key.removeprefix("[grid].")
    ok = (
        isinstance(value, bool) if kind is bool
        else isinstance(value, int) and not isinstance(value, bool) if kind is int
        else isinstance(value, (int, float)) and not isinstance(value, bool) if kind is float
        else isinstance(value, str)
    )  # fmt: skip
    if not ok:
        raise SweepError(f"{source}: {key} must be a {kind.__name__}; got {value!r}")
    if kind is float:
        number(value, f"{source}: {key}", lo=0, hi=FLOAT_MAX.get(name, np.inf), error=SweepError)
        if name == "break_hz":
            check_break_hz(value, f"{source}: {key}", SweepError)  # type: ignore[arg-type]
    if kind is int and value < 0:  # type: ignore[operator]
        raise SweepError(f"{source}: {key} must be >= 0; got {value!r}")
    if name == "dof" and value not in DOF_NAMES:
        raise SweepError(f"{source}: {key} must be one of {', '.join(DOF_NAMES)}; got {value!r}")
    if name == "pilot" and value not in ("fixed", "adaptive"):
        raise SweepError(f"{source}: {key} must be 'fixed' or 'adaptive'; got {value!r}")
    return float(value) if kind is float else value  # type: ignore[arg-type]


def _setting(source: str, task: str, key: str, value: object) -> Any:
    if key == "model":
        if value not in ("full", "reduced"):
            raise SweepError(f"{source}: model must be 'full' or 'reduced'; got {value!r}")
        return value
    if key == "runs":
        if not isinstance(value, int) or isinstance(value, bool) or not 1 <= value <= MAX_RUNS:
            raise SweepError(f"{source}: runs must be an integer in [1, {MAX_RUNS}]; got {value!r}")
        return value
    return number(value, f"{source}: remnant", lo=0, hi=1, lo_open=True, hi_open=True,
                  error=SweepError)  # fmt: skip


def run_point(
    task: str, point: dict[str, Any], config: MotionSystem, settings: dict[str, Any]
) -> dict[str, Any]:
    """Compute one point (a task): ``{"rows": [...], "result": {...}}``.

    A pure function of its arguments: the configuration is passed in (built where the sweep
    file was read), the randomness comes from ``point["seed"]``.
    """
    if task == "df":
        return _df_point(point, config, settings)
    return _pilot_point(point, config, settings)


def _df_point(point, config, settings):
    from twin.agard.df import sweep as df_sweep
    from twin.measurement.measure import Bench

    d = df_sweep(Bench(config, settings["model"], int(point["seed"])), [point["dof"]], workers=1)
    r = d[point["dof"]]
    a = r.analytic()
    rows = [
        dict(zip(DF_COLUMNS, values, strict=True))
        for values in zip(
            r.frequencies_hz.tolist(),
            (20 * np.log10(r.gain)).tolist(),
            r.phase_deg.tolist(),
            (20 * np.log10(np.abs(a))).tolist(),
            r.analytic_phase_deg().tolist(),
            r.snr_db.tolist(),
            [r.delay_s * 1e3] * r.gain.size,
            strict=True,
        )
    ]
    return {"rows": rows, "result": r.to_dict()}


def _pilot_point(point, config, settings):
    from twin.pilot.models.adapt import adapt
    from twin.pilot.models.pitch import PitchPilot
    from twin.pilot.studies.experiment import fly, pitch_remnant_scale

    pilot = adapt(config).pilot if point["pilot"] == "adaptive" else PitchPilot()
    seed = int(point["seed"])
    scale = pitch_remnant_scale(pilot, settings["remnant"], seed)
    m = fly(pilot, config, settings["runs"], seed, scale)
    values = [m["var_e"], m["var_u"], m["var_theta"], m["crossover_d"], m["phase_margin_d"],
              m["crossover_t"], m["phase_margin_t"], pilot.k_v, pilot.t_lead, pilot.t_lag,
              pilot.k_m]  # fmt: skip
    row = {c: float(v) for c, v in zip(PILOT_COLUMNS, values, strict=True)}
    return {"rows": [row], "result": {**m, "pilot": pilot.__dict__}}


@dataclass
class SweepResult:
    """A sweep's points, each point's result (None where it failed) and the failures.

    Attributes
    ----------
    grid : Grid
        What was swept.
    points : list of dict
        The points, in grid order.
    configs : list of MotionSystem
        Each point's configuration.
    results : list of dict or None
        ``{"rows": [...], "result": {...}}`` per point (None: failed).
    failures : list of Failure
        Failed points with their inputs.
    scheduler : str
        Where the tasks ran.

    """

    grid: Grid
    points: list[dict[str, Any]]
    configs: list[MotionSystem]
    results: list[dict[str, Any] | None]
    failures: list[Failure]
    scheduler: str

    def rows(self) -> list[dict[str, Any]]:
        """Return the tidy table's rows: ``point``, the axes, the measures (no failed point)."""
        axes = list(self.grid.axes) or ["config"]
        out = []
        for i, (p, r) in enumerate(zip(self.points, self.results, strict=True)):
            if r is not None:
                out += [{"point": i, **{a: p[a] for a in axes}, **row} for row in r["rows"]]
        return out

    def table(self):
        """Return the tidy table as a pandas DataFrame (with its columns when empty)."""
        import pandas as pd

        measures = DF_COLUMNS if self.grid.task == "df" else PILOT_COLUMNS
        columns = ["point", *(list(self.grid.axes) or ["config"]), *measures]
        return pd.DataFrame(self.rows(), columns=columns)


def run_sweep(
    grid: Grid, scheduler: Engine | str | None = None, progress: ProgressFn | None = None
) -> SweepResult:
    """Run every point of ``grid`` as a task; failed points are kept as failures.

    Raises
    ------
    SweepError
        Before any run, for a point whose configuration is not allowed.

    """
    points = grid.points()
    configs = [grid.config(p) for p in points]
    with using(scheduler) as engine:
        outcome = engine.map(
            run_point,
            [(grid.task, p, c, grid.settings) for p, c in zip(points, configs, strict=True)],
            points,
            "sweep points",
            progress,
        )
        where = engine.spec.describe()
    return SweepResult(grid, points, configs, outcome.results, outcome.failures, where)
