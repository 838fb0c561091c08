"""``twin import``: measured CSV logs -> a ``twin-run/1`` folder the twin can analyse.

What a lab's logs bring, and what is done with it (every step is written to ``meta.json``
under ``import``, and every assumption is stated):

- **Columns and units** (:mod:`twin.ingest.columns`): names and units from the headers or
  ``--map``; where a unit is not given it is inferred only when the data leave no doubt
  (accelerometers from gravity's magnitude at rest, time from the step, commands and gyros
  from what the platform can do) and the inference is stated.
- **Axes**: the twin's cabin axes are x forward, y right, z down (a cabin at rest reads
  az = -9.81 m/s^2); an IMU logging z up (az = +9.81) is turned (y and z negated). Gravity
  along x or y means a mapping error or a rotated mount: an error.
- **Time bases** (:mod:`twin.ingest.timebase`): jittery stamps, irregular sampling, gaps.
- **Clocks**: the IMU's clock minus the commands' is the *clock offset*. It is given
  (``--clock-offset``), measured (a copy of the commands logged on the IMU's clock: the
  two copies are cross-correlated; the motion system's delay stays in the data), zero (one
  file holds both), or estimated by aligning the measured response with the nominal twin's.
  A clock offset and a motion-system delay look alike; the import says which one the data
  can tell apart. When the offset had to be estimated from the response, a delay different
  from the nominal is absorbed in it: ``meta.json`` records ``delay_identifiable: false`` and
  ``twin diagnose`` then does not name ``delay``.
- **IMU mount**: given (``--imu-position``) or estimated from the rotation the runs hold
  (:func:`twin.ingest.align.estimate_mount`); with no rotation it is not identifiable and
  does not matter (the UGP is taken).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from twin.chain.config import MotionSystem, motion_system
from twin.chain.imu import G, ImuRecord, postprocess
from twin.chain.signals import check_signal
from twin.chain.simulate import default_imu
from twin.chain.trajectory import Trajectory, interp_columns
from twin.core.errors import DataError, UsageError
from twin.core.ownership import reading
from twin.core.progress import ProgressFn
from twin.formats.run_checks import IMU_RATE_HZ, MAX_EXTRA_DELAY_S, check_plausible
from twin.formats.runs import HEADERS, RecordedRun, RunWriter, check_run_output, check_values
from twin.ingest.align import MountEstimate, estimate_mount, lag_s
from twin.ingest.columns import (
    COMMAND_TARGETS,
    IMU_TARGETS,
    UNITS,
    Column,
    Table,
    parse_mapping,
    read_table,
    recognise,
)
from twin.ingest.timebase import Regular, check_stamps, decimate, regularise
from twin.measurement.measure import clean_config, from_imu, simulate_measurement

FloatArray = NDArray[np.float64]
#: Rate of the grids the clocks are compared on [Hz].
ALIGN_RATE_HZ = 100.0
#: An apparent extra lag beyond this [s] is not taken for a motion-system delay (what the
#: reader allows, :data:`twin.formats.run_checks.MAX_EXTRA_DELAY_S`).
MAX_PLAUSIBLE_DELAY_S = MAX_EXTRA_DELAY_S
#: Accelerometer units tried, with the magnitude of gravity each would read.
_GRAVITY_UNITS = ("m/s^2", "g", "mg", "ft/s^2")
#: IMU axes ``--imu-axes`` may name (besides ``auto``), and what they are.
AXES = {"frd": "z down", "flu": "z up"}
#: Sample rates a motion log must lie in [Hz].
RATE_RANGE_HZ = (20.0, 20000.0)
#: Commands logged faster than this are resampled to :data:`COMMAND_RATE_HZ` [Hz].
MAX_COMMAND_RATE_HZ = 250.0
COMMAND_RATE_HZ = 100.0
#: The least overlap of commands and IMU [s].
MIN_OVERLAP_S = 5.0


@dataclass(frozen=True)
class Clock:
    """How the IMU's clock was put on the commands' clock.

    Attributes
    ----------
    offset_s : float
        IMU clock minus command clock [s] (subtracted from the IMU stamps).
    how : str
        ``given``, ``measured`` (a command copy on the IMU clock), ``shared`` (one file, or
        one clock assumed), or ``estimated`` (aligned with the nominal twin).
    delay_identifiable : bool
        Whether a motion-system delay different from the nominal can still be seen.
    apparent_extra_delay_s : float
        Lag of the measured response behind the nominal twin's after the offset [s].
    statement : str
        What the data say about clock offset and delay.

    """

    offset_s: float
    how: str
    delay_identifiable: bool
    apparent_extra_delay_s: float
    statement: str

    def to_dict(self) -> dict[str, object]:
        """Return the ``import.clock`` entry of ``meta.json``."""
        return dict(self.__dict__)


@dataclass(frozen=True, eq=False)
class ImportReport:
    """What ``twin import`` made of the logs.

    Attributes
    ----------
    folder : Path
        The ``twin-run/1`` folder written.
    platform : str
        Platform.
    clock : Clock
        Clock alignment.
    mount : dict
        ``position_m``, ``how`` and, when estimated, ``std_m``.
    files : dict
        Per file: columns used (target -> header and unit), columns ignored, time base.
    notes : list of str
        Assumptions and corrections, one sentence each.
    duration_s : float
        Length of the imported run [s].

    """

    folder: Path
    platform: str
    clock: Clock
    mount: dict[str, object]
    files: dict[str, dict[str, object]]
    notes: list[str] = field(default_factory=list)
    duration_s: float = 0.0

    def to_dict(self) -> dict[str, object]:
        """Return the report as JSON-able data (also ``meta.json``'s ``import``)."""
        return {"folder": str(self.folder), "platform": self.platform,
                "clock": self.clock.to_dict(), "mount": self.mount, "files": self.files,
                "notes": self.notes, "duration_s": self.duration_s}  # fmt: skip

    def format_text(self) -> str:
        """Return a short human-readable summary."""
        pos = ", ".join(f"{v:+.3f}" for v in self.mount["position_m"])  # type: ignore[union-attr]
        lines = [
            f"imported {self.duration_s:.1f} s of {self.platform} data into {self.folder}",
            f"clock: offset {1e3 * self.clock.offset_s:+.1f} ms ({self.clock.how}); "
            f"{self.clock.statement}",
            f"IMU mount: ({pos}) m ({self.mount['how']})",
        ]
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)


@dataclass(eq=False)
class _Source:
    """One file: its table, recognised columns and time base."""

    table: Table
    columns: dict[str, Column]
    ignored: list[str]

    @property
    def name(self) -> str:
        return str(self.table.path)

    def has(self, targets: Sequence[str]) -> bool:
        return any(t in self.columns for t in targets)

    def raw(self, target: str) -> FloatArray:
        return self.table.data[:, self.columns[target].index]


def _sources(files: Sequence[str | Path], mapping: Mapping[str, tuple[str, str | None]]):
    if not files:
        raise UsageError("give at least one CSV file to import")
    out = []
    for f in files:
        table = read_table(f)
        cols, ignored = recognise(table, mapping)
        out.append(_Source(table, cols, ignored))
    found = {c.header for s in out for c in s.columns.values()}
    for target, (header, _) in mapping.items():
        if header not in found:
            raise DataError(f"--map {target}={header}: no column {header!r} in "
                            f"{', '.join(str(f) for f in files)}")  # fmt: skip
    for s in out:
        if "t" not in s.columns:
            raise DataError(f"{s.name}: no time column among {', '.join(s.table.header)}; name "
                            "it t or time, or give --map t=COLUMN")  # fmt: skip
    return out


def _roles(sources: list[_Source]) -> tuple[_Source, _Source, _Source | None]:
    """Return the command source, the IMU source and a command copy on the IMU clock."""
    imu = [s for s in sources if s.has(IMU_TARGETS)]
    if len(imu) != 1:
        what = "no file has" if not imu else f"{len(imu)} files have"
        raise DataError(f"{what} IMU columns ({', '.join(IMU_TARGETS)}); exactly one must. "
                        f"Columns seen: {_listing(sources)}")  # fmt: skip
    cmd_only = [s for s in sources if s.has(COMMAND_TARGETS) and not s.has(IMU_TARGETS)]
    if len(cmd_only) > 1:
        raise DataError("commands in several files (" + ", ".join(s.name for s in cmd_only)
                        + "); give one command file")  # fmt: skip
    if cmd_only:
        copy = imu[0] if imu[0].has(COMMAND_TARGETS) else None
        return cmd_only[0], imu[0], copy
    if not imu[0].has(COMMAND_TARGETS):
        raise DataError(f"no command columns ({', '.join(COMMAND_TARGETS)}) in any file. "
                        f"Columns seen: {_listing(sources)}")  # fmt: skip
    return imu[0], imu[0], None


def _listing(sources: list[_Source]) -> str:
    return "; ".join(f"{Path(s.name).name}: {', '.join(s.table.header)}" for s in sources)


def _finite_rows(s: _Source, targets: Sequence[str]) -> FloatArray:
    idx = [s.columns["t"].index] + [s.columns[t].index for t in targets if t in s.columns]
    data = s.table.data[:, idx]
    bad = np.argwhere(~np.isfinite(data))
    if bad.size:
        row, col = bad[0]
        header = s.table.header[idx[col]]
        raise DataError(f"{s.name}: line {row + 2}, column {header!r} is empty or not finite; "
                        "every used cell must be a number")  # fmt: skip
    return data


def _time_unit(s: _Source, notes: list[str]) -> float:
    col = s.columns["t"]
    step = float(np.median(np.diff(check_stamps(s.raw("t"), s.name))))
    if col.unit is not None:
        rate = 1.0 / (step * col.factor())
        if not RATE_RANGE_HZ[0] <= rate <= RATE_RANGE_HZ[1]:
            raise DataError(f"{s.name}: column {col.header!r} in {col.unit} gives a sample rate "
                            f"of {rate:.4g} Hz; a motion log must be sampled at "
                            f"{RATE_RANGE_HZ[0]:g}-{RATE_RANGE_HZ[1]:g} Hz")  # fmt: skip
        return col.factor()
    for unit, factor in UNITS["time"].items():
        if RATE_RANGE_HZ[0] <= 1.0 / (step * factor) <= RATE_RANGE_HZ[1]:
            if unit != "s":
                notes.append(f"{Path(s.name).name}: time {col.header!r} taken as {unit} "
                             f"(a step of {step:g} s would be {1 / step:.3g} Hz)")  # fmt: skip
            return factor
    raise DataError(f"{s.name}: the time column {col.header!r} steps by {step:g}; no unit of "
                    f"{', '.join(UNITS['time'])} makes that {RATE_RANGE_HZ[0]:g}-"
                    f"{RATE_RANGE_HZ[1]:g} Hz")  # fmt: skip


def _accel_factor(s: _Source, notes: list[str]) -> float:
    cols = [s.columns[a] for a in ("ax", "ay", "az") if a in s.columns]
    if "az" not in s.columns:
        raise DataError(f"{s.name}: no az column; the vertical accelerometer is needed (it reads "
                        "gravity and heave)")  # fmt: skip
    units = {c.unit for c in cols if c.unit}
    if len(units) > 1:
        raise DataError(f"{s.name}: accelerometers in different units ({', '.join(units)})")
    raw = np.column_stack([s.raw(c.target) for c in cols])
    magnitude = float(np.nanmedian(np.linalg.norm(raw, axis=1)))
    if units:
        unit = units.pop()
        if abs(magnitude * UNITS["acceleration"][unit] / G - 1) > 0.3:
            raise DataError(f"{s.name}: the accelerometers read {magnitude:.4g} {unit} of "
                            f"gravity; 1 g is {G / UNITS['acceleration'][unit]:.4g} {unit}: "
                            "check the unit or the columns")  # fmt: skip
        return UNITS["acceleration"][unit]
    for unit in _GRAVITY_UNITS:
        if abs(magnitude * UNITS["acceleration"][unit] / G - 1) < 0.2:
            if unit != "m/s^2":
                notes.append(f"{Path(s.name).name}: accelerometers taken as {unit} (gravity "
                             f"reads {magnitude:.4g})")  # fmt: skip
            return UNITS["acceleration"][unit]
    raise DataError(f"{s.name}: the accelerometers read gravity as {magnitude:.4g}; that is "
                    f"1 g in none of {', '.join(_GRAVITY_UNITS)}; give the unit, e.g. --map "
                    "az=COLUMN:g")  # fmt: skip


def _command_factor(s: _Source, target: str, limit: float, alt: str, notes: list[str]) -> float:
    col = s.columns[target]
    if col.unit is not None:
        return col.factor()
    peak = float(np.nanmax(np.abs(s.raw(target))))
    si = next(iter(UNITS[col.kind]))
    if peak > limit and peak * UNITS[col.kind][alt] <= limit:
        notes.append(f"{Path(s.name).name}: {col.header!r} taken as {alt} (up to {peak:.4g}: "
                     f"beyond any simulator in {si})")  # fmt: skip
        return UNITS[col.kind][alt]
    return 1.0


def _gyro_factor(s: _Source, commands: Trajectory, notes: list[str]) -> float:
    cols = [s.columns[g] for g in ("p", "q", "r") if g in s.columns]
    units = {c.unit for c in cols if c.unit}
    if len(units) > 1:
        raise DataError(f"{s.name}: gyros in different units ({', '.join(units)})")
    if units:
        return UNITS["rate"][units.pop()]
    if not cols:
        return 1.0
    commanded = commands.at(commands.t, 1)[:, 3:]
    best = None
    for c in cols:
        k = ("p", "q", "r").index(c.target)
        want = float(np.std(commanded[:, k]))
        got = float(np.nanstd(s.raw(c.target)))
        if want > 0 and (best is None or want > best[0]):
            best = (want, got)
    if best is not None and best[0] > 1e-3:
        ratio = best[1] / best[0]
        if 0.3 * np.degrees(1) < ratio < 3 * np.degrees(1):
            notes.append(f"{Path(s.name).name}: gyros taken as deg/s (they read "
                         f"{ratio:.3g}x the commanded rate in rad/s)")  # fmt: skip
            return UNITS["rate"]["deg/s"]
    return 1.0


def _commands(src: _Source, notes: list[str]) -> tuple[Regular, Trajectory]:
    data = _finite_rows(src, COMMAND_TARGETS)
    tf = _time_unit(src, notes)
    present = [t for t in COMMAND_TARGETS if t in src.columns]
    factors = [
        _command_factor(src, t, 1.0, "mm", notes) if t in ("x", "y", "z")
        else _command_factor(src, t, 1.2, "deg", notes)
        for t in present
    ]  # fmt: skip
    reg = regularise(data[:, 0] * tf, data[:, 1:] * np.array(factors), src.name, smooth=True)
    if reg.rate_hz > MAX_COMMAND_RATE_HZ:
        notes.append(f"{Path(src.name).name}: commands logged at {reg.rate_hz:g} Hz; low-passed "
                     f"and resampled to {COMMAND_RATE_HZ:g} Hz (their rounding would otherwise "
                     "read as acceleration)")  # fmt: skip
        reg = decimate(reg, COMMAND_RATE_HZ)
    values = np.zeros((len(reg.values), 6))
    for j, t in enumerate(present):
        values[:, COMMAND_TARGETS.index(t)] = reg.values[:, j]
    return reg, Trajectory(reg.rate_hz, values, reg.t0)


def _imu(src: _Source, commands: Trajectory, axes: str, notes: list[str]) -> Regular:
    """Return the IMU file on a uniform grid: ax..r in SI, cabin axes (six columns)."""
    data = _finite_rows(src, IMU_TARGETS)
    tf = _time_unit(src, notes)
    fa, fg = _accel_factor(src, notes), _gyro_factor(src, commands, notes)
    present = [t for t in IMU_TARGETS if t in src.columns]
    values = np.zeros((len(data), 6))
    values[:, 2] = -G
    for j, t in enumerate(present):
        values[:, IMU_TARGETS.index(t)] = data[:, 1 + j] * (fa if t[0] == "a" else fg)
    missing = [t for t in IMU_TARGETS if t not in src.columns]
    if missing:
        notes.append(f"{Path(src.name).name}: no {', '.join(missing)}; taken as at rest")
    gravity = np.median(values[:, :3], axis=0)
    if axes in AXES and abs(gravity[2]) >= 0.8 * G and (gravity[2] > 0) != (axes == "flu"):
        implied = "flu" if gravity[2] > 0 else "frd"
        raise DataError(f"{src.name}: --imu-axes {axes}, but gravity reads az {gravity[2]:+.2f} "
                        f"m/s^2 at rest, which is {AXES[implied]} ({implied}); give --imu-axes "
                        f"{implied}, or auto to take the axes from gravity")  # fmt: skip
    if axes == "auto":
        if abs(gravity[2]) < 0.8 * G:
            raise DataError(f"{src.name}: gravity reads ({', '.join(f'{g:.2f}' for g in gravity)})"
                            " m/s^2 at rest; the twin needs it along z (about -9.81 for z down, "
                            "+9.81 for z up): check the column mapping; a rotated IMU mount is "
                            "not supported")  # fmt: skip
        axes = "flu" if gravity[2] > 0 else "frd"
        if axes == "flu":
            notes.append(
                f"{Path(src.name).name}: the IMU logs z up (az reads {gravity[2]:+.2f} m/s^2 at "
                "rest); turned to the twin's z down (y, z, q, r negated)"
            )
    if axes == "flu":
        values[:, [1, 2, 4, 5]] *= -1
    elif axes != "frd":
        raise UsageError(f"IMU axes must be auto, frd or flu; got {axes!r}")
    reg = regularise(data[:, 0] * tf, values, src.name, smooth=False)
    if reg.rate_hz < IMU_RATE_HZ[0]:
        raise DataError(f"{src.name}: the IMU is logged at {reg.rate_hz:.4g} Hz; the analyses "
                        f"need at least {IMU_RATE_HZ[0]:g} Hz (App. C.2.3's grid)")  # fmt: skip
    return reg


def _grid(t0: float, t1: float) -> FloatArray:
    return t0 + np.arange(int(np.floor((t1 - t0) * ALIGN_RATE_HZ)) + 1) / ALIGN_RATE_HZ


def _overlap_guess(cmd: Regular, imu: Regular) -> bool:
    """Whether the two files' times plausibly share an epoch (their spans overlap by half)."""
    a0, a1 = cmd.t[0], cmd.t[-1]
    b0, b1 = imu.t[0], imu.t[-1]
    return min(a1, b1) - max(a0, b0) > 0.5 * min(a1 - a0, b1 - b0)


def _search(ref_t0: float, ref: FloatArray, other_t0: float, other: FloatArray,
            shared: bool, what: str) -> float | None:  # fmt: skip
    """Return the offset (other clock minus reference) that best aligns two 100 Hz series.

    None where the files' times overlap (``shared``) but the series correlate too weakly to
    check it (a run whose response is small against the noise, e.g. lines far above the
    MPI's 1 Hz filter): one clock is then assumed.
    """
    span = max(len(ref), len(other)) / ALIGN_RATE_HZ
    start = other_t0 - ref_t0  # offset if both clocks were one
    if shared:
        lag, peak = lag_s(ref, other, ALIGN_RATE_HZ, 1.0, centre_s=-start)
        if np.isfinite(lag) and peak > 0.3:
            return start + lag
    lag, peak = lag_s(ref, other, ALIGN_RATE_HZ, span)
    if not np.isfinite(lag) or peak < 0.1:
        if shared:
            return None
        raise DataError(f"cannot align the clocks: {what} do not correlate (peak {peak:.2f}); "
                        "give --clock-offset")  # fmt: skip
    return start + lag


def _measurement(commands: Trajectory, imu: Regular, offset: float, config: MotionSystem):
    """Post-processed measured accelerations on the command clock (IMU cropped to commands)."""
    t = imu.t - offset
    inside = (t >= commands.t[0]) & (t <= commands.t[-1])
    if inside.sum() / imu.rate_hz < MIN_OVERLAP_S:
        raise DataError(
            f"the IMU overlaps the commands by {inside.sum() / imu.rate_hz:.2f} s after aligning "
            f"the clocks; at least {MIN_OVERLAP_S:g} s are needed"
        )
    rec = ImuRecord(t[inside], imu.values[inside, :3], imu.values[inside, 3:])
    return rec, from_imu(commands, rec, "import", config, {})


def _nominal_prediction(config: MotionSystem, commands: Trajectory, t: FloatArray,
                        imu_rate: float) -> FloatArray:  # fmt: skip
    imu = default_imu(config.platform)
    spec = type(imu)(rate_hz=imu_rate, accel_range=imu.accel_range, gyro_range=imu.gyro_range)
    return simulate_measurement(clean_config(config), commands, t, "reduced", 0, spec.ideal())


def _clock(
    given: float | None,
    cmd_src: _Source,
    imu_src: _Source,
    copy: _Source | None,
    cmd: Regular,
    commands: Trajectory,
    imu: Regular,
    config: MotionSystem,
) -> Clock:
    """Align the clocks (see module docstring)."""
    shared_guess = _overlap_guess(cmd, imu)
    if given is not None:
        offset, how = float(given), "given"
    elif copy is None and cmd_src is imu_src:
        offset, how = 0.0, "shared"
    elif copy is not None:
        targets = [t for t in COMMAND_TARGETS if t in copy.columns]
        rows = _finite_rows(copy, targets)
        tf = _time_unit(copy, [])
        factors = np.array([cmd_src.columns[t].factor() if t in cmd_src.columns else 1.0
                            for t in targets])  # fmt: skip
        reg = regularise(rows[:, 0] * tf, rows[:, 1:] * factors, copy.name, smooth=True)
        idx = [COMMAND_TARGETS.index(t) for t in targets]
        g_ref = _grid(commands.t[0], commands.t[-1])
        g_copy = _grid(reg.t[0], reg.t[-1])
        ref = commands.at(g_ref)[:, idx]
        other = interp_columns(g_copy, reg.t, reg.values[:, : len(idx)])
        found = _search(g_ref[0], ref, g_copy[0], other, shared_guess,
                        "the commands and their copy in the IMU file")  # fmt: skip
        offset, how = (0.0, "shared") if found is None else (found, "measured")
    else:  # the measured response against the nominal twin's, each on its own clock
        g_ref = _grid(commands.t[0], commands.t[-1])
        ref = _nominal_prediction(config, commands, g_ref, imu.rate_hz)
        p = postprocess(ImuRecord(imu.t, imu.values[:, :3], imu.values[:, 3:]), ALIGN_RATE_HZ)
        measured = np.hstack([p.accel + np.array([0.0, 0.0, G]), p.angular_acceleration])
        use = _informative(ref)
        found = _search(g_ref[0], ref[:, use], p.t[0], measured[:, use], shared_guess,
                        "the measured and the nominal twin's accelerations")  # fmt: skip
        if found is None:
            return Clock(0.0, "shared", True, 0.0, (
                "the files' times overlap: one clock assumed; the response is too weak against "
                "the noise to check it by aligning it with the nominal twin (give "
                "--clock-offset if the clocks differ)"))  # fmt: skip
        offset, how = found, "estimated"
    nominal_delay = float(np.max(config.delays_s))
    if how == "estimated" and shared_guess and -nominal_delay <= offset <= MAX_PLAUSIBLE_DELAY_S:
        extra, offset = offset, 0.0
        statement = (
            f"the files' times overlap: one clock assumed; the response lags the nominal "
            f"twin by {1e3 * extra:+.1f} ms more: a motion-system delay or a clock offset, "
            "which these data cannot tell apart (no copy of the commands on the IMU clock); "
            "the diagnosis sees it as delay; give --clock-offset if the clocks differ"
        )
        return Clock(0.0, "shared", True, extra, statement)
    if how == "estimated":
        if not shared_guess:
            why = "the files' clocks differ"
        elif offset < -nominal_delay:
            why = (f"on one clock the IMU responds {-1e3 * (offset + nominal_delay):.0f} ms "
                   "before its commands, which no motion system does: a clock offset")  # fmt: skip
        else:
            why = f"on one clock the IMU would lag by {1e3 * offset:.0f} ms: a clock offset"
        statement = (f"{why}; estimated by aligning the response with the nominal twin, so a "
                     "motion-system delay different from the nominal is absorbed in it and "
                     "cannot be diagnosed from these runs (log the commands on the IMU clock, "
                     "or give --clock-offset, to tell them apart)")  # fmt: skip
        return Clock(offset, how, False, 0.0, statement)
    _, m = _measurement(commands, imu, offset, config)
    pred = _nominal_prediction(config, commands, m.t, imu.rate_hz)
    use = _informative(pred)
    extra, _ = lag_s(pred[:, use], m.measured[:, use], ALIGN_RATE_HZ, MAX_PLAUSIBLE_DELAY_S)
    extra = float(extra) if np.isfinite(extra) else 0.0
    statement = {
        "given": "the offset is given",
        "shared": "one file holds commands and IMU (one clock)",
        "measured": "measured from the command copy on the IMU clock (told apart from the "
        "motion-system delay)",
    }[how] + (f"; the response lags the nominal twin by {1e3 * extra:+.1f} ms more: a "
              "motion-system delay, for the diagnosis to name")  # fmt: skip
    return Clock(offset, how, True, extra, statement)


def _informative(pred: FloatArray) -> list[int]:
    """Channels the nominal twin predicts a clear response in (within 5 % of the largest)."""
    sd = pred.std(axis=0)
    out = [k for g in (slice(0, 3), slice(3, 6)) for k in range(g.start, g.stop)
           if sd[g].max() > 0 and sd[k] >= 0.05 * sd[g].max()]  # fmt: skip
    if not out:
        raise DataError("the nominal twin predicts no response to these commands")
    return out


def _mount(given: Sequence[float] | None, m, pred: FloatArray, rec: ImuRecord) -> dict:
    if given is not None:
        pos = [float(v) for v in given]
        if len(pos) != 3 or not np.all(np.isfinite(pos)) or max(map(abs, pos)) > 5.0:
            raise UsageError(f"--imu-position must be 3 finite numbers within 5 m; got {given}")
        return {"position_m": pos, "how": "given"}
    p = postprocess(rec, ALIGN_RATE_HZ)
    n = min(len(p.t), len(m.t))
    est: MountEstimate = estimate_mount(m.t[:n], m.measured[:n, :3] - pred[:n, :3],
                                        p.gyro[:n], m.measured[:n, 3:], pred[:n, 3:])  # fmt: skip
    if not est.identifiable:
        return {"position_m": [0.0, 0.0, 0.0], "how": "not identifiable (the runs do not "
                "rotate; a mount offset does not show, nor matter); the UGP taken",
                "angular_acceleration_rms": est.angular_acceleration_rms}  # fmt: skip
    hidden = [a for a, s in zip("xyz", est.std_m, strict=True) if not np.isfinite(s)]
    how = "estimated from the rotation (coordinates within 4 sd of zero set to zero"
    if hidden:
        how += f"; {', '.join(hidden)} not identifiable: no rotation shows it, taken 0"
    how += ")"
    return {"position_m": list(est.significant()), "how": how,
            "estimate_m": [v if np.isfinite(s) else None for v, s in zip(est.position_m,
                                                                        est.std_m, strict=True)],
            "std_m": [s if np.isfinite(s) else None for s in est.std_m]}  # fmt: skip


def import_run(
    files: Sequence[str | Path],
    out: str | Path,
    platform: str | None = None,
    config: str | MotionSystem | None = None,
    mapping: Sequence[str] = (),
    clock_offset_s: float | None = None,
    imu_position_m: Sequence[float] | None = None,
    imu_axes: str = "auto",
    overwrite: bool = False,
    progress: ProgressFn | None = None,
) -> ImportReport:
    """Turn measured CSV logs into a ``twin-run/1`` folder (see module docstring).

    Parameters
    ----------
    files : sequence of path
        One CSV holding commands and IMU, or a command CSV and an IMU CSV (which may also
        hold a copy of the commands, logged on its clock).
    out : path
        The run folder to write (written completely or not at all).
    platform : str, optional
        ``mpi`` or ``srs`` (the platform of ``config`` when given).
    config : str or MotionSystem, optional
        The motion system the run was made on (``meta.json``'s ``platform_config``; the
        nominal of a later diagnosis); the platform's named configuration by default.
    mapping : sequence of str
        ``TARGET=COLUMN[:UNIT]`` items for columns the names do not give.
    clock_offset_s : float, optional
        IMU clock minus command clock [s], when known.
    imu_position_m : sequence of float, optional
        IMU mount relative to the UGP in cabin axes [m], when known.
    imu_axes : str
        ``auto`` (from gravity), ``frd`` (x fwd, y right, z down) or ``flu`` (z up).
    overwrite : bool
        Replace an existing folder.
    progress : callable, optional
        Called with a message at each step.

    Raises
    ------
    DataError
        A file or column that cannot be used (the message says which and why).
    UsageError
        Options that are not allowed.

    """
    say = progress or (lambda _msg: None)
    if config is None and platform is None:
        raise UsageError("give the platform (mpi or srs) or the configuration the run was made on")
    cfg = config if isinstance(config, MotionSystem) else motion_system(config or platform)
    if platform is not None and cfg.platform != platform:
        raise UsageError(f"configuration {cfg.name!r} is of the {cfg.platform} platform, not "
                         f"{platform}")  # fmt: skip
    if clock_offset_s is not None and not np.isfinite(clock_offset_s):
        raise UsageError(f"--clock-offset must be a finite number of seconds; got {clock_offset_s}")
    with reading(*files):  # the logs are inputs: never replaced, --overwrite or not
        return _import(files, out, cfg, mapping, clock_offset_s, imu_position_m, imu_axes,
                       overwrite, say)  # fmt: skip


def _import(
    files: Sequence[str | Path],
    out: str | Path,
    cfg: MotionSystem,
    mapping: Sequence[str],
    clock_offset_s: float | None,
    imu_position_m: Sequence[float] | None,
    imu_axes: str,
    overwrite: bool,
    say: ProgressFn,
) -> ImportReport:
    """Import the logs (:func:`import_run`'s work, once its options are checked)."""
    check_run_output(out, overwrite)
    sources = _sources(files, parse_mapping(mapping))
    cmd_src, imu_src, copy = _roles(sources)
    notes: list[str] = []
    say("reading the commands")
    cmd_reg, commands = _commands(cmd_src, notes)
    say("reading the IMU")
    imu_reg = _imu(imu_src, commands, imu_axes, notes)
    say("aligning the clocks with the nominal twin")
    clock = _clock(clock_offset_s, cmd_src, imu_src, copy, cmd_reg, commands, imu_reg, cfg)
    rec, m = _measurement(commands, imu_reg, clock.offset_s, cfg)
    pred = _nominal_prediction(cfg, commands, m.t, imu_reg.rate_hz)
    say("locating the IMU")
    mount = _mount(imu_position_m, m, pred, rec)
    t0 = commands.t0  # the run starts at its first command
    commands = Trajectory(commands.rate_hz, commands.values, 0.0)
    check_signal(commands, cfg.platform, f"the commands of {cmd_src.name}")
    files_info = {}
    for s, reg in ((cmd_src, cmd_reg), (imu_src, imu_reg)):
        files_info[s.name] = {
            "columns": {c.target: {"header": c.header, "unit": c.unit or "inferred"}
                        for c in s.columns.values()},
            "ignored": s.ignored,
            "time_base": reg.to_dict(),
        }  # fmt: skip
    report = ImportReport(Path(out), cfg.platform, clock, mount, files_info, notes,
                          float(commands.duration))  # fmt: skip
    meta = {
        "platform": cfg.platform,
        "platform_config": cfg.to_meta(),
        "command_rate_hz": commands.rate_hz,
        "imu": {"position_m": mount["position_m"], "rate_hz": imu_reg.rate_hz},
        "notes": f"imported by twin import from {', '.join(str(f) for f in files)}",
        "import": report.to_dict() | {"folder": None},
    }
    imu = np.hstack([rec.accel, rec.gyro])
    check_values(imu, HEADERS["imu.csv"][1:], f"the IMU of {imu_src.name} (in m/s^2 and rad/s)")
    check_plausible(RecordedRun(Path(out), meta, commands, rec.t - t0, imu, None),
                    f"the IMU of {imu_src.name}, imported")  # fmt: skip
    with RunWriter(out, meta, overwrite=overwrite, files=("commands.csv", "imu.csv")) as w:
        w.write("commands.csv", commands.t, commands.values)
        w.write("imu.csv", rec.t - t0, imu)
    say(f"wrote {out}")
    return report
